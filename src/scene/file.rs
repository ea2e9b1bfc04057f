//! The scene file's schema (TOML, or JSON with the same fields), exactly as
//! written: serde rejects unknown fields so that a typo is an error, not a
//! silently ignored setting. Units are documented in docs/scene-format.md.

use std::collections::BTreeMap;

use serde::Deserialize;

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    pub film: FilmSpec,
    pub camera: CameraSpec,
    #[serde(default)]
    pub materials: BTreeMap<String, MaterialSpec>,
    #[serde(default)]
    pub shapes: Vec<ShapeSpec>,
    #[serde(default)]
    pub lights: Vec<LightSpec>,
    #[serde(default)]
    pub render: RenderSpec,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FilmSpec {
    /// Pixels.
    pub width: u32,
    /// Pixels.
    pub height: u32,
    /// Samples per pixel.
    #[serde(default = "one")]
    pub spp: u32,
}

fn one() -> u32 {
    1
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSpec {
    /// Metres (scene units).
    pub eye: [f32; 3],
    pub look_at: [f32; 3],
    #[serde(default = "up_y")]
    pub up: [f32; 3],
    /// Vertical field of view in degrees.
    pub fov_y: f32,
}

fn up_y() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// Diffuse albedo (reflectance, 0..1 per channel).
    pub albedo: Option<[f32; 3]>,
    /// A PNG whose sRGB colours are the diffuse albedo (relative to the scene file).
    pub texture: Option<String>,
    /// Texture repeats across the shape's (u, v) range.
    #[serde(default = "unit_scale")]
    pub texture_scale: [f32; 2],
    /// Phong specular colour k_s (0..1).
    #[serde(default)]
    pub specular: [f32; 3],
    /// Phong exponent n.
    #[serde(default)]
    pub exponent: f32,
    /// Perfect mirror reflectance (0..1).
    #[serde(default)]
    pub mirror: [f32; 3],
}

fn unit_scale() -> [f32; 2] {
    [1.0, 1.0]
}

#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum ShapeSpec {
    /// A parallelogram: corner, corner + u, corner + u + v, corner + v.
    Quad { corner: [f32; 3], u: [f32; 3], v: [f32; 3], material: String },
    /// An axis-aligned box.
    Box { min: [f32; 3], max: [f32; 3], material: String },
    /// A UV sphere tessellated into `segments` longitudes and `segments / 2` latitudes.
    Sphere {
        center: [f32; 3],
        radius: f32,
        material: String,
        #[serde(default = "sphere_segments")]
        segments: u32,
    },
    /// A Wavefront OBJ file (relative to the scene file), scaled then translated.
    Mesh {
        file: String,
        material: String,
        #[serde(default = "unit_f32")]
        scale: f32,
        #[serde(default)]
        translate: [f32; 3],
    },
}

fn sphere_segments() -> u32 {
    48
}

fn unit_f32() -> f32 {
    1.0
}

#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum LightSpec {
    /// One point light; intensity in W/sr per RGB channel.
    Point { position: [f32; 3], intensity: [f32; 3] },
    /// count[0] x count[1] point lights spread evenly over the parallelogram
    /// corner + s u + t v, each with `intensity` W/sr.
    Grid { corner: [f32; 3], u: [f32; 3], v: [f32; 3], count: [u32; 2], intensity: [f32; 3] },
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderSpec {
    /// Mirror bounces followed before a path stops.
    #[serde(default = "mirror_depth")]
    pub max_mirror_depth: u32,
}

impl Default for RenderSpec {
    fn default() -> Self {
        Self { max_mirror_depth: mirror_depth() }
    }
}

fn mirror_depth() -> u32 {
    4
}
