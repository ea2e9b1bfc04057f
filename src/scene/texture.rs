//! PNG textures: sRGB-encoded colours decoded to linear reflectance, looked
//! up bilinearly with wrap-around.

use std::path::Path;

use glam::{Vec2, Vec3};

use super::error::SceneError;

#[derive(Debug, Clone)]
pub struct Texture {
    width: usize,
    height: usize,
    /// Linear RGB, row 0 at the top of the image.
    texels: Vec<Vec3>,
}

/// The sRGB electro-optical transfer function (IEC 61966-2-1).
#[must_use]
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

impl Texture {
    pub fn load_png(path: &Path) -> Result<Self, SceneError> {
        let err = |m: String| SceneError::new(path, "PNG", m);
        let file = std::fs::File::open(path).map_err(|e| err(format!("cannot open texture: {e}")))?;
        let mut decoder = png::Decoder::new(std::io::BufReader::new(file));
        // Expand palettes and low bit depths to 8 bits; keep 16-bit as is.
        decoder.set_transformations(png::Transformations::EXPAND);
        let mut reader = decoder.read_info().map_err(|e| err(format!("not a readable PNG: {e}")))?;
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).map_err(|e| err(format!("corrupt PNG data: {e}")))?;
        let (width, height) = (info.width as usize, info.height as usize);
        let channels = info.color_type.samples();
        let sixteen = info.bit_depth == png::BitDepth::Sixteen;
        let sample = |i: usize| -> f32 {
            if sixteen {
                f32::from(u16::from_be_bytes([buf[2 * i], buf[2 * i + 1]])) / 65535.0
            } else {
                f32::from(buf[i]) / 255.0
            }
        };
        let mut texels = Vec::with_capacity(width * height);
        for p in 0..width * height {
            let base = p * channels;
            let rgb = match channels {
                1 | 2 => Vec3::splat(sample(base)),
                _ => Vec3::new(sample(base), sample(base + 1), sample(base + 2)),
            };
            texels.push(Vec3::new(srgb_to_linear(rgb.x), srgb_to_linear(rgb.y), srgb_to_linear(rgb.z)));
        }
        if texels.is_empty() {
            return Err(err("texture has no pixels".into()));
        }
        Ok(Self { width, height, texels })
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
    fn srgb_decoding_hits_known_points() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        assert!((srgb_to_linear(0.5) - 0.214).abs() < 1e-3);
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
}
