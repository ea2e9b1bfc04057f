//! Textures: linear values (reflectance decoded from sRGB by `image`, or
//! linear data), looked up bilinearly or at the nearest texel, each axis
//! repeating, clamped to its edge or mirrored (glTF's samplers).

use glam::{Vec2, Vec3};

use super::image::RgbImage;

/// What a lookup outside [0, 1] reads, per axis (glTF's `wrapS`, `wrapT`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wrap {
    Repeat,
    ClampToEdge,
    MirroredRepeat,
    /// Black outside [0, 1] (UsdUVTexture's `black`).
    Black,
}

/// How a lookup between texel centres is filtered (glTF's `magFilter`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Filter {
    /// Bilinear between the four nearest texels.
    Linear,
    /// The nearest texel.
    Nearest,
}

/// Texels as compactly as they can be kept exactly (docs/design.md §5.3,
/// "Textures in memory"): what a lookup reads is the same f32 either way.
#[derive(Debug, Clone)]
enum Texels {
    /// 8-bit codes, each channel read through `table` (an encoding's
    /// decoding of k/255: sRGB's, or linear's): 3 bytes a texel.
    Codes { codes: Vec<[u8; 3]>, table: &'static [f32; 256] },
    /// Half floats (an OpenEXR's half channels): 6 bytes a texel.
    Half(Vec<[half::f16; 3]>),
    /// Anything else (16-bit and float data, generated texels): 12 bytes.
    Float(Vec<Vec3>),
}

/// The decoding of 8-bit code k as an sRGB value and as a linear one,
/// computed as the image readers compute it (k as f32 / 255, then decoded),
/// so a code stands for exactly the f32 the reader made.
fn tables() -> [&'static [f32; 256]; 2] {
    static TABLES: std::sync::OnceLock<[[f32; 256]; 2]> = std::sync::OnceLock::new();
    let tables = TABLES.get_or_init(|| {
        let code = |k: usize| f32::from(k as u8) / 255.0;
        [std::array::from_fn(|k| crate::util::color::srgb_to_linear(code(k))), std::array::from_fn(code)]
    });
    [&tables[0], &tables[1]]
}

impl Texels {
    /// The most compact exact form of `texels`.
    fn compact(texels: Vec<Vec3>) -> Self {
        for table in tables() {
            let code = |v: f32| -> Option<u8> {
                let k = table.partition_point(|&t| t < v);
                (k < 256 && table[k].to_bits() == v.to_bits()).then_some(k as u8)
            };
            let codes: Option<Vec<[u8; 3]>> =
                texels.iter().map(|t| Some([code(t.x)?, code(t.y)?, code(t.z)?])).collect();
            if let Some(codes) = codes {
                return Self::Codes { codes, table };
            }
        }
        let half = |v: f32| -> Option<half::f16> {
            let h = half::f16::from_f32(v);
            (h.to_f32().to_bits() == v.to_bits()).then_some(h)
        };
        let halves: Option<Vec<[half::f16; 3]>> =
            texels.iter().map(|t| Some([half(t.x)?, half(t.y)?, half(t.z)?])).collect();
        match halves {
            Some(halves) => Self::Half(halves),
            None => Self::Float(texels),
        }
    }

    fn get(&self, index: usize) -> Vec3 {
        match self {
            Self::Codes { codes, table } => {
                let [r, g, b] = codes[index];
                Vec3::new(table[r as usize], table[g as usize], table[b as usize])
            }
            Self::Half(halves) => {
                let [r, g, b] = halves[index];
                Vec3::new(r.to_f32(), g.to_f32(), b.to_f32())
            }
            Self::Float(texels) => texels[index],
        }
    }

    fn bytes_per_texel(&self) -> usize {
        match self {
            Self::Codes { .. } => 3,
            Self::Half(_) => 6,
            Self::Float(_) => 12,
        }
    }
}

#[derive(Debug, Clone)]
pub struct Texture {
    width: usize,
    height: usize,
    /// Linear RGB, row 0 at the top of the image.
    texels: Texels,
    /// Along u and along v.
    wrap: [Wrap; 2],
    filter: Filter,
}

impl Texture {
    /// A texture of a decoded image (see [`super::image::read_texture`]).
    #[must_use]
    pub fn from_image(image: RgbImage) -> Self {
        Self::from_texels(image.width, image.height, image.texels)
    }

    /// A texture from linear texels (tests and generated scenes).
    #[must_use]
    pub fn from_texels(width: usize, height: usize, texels: Vec<Vec3>) -> Self {
        assert_eq!(width * height, texels.len());
        Self { width, height, texels: Texels::compact(texels), wrap: [Wrap::Repeat; 2], filter: Filter::Linear }
    }

    /// The texture read with a sampler's wrap modes (along u, along v) and
    /// filter.
    #[must_use]
    pub fn with_sampler(self, wrap: [Wrap; 2], filter: Filter) -> Self {
        Self { wrap, filter, ..self }
    }

    /// Width and height, texels.
    #[must_use]
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// The linear texel at `index` (row-major, row 0 at the top).
    #[must_use]
    pub fn texel_at(&self, index: usize) -> Vec3 {
        self.texels.get(index)
    }

    /// The bytes each texel takes in memory: 3 for 8-bit codes, 6 for
    /// half floats, 12 otherwise.
    #[must_use]
    pub fn bytes_per_texel(&self) -> usize {
        self.texels.bytes_per_texel()
    }

    fn texel(&self, x: i64, y: i64) -> Vec3 {
        let outside = |i: i64, n: usize, wrap: Wrap| wrap == Wrap::Black && !(0..n as i64).contains(&i);
        if outside(x, self.width, self.wrap[0]) || outside(y, self.height, self.wrap[1]) {
            return Vec3::ZERO;
        }
        let index = |i: i64, n: usize, wrap: Wrap| -> usize {
            let n = n as i64;
            (match wrap {
                Wrap::Repeat => i.rem_euclid(n),
                Wrap::ClampToEdge | Wrap::Black => i.clamp(0, n - 1),
                Wrap::MirroredRepeat => {
                    let m = i.rem_euclid(2 * n);
                    if m < n {
                        m
                    } else {
                        2 * n - 1 - m
                    }
                }
            }) as usize
        };
        let (x, y) = (index(x, self.width, self.wrap[0]), index(y, self.height, self.wrap[1]));
        self.texels.get(y * self.width + x)
    }

    /// The lookup at uv, v = 0 at the bottom of the image.
    #[must_use]
    pub fn lookup(&self, uv: Vec2) -> Vec3 {
        // Keep the coordinate small before scaling so huge uv stay accurate:
        // within one period of the wrap (the texel index wraps again).
        let reduce = |t: f32, wrap: Wrap| match wrap {
            Wrap::Repeat => t.rem_euclid(1.0),
            Wrap::MirroredRepeat => t.rem_euclid(2.0),
            Wrap::ClampToEdge | Wrap::Black => t.clamp(-1.0, 2.0),
        };
        let u = reduce(uv.x, self.wrap[0]) * self.width as f32;
        let v = (1.0 - reduce(uv.y, self.wrap[1])) * self.height as f32;
        if self.filter == Filter::Nearest {
            return self.texel(u.floor() as i64, v.floor() as i64);
        }
        let (u, v) = (u - 0.5, v - 0.5);
        let (x0, y0) = (u.floor(), v.floor());
        let (fx, fy) = (u - x0, v - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let top = self.texel(x0, y0).lerp(self.texel(x0 + 1, y0), fx);
        let bottom = self.texel(x0, y0 + 1).lerp(self.texel(x0 + 1, y0 + 1), fx);
        top.lerp(bottom, fy)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texels_are_kept_in_the_most_compact_exact_form() {
        let srgb = |k: u8| crate::util::color::srgb_to_linear(f32::from(k) / 255.0);
        let cases: [(Vec<Vec3>, usize); 4] = [
            // An 8-bit sRGB image as the readers decode it.
            ((0..=255u8).map(|k| Vec3::new(srgb(k), srgb(255 - k), srgb(k / 2))).collect(), 3),
            // 8-bit linear data (a metallic-roughness map).
            ((0..=255u8).map(|k| Vec3::splat(f32::from(k) / 255.0)).collect(), 3),
            // Half floats (an OpenEXR's), beyond 1.
            ((0..256).map(|k| Vec3::new(k as f32 * 0.25, 1000.0, 0.5)).collect(), 6),
            // Anything else.
            ((0..256).map(|k| Vec3::splat(k as f32 * 0.123_456_7)).collect(), 12),
        ];
        for (texels, bytes) in cases {
            let texture = Texture::from_texels(256, 1, texels.clone()).with_sampler([Wrap::Repeat; 2], Filter::Nearest);
            assert_eq!(texture.bytes_per_texel(), bytes);
            for (i, t) in texels.iter().enumerate() {
                assert_eq!(texture.texel_at(i).to_array().map(f32::to_bits), t.to_array().map(f32::to_bits));
                let uv = Vec2::new((i as f32 + 0.5) / 256.0, 0.5);
                assert_eq!(texture.lookup(uv), *t, "texel {i}");
            }
        }
    }

    #[test]
    fn lookup_wraps_and_interpolates() {
        let t = Texture::from_texels(2, 1, vec![Vec3::ZERO, Vec3::ONE]);
        // Texel centres at u = 0.25 and 0.75.
        assert!((t.lookup(Vec2::new(0.25, 0.5)) - Vec3::ZERO).length() < 1e-6);
        assert!((t.lookup(Vec2::new(0.75, 0.5)) - Vec3::ONE).length() < 1e-6);
        assert!((t.lookup(Vec2::new(0.5, 0.5)) - Vec3::splat(0.5)).length() < 1e-6);
        assert!((t.lookup(Vec2::new(1.75, -3.5)) - Vec3::ONE).length() < 1e-6);
        // Halfway across the wrap seam, between the last and first texel.
        assert!((t.lookup(Vec2::new(0.0, 0.5)) - Vec3::splat(0.5)).length() < 1e-6);
    }

    /// glTF's wrap modes, per axis, and the nearest filter, on a 4 x 1
    /// ramp (0, 1, 2, 3 at u = 0.125, 0.375, 0.625, 0.875).
    #[test]
    fn wrap_modes_and_the_nearest_filter_read_the_texels_they_name() {
        let ramp = |wrap: Wrap, filter: Filter| {
            let texels = (0..4).map(|i| Vec3::splat(i as f32)).collect();
            Texture::from_texels(4, 1, texels).with_sampler([wrap, Wrap::Repeat], filter)
        };
        let at = |t: &Texture, u: f32| t.lookup(Vec2::new(u, 0.5)).x;
        let nearest = |wrap| ramp(wrap, Filter::Nearest);
        // Repeat: u + 1 is u.
        assert_eq!(at(&nearest(Wrap::Repeat), 1.125), 0.0);
        assert_eq!(at(&nearest(Wrap::Repeat), -0.125), 3.0);
        // Clamp: the edge texel beyond [0, 1].
        assert_eq!(at(&nearest(Wrap::ClampToEdge), 1.6), 3.0);
        assert_eq!(at(&nearest(Wrap::ClampToEdge), -7.0), 0.0);
        // Mirror: [1, 2] reads the image backwards.
        assert_eq!(at(&nearest(Wrap::MirroredRepeat), 1.125), 3.0);
        assert_eq!(at(&nearest(Wrap::MirroredRepeat), 1.875), 0.0);
        assert_eq!(at(&nearest(Wrap::MirroredRepeat), -0.125), 0.0);
        // Nearest does not blend; linear does, and clamps at the edge.
        assert_eq!(at(&nearest(Wrap::Repeat), 0.49), 1.0);
        assert!((at(&ramp(Wrap::Repeat, Filter::Linear), 0.5) - 1.5).abs() < 1e-6);
        assert!((at(&ramp(Wrap::ClampToEdge, Filter::Linear), 0.99) - 3.0).abs() < 1e-6);
        // Linear and repeating: halfway between the last texel and the first.
        assert!((at(&ramp(Wrap::Repeat, Filter::Linear), 0.0) - 1.5).abs() < 1e-6);
    }
}
