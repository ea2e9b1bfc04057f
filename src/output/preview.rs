//! A tone-mapped 8-bit sRGB PNG preview of the beauty pass: exposure in stops,
//! clamp to [0, 1], then the sRGB transfer curve (IEC 61966-2-1).

use std::path::Path;

use super::{stage, OutputError, Staged};
use crate::render::Film;
use crate::util::color::linear_to_srgb;

/// 8-bit sRGB value of a linear value after `exposure` stops.
#[must_use]
pub fn to_srgb8(linear: f32, scale: f32) -> u8 {
    let v = (linear * scale).clamp(0.0, 1.0);
    (linear_to_srgb(v) * 255.0 + 0.5) as u8
}

/// Writes the film's window as an RGB PNG.
pub fn write_png(path: &Path, film: &Film, exposure_stops: f32) -> Result<(), OutputError> {
    stage_png(path, film, exposure_stops)?.commit()
}

/// [`write_png`] up to the rename (see [`super::Staged`]).
pub fn stage_png(path: &Path, film: &Film, exposure_stops: f32) -> Result<Staged, OutputError> {
    let scale = exposure_stops.exp2();
    let data: Vec<u8> = film.rgb().iter().flat_map(|p| p.map(|c| to_srgb8(c, scale))).collect();
    stage_rgb_png(path, film.bounds.width(), film.bounds.height(), &data)
}

/// Writes 8-bit RGB data as a PNG, atomically.
pub fn write_rgb_png(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<(), OutputError> {
    stage_rgb_png(path, width, height, rgb)?.commit()
}

/// [`write_rgb_png`] up to the rename (see [`super::Staged`]).
pub fn stage_rgb_png(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<Staged, OutputError> {
    let png_error = |source| OutputError::Png { path: path.to_path_buf(), source };
    stage(path, |file| {
        let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        let mut writer = encoder.write_header().map_err(png_error)?;
        writer.write_image_data(rgb).map_err(png_error)?;
        writer.finish().map_err(png_error)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn previews_clamp_and_map_nan_to_black() {
        assert_eq!(to_srgb8(2.0, 1.0), 255);
        assert_eq!(to_srgb8(-1.0, 1.0), 0);
        assert_eq!(to_srgb8(f32::NAN, 1.0), 0);
    }
}
