//! Textures: linear values (reflectance decoded from sRGB by `image`, or
//! linear data), looked up bilinearly or at the nearest texel, each axis
//! repeating, clamped to its edge or mirrored (glTF's samplers); filtered
//! over a pixel's footprint by a MIP map (docs/design.md §5.3, "MIP maps").

use glam::{Vec2, Vec3};

use super::image::RgbImage;
use super::texels::Texels;

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

/// One level of a texture's MIP map.
#[derive(Debug, Clone)]
struct Level {
    width: usize,
    height: usize,
    /// Linear RGB, row 0 at the top of the image.
    texels: Texels,
}

impl Level {
    /// The next coarser level: half the size, rounded up; each texel the
    /// mean of the 2 x 2 texels of this level it covers (the last row or
    /// column counted twice where the size is odd).
    fn halved(&self) -> Self {
        let (width, height) = (self.width.div_ceil(2), self.height.div_ceil(2));
        let at = |x: usize, y: usize| self.texels.get(y.min(self.height - 1) * self.width + x.min(self.width - 1));
        let texels = (0..height)
            .flat_map(|y| (0..width).map(move |x| (x, y)))
            .map(|(x, y)| {
                let (x, y) = (2 * x, 2 * y);
                0.25 * (at(x, y) + at(x + 1, y) + at(x, y + 1) + at(x + 1, y + 1))
            })
            .collect();
        Self { width, height, texels: self.texels.encoded_like(texels) }
    }
}

/// The longest a filter's ellipse may be for its width (pbrt-v4's
/// `maxAnisotropy` default): a longer one is widened, which bounds the
/// texels a lookup sums.
const MAX_ANISOTROPY: f32 = 8.0;

/// The most texels one EWA lookup visits.
const MAX_EWA_TEXELS: i64 = 4096;

#[derive(Debug, Clone)]
pub struct Texture {
    /// The MIP map: level 0 is the image, each next level half the size
    /// of the one before, down to a single texel (docs/design.md §5.3).
    levels: Vec<Level>,
    /// Along u and along v.
    wrap: [Wrap; 2],
    filter: Filter,
}

impl Texture {
    /// A texture of a decoded image (see [`super::image::read_texture`]).
    #[must_use]
    pub fn from_image(image: RgbImage) -> Self {
        Self::from_compact(image.width, image.height, image.texels)
    }

    /// A texture from linear texels (tests and generated scenes).
    #[must_use]
    pub fn from_texels(width: usize, height: usize, texels: Vec<Vec3>) -> Self {
        Self::from_compact(width, height, Texels::compact(texels))
    }

    /// A texture of `texels` as they are kept (f32 ones put in their most
    /// compact exact form).
    #[must_use]
    pub fn from_compact(width: usize, height: usize, texels: Texels) -> Self {
        assert_eq!(width * height, texels.len());
        let texels = match texels {
            Texels::Float(floats) => Texels::compact(floats),
            kept => kept,
        };
        let mut levels = vec![Level { width, height, texels }];
        while let Some(last) = levels.last().filter(|l| l.width * l.height > 1) {
            levels.push(last.halved());
        }
        Self { levels, wrap: [Wrap::Repeat; 2], filter: Filter::Linear }
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
        (self.levels[0].width, self.levels[0].height)
    }

    /// The linear texel at `index` of the image (row-major, row 0 at the top).
    #[must_use]
    pub fn texel_at(&self, index: usize) -> Vec3 {
        self.levels[0].texels.get(index)
    }

    /// The bytes each texel of the image takes in memory: 3 for 8-bit
    /// codes, 6 for half floats, 12 otherwise.
    #[must_use]
    pub fn bytes_per_texel(&self) -> usize {
        self.levels[0].texels.bytes_per_texel()
    }

    /// The bytes its texels take, every MIP level counted (about 4/3 of
    /// the image's).
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.levels.iter().map(|l| l.width * l.height * l.texels.bytes_per_texel()).sum()
    }

    /// How many levels its MIP map has (1 for a single texel).
    #[must_use]
    pub fn levels(&self) -> usize {
        self.levels.len()
    }

    fn texel(&self, level: usize, x: i64, y: i64) -> Vec3 {
        let Level { width, height, ref texels } = self.levels[level];
        let outside = |i: i64, n: usize, wrap: Wrap| wrap == Wrap::Black && !(0..n as i64).contains(&i);
        if outside(x, width, self.wrap[0]) || outside(y, height, self.wrap[1]) {
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
        let (x, y) = (index(x, width, self.wrap[0]), index(y, height, self.wrap[1]));
        texels.get(y * width + x)
    }

    /// The lookup at uv, v = 0 at the bottom of the image, of the image
    /// itself (MIP level 0).
    #[must_use]
    pub fn lookup(&self, uv: Vec2) -> Vec3 {
        self.lookup_level(0, uv)
    }

    /// The lookup at uv filtered over a pixel's footprint, `duv_dx` and
    /// `duv_dy` the change of uv from one pixel to the next along the
    /// film's x and y: pbrt-v4's `MIPMap::Filter` with its EWA filter
    /// (Heckbert's elliptically weighted average). The two changes span an
    /// ellipse, its ratio of axes clamped to [`MAX_ANISOTROPY`] by
    /// widening the minor one; the level whose texels are as wide as the
    /// minor axis is chosen, and a Gaussian over the ellipse is summed at
    /// the two levels either side, blended by where between them it falls.
    /// A footprint within one texel of the image reads it bilinearly (so a
    /// zero footprint is [`Texture::lookup`] exactly); so does the nearest
    /// filter (glTF's pixel art) read the image.
    #[must_use]
    pub fn filtered(&self, uv: Vec2, duv_dx: Vec2, duv_dy: Vec2) -> Vec3 {
        let (width, height) = self.size();
        // The changes in texels of the image, rows downwards.
        let texels = Vec2::new(width as f32, -(height as f32));
        let (mut major, mut minor) = (duv_dx * texels, duv_dy * texels);
        if major.length_squared() < minor.length_squared() {
            std::mem::swap(&mut major, &mut minor);
        }
        let (long, mut short) = (major.length(), minor.length());
        // Also a NaN footprint reads the image.
        if self.filter == Filter::Nearest || long.is_nan() || long <= 1.0 {
            return self.lookup(uv);
        }
        if short * MAX_ANISOTROPY < long {
            let widen = long / (short * MAX_ANISOTROPY);
            // A footprint of one direction (short 0) is widened to a
            // direction across it.
            minor = if short > 0.0 { minor * widen } else { major.perp() / MAX_ANISOTROPY };
            short = long / MAX_ANISOTROPY;
        }
        let last = self.levels.len() - 1;
        let level = short.log2().max(0.0);
        // Wider than the whole image: its mean, the last level's texel (an
        // ellipse there could span more texels than any loop should visit).
        if level >= last as f32 {
            return self.lookup_level(last, uv);
        }
        let below = level.floor();
        let (i, blend) = (below as usize, level - below);
        self.ewa(i, uv, major, minor).lerp(self.ewa(i + 1, uv, major, minor), blend)
    }

    /// pbrt-v4's `MIPMap::EWA`: the texels of level `level` inside the
    /// ellipse of axes `major` and `minor` (texels of the image) about uv,
    /// each weighed by a Gaussian of its squared radius r² in the ellipse,
    /// e^(-2 r²) - e^(-2); the ellipse grown by a texel of this level
    /// either way, so that it always holds one.
    fn ewa(&self, level: usize, uv: Vec2, major: Vec2, minor: Vec2) -> Vec3 {
        let Level { width, height, .. } = self.levels[level];
        let (full_width, full_height) = self.size();
        let shrink = Vec2::new(width as f32 / full_width as f32, height as f32 / full_height as f32);
        let (d0, d1) = (major * shrink, minor * shrink);
        let (x, y) = self.texel_coordinates(level, uv);
        let (x, y) = (x - 0.5, y - 0.5);
        // The ellipse A s² + B s t + C t² < 1.
        let mut a = d0.y * d0.y + d1.y * d1.y + 1.0;
        let mut b = -2.0 * (d0.x * d0.y + d1.x * d1.y);
        let mut c = d0.x * d0.x + d1.x * d1.x + 1.0;
        let scale = 1.0 / (a * c - 0.25 * b * b);
        (a, b, c) = (a * scale, b * scale, c * scale);
        let det = 4.0 * a * c - b * b;
        let (half_x, half_y) = (2.0 * (det * c).max(0.0).sqrt() / det, 2.0 * (det * a).max(0.0).sqrt() / det);
        let (x0, x1) = ((x - half_x).ceil() as i64, (x + half_x).floor() as i64);
        let (y0, y1) = ((y - half_y).ceil() as i64, (y + half_y).floor() as i64);
        // The chosen level holds the ellipse in about 16 x 16 texels; only a
        // strip of an image (one texel high, whose levels stop halving
        // across it) could ask for far more: read that bilinearly.
        if (x1 - x0).saturating_add(1).saturating_mul((y1 - y0).saturating_add(1)) > MAX_EWA_TEXELS {
            return self.lookup_level(level, uv);
        }
        let (mut sum, mut weights) = (Vec3::ZERO, 0.0);
        for ty in y0..=y1 {
            let t = ty as f32 - y;
            for tx in x0..=x1 {
                let s = tx as f32 - x;
                let r2 = a * s * s + b * s * t + c * t * t;
                if r2 < 1.0 {
                    let weight = (-2.0 * r2).exp() - (-2.0f32).exp();
                    sum += weight * self.texel(level, tx, ty);
                    weights += weight;
                }
            }
        }
        if weights > 0.0 {
            sum / weights
        } else {
            self.lookup_level(level, uv)
        }
    }

    /// Where uv falls on level `level`, in its texels (rows downwards),
    /// the coordinates kept within one period of the wrap first, so that
    /// huge ones stay accurate (the texel index wraps again).
    fn texel_coordinates(&self, level: usize, uv: Vec2) -> (f32, f32) {
        let Level { width, height, .. } = self.levels[level];
        let reduce = |t: f32, wrap: Wrap| match wrap {
            Wrap::Repeat => t.rem_euclid(1.0),
            Wrap::MirroredRepeat => t.rem_euclid(2.0),
            Wrap::ClampToEdge | Wrap::Black => t.clamp(-1.0, 2.0),
        };
        (reduce(uv.x, self.wrap[0]) * width as f32, (1.0 - reduce(uv.y, self.wrap[1])) * height as f32)
    }

    fn lookup_level(&self, level: usize, uv: Vec2) -> Vec3 {
        let (u, v) = self.texel_coordinates(level, uv);
        if self.filter == Filter::Nearest {
            return self.texel(level, u.floor() as i64, v.floor() as i64);
        }
        let (u, v) = (u - 0.5, v - 0.5);
        let (x0, y0) = (u.floor(), v.floor());
        let (fx, fy) = (u - x0, v - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let top = self.texel(level, x0, y0).lerp(self.texel(level, x0 + 1, y0), fx);
        let bottom = self.texel(level, x0, y0 + 1).lerp(self.texel(level, x0 + 1, y0 + 1), fx);
        top.lerp(bottom, fy)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 64 x 64 checkerboard of 8-texel checks, 0 and 1.
    fn checks() -> Texture {
        let texels = (0..64 * 64).map(|i| Vec3::splat(((i % 64 / 8 + i / 64 / 8) % 2) as f32)).collect();
        Texture::from_texels(64, 64, texels)
    }

    #[test]
    fn a_footprint_as_wide_as_two_checks_reads_their_mean() {
        let texture = checks();
        assert_eq!(texture.levels(), 7);
        // 8-bit codes at every level: 4/3 of the image's 3 bytes a texel.
        assert_eq!(texture.memory_bytes(), 3 * (4096 + 1024 + 256 + 64 + 16 + 4 + 1));
        let texel = 1.0 / 64.0;
        for k in 0..97 {
            let uv = Vec2::new(0.013 + 0.0101 * k as f32, 0.977 - 0.0093 * k as f32);
            // No footprint, or one within a texel: the image itself.
            assert_eq!(texture.filtered(uv, Vec2::ZERO, Vec2::ZERO), texture.lookup(uv));
            assert_eq!(
                texture.filtered(uv, Vec2::new(0.7 * texel, 0.0), Vec2::new(0.0, 0.7 * texel)),
                texture.lookup(uv)
            );
            // 16 texels a pixel either way: level 4, whose texels each
            // cover 2 x 2 checks; a footprint wider than the image reads
            // the last level, their mean too. To the precision of the
            // levels' 8-bit codes (sRGB's, which hold 0 and 1 exactly:
            // half a step near 0.5 is under 0.004).
            let (dx, dy) = (Vec2::new(16.0 * texel, 0.0), Vec2::new(0.0, -16.0 * texel));
            assert!((texture.filtered(uv, dx, dy) - Vec3::splat(0.5)).abs().max_element() < 0.004, "{uv}");
            let far = texture.filtered(uv, Vec2::new(1e8, 0.0), Vec2::new(0.0, 1e8));
            assert!((far - Vec3::splat(0.5)).abs().max_element() < 0.008);
        }
        // Growing footprints read from the image's check to the mean.
        // (The centre of texel (12, 4), in a check of 1s.)
        let uv = Vec2::new(12.5 * texel, 1.0 - 4.5 * texel);
        let read: Vec<f32> = [0.5, 1.0, 2.0, 4.0, 5.66, 8.0, 16.0]
            .iter()
            .map(|w| texture.filtered(uv, Vec2::new(w * texel, 0.0), Vec2::new(0.0, w * texel)).x)
            .collect();
        assert_eq!(read[0], 1.0);
        assert!(read.iter().all(|r| (0.49..=1.0).contains(r)) && (read[6] - 0.5).abs() < 0.004, "{read:?}");
    }

    /// The EWA filter is anisotropic: a footprint long across stripes
    /// averages them, one long along them keeps each stripe's value.
    #[test]
    fn a_long_footprint_blurs_along_its_length_only() {
        // Vertical stripes 8 texels wide: 1 where x / 8 is odd.
        let texels = (0..64 * 64).map(|i| Vec3::splat((i % 64 / 8 % 2) as f32)).collect();
        let texture = Texture::from_texels(64, 64, texels);
        let texel = 1.0 / 64.0;
        for k in 0..8 {
            // The centre of a stripe of 1s, anywhere down it.
            let uv = Vec2::new(12.0 * texel, 0.1 + 0.1 * k as f32);
            let (short, long) = (Vec2::new(0.0, 2.0 * texel), Vec2::new(0.0, 16.0 * texel));
            // Long down the stripe, two texels across: the stripe.
            let along = texture.filtered(uv, short.perp(), long).x;
            // Long across the stripes: their mean, within the Gaussian's
            // lopsidedness over two of them.
            let across = texture.filtered(uv, long.perp(), short).x;
            assert!(along > 0.95, "{along} at {uv}");
            assert!((across - 0.5).abs() < 0.15, "{across} at {uv}");
        }
    }

    /// Footprints from a thousandth of a texel to a million images, of
    /// any shape, on a square image and on a strip one texel high, read a
    /// value among the texels' (and in bounded time: an ellipse on the
    /// last level once spanned millions of texels, which the fuzzer found).
    #[test]
    fn every_footprint_reads_a_value_among_the_texels() {
        let strip = Texture::from_texels(64, 1, (0..64).map(|i| Vec3::splat((i % 2) as f32)).collect());
        for texture in [checks(), strip] {
            for e in -3..=6 {
                for shape in [Vec2::new(1.0, 1.0), Vec2::new(1.0, 0.01), Vec2::new(0.3, 7.0), Vec2::new(0.0, 1.0)] {
                    let (dx, dy) = (Vec2::new(shape.x, 0.2 * shape.y), Vec2::new(-0.1 * shape.x, shape.y));
                    let scale = 10f32.powi(e) / 64.0;
                    let read = texture.filtered(Vec2::new(0.37, 0.61), dx * scale, dy * scale);
                    assert!((0.0..=1.0).contains(&read.x) && read.x == read.y, "{read} at {e}, {shape}");
                }
            }
        }
    }

    #[test]
    fn mip_levels_halve_odd_sizes_and_keep_the_encoding() {
        let srgb = |k: u8| crate::util::color::srgb_to_linear(f32::from(k) / 255.0);
        let texels: Vec<Vec3> = (0..15u8).map(|k| Vec3::new(srgb(17 * k), srgb(255 - 17 * k), srgb(100))).collect();
        let texture = Texture::from_texels(5, 3, texels.clone());
        // 5 x 3, 3 x 2, 2 x 1, 1 x 1.
        assert_eq!(texture.levels(), 4);
        assert_eq!(texture.memory_bytes(), 3 * (15 + 6 + 2 + 1));
        // Level 1's first texel is the mean of the image's 2 x 2 corner,
        // rounded to the nearest sRGB code (within half a code's step).
        let mean = 0.25 * (texels[0] + texels[1] + texels[5] + texels[6]);
        let level1 = texture.lookup_level(1, Vec2::new(1.0 / 6.0, 0.75));
        for (got, want) in level1.to_array().into_iter().zip(mean.to_array()) {
            let code = crate::util::color::linear_to_srgb(want) * 255.0;
            let step = srgb(code.ceil() as u8) - srgb(code.floor() as u8);
            assert!((got - want).abs() <= 0.5 * step + 1e-6, "{got} for {want}");
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
