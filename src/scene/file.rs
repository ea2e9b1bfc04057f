//! The scene file's schema (TOML, or JSON with the same fields), exactly as
//! written: serde rejects unknown fields so that a typo is an error, not a
//! silently ignored setting. Units are documented in docs/scene-format.md.

use std::collections::BTreeMap;

use serde::Deserialize;

#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// Required unless a glTF file is imported (then 640 pixels wide at its
    /// camera's aspect ratio, 1 sample per pixel).
    pub film: Option<FilmSpec>,
    /// Required unless an imported glTF file has a camera.
    pub camera: Option<CameraSpec>,
    /// A glTF 2.0 file whose meshes, materials, lights and cameras join the scene.
    pub gltf: Option<GltfSpec>,
    /// A USD stage whose meshes, materials, lights and cameras join the scene.
    pub usd: Option<UsdSpec>,
    #[serde(default)]
    pub materials: BTreeMap<String, MaterialSpec>,
    /// Each a table with a `type`; parsed into [`ShapeSpec`] by
    /// [`ShapeSpec::parse`] (serde's internally tagged enums buffer their
    /// content and lose the field path of errors inside it).
    #[serde(default)]
    pub shapes: Vec<toml::Value>,
    /// Each a table with a `type`; parsed into [`LightSpec`] by [`LightSpec::parse`].
    #[serde(default)]
    pub lights: Vec<toml::Value>,
    #[serde(default)]
    pub render: RenderSpec,
    /// Light arriving from infinitely far away, visible in the background.
    pub environment: Option<EnvironmentSpec>,
    /// Indirect light: camera paths or instant radiosity.
    pub indirect: Option<IndirectSpec>,
}

/// `[gltf]`: what to import from a glTF 2.0 file, and how.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GltfSpec {
    /// The `.gltf` or `.glb` file, relative to the scene file.
    pub file: String,
    /// The camera (by its glTF name) to render through; the first in the
    /// node hierarchy when absent.
    pub camera: Option<String>,
    /// Luminous efficacy dividing KHR_lights_punctual's photometric units
    /// (candela, lux) into radiometric ones (W/sr, W/m^2): 683 lm/W, as
    /// Blender's exporter and importer use in their "Standard" mode.
    #[serde(default = "lumens_per_watt")]
    pub lumens_per_watt: f32,
    /// About how many triangle lights each emissive mesh primitive becomes.
    #[serde(default = "emitter_samples")]
    pub emitter_samples: u32,
    /// `[[gltf.groups]]`: which light group the file's lights join, by the
    /// name of the light, its node or its emissive material; the first rule
    /// that matches wins, and a light no rule matches is in `default`.
    #[serde(default)]
    pub groups: Vec<GroupRule>,
    /// The animation played over an open shutter, by name; the file's
    /// first when absent.
    pub animation: Option<String>,
    /// The shutter `--shutter` gives (seconds of the file's animation),
    /// when the TOML's camera gives none.
    #[serde(skip)]
    pub shutter: Option<[f32; 2]>,
}

/// `[usd]`: what to import from a USD stage (`.usd`, `.usda`, `.usdc`,
/// `.usdz`), and how.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UsdSpec {
    /// The stage's root layer, relative to the scene file.
    pub file: String,
    /// The camera to render through, by prim path (`/World/Cam`); the
    /// first under the default prim (else on the stage) when absent.
    pub camera: Option<String>,
    /// The time code everything is read at; the stage's start time code
    /// when absent (0 when it has none).
    pub time: Option<f64>,
    /// About how many triangle lights each emissive surface and area light becomes.
    #[serde(default = "emitter_samples")]
    pub emitter_samples: u32,
    /// Directories (relative to the scene file) where an asset path that
    /// is not beside the layer naming it is looked for: USD's default
    /// resolver's search paths.
    #[serde(default)]
    pub asset_paths: Vec<String>,
    /// The shutter `--shutter` gives, in the stage's time codes.
    #[serde(skip)]
    pub shutter: Option<[f32; 2]>,
    /// `--asset-path`'s directories, searched after `asset_paths`.
    #[serde(skip)]
    pub search_paths: Vec<std::path::PathBuf>,
    /// `--strict`: a layer composition cannot read fails the import.
    #[serde(skip)]
    pub strict: bool,
}

impl UsdSpec {
    /// Importing `file` with every default.
    #[must_use]
    pub fn file(file: String) -> Self {
        Self {
            file,
            camera: None,
            time: None,
            emitter_samples: emitter_samples(),
            asset_paths: Vec::new(),
            shutter: None,
            search_paths: Vec::new(),
            strict: false,
        }
    }
}

/// One `[[gltf.groups]]` rule: lights whose light, node or material name
/// matches `light`, `node` or `material` (exactly one of them; `*` matches
/// any run of characters) join `group`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GroupRule {
    pub group: String,
    pub light: Option<String>,
    pub node: Option<String>,
    pub material: Option<String>,
}

/// Blender's luminous efficacy for glTF's photometric lights, lm/W.
pub const DEFAULT_LUMENS_PER_WATT: f32 = 683.0;

fn lumens_per_watt() -> f32 {
    DEFAULT_LUMENS_PER_WATT
}

fn emitter_samples() -> u32 {
    256
}

impl GltfSpec {
    /// Importing `file` with every default.
    #[must_use]
    pub fn file(file: String) -> Self {
        Self {
            file,
            camera: None,
            lumens_per_watt: lumens_per_watt(),
            emitter_samples: emitter_samples(),
            groups: Vec::new(),
            animation: None,
            shutter: None,
        }
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EnvironmentSpec {
    /// Constant radiance, W/(m^2 sr); give this or `file`.
    pub radiance: Option<[f32; 3]>,
    /// A latitude-longitude OpenEXR (R, G, B in W/(m^2 sr)), +y up.
    pub file: Option<String>,
    /// Multiplies the file's radiance.
    #[serde(default = "unit_f32")]
    pub scale: f32,
    /// Directional lights the environment becomes.
    #[serde(default = "environment_samples")]
    pub samples: u32,
    /// The light group of the environment's light (and of the background).
    pub group: Option<String>,
}

fn environment_samples() -> u32 {
    4096
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IndirectSpec {
    /// `"path"` or `"vpl"`; `"vpl"` when absent and `paths` is given,
    /// `"path"` otherwise.
    pub method: Option<String>,
    /// VPLs: light paths traced from the emitters (each leaves up to
    /// `bounces` VPLs).
    pub paths: Option<u32>,
    /// VPLs: diffuse bounces per light path (1 = one-bounce indirect light).
    pub bounces: Option<u32>,
    /// Paths: surface interactions per camera path (1 = direct light only).
    pub max_depth: Option<u32>,
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

/// A perspective camera a glTF or USD file brings, as a TOML's `[camera]`
/// would say it.
#[derive(Debug, Clone)]
pub struct ImportedCamera {
    pub spec: CameraSpec,
    /// Width over height, when the file gives one.
    pub aspect_ratio: Option<f32>,
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
    /// The thin lens's radius, scene units (pbrt's `lensradius`); 0, the
    /// default, is a pinhole: everything sharp.
    #[serde(default)]
    pub lens_radius: f32,
    /// Distance of the plane in focus along the view direction, scene
    /// units; by default the distance from the eye to `look_at`.
    #[serde(default)]
    pub focus_distance: Option<f32>,
    /// When the shutter opens and closes, in seconds (`[0, 0]`, the
    /// default: no motion blur). Motion given in the scene (`eye_end`,
    /// shapes' `motion`, lights' `position_end`) spans the whole interval.
    #[serde(default)]
    pub shutter: [f32; 2],
    /// Where the eye is at the shutter's close (it travels from `eye` in a
    /// straight line); by default it stays.
    pub eye_end: Option<[f32; 3]>,
    /// Where the point looked at is at the shutter's close.
    pub look_at_end: Option<[f32; 3]>,
}

impl CameraSpec {
    /// A pinhole camera (no lens).
    #[must_use]
    pub fn pinhole(eye: [f32; 3], look_at: [f32; 3], up: [f32; 3], fov_y: f32) -> Self {
        Self {
            eye,
            look_at,
            up,
            fov_y,
            lens_radius: 0.0,
            focus_distance: None,
            shutter: [0.0; 2],
            eye_end: None,
            look_at_end: None,
        }
    }

    /// The point a camera at `eye` looking along unit `forward` aims at:
    /// `distance` ahead, or further when the eye is far from the origin, so
    /// that `look_at - eye` keeps the direction in `f32` (an eye at 9e15 m
    /// plus 1 m rounds to the eye itself: 1/256 of its distance keeps the
    /// direction within 2e-5 radians).
    #[must_use]
    pub fn aim(eye: glam::DVec3, forward: glam::DVec3, distance: f64) -> [f32; 3] {
        (eye + forward * distance.max(eye.length() / 256.0)).as_vec3().to_array()
    }

    /// Whether the shutter stays open for a while: then motion blurs.
    #[must_use]
    pub fn shutter_open(&self) -> bool {
        self.shutter[1] > self.shutter[0]
    }
}

fn up_y() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// `phong` (the default: diffuse + Phong + mirror) or `pbr` (glTF's
    /// metallic-roughness BRDF, `albedo` or `texture` its base colour).
    #[serde(rename = "type", default)]
    pub kind: MaterialKind,
    /// Diffuse albedo (reflectance, 0..1 per channel); a `pbr` material's
    /// base colour.
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
    /// `pbr`: metallic, 0..1.
    pub metallic: Option<f32>,
    /// `pbr`: roughness, 0..1 (alpha = roughness^2).
    pub roughness: Option<f32>,
    /// `pbr`: a PNG of linear data, G roughness and B metallic (glTF's
    /// convention), multiplying `roughness` and `metallic`.
    pub metallic_roughness_texture: Option<String>,
    /// `pbr`: the fraction of the base transmitted, 0..1 (glTF's
    /// KHR_materials_transmission; 0, opaque, unless given).
    pub transmission: Option<f32>,
    /// `pbr`: the index of refraction, 1 or more (1.5 unless given).
    pub ior: Option<f32>,
    /// `pbr` with `transmission`: a thin wall, which rays pass straight
    /// through, instead of the boundary of a solid, which bends them.
    #[serde(default)]
    pub thin_walled: bool,
    /// `pbr` with `transmission`, a solid: the colour white light keeps
    /// after `attenuation_distance` metres inside it (Beer-Lambert).
    pub attenuation_colour: Option<[f32; 3]>,
    pub attenuation_distance: Option<f32>,
    /// `pbr`: a clear coat's weight, 0..1 (glTF's KHR_materials_clearcoat;
    /// 0, none, unless given), and its roughness, 0..1 (0 unless given).
    pub clearcoat: Option<f32>,
    pub clearcoat_roughness: Option<f32>,
    /// `pbr`: a sheen's colour, 0..1 (glTF's KHR_materials_sheen; black,
    /// none, unless given), and its roughness, 0..1 (0 unless given).
    pub sheen_colour: Option<[f32; 3]>,
    pub sheen_roughness: Option<f32>,
}

/// The BRDF of a `[materials.NAME]`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MaterialKind {
    #[default]
    Phong,
    Pbr,
}

fn unit_scale() -> [f32; 2] {
    [1.0, 1.0]
}

/// A parallelogram: corner, corner + u, corner + u + v, corner + v.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct QuadSpec {
    pub corner: [f32; 3],
    pub u: [f32; 3],
    pub v: [f32; 3],
    pub material: String,
}

/// An axis-aligned box.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxSpec {
    pub min: [f32; 3],
    pub max: [f32; 3],
    pub material: String,
}

/// A UV sphere tessellated into `segments` longitudes and `segments / 2` latitudes.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SphereSpec {
    pub center: [f32; 3],
    pub radius: f32,
    pub material: String,
    #[serde(default = "sphere_segments")]
    pub segments: u32,
}

/// A shape's `motion`: over the shutter it moves by `translate` and turns
/// by `rotate_degrees` about `rotate_axis` through its own centre (the
/// centre of its bounding box at the shutter's open), both growing
/// linearly with time.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MotionSpec {
    /// Metres, the displacement from the shutter's open to its close.
    #[serde(default)]
    pub translate: [f32; 3],
    #[serde(default)]
    pub rotate_axis: Option<[f32; 3]>,
    /// Degrees, right-handed about `rotate_axis`; at most 360 in magnitude.
    #[serde(default)]
    pub rotate_degrees: f32,
}

/// A Wavefront OBJ file (relative to the scene file), scaled then translated.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshSpec {
    pub file: String,
    pub material: String,
    #[serde(default = "unit_f32")]
    pub scale: f32,
    #[serde(default)]
    pub translate: [f32; 3],
}

#[derive(Debug, Clone)]
pub enum ShapeSpec {
    Quad(QuadSpec),
    Box(BoxSpec),
    Sphere(SphereSpec),
    Mesh(MeshSpec),
}

fn sphere_segments() -> u32 {
    48
}

fn unit_f32() -> f32 {
    1.0
}

/// One point light; intensity in W/sr per RGB channel.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointSpec {
    pub position: [f32; 3],
    pub intensity: [f32; 3],
    /// Where the light is at the shutter's close (it travels from
    /// `position` in a straight line); by default it stays.
    pub position_end: Option<[f32; 3]>,
}

/// A spot light: intensity in W/sr along `direction`, with the smooth
/// falloff of KHR_lights_punctual between the inner and outer half-angles.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpotSpec {
    pub position: [f32; 3],
    pub direction: [f32; 3],
    pub intensity: [f32; 3],
    /// Degrees from the axis where the falloff begins.
    #[serde(default)]
    pub inner_angle: f32,
    /// Degrees from the axis where the light ends (at most 90).
    #[serde(default = "spot_outer")]
    pub outer_angle: f32,
}

fn spot_outer() -> f32 {
    45.0
}

/// count[0] x count[1] point lights spread evenly over the parallelogram
/// corner + s u + t v, each with `intensity` W/sr.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridSpec {
    pub corner: [f32; 3],
    pub u: [f32; 3],
    pub v: [f32; 3],
    pub count: [u32; 2],
    pub intensity: [f32; 3],
}

/// A parallelogram emitter of radiance `radiance` (W/(m^2 sr)) from the side
/// u x v points to, visible to the camera, as about `samples` triangle
/// lights (docs/design.md §6.1).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AreaSpec {
    pub corner: [f32; 3],
    pub u: [f32; 3],
    pub v: [f32; 3],
    pub radiance: [f32; 3],
    #[serde(default = "area_samples")]
    pub samples: u32,
}

/// A triangle-mesh emitter (OBJ; emits from the side its winding faces).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AreaMeshSpec {
    pub file: String,
    #[serde(default = "unit_f32")]
    pub scale: f32,
    #[serde(default)]
    pub translate: [f32; 3],
    pub radiance: [f32; 3],
    #[serde(default = "area_samples")]
    pub samples: u32,
}

fn area_samples() -> u32 {
    1024
}

/// The sun: irradiance (W/m^2 on a surface facing it) from `direction`
/// (towards the sun), optionally a disc of `angular_radius` degrees.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SunSpec {
    pub direction: [f32; 3],
    pub irradiance: [f32; 3],
    #[serde(default)]
    pub angular_radius: f32,
    #[serde(default = "sun_samples")]
    pub samples: u32,
}

fn sun_samples() -> u32 {
    16
}

#[derive(Debug, Clone)]
pub enum LightSpec {
    Point(PointSpec),
    Spot(SpotSpec),
    Grid(GridSpec),
    Area(AreaSpec),
    AreaMesh(AreaMeshSpec),
    Sun(SunSpec),
}

/// Why one `[[shapes]]` or `[[lights]]` entry does not parse: the user's
/// file. [`SpecError::field`] is the path below the entry.
#[derive(Debug, thiserror::Error)]
pub enum SpecError {
    /// The entry is not a table (e.g. `shapes = [1]`).
    #[error("expected a table with a `type`, got {found}")]
    NotATable { found: &'static str },
    /// The table has no `type`.
    #[error("missing field `type`")]
    MissingType,
    /// `type` is not a string.
    #[error("expected a string, got {found}")]
    TypeNotAString { found: &'static str },
    /// A string field every entry may have (`name`, `group`) is not a string.
    #[error("expected a string, got {found}")]
    NotAString { path: &'static str, found: &'static str },
    /// `type` names no known shape or light.
    #[error("unknown {what} type '{kind}', expected {expected}")]
    UnknownType { what: &'static str, kind: String, expected: &'static str },
    /// A field of the entry is missing, misspelt or of the wrong type.
    #[error("{source}")]
    Field {
        /// Path below the entry, e.g. `.radius` (empty for the entry itself).
        path: String,
        #[source]
        source: toml::de::Error,
    },
}

impl SpecError {
    /// The field path below the entry (`""`, `".type"`, `".radius"`), to be
    /// appended to `shapes[i]` or `lights[i]`.
    #[must_use]
    pub fn field(&self) -> &str {
        match self {
            Self::NotATable { .. } | Self::MissingType => "",
            Self::TypeNotAString { .. } | Self::UnknownType { .. } => ".type",
            Self::NotAString { path, .. } => path,
            Self::Field { path, .. } => path,
        }
    }
}

/// Takes the optional string field `key` out of a `[[shapes]]` or
/// `[[lights]]` table (`name` and `group`, which every type has), leaving
/// the rest for the type's own fields. `path` is `".name"` or `".group"`.
pub fn take_string(value: &mut toml::Value, key: &str, path: &'static str) -> Result<Option<String>, SpecError> {
    let toml::Value::Table(table) = value else { return Ok(None) };
    match table.remove(key) {
        None => Ok(None),
        Some(toml::Value::String(s)) => Ok(Some(s)),
        Some(other) => Err(SpecError::NotAString { path, found: other.type_str() }),
    }
}

/// Takes the optional `motion` table out of a `[[shapes]]` entry, leaving
/// the rest for the shape's own fields.
pub fn take_motion(value: &mut toml::Value) -> Result<Option<MotionSpec>, SpecError> {
    let toml::Value::Table(table) = value else { return Ok(None) };
    table
        .remove("motion")
        .map(|motion| {
            fields(motion).map_err(|e| match e {
                SpecError::Field { path, source } => SpecError::Field { path: format!(".motion{path}"), source },
                other => other,
            })
        })
        .transpose()
}

/// Splits a `{ type = "...", ... }` table into its type and the rest.
fn tagged(value: &toml::Value) -> Result<(String, toml::Value), SpecError> {
    let toml::Value::Table(table) = value else {
        return Err(SpecError::NotATable { found: value.type_str() });
    };
    let mut rest = table.clone();
    match rest.remove("type") {
        Some(toml::Value::String(kind)) => Ok((kind, toml::Value::Table(rest))),
        Some(other) => Err(SpecError::TypeNotAString { found: other.type_str() }),
        None => Err(SpecError::MissingType),
    }
}

/// Deserializes one variant's fields, keeping the path of any error.
fn fields<T: serde::de::DeserializeOwned>(value: toml::Value) -> Result<T, SpecError> {
    serde_path_to_error::deserialize(value).map_err(|e| {
        let path = e.path().to_string();
        let path = if path == "." { String::new() } else { format!(".{path}") };
        SpecError::Field { path, source: e.into_inner() }
    })
}

impl ShapeSpec {
    /// Parses one `[[shapes]]` entry.
    pub fn parse(value: &toml::Value) -> Result<Self, SpecError> {
        let (kind, rest) = tagged(value)?;
        match kind.as_str() {
            "quad" => fields(rest).map(Self::Quad),
            "box" => fields(rest).map(Self::Box),
            "sphere" => fields(rest).map(Self::Sphere),
            "mesh" => fields(rest).map(Self::Mesh),
            _ => Err(SpecError::UnknownType { what: "shape", kind, expected: "quad, box, sphere or mesh" }),
        }
    }
}

impl LightSpec {
    /// Parses one `[[lights]]` entry.
    pub fn parse(value: &toml::Value) -> Result<Self, SpecError> {
        let (kind, rest) = tagged(value)?;
        match kind.as_str() {
            "point" => fields(rest).map(Self::Point),
            "spot" => fields(rest).map(Self::Spot),
            "grid" => fields(rest).map(Self::Grid),
            "area" => fields(rest).map(Self::Area),
            "area_mesh" => fields(rest).map(Self::AreaMesh),
            "sun" => fields(rest).map(Self::Sun),
            _ => Err(SpecError::UnknownType {
                what: "light",
                kind,
                expected: "point, spot, grid, area, area_mesh or sun",
            }),
        }
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderSpec {
    /// Mirror bounces followed before a path stops.
    #[serde(default = "mirror_depth")]
    pub max_mirror_depth: u32,
    /// Metres: every light's 1/d^2 is evaluated at no less than this distance
    /// (the instant-radiosity clamp against spikes near virtual lights),
    /// identically in every render mode.
    #[serde(default)]
    pub distance_clamp: f32,
}

impl Default for RenderSpec {
    fn default() -> Self {
        Self { max_mirror_depth: mirror_depth(), distance_clamp: 0.0 }
    }
}

fn mirror_depth() -> u32 {
    4
}
