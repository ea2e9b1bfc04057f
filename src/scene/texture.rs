//! Textures: linear reflectance (decoded from sRGB PNGs by `image`), looked
//! up bilinearly with wrap-around.

use glam::{Vec2, Vec3};

use super::image::RgbImage;

#[derive(Debug, Clone)]
pub struct Texture {
    width: usize,
    height: usize,
    /// Linear RGB, row 0 at the top of the image.
    texels: Vec<Vec3>,
}

impl Texture {
    /// A texture of a decoded image (see [`super::image::read_srgb_png`]).
    #[must_use]
    pub fn from_image(image: RgbImage) -> Self {
        Self::from_texels(image.width, image.height, image.texels)
    }

    /// A texture from linear texels (tests and generated scenes).
    #[must_use]
    pub fn from_texels(width: usize, height: usize, texels: Vec<Vec3>) -> Self {
        assert_eq!(width * height, texels.len());
        Self { width, height, texels }
    }

    fn texel(&self, x: i64, y: i64) -> Vec3 {
        let x = x.rem_euclid(self.width as i64) as usize;
        let y = y.rem_euclid(self.height as i64) as usize;
        self.texels[y * self.width + x]
    }

    /// Bilinear lookup; uv repeats, v = 0 at the bottom of the image.
    #[must_use]
    pub fn lookup(&self, uv: Vec2) -> Vec3 {
        // Keep the coordinate small before scaling so huge uv stay accurate.
        let u = uv.x.rem_euclid(1.0) * self.width as f32 - 0.5;
        let v = (1.0 - uv.y.rem_euclid(1.0)) * self.height as f32 - 0.5;
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
}
