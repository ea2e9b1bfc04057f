//! Reading the images a scene names: PNG textures (sRGB-encoded colours,
//! decoded to linear reflectance) and OpenEXR environment maps (linear
//! radiance). Both become linear RGB texels, row 0 at the top of the image.

use std::path::Path;

use glam::Vec3;

use crate::util::color::srgb_to_linear;

/// Linear RGB texels, `width * height` of them, row by row from the top.
#[derive(Debug, Clone, PartialEq)]
pub struct RgbImage {
    pub width: usize,
    pub height: usize,
    pub texels: Vec<Vec3>,
    /// Coverage (linear, 0 to 1) per texel, for a PNG with an alpha channel.
    pub alpha: Option<Vec<f32>>,
}

/// Why an image a scene names cannot be used. Caused by the user's file.
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    /// The file cannot be opened (missing, a directory, no permission).
    #[error("cannot open: {0}")]
    Open(#[source] std::io::Error),
    /// The PNG decoder rejected the file (not a PNG, truncated, corrupt).
    #[error("not a readable PNG: {0}")]
    Png(#[source] png::DecodingError),
    /// The JPEG decoder rejected the file (truncated, corrupt, unsupported).
    #[error("not a readable JPEG: {0}")]
    Jpeg(#[source] jpeg_decoder::Error),
    /// Neither PNG nor JPEG.
    #[error("not a PNG or JPEG image")]
    UnknownFormat,
    /// The EXR reader rejected the file (not an EXR, truncated, no R, G and B).
    #[error("cannot read EXR: {0}")]
    Exr(#[source] exr::error::Error),
    /// The image has no pixels.
    #[error("the image is empty")]
    Empty,
    /// A radiance that no light can have (NaN, infinite or negative).
    #[error("pixel {index} is not a finite, non-negative radiance")]
    BadRadiance { index: usize },
}

/// Reads a PNG (8 or 16 bits, grey or colour, palettes expanded) and decodes
/// its sRGB values to linear.
pub fn read_srgb_png(path: &Path) -> Result<RgbImage, ImageError> {
    read_png(path, Encoding::Srgb)
}

/// Reads a PNG whose colours are encoded as `encoding` says.
pub fn read_png(path: &Path, encoding: Encoding) -> Result<RgbImage, ImageError> {
    let file = std::fs::File::open(path).map_err(ImageError::Open)?;
    decode_png(std::io::BufReader::new(file), encoding)
}

/// How an image's colour values are encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Encoding {
    /// sRGB-encoded colours (base colour, emission), decoded to linear.
    Srgb,
    /// Linear data (glTF's metallic-roughness texture), read as is.
    Linear,
}

impl Encoding {
    fn decode(self, value: f32) -> f32 {
        match self {
            Self::Srgb => srgb_to_linear(value),
            Self::Linear => value,
        }
    }
}

/// Decodes an in-memory PNG or JPEG (told apart by their signatures) from
/// sRGB to linear.
pub fn decode_srgb(bytes: &[u8]) -> Result<RgbImage, ImageError> {
    decode(bytes, Encoding::Srgb)
}

/// Decodes an in-memory PNG or JPEG (told apart by their signatures),
/// colours encoded as `encoding` says.
pub fn decode(bytes: &[u8], encoding: Encoding) -> Result<RgbImage, ImageError> {
    if bytes.starts_with(b"\x89PNG") {
        decode_png(std::io::Cursor::new(bytes), encoding)
    } else if bytes.starts_with(&[0xff, 0xd8]) {
        decode_jpeg(bytes, encoding)
    } else {
        Err(ImageError::UnknownFormat)
    }
}

fn decode_jpeg(bytes: &[u8], encoding: Encoding) -> Result<RgbImage, ImageError> {
    let mut decoder = jpeg_decoder::Decoder::new(std::io::Cursor::new(bytes));
    // Refuse absurd headers before allocating for them (64 MiB of pixels).
    decoder.set_max_decoding_buffer_size(64 << 20);
    let pixels = decoder.decode().map_err(ImageError::Jpeg)?;
    let info = decoder.info().ok_or(ImageError::Empty)?;
    let (width, height) = (usize::from(info.width), usize::from(info.height));
    let channels = match info.pixel_format {
        jpeg_decoder::PixelFormat::L8 => 1,
        jpeg_decoder::PixelFormat::RGB24 => 3,
        jpeg_decoder::PixelFormat::L16 | jpeg_decoder::PixelFormat::CMYK32 => return Err(ImageError::UnknownFormat),
    };
    if width * height == 0 || pixels.len() < width * height * channels {
        return Err(ImageError::Empty);
    }
    let texels = (0..width * height)
        .map(|p| {
            let c = |k: usize| encoding.decode(f32::from(pixels[p * channels + k.min(channels - 1)]) / 255.0);
            Vec3::new(c(0), c(1), c(2))
        })
        .collect();
    Ok(RgbImage { width, height, texels, alpha: None })
}

fn decode_png(reader: impl std::io::Read, encoding: Encoding) -> Result<RgbImage, ImageError> {
    let mut decoder = png::Decoder::new(reader);
    // Expand palettes and low bit depths to 8 bits; keep 16-bit as is.
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().map_err(ImageError::Png)?;
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).map_err(ImageError::Png)?;
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
        texels.push(Vec3::new(encoding.decode(rgb.x), encoding.decode(rgb.y), encoding.decode(rgb.z)));
    }
    if texels.is_empty() {
        return Err(ImageError::Empty);
    }
    // Alpha is linear coverage (PNG's grey + alpha and RGBA), not sRGB.
    let alpha =
        matches!(channels, 2 | 4).then(|| (0..width * height).map(|p| sample(p * channels + channels - 1)).collect());
    Ok(RgbImage { width, height, texels, alpha })
}

/// Reads the R, G and B channels of an OpenEXR's first RGB layer as radiance,
/// each finite and non-negative.
pub fn read_radiance_exr(path: &Path) -> Result<RgbImage, ImageError> {
    let file = std::fs::File::open(path).map_err(ImageError::Open)?;
    radiance_exr(std::io::BufReader::new(file))
}

/// [`read_radiance_exr`] of an EXR in memory (a texture inside a `.usdz`).
pub fn decode_radiance_exr(bytes: &[u8]) -> Result<RgbImage, ImageError> {
    radiance_exr(std::io::Cursor::new(bytes))
}

fn radiance_exr(reader: impl std::io::Read + std::io::Seek) -> Result<RgbImage, ImageError> {
    use exr::prelude::{ReadChannels, ReadLayers};
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |size, _| RgbImage {
                width: size.width(),
                height: size.height(),
                texels: vec![Vec3::ZERO; size.area()],
                alpha: None,
            },
            |image: &mut RgbImage, at, (r, g, b, _): (f32, f32, f32, f32)| {
                image.texels[at.y() * image.width + at.x()] = Vec3::new(r, g, b);
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(reader)
        .map_err(ImageError::Exr)?;
    let image = image.layer_data.channel_data.pixels;
    if let Some(index) = image.texels.iter().position(|t| !t.is_finite() || t.min_element() < 0.0) {
        return Err(ImageError::BadRadiance { index });
    }
    if image.texels.is_empty() {
        return Err(ImageError::Empty);
    }
    Ok(image)
}
