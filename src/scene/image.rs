//! Reading the images a scene names: textures (PNG, JPEG, TGA, BMP, TIFF,
//! OpenEXR, Radiance HDR; 8- and 16-bit colours decoded from sRGB where the
//! scene says they are encoded so, float images scene-linear as stored) and
//! OpenEXR environment maps (linear radiance). All become linear RGB texels,
//! row 0 at the top of the image; an 8-bit image is kept as its codes
//! (`texels`, docs/design.md §5.3 "Textures in memory").

use std::path::Path;

use glam::Vec3;

pub use super::texels::Encoding;
use super::texels::{Coverage, Texels};

/// Linear RGB texels, `width * height` of them, row by row from the top.
#[derive(Debug, Clone, PartialEq)]
pub struct RgbImage {
    pub width: usize,
    pub height: usize,
    /// 8-bit codes for an 8-bit image, f32 otherwise.
    pub texels: Texels,
    /// Coverage (linear, 0 to 1) per texel, for an image with an alpha
    /// channel.
    pub alpha: Option<Coverage>,
    /// The file stores scene-linear floats (OpenEXR, Radiance HDR, float
    /// TIFF): no sRGB decoding applies to them, whatever the scene says.
    pub scene_linear: bool,
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
    /// Not a format this reader reads.
    #[error("not a PNG, JPEG, TGA, BMP, TIFF, OpenEXR or Radiance HDR image")]
    UnknownFormat,
    /// The decoder of a TGA, BMP, TIFF or HDR file rejected it.
    #[error("not a readable {format}: {message}")]
    Other { format: &'static str, message: String },
    /// A texel that is not a finite number (a float image).
    #[error("pixel ({x}, {y}) is not finite")]
    NotFinite { x: usize, y: usize },
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

/// The largest texture file read, bytes (a 16k x 8k float RGBA EXR is 2 GiB
/// uncompressed; the texel limit refuses larger images anyway).
pub const MAX_TEXTURE_FILE_BYTES: u64 = 1 << 31;

/// Reads a texture in any format [`decode_named`] reads, its 8- and 16-bit
/// colours encoded as `encoding` says.
pub fn read_texture(path: &Path, encoding: Encoding) -> Result<RgbImage, ImageError> {
    let bytes = crate::util::file::read_regular(path, MAX_TEXTURE_FILE_BYTES).map_err(ImageError::Open)?;
    decode_named(&bytes, &path.to_string_lossy(), encoding)
}

/// [`decode`] from sRGB to linear.
pub fn decode_srgb(bytes: &[u8]) -> Result<RgbImage, ImageError> {
    decode(bytes, Encoding::Srgb)
}

/// Decodes an in-memory image (its format told by its signature), 8- and
/// 16-bit colours encoded as `encoding` says.
pub fn decode(bytes: &[u8], encoding: Encoding) -> Result<RgbImage, ImageError> {
    decode_named(bytes, "", encoding)
}

/// [`decode`], with the file's `name` telling a TGA (the one format without
/// a signature) by its extension.
pub fn decode_named(bytes: &[u8], name: &str, encoding: Encoding) -> Result<RgbImage, ImageError> {
    if bytes.starts_with(b"\x89PNG") {
        decode_png(std::io::Cursor::new(bytes), bytes.len() as u64, encoding)
    } else if bytes.starts_with(&[0xff, 0xd8]) {
        decode_jpeg(bytes, encoding)
    } else if bytes.starts_with(&EXR_MAGIC) {
        check_exr_header(bytes, bytes.len() as u64)?;
        texture_exr(std::io::Cursor::new(bytes))
    } else {
        decode_other(bytes, name, encoding)
    }
}

/// OpenEXR's magic number, its first four bytes.
pub const EXR_MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];

/// TGA, BMP, TIFF and Radiance HDR, through the `image` crate: the header's
/// size checked first, as for PNG and JPEG.
fn decode_other(bytes: &[u8], name: &str, encoding: Encoding) -> Result<RgbImage, ImageError> {
    use image::ImageFormat;
    let reader = || -> Result<image::ImageReader<std::io::Cursor<&[u8]>>, ImageError> {
        let mut reader = image::ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|_| ImageError::UnknownFormat)?;
        if reader.format().is_none() {
            let tga = Path::new(name).extension().is_some_and(|e| e.eq_ignore_ascii_case("tga"));
            if !tga {
                return Err(ImageError::UnknownFormat);
            }
            reader.set_format(ImageFormat::Tga);
        }
        let mut limits = image::Limits::default();
        limits.max_alloc = Some(MAX_TEXELS * 16);
        reader.limits(limits);
        Ok(reader)
    };
    let format = match reader()?.format() {
        Some(ImageFormat::Tga) => "TGA",
        Some(ImageFormat::Bmp) => "BMP",
        Some(ImageFormat::Tiff) => "TIFF",
        Some(ImageFormat::Hdr) => "Radiance HDR",
        _ => return Err(ImageError::UnknownFormat),
    };
    let failed = |e: image::ImageError| ImageError::Other { format, message: e.to_string() };
    let (width, height) = reader()?.into_dimensions().map_err(failed)?;
    // A TGA's or BMP's run-length packets, like deflate, may outweigh the
    // file by MAX_EXPANSION at most.
    check_size("header", width.into(), height.into(), 4, bytes.len() as u64)?;
    let image = reader()?.decode().map_err(failed)?;
    let alpha = image.color().has_alpha();
    if image.color().bytes_per_pixel() == image.color().channel_count() {
        return Ok(eight_bit_image(image.into_rgba8(), alpha, encoding));
    }
    let scene_linear = matches!(image.color(), image::ColorType::Rgb32F | image::ColorType::Rgba32F);
    let rgba = image.into_rgba32f();
    let (width, height) = (rgba.width() as usize, rgba.height() as usize);
    if width * height == 0 {
        return Err(ImageError::Empty);
    }
    let mut texels = Vec::with_capacity(width * height);
    for (p, texel) in rgba.pixels().enumerate() {
        let [r, g, b, _] = texel.0;
        if !(r.is_finite() && g.is_finite() && b.is_finite()) {
            return Err(ImageError::NotFinite { x: p % width, y: p / width });
        }
        let c = |v: f32| if scene_linear { v } else { encoding.decode(v) };
        texels.push(Vec3::new(c(r), c(g), c(b)));
    }
    let alpha = alpha.then(|| Coverage::Float(rgba.pixels().map(|t| t.0[3].clamp(0.0, 1.0)).collect()));
    Ok(RgbImage { width, height, texels: Texels::Float(texels), alpha, scene_linear })
}

/// An image of 8 bits a channel, kept as its codes.
fn eight_bit_image(rgba: image::RgbaImage, alpha: bool, encoding: Encoding) -> RgbImage {
    let (width, height) = (rgba.width() as usize, rgba.height() as usize);
    let codes = rgba.pixels().map(|t| [t.0[0], t.0[1], t.0[2]]).collect();
    let alpha = alpha.then(|| Coverage::Codes(rgba.pixels().map(|t| t.0[3]).collect()));
    RgbImage { width, height, texels: Texels::codes(codes, encoding), alpha, scene_linear: false }
}

/// An OpenEXR texture: R, G, B (and A) of its first RGB layer, scene-linear,
/// each finite.
fn texture_exr(reader: impl std::io::Read + std::io::Seek) -> Result<RgbImage, ImageError> {
    let image = exr_rgba(reader, true)?;
    if let Some(index) = (0..image.texels.len()).position(|k| !image.texels.get(k).is_finite()) {
        return Err(ImageError::NotFinite { x: index % image.width, y: index / image.width });
    }
    if image.texels.is_empty() {
        return Err(ImageError::Empty);
    }
    Ok(image)
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
        jpeg_decoder::PixelFormat::L16 => 2,
        jpeg_decoder::PixelFormat::RGB24 => 3,
        jpeg_decoder::PixelFormat::CMYK32 => 4,
    };
    if width * height == 0 || pixels.len() < width * height * channels {
        return Err(ImageError::Empty);
    }
    let texel = |p: usize| -> Vec3 {
        let at = |k: usize| f32::from(pixels[p * channels + k]) / 255.0;
        let rgb = match channels {
            // 16-bit grey, big-endian.
            2 => Vec3::splat(f32::from(u16::from_be_bytes([pixels[2 * p], pixels[2 * p + 1]])) / 65535.0),
            // CMYK: RGB = (1 - CMY)(1 - K), as the `image` crate converts
            // the same decoder's output.
            _ => (Vec3::ONE - Vec3::new(at(0), at(1), at(2))) * (1.0 - at(3)),
        };
        Vec3::new(encoding.decode(rgb.x), encoding.decode(rgb.y), encoding.decode(rgb.z))
    };
    let texels = match channels {
        1 => Texels::codes(pixels[..width * height].iter().map(|&g| [g; 3]).collect(), encoding),
        3 => Texels::codes(pixels.chunks_exact(3).take(width * height).map(|c| [c[0], c[1], c[2]]).collect(), encoding),
        _ => Texels::Float((0..width * height).map(texel).collect()),
    };
    Ok(RgbImage { width, height, texels, alpha: None, scene_linear: false })
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
    if width * height == 0 {
        return Err(ImageError::Empty);
    }
    if !sixteen {
        // Grey, grey + alpha, RGB or RGBA codes, as they are.
        let codes = buf.chunks_exact(channels).take(width * height);
        let texels = match channels {
            1 | 2 => codes.clone().map(|c| [c[0]; 3]).collect(),
            _ => codes.clone().map(|c| [c[0], c[1], c[2]]).collect(),
        };
        // Alpha is linear coverage (PNG's grey + alpha and RGBA), not sRGB.
        let alpha = matches!(channels, 2 | 4).then(|| Coverage::Codes(codes.map(|c| c[channels - 1]).collect()));
        return Ok(RgbImage { width, height, texels: Texels::codes(texels, encoding), alpha, scene_linear: false });
    }
    let sample = |i: usize| -> f32 { f32::from(u16::from_be_bytes([buf[2 * i], buf[2 * i + 1]])) / 65535.0 };
    let texels = (0..width * height)
        .map(|p| {
            let base = p * channels;
            let rgb = match channels {
                1 | 2 => Vec3::splat(sample(base)),
                _ => Vec3::new(sample(base), sample(base + 1), sample(base + 2)),
            };
            Vec3::new(encoding.decode(rgb.x), encoding.decode(rgb.y), encoding.decode(rgb.z))
        })
        .collect();
    let alpha = matches!(channels, 2 | 4)
        .then(|| Coverage::Float((0..width * height).map(|p| sample(p * channels + channels - 1)).collect()));
    Ok(RgbImage { width, height, texels: Texels::Float(texels), alpha, scene_linear: false })
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
    let image = exr_rgba(reader, false)?;
    check_radiance(&image)?;
    Ok(image)
}

/// R, G, B of an OpenEXR's first RGB layer, unchecked, scene-linear; its
/// A too (1 where it is not finite) when `alpha` asks and the file has one.
fn exr_rgba(reader: impl std::io::Read + std::io::Seek, alpha: bool) -> Result<RgbImage, ImageError> {
    use exr::prelude::{ReadChannels, ReadLayers};
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |size, channels: &exr::prelude::RgbaChannels| {
                let alpha = (alpha && channels.3.is_some()).then(|| vec![1.0; size.area()]);
                (size.width(), size.height(), vec![Vec3::ZERO; size.area()], alpha)
            },
            |(width, _, texels, alpha): &mut (usize, usize, Vec<Vec3>, Option<Vec<f32>>),
             at,
             (r, g, b, a): (f32, f32, f32, f32)| {
                let index = at.y() * *width + at.x();
                texels[index] = Vec3::new(r, g, b);
                if let Some(alpha) = alpha.as_mut() {
                    alpha[index] = if a.is_finite() { a.clamp(0.0, 1.0) } else { 1.0 };
                }
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(reader)
        .map_err(ImageError::Exr)?;
    let (width, height, texels, alpha) = image.layer_data.channel_data.pixels;
    Ok(RgbImage { width, height, texels: Texels::Float(texels), alpha: alpha.map(Coverage::Float), scene_linear: true })
}

/// `image` as radiance: every texel finite, non-negative and at most
/// [`MAX_EMISSION`](super::MAX_EMISSION), and at least one.
pub fn check_radiance(image: &RgbImage) -> Result<(), ImageError> {
    let bad = |t: Vec3| !t.is_finite() || t.min_element() < 0.0 || t.max_element() > super::MAX_EMISSION;
    if let Some(index) = (0..image.texels.len()).position(|k| bad(image.texels.get(k))) {
        let t = image.texels.get(index);
        let value = format!("({:e}, {:e}, {:e})", t.x, t.y, t.z);
        return Err(ImageError::BadRadiance { x: index % image.width, y: index / image.width, value });
    }
    if image.texels.is_empty() {
        return Err(ImageError::Empty);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::util::color::srgb_to_linear;

    /// The quadrants `scenes/textures/make_textures.py` wrote: 8-bit sRGB
    /// colours with their alpha, and the float files' linear values.
    const QUADRANTS: [[u8; 4]; 4] = [[200, 30, 30, 255], [30, 200, 30, 128], [30, 30, 200, 64], [255, 255, 255, 0]];
    const LINEAR: [[f32; 3]; 4] = [[0.5, 0.1, 0.1], [0.1, 0.5, 0.1], [0.1, 0.1, 0.5], [4.0, 2.0, 1.0]];

    fn read(name: &str, encoding: Encoding) -> RgbImage {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/textures").join(name);
        let image = read_texture(&path, encoding).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!((image.width, image.height), (16, 16), "{name}");
        image
    }

    /// The texel at the centre of quadrant `k` (0 top-left, 3 bottom-right).
    fn at(image: &RgbImage, k: usize) -> usize {
        let (y, x) = (k / 2, k % 2);
        (8 * y + 4) * image.width + 8 * x + 4
    }

    /// Every quadrant's texels (all 64) within `tolerance` of `expected(k)`.
    fn check(name: &str, image: &RgbImage, tolerance: f32, expected: impl Fn(usize) -> Vec3) {
        for k in 0..4 {
            let (y0, x0) = (8 * (k / 2), 8 * (k % 2));
            for y in y0..y0 + 8 {
                for x in x0..x0 + 8 {
                    let got = image.texels.get(y * image.width + x);
                    let want = expected(k);
                    assert!(
                        (got - want).abs().max_element() <= tolerance * want.max_element().max(1.0),
                        "{name}: texel ({x}, {y}) is {got}, expected {want}"
                    );
                }
            }
        }
    }

    fn srgb(k: usize) -> Vec3 {
        let q = QUADRANTS[k];
        Vec3::new(q[0].into(), q[1].into(), q[2].into()).map(|v| srgb_to_linear(v / 255.0))
    }

    #[test]
    fn eight_bit_formats_decode_their_srgb_to_the_same_linear_texels() {
        for (name, tolerance, alpha) in [
            ("rgba8.png", 1e-6, true),
            ("palette.png", 1e-6, false),
            ("rgba8.tga", 1e-6, true),
            ("rgb8.bmp", 1e-6, false),
            ("rgb8.tif", 1e-6, false),
            // JPEG is lossy: quality 100, no chroma subsampling.
            ("baseline.jpg", 0.02, false),
            ("progressive.jpg", 0.02, false),
            ("cmyk.jpg", 0.02, false),
        ] {
            let image = read(name, Encoding::Srgb);
            assert!(!image.scene_linear, "{name}");
            // Kept as their 8-bit codes (CMYK's product of two is not one).
            let codes = if name == "cmyk.jpg" { 12 } else { 3 };
            assert_eq!(image.texels.bytes_per_texel(), codes, "{name}");
            check(name, &image, tolerance, srgb);
            assert_eq!(image.alpha.is_some(), alpha, "{name}");
            if let Some(a) = &image.alpha {
                for (k, quadrant) in QUADRANTS.iter().enumerate() {
                    assert!((a.get(at(&image, k)) - f32::from(quadrant[3]) / 255.0).abs() < 1e-6, "{name}");
                }
            }
            // Linear data is read as stored.
            let raw = read(name, Encoding::Linear);
            let q = QUADRANTS[0];
            let want = Vec3::new(q[0].into(), q[1].into(), q[2].into()) / 255.0;
            assert!((raw.texels.get(at(&raw, 0)) - want).abs().max_element() <= tolerance.max(0.01), "{name}");
        }
    }

    #[test]
    fn sixteen_bit_grey_reads_its_full_precision() {
        for name in ["grey16.png", "grey16.tif"] {
            let image = read(name, Encoding::Srgb);
            assert_eq!(image.texels.bytes_per_texel(), 12, "{name}");
            check(name, &image, 1e-6, |k| Vec3::splat(srgb(k).x));
        }
    }

    #[test]
    fn float_formats_are_scene_linear_whatever_the_encoding() {
        for (name, tolerance, grey) in [
            ("half.exr", 1e-3, false),
            ("float.exr", 0.0, false),
            ("float32.tif", 0.0, false),
            // RGBE keeps 8 bits of mantissa under a shared exponent.
            ("radiance.hdr", 1.0 / 64.0, false),
        ] {
            let image = read(name, Encoding::Srgb);
            assert!(image.scene_linear, "{name}");
            let expected = |k: usize| if grey { Vec3::splat(LINEAR[k][0]) } else { Vec3::from_array(LINEAR[k]) };
            check(name, &image, tolerance, expected);
        }
    }

    #[test]
    fn unknown_and_corrupt_images_are_refused_with_their_format() {
        assert!(matches!(decode(b"GIF89a......", Encoding::Srgb), Err(ImageError::UnknownFormat)));
        // A TGA has no signature: told by its name, else unknown.
        let tga = std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/textures/rgba8.tga")).unwrap();
        assert!(matches!(decode(&tga, Encoding::Srgb), Err(ImageError::UnknownFormat)));
        let cut = decode_named(&tga[..40], "x.tga", Encoding::Srgb).unwrap_err();
        assert!(cut.to_string().contains("TGA"), "{cut}");
        let bmp = std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/textures/rgb8.bmp")).unwrap();
        let cut = decode_named(&bmp[..100], "x.bmp", Encoding::Srgb).unwrap_err();
        assert!(cut.to_string().contains("BMP"), "{cut}");
    }
}
