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
    /// A radiance that no light can have (NaN, infinite, negative, or above
    /// [`MAX_EMISSION`](super::MAX_EMISSION)).
    #[error(
        "pixel ({x}, {y}) holds {value}: a radiance must be finite, >= 0 and at most {:e} W/(m^2 sr)",
        super::MAX_EMISSION
    )]
    BadRadiance { x: usize, y: usize, value: String },
    /// The header asks for more than an image may be ([`MAX_TEXELS`]), or
    /// for more pixels than the file's bytes can hold: a corrupt or hostile
    /// header, refused before anything is allocated for it.
    #[error("{field}: {message}")]
    Header { field: String, message: String },
}

/// The most texels an image a scene reads may have (2^27: a 16,384 x
/// 8,192 environment map); at 12 bytes a linear texel, 1.5 GiB.
pub const MAX_TEXELS: u64 = 1 << 27;

/// The most an image's pixels may outweigh its file: deflate (PNG; EXR's
/// ZIP and PXR24) expands at most 1,032-fold, EXR's RLE 64-fold, B44 under
/// 11-fold, PIZ's Huffman runs a few hundred-fold, a JPEG block costs at
/// least a bit a component (under 1,000-fold); twice deflate's bound leaves
/// a margin.
pub const MAX_EXPANSION: u64 = 2048;

/// Refuses a header's `width` x `height` image of `bytes_per_texel`
/// before anything is allocated for it: more than [`MAX_TEXELS`], or more
/// bytes than a file of `length` bytes can expand to ([`MAX_EXPANSION`]).
fn check_size(field: &str, width: u64, height: u64, bytes_per_texel: u64, length: u64) -> Result<(), ImageError> {
    let header = |message: String| ImageError::Header { field: field.to_string(), message };
    let texels = width.saturating_mul(height);
    if texels == 0 || texels > MAX_TEXELS {
        return Err(header(format!("{width} x {height} pixels (at most {MAX_TEXELS} in all, at least 1)")));
    }
    if texels.saturating_mul(bytes_per_texel) > length.saturating_mul(MAX_EXPANSION) {
        return Err(header(format!(
            "{width} x {height} pixels of {bytes_per_texel} bytes cannot be stored in a file of {length} bytes"
        )));
    }
    Ok(())
}

/// Reads an OpenEXR's headers (nothing of its pixels) and refuses one whose
/// layers could not be read within [`MAX_TEXELS`], or whose pixels and chunk
/// offsets `length` bytes cannot hold ([`MAX_EXPANSION`]). The `exr`
/// crate trusts the header's data window: one flipped byte of it made the
/// reader allocate 103 GB, so every EXR path calls this first.
pub fn check_exr_header(reader: impl std::io::Read, length: u64) -> Result<(), ImageError> {
    let meta = exr::meta::MetaData::read_from_buffered(reader, false).map_err(ImageError::Exr)?;
    for (i, layer) in meta.headers.iter().enumerate() {
        let field = |name: &str| if meta.headers.len() == 1 { name.to_string() } else { format!("part {i}: {name}") };
        let (width, height) = (layer.layer_size.width() as u64, layer.layer_size.height() as u64);
        check_size(&field("dataWindow"), width, height, layer.channels.bytes_per_pixel as u64, length)?;
        if (layer.chunk_count as u64).saturating_mul(8) > length {
            return Err(ImageError::Header {
                field: field("dataWindow"),
                message: format!(
                    "{width} x {height} pixels need {} chunks, more than a file of {length} bytes can list",
                    layer.chunk_count
                ),
            });
        }
    }
    Ok(())
}

/// Reads a PNG (8 or 16 bits, grey or colour, palettes expanded) and decodes
/// its sRGB values to linear.
pub fn read_srgb_png(path: &Path) -> Result<RgbImage, ImageError> {
    read_png(path, Encoding::Srgb)
}

/// Reads a PNG whose colours are encoded as `encoding` says.
pub fn read_png(path: &Path, encoding: Encoding) -> Result<RgbImage, ImageError> {
    let file = crate::util::file::open_regular(path).map_err(ImageError::Open)?;
    let length = file.metadata().map_err(ImageError::Open)?.len();
    decode_png(std::io::BufReader::new(file), length, encoding)
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
        decode_png(std::io::Cursor::new(bytes), bytes.len() as u64, encoding)
    } else if bytes.starts_with(&[0xff, 0xd8]) {
        decode_jpeg(bytes, encoding)
    } else {
        Err(ImageError::UnknownFormat)
    }
}

fn decode_jpeg(bytes: &[u8], encoding: Encoding) -> Result<RgbImage, ImageError> {
    let mut decoder = jpeg_decoder::Decoder::new(std::io::Cursor::new(bytes));
    // The frame header first: the decoder's own buffer limit is not kept
    // by every allocation it makes (65,535 x 65,535 took 8.6 GB).
    decoder.read_info().map_err(ImageError::Jpeg)?;
    let info = decoder.info().ok_or(ImageError::Empty)?;
    check_size("SOF", info.width.into(), info.height.into(), 4, bytes.len() as u64)?;
    decoder.set_max_decoding_buffer_size(MAX_TEXELS as usize * 4);
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

fn decode_png(reader: impl std::io::Read, length: u64, encoding: Encoding) -> Result<RgbImage, ImageError> {
    let mut decoder = png::Decoder::new(reader);
    // Expand palettes and low bit depths to 8 bits; keep 16-bit as is.
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().map_err(ImageError::Png)?;
    let (width, height) = reader.info().size();
    let (color, depth) = reader.output_color_type();
    let bytes_per_texel = color.samples() as u64 * if depth == png::BitDepth::Sixteen { 2 } else { 1 };
    check_size("IHDR", width.into(), height.into(), bytes_per_texel, length)?;
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
    let mut file = crate::util::file::open_regular(path).map_err(ImageError::Open)?;
    let length = file.metadata().map_err(ImageError::Open)?.len();
    check_exr_header(std::io::BufReader::new(&mut file), length)?;
    use std::io::Seek;
    file.rewind().map_err(ImageError::Open)?;
    radiance_exr(std::io::BufReader::new(file))
}

/// [`read_radiance_exr`] of an EXR in memory (a texture inside a `.usdz`).
pub fn decode_radiance_exr(bytes: &[u8]) -> Result<RgbImage, ImageError> {
    check_exr_header(bytes, bytes.len() as u64)?;
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
    let bad = |t: &Vec3| !t.is_finite() || t.min_element() < 0.0 || t.max_element() > super::MAX_EMISSION;
    if let Some(index) = image.texels.iter().position(bad) {
        let t = image.texels[index];
        let value = format!("({:e}, {:e}, {:e})", t.x, t.y, t.z);
        return Err(ImageError::BadRadiance { x: index % image.width, y: index / image.width, value });
    }
    if image.texels.is_empty() {
        return Err(ImageError::Empty);
    }
    Ok(image)
}
