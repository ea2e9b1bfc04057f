//! OpenEXR output: single part, scanlines, ZIP compression, the film's
//! channels: `R,G,B,A` and the AOVs the pass filled (`albedo.R/G/B`,
//! `N.X/Y/Z`, `Z`, `lightcuts.cut_size`, `lightcuts.shadow_rays`, each light
//! group's `Combined_<group>.R/G/B`, Cryptomatte's `CryptoObject00..02` and
//! `CryptoMaterial00..02`; see `render::Aovs`). The data window is the
//! rendered window; the display window the full frame.

use std::path::{Path, PathBuf};

use exr::prelude::*;

use super::{stage, OutputError, Staged};
use crate::render::{Film, BEAUTY};

/// Header attributes describing how the image was made.
#[derive(Debug, Clone)]
pub struct ExrMetadata {
    pub scene_file: PathBuf,
    /// `exact` or `lightcuts error=0.02 max_cut=1000`.
    pub render_mode: String,
    pub render_seconds: f64,
    pub lights: u64,
    pub spp: u32,
    pub seed: u64,
    /// Hash of every file the scene read (16 hex digits).
    pub scene_hash: String,
    /// OpenEXR's `worldToCamera` and `worldToNDC` (Imath's row-vector
    /// matrices, 16 floats row by row).
    pub world_to_camera: Option<[f32; 16]>,
    pub world_to_ndc: Option<[f32; 16]>,
}

/// The primaries and white point of the renderer's RGB: Rec. 709 / sRGB, D65.
fn rec709() -> exr::meta::attribute::Chromaticities {
    exr::meta::attribute::Chromaticities {
        red: Vec2(0.64, 0.33),
        green: Vec2(0.30, 0.60),
        blue: Vec2(0.15, 0.06),
        white: Vec2(0.3127, 0.3290),
    }
}

/// An attribute's text as UTF-8 bytes, as OpenEXR stores strings (the exr
/// crate's `Text::from` accepts only Latin-1 and panics on the rest, and a
/// glTF name in a Cryptomatte manifest may be anything).
fn utf8_text(value: &str) -> Text {
    Text::from_bytes_unchecked(value.as_bytes().iter().copied().collect())
}

/// Largest finite half float: beauty values beyond it are clamped, never Inf.
const HALF_MAX: f32 = 65504.0;

/// Writes `film` (every channel it has) with `meta`'s attributes; with
/// `half_beauty`, the beauty (R, G, B, A) as 16-bit half floats (AOVs stay
/// 32-bit).
pub fn write_exr(
    path: &Path,
    film: &Film,
    half_beauty: bool,
    meta: &ExrMetadata,
) -> std::result::Result<(), OutputError> {
    stage_exr(path, film, half_beauty, meta)?.commit()
}

/// [`write_exr`] up to the rename: the EXR written beside `path`, to be
/// committed with the command's other outputs.
pub fn stage_exr(
    path: &Path,
    film: &Film,
    half_beauty: bool,
    meta: &ExrMetadata,
) -> std::result::Result<Staged, OutputError> {
    let b = film.bounds;
    let size = (b.width() as usize, b.height() as usize);
    let list: Vec<AnyChannel<FlatSamples>> = film
        .channels
        .iter()
        .map(|channel| {
            let values = channel.values.clone();
            let samples = if half_beauty && BEAUTY.contains(&channel.name.as_str()) {
                FlatSamples::F16(values.into_iter().map(|v| f16::from_f32(v.min(HALF_MAX))).collect())
            } else {
                FlatSamples::F32(values)
            };
            let mut c = AnyChannel::new(channel.name.as_str(), samples);
            // pLinear is only a hint for lossy B44 compression: true for alpha alone.
            c.quantize_linearly = channel.name == "A";
            c
        })
        .collect();

    let mut attributes = LayerAttributes {
        layer_position: Vec2(b.x0 as i32, b.y0 as i32),
        software_name: Some(Text::from(concat!("lightcuts ", env!("CARGO_PKG_VERSION")))),
        world_to_camera: meta.world_to_camera,
        world_to_normalized_device: meta.world_to_ndc,
        ..LayerAttributes::default()
    };
    let mut other = |key: &str, value: AttributeValue| {
        attributes.other.insert(Text::from(key), value);
    };
    other("lightcuts:sceneFile", AttributeValue::Text(utf8_text(&meta.scene_file.display().to_string())));
    other("lightcuts:renderMode", AttributeValue::Text(Text::from(meta.render_mode.as_str())));
    other("lightcuts:renderTimeSeconds", AttributeValue::F64(meta.render_seconds));
    other("lightcuts:lights", AttributeValue::Text(Text::from(meta.lights.to_string().as_str())));
    other("lightcuts:samplesPerPixel", AttributeValue::I32(meta.spp.min(i32::MAX as u32) as i32));
    other("lightcuts:seed", AttributeValue::Text(Text::from(meta.seed.to_string().as_str())));
    other("lightcuts:sceneHash", AttributeValue::Text(Text::from(meta.scene_hash.as_str())));
    for (key, value) in &film.attributes {
        other(key, AttributeValue::Text(utf8_text(value)));
    }

    let encoding =
        Encoding { compression: Compression::ZIP16, blocks: Blocks::ScanLines, line_order: LineOrder::Increasing };
    let layer = Layer::new(size, attributes, encoding, AnyChannels::sort(list.into()));
    let display = IntegerBounds::new(Vec2(0, 0), Vec2(film.full_width as usize, film.full_height as usize));
    let mut image_attributes = ImageAttributes::new(display);
    image_attributes.chromaticities = Some(rec709());
    image_attributes.pixel_aspect = 1.0;
    let image = Image::new(image_attributes, layer);
    stage(path, |file| image.write().to_unbuffered(file).map_err(write_error(path)))
}

/// The error of encoding the EXR behind `path`.
fn write_error(path: &Path) -> impl FnOnce(::exr::error::Error) -> OutputError + '_ {
    move |source| OutputError::Exr { path: path.to_path_buf(), action: "write", source }
}

/// A comparison as an EXR, staged (see [`Staged`]): per-channel absolute
/// difference (R, G, B) and the relative error on luminance
/// (`relative_error`).
pub fn stage_diff_exr(
    path: &Path,
    result: &super::compare::ComparisonResult,
) -> std::result::Result<Staged, OutputError> {
    let channel = |name: &str, v: Vec<f32>| AnyChannel::new(name, FlatSamples::F32(v));
    let d = &result.difference;
    let finite = |x: f64| x.min(f64::from(f32::MAX)) as f32;
    let channels = vec![
        channel("R", d.iter().map(|c| finite(c.x)).collect()),
        channel("G", d.iter().map(|c| finite(c.y)).collect()),
        channel("B", d.iter().map(|c| finite(c.z)).collect()),
        channel("relative_error", result.relative.iter().map(|&e| finite(e)).collect()),
    ];
    let image = Image::from_channels((result.width, result.height), AnyChannels::sort(channels.into()));
    stage(path, |file| image.write().to_unbuffered(file).map_err(write_error(path)))
}
