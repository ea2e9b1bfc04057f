//! Reading our EXRs back (for `compare` and tests): every channel as f32.

use std::collections::BTreeMap;
use std::path::Path;

use exr::prelude::*;

use super::OutputError;

/// A single-layer EXR with all channels as f32, scanline order.
#[derive(Debug, Clone)]
pub struct ExrImage {
    /// Data window origin and size, in pixels.
    pub x0: i32,
    pub y0: i32,
    pub width: usize,
    pub height: usize,
    /// Display window origin and size.
    pub display_x0: i32,
    pub display_y0: i32,
    pub display_width: usize,
    pub display_height: usize,
    pub channels: BTreeMap<String, Vec<f32>>,
    /// Custom header attributes rendered as text.
    pub attributes: BTreeMap<String, String>,
    /// The channels stored as 16-bit half floats.
    pub half: std::collections::BTreeSet<String>,
    /// OpenEXR's `worldToCamera` and `worldToNDC`, when present.
    pub world_to_camera: Option<[f32; 16]>,
    pub world_to_ndc: Option<[f32; 16]>,
}

impl ExrImage {
    /// The named channel, or an error naming the file and the channel.
    pub fn channel(&self, path: &Path, name: &str) -> std::result::Result<&[f32], OutputError> {
        self.channels.get(name).map(Vec::as_slice).ok_or_else(|| OutputError::MissingChannel {
            path: path.to_path_buf(),
            channel: name.to_string(),
            available: self.channels.keys().cloned().collect::<Vec<_>>().join(", "),
        })
    }
}

pub fn read_exr(path: &Path) -> std::result::Result<ExrImage, OutputError> {
    use crate::scene::image::{check_exr_header, ImageError};
    let refused = |source| OutputError::ExrHeader { path: path.to_path_buf(), source };
    let file = crate::util::file::open_regular(path).map_err(|e| refused(ImageError::Open(e)))?;
    let length = file.metadata().map_err(|e| refused(ImageError::Open(e)))?.len();
    check_exr_header(std::io::BufReader::new(file), length).map_err(refused)?;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|source| OutputError::Exr { path: path.to_path_buf(), action: "read", source })?;
    let layer = &image.layer_data;
    let mut channels = BTreeMap::new();
    let mut half = std::collections::BTreeSet::new();
    for channel in &layer.channel_data.list {
        if matches!(channel.sample_data, FlatSamples::F16(_)) {
            half.insert(channel.name.to_string());
        }
        let values: Vec<f32> = channel.sample_data.values_as_f32().collect();
        channels.insert(channel.name.to_string(), values);
    }
    let mut attributes = BTreeMap::new();
    for (key, value) in &layer.attributes.other {
        let text = match value {
            // OpenEXR strings are UTF-8 by convention (the writer stores them so).
            AttributeValue::Text(t) => String::from_utf8_lossy(t.as_slice()).into_owned(),
            AttributeValue::F64(v) => v.to_string(),
            AttributeValue::F32(v) => v.to_string(),
            AttributeValue::I32(v) => v.to_string(),
            other => format!("{other:?}"),
        };
        attributes.insert(key.to_string(), text);
    }
    if let Some(software) = &layer.attributes.software_name {
        attributes.insert("software".into(), software.to_string());
    }
    let display = image.attributes.display_window;
    Ok(ExrImage {
        x0: layer.attributes.layer_position.x(),
        y0: layer.attributes.layer_position.y(),
        width: layer.size.width(),
        height: layer.size.height(),
        display_x0: display.position.x(),
        display_y0: display.position.y(),
        display_width: display.size.width(),
        display_height: display.size.height(),
        channels,
        attributes,
        half,
        world_to_camera: layer.attributes.world_to_camera,
        world_to_ndc: layer.attributes.world_to_normalized_device,
    })
}
