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

#[derive(Debug, Clone)]
pub struct Texture {
    width: usize,
    height: usize,
    /// Linear RGB, row 0 at the top of the image.
    texels: Vec<Vec3>,
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
        Self { width, height, texels, wrap: [Wrap::Repeat; 2], filter: Filter::Linear }
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

    /// The linear texels, row 0 at the top.
    #[must_use]
    pub fn texels(&self) -> &[Vec3] {
        &self.texels
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
        self.texels[y * self.width + x]
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
