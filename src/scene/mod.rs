//! Scenes: the file format (`file`), its validation into world-space meshes,
//! materials, light sources and the camera, and the images it names. Every
//! error names the file and the field path. Relative paths resolve against
//! the scene file's directory. The light sources are descriptions: the
//! `light` layer above turns them into the point lights the trees cluster.

pub mod camera;
pub mod environment;
pub mod error;
pub mod file;
pub mod gltf;
pub mod groups;
pub mod image;
pub mod material;
pub mod mesh;
pub mod texture;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{Affine2, Vec2, Vec3};

pub use camera::Camera;
pub use environment::{Environment, EnvironmentMap};
pub use error::SceneError;
use file::{
    AreaMeshSpec, AreaSpec, GridSpec, LightSpec, MeshSpec, PointSpec, QuadSpec, SceneFile, ShapeSpec, SphereSpec,
    SunSpec,
};
pub use groups::LightGroups;
pub use material::{Albedo, Material};
pub use mesh::Mesh;
use texture::Texture;

/// Largest film accepted: 2^27 pixels (about 11600 x 11600). The renderer
/// keeps about 70 bytes per pixel, so this caps the image at about 9 GiB.
pub const MAX_PIXELS: u64 = 1 << 27;
/// Largest coordinate magnitude a scene may use, metres. Embree rejects a
/// ray whose origin or direction has a component beyond 1.844e18
/// (`FLT_LARGE`; Debian builds it with assertions, which abort), and a
/// shadow ray's direction spans two points: 1e16 keeps a wide margin.
pub const MAX_COORDINATE: f32 = 1e16;
/// Largest number of lights a grid may generate (memory: ~28 bytes each).
pub const MAX_GRID_LIGHTS: u64 = 1 << 26;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
}

/// A light as the scene file describes it, validated. `light::Lights::from_scene`
/// turns each into point lights of one kind ([LC05] sec. 5).
#[derive(Debug, Clone, PartialEq)]
pub enum LightSource {
    /// One omni light of `intensity` W/sr.
    Point { position: Vec3, intensity: Vec3 },
    /// A spot light of `intensity` W/sr along `direction` (any length),
    /// falling off smoothly from the inner to the outer cone half-angle.
    Spot { position: Vec3, direction: Vec3, intensity: Vec3, inner_angle_degrees: f32, outer_angle_degrees: f32 },
    /// count[0] x count[1] omni lights of `intensity` W/sr each, at the cell
    /// centres of the parallelogram corner + s u + t v.
    Grid { corner: Vec3, u: Vec3, v: Vec3, count: [u32; 2], intensity: Vec3 },
    /// An area emitter: the mesh `meshes[mesh]` (visible, emitting `radiance`
    /// W/(m^2 sr) from the side its winding faces, and from the other too when
    /// `both_sides`) as `samples` oriented lights per side.
    Area { mesh: usize, radiance: Vec3, samples: u32, seed: u64, both_sides: bool },
    /// The sun: `irradiance` W/m^2 from `direction` (towards the sun, any length),
    /// as `samples` directional lights over a disc of `angular_radius_degrees`.
    Sun { direction: Vec3, irradiance: Vec3, angular_radius_degrees: f32, samples: u32, seed: u64 },
}

/// A loaded, validated scene.
#[derive(Debug, Clone)]
pub struct Scene {
    pub path: PathBuf,
    pub film: Film,
    pub camera_spec: file::CameraSpec,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    pub meshes: Vec<Mesh>,
    /// The lights of `[[lights]]`, in file order, then the glTF file's.
    pub lights: Vec<LightSource>,
    /// The light group of each light and of the environment.
    pub groups: LightGroups,
    pub max_mirror_depth: u32,
    /// Radiance from infinitely far away: visible in the background, and
    /// sampled into directional lights.
    pub environment: Option<Environment>,
    /// Instant radiosity: VPLs are traced per render (they need Embree and the seed).
    pub indirect: Option<IndirectSettings>,
    /// Metres: 1/d^2 is evaluated at no less than this distance.
    pub distance_clamp: f32,
    /// Every file the scene was read from, in the order it was read: the scene
    /// file itself (when loaded from one), then its meshes, textures and
    /// environment map. What a fresh clone must contain to render it, and
    /// what a cached reference render depends on.
    pub inputs: Vec<PathBuf>,
    /// What the scene asks for that is rendered otherwise (a glTF alpha
    /// mask drawn opaque, a skin in its bind pose), one line each with the
    /// file and location: the commands print them.
    pub warnings: Vec<String>,
}

/// Film width of a glTF file rendered without a TOML, pixels.
pub const DEFAULT_GLTF_WIDTH: u32 = 640;

/// Checks a camera (`field` names it in messages).
fn check_camera(v: &Validator<'_>, cam: &file::CameraSpec, field: &str) -> Result<(), SceneError> {
    let f = |name: &str| format!("{field}.{name}");
    let eye = v.point(cam.eye, &f("eye"))?;
    let look_at = v.point(cam.look_at, &f("look_at"))?;
    let up = v.point(cam.up, &f("up"))?;
    v.check(cam.fov_y.is_finite() && cam.fov_y > 0.0 && cam.fov_y < 180.0, &f("fov_y"), || {
        format!("must be between 0 and 180 degrees (exclusive), got {}", cam.fov_y)
    })?;
    let forward = look_at - eye;
    v.check(forward.length() > 0.0, &f("look_at"), || "must differ from the eye".into())?;
    v.check(forward.normalize().cross(up).length() > 1e-6, &f("up"), || {
        "must not be parallel to the viewing direction".into()
    })
}

/// Instant-radiosity settings of a scene.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct IndirectSettings {
    pub paths: usize,
    pub bounces: u32,
}

/// Most light paths a scene may ask for (each leaves up to `bounces` VPLs).
pub const MAX_VPL_PATHS: u32 = 1 << 24;
/// Most samples one emitter may become.
pub const MAX_EMITTER_SAMPLES: u32 = 1 << 24;

/// Adds an area emitter's geometry: visible, black, emitting `radiance` from
/// the side its triangles' winding faces. Returns its light: `samples`
/// oriented lights drawn with `seed`.
fn add_emitter(
    meshes: &mut Vec<Mesh>,
    materials: &mut Vec<Material>,
    mut mesh: Mesh,
    radiance: Vec3,
    samples: u32,
    seed: u64,
) -> LightSource {
    mesh.material = materials.len();
    mesh.normals = None; // emission is one-sided by the triangles' winding
    materials.push(Material {
        name: format!("emitter {seed}"),
        albedo: Albedo::Constant(Vec3::ZERO),
        specular: Vec3::ZERO,
        exponent: 0.0,
        mirror: Vec3::ZERO,
        emission: radiance,
        emits_both_sides: false,
        cutout: None,
    });
    meshes.push(mesh);
    LightSource::Area { mesh: meshes.len() - 1, radiance, samples, seed, both_sides: false }
}

impl Scene {
    /// Reads, parses and validates a scene file (`.json` as JSON, anything
    /// else as TOML).
    pub fn load(path: &Path) -> Result<Self, SceneError> {
        Self::load_with_camera(path, None)
    }

    /// [`Scene::load`], rendering through the glTF camera named `camera`
    /// (the `--camera` option) instead of the scene's default one. A `.gltf`
    /// or `.glb` file is a scene by itself: the import of `[gltf]` with
    /// every default.
    pub fn load_with_camera(path: &Path, camera: Option<&str>) -> Result<Self, SceneError> {
        let extension = |x: &str| path.extension().is_some_and(|e| e.eq_ignore_ascii_case(x));
        let mut spec = if extension("gltf") || extension("glb") {
            let file = path.file_name().map_or_else(String::new, |f| f.to_string_lossy().into_owned());
            SceneFile { gltf: Some(file::GltfSpec::file(file)), ..SceneFile::default() }
        } else {
            let text =
                std::fs::read(path).map_err(|e| SceneError::new(path, "file", format!("cannot read scene: {e}")))?;
            let text = String::from_utf8(text).map_err(|e| {
                SceneError::new(
                    path,
                    format!("byte {}", e.utf8_error().valid_up_to()),
                    "the scene file is not UTF-8 text",
                )
            })?;
            if extension("json") {
                parse_json(path, &text)?
            } else {
                parse_toml(path, &text)?
            }
        };
        if let Some(name) = camera {
            let Some(gltf) = spec.gltf.as_mut() else {
                return Err(SceneError::new(
                    path,
                    "--camera",
                    "picks a glTF camera, but the scene imports no glTF file",
                ));
            };
            gltf.camera = Some(name.to_string());
            // The TOML's own camera would win over the one asked for.
            spec.camera = None;
        }
        let imports_itself =
            spec.gltf.as_ref().is_some_and(|g| path.file_name() == Some(std::ffi::OsStr::new(&g.file)))
                && (extension("gltf") || extension("glb"));
        let mut scene = Self::from_spec(path, spec)?;
        if !imports_itself {
            scene.inputs.insert(0, path.to_path_buf());
        }
        Ok(scene)
    }

    /// Validates a parsed scene file; `path` is used for messages and to
    /// resolve relative mesh and texture paths.
    pub fn from_spec(path: &Path, spec: SceneFile) -> Result<Self, SceneError> {
        let v = Validator { file: path };
        let base = path.parent().unwrap_or(Path::new("."));

        if spec.gltf.is_none() {
            v.check(spec.film.is_some(), "film", || "missing: give [film] (or import a glTF file with [gltf])".into())?;
            v.check(spec.camera.is_some(), "camera", || {
                "missing: give [camera] (or import a glTF file with a camera, with [gltf])".into()
            })?;
        }
        if let Some(f) = &spec.film {
            v.check(f.width >= 1, "film.width", || "must be at least 1".into())?;
            v.check(f.height >= 1, "film.height", || "must be at least 1".into())?;
            v.check(f.spp >= 1, "film.spp", || "must be at least 1".into())?;
            check_resolution(path, "film", f.width, f.height)?;
        }
        if let Some(cam) = &spec.camera {
            check_camera(&v, cam, "camera")?;
        }

        let mut inputs = Vec::new();
        let mut textures = Vec::new();
        let mut materials = Vec::new();
        let mut material_index = HashMap::new();
        for (name, m) in &spec.materials {
            let field = |f: &str| format!("materials.{name}.{f}");
            let albedo = match (&m.albedo, &m.texture) {
                (Some(_), Some(_)) => {
                    return Err(v.error(&field("texture"), "give either albedo or texture, not both"));
                }
                (None, None) => return Err(v.error(&field("albedo"), "missing: give albedo or texture")),
                (Some(a), None) => Albedo::Constant(v.unit_rgb(*a, &field("albedo"))?),
                (None, Some(t)) => {
                    let scale = Vec2::from_array(m.texture_scale);
                    v.check(scale.is_finite() && scale.min_element() > 0.0, &field("texture_scale"), || {
                        format!("must be finite and > 0, got {:?}", m.texture_scale)
                    })?;
                    let texture_path = base.join(t);
                    inputs.push(texture_path.clone());
                    let image = image::read_srgb_png(&texture_path)
                        .map_err(|e| SceneError::new(&texture_path, field("texture"), e.to_string()))?;
                    textures.push(Texture::from_image(image));
                    Albedo::Texture { texture: textures.len() - 1, transform: Affine2::from_scale(scale) }
                }
            };
            let specular = v.unit_rgb(m.specular, &field("specular"))?;
            v.check(m.exponent.is_finite() && (0.0..=1e6).contains(&m.exponent), &field("exponent"), || {
                format!("must be between 0 and 1e6, got {}", m.exponent)
            })?;
            let mirror = v.unit_rgb(m.mirror, &field("mirror"))?;
            material_index.insert(name.clone(), materials.len());
            materials.push(Material {
                name: name.clone(),
                albedo,
                specular,
                exponent: m.exponent,
                mirror,
                emission: Vec3::ZERO,
                emits_both_sides: false,
                cutout: None,
            });
        }

        let mut meshes = Vec::new();
        for (i, raw) in spec.shapes.iter().enumerate() {
            let field = |f: &str| format!("shapes[{i}].{f}");
            let entry_error = |e: file::SpecError| v.error(&format!("shapes[{i}]{}", e.field()), &e.to_string());
            let mut raw = raw.clone();
            let name = file::take_string(&mut raw, "name", ".name").map_err(entry_error)?;
            let shape = ShapeSpec::parse(&raw).map_err(entry_error)?;
            let material_of = |name: &String| {
                material_index
                    .get(name)
                    .copied()
                    .ok_or_else(|| v.error(&field("material"), &format!("no material named '{name}' in [materials]")))
            };
            let mesh = match &shape {
                ShapeSpec::Quad(QuadSpec { corner, u, v: edge_v, material }) => {
                    let m = material_of(material)?;
                    let (c, u, w) = (
                        v.point(*corner, &field("corner"))?,
                        v.point(*u, &field("u"))?,
                        v.point(*edge_v, &field("v"))?,
                    );
                    v.check(u.cross(w).length() > 0.0, &field("v"), || {
                        "the quad has zero area (u and v are parallel)".into()
                    })?;
                    Mesh::quad(c, u, w, m)
                }
                ShapeSpec::Box(file::BoxSpec { min, max, material }) => {
                    let m = material_of(material)?;
                    let (lo, hi) = (v.point(*min, &field("min"))?, v.point(*max, &field("max"))?);
                    v.check(lo.cmplt(hi).all(), &field("max"), || {
                        format!("must exceed min in x, y and z, got {max:?} vs {min:?}")
                    })?;
                    Mesh::cuboid(lo, hi, m)
                }
                ShapeSpec::Sphere(SphereSpec { center, radius, material, segments }) => {
                    let m = material_of(material)?;
                    let c = v.point(*center, &field("center"))?;
                    v.check(radius.is_finite() && *radius > 0.0, &field("radius"), || {
                        format!("must be finite and > 0, got {radius}")
                    })?;
                    v.check((3..=4096).contains(segments), &field("segments"), || {
                        format!("must be between 3 and 4096, got {segments}")
                    })?;
                    Mesh::sphere(c, *radius, *segments, m)
                }
                ShapeSpec::Mesh(MeshSpec { file, material, scale, translate }) => {
                    let m = material_of(material)?;
                    v.check(scale.is_finite() && *scale > 0.0, &field("scale"), || {
                        format!("must be finite and > 0, got {scale}")
                    })?;
                    let t = v.point(*translate, &field("translate"))?;
                    let mesh_path = base.join(file);
                    inputs.push(mesh_path.clone());
                    if !mesh_path.is_file() {
                        return Err(v.error(&field("file"), &format!("mesh file '{}' not found", mesh_path.display())));
                    }
                    Mesh::load_obj(&mesh_path, *scale, t, m)?
                }
            };
            if let Some(bad) = mesh.positions.iter().position(|p| !within_limits(*p)) {
                return Err(v.error(
                    &format!("shapes[{i}]"),
                    &format!(
                        "vertex {bad} is {}: coordinates must be finite and within +/-{MAX_COORDINATE:e} m",
                        mesh.positions[bad]
                    ),
                ));
            }
            meshes.push(Mesh { name: name.unwrap_or_else(|| format!("shapes[{i}]")), ..mesh });
        }

        let mut lights = Vec::new();
        // The group each light asks for, with the field that names it.
        let mut requested_groups = Vec::new();
        for (i, raw) in spec.lights.iter().enumerate() {
            let field = |f: &str| format!("lights[{i}].{f}");
            let entry_error = |e: file::SpecError| v.error(&format!("lights[{i}]{}", e.field()), &e.to_string());
            let mut raw = raw.clone();
            let name = file::take_string(&mut raw, "name", ".name").map_err(entry_error)?;
            let group = file::take_string(&mut raw, "group", ".group").map_err(entry_error)?;
            requested_groups.push((group, field("group")));
            let light = LightSpec::parse(&raw).map_err(entry_error)?;
            // An emitter's geometry is an object too (Cryptomatte).
            let emitter_name = name.unwrap_or_else(|| format!("lights[{i}]"));
            match &light {
                LightSpec::Point(PointSpec { position, intensity }) => {
                    let position = v.point(*position, &field("position"))?;
                    let intensity = v.non_negative_rgb(*intensity, &field("intensity"))?;
                    lights.push(LightSource::Point { position, intensity });
                }
                LightSpec::Spot(file::SpotSpec { position, direction, intensity, inner_angle, outer_angle }) => {
                    let position = v.point(*position, &field("position"))?;
                    let direction = v.point(*direction, &field("direction"))?;
                    v.check(direction.length() > 0.0, &field("direction"), || "must not be zero".into())?;
                    let intensity = v.non_negative_rgb(*intensity, &field("intensity"))?;
                    v.check(
                        outer_angle.is_finite() && *outer_angle > 0.0 && *outer_angle <= 90.0,
                        &field("outer_angle"),
                        || format!("must be above 0 and at most 90 degrees, got {outer_angle}"),
                    )?;
                    v.check(
                        inner_angle.is_finite() && *inner_angle >= 0.0 && inner_angle < outer_angle,
                        &field("inner_angle"),
                        || format!("must be at least 0 and below outer_angle ({outer_angle}), got {inner_angle}"),
                    )?;
                    lights.push(LightSource::Spot {
                        position,
                        direction,
                        intensity,
                        inner_angle_degrees: *inner_angle,
                        outer_angle_degrees: *outer_angle,
                    });
                }
                LightSpec::Grid(GridSpec { corner, u, v: edge_v, count, intensity }) => {
                    let c = v.point(*corner, &field("corner"))?;
                    let (u, w) = (v.point(*u, &field("u"))?, v.point(*edge_v, &field("v"))?);
                    let intensity = v.non_negative_rgb(*intensity, &field("intensity"))?;
                    let total = u64::from(count[0]) * u64::from(count[1]);
                    v.check(count[0] >= 1 && count[1] >= 1 && total <= MAX_GRID_LIGHTS, &field("count"), || {
                        format!("must be at least [1, 1] and at most {MAX_GRID_LIGHTS} lights in all, got {count:?}")
                    })?;
                    // The lights are convex combinations of the corners: corners
                    // within the limits keep every light within them.
                    for (corner, name) in [(c + u, "u"), (c + w, "v"), (c + u + w, "v")] {
                        v.check(within_limits(corner), &field(name), || {
                            format!("the grid reaches {corner}: coordinates must be within +/-{MAX_COORDINATE:e} m")
                        })?;
                    }
                    lights.push(LightSource::Grid { corner: c, u, v: w, count: *count, intensity });
                }
                LightSpec::Area(AreaSpec { corner, u, v: edge_v, radiance, samples }) => {
                    let c = v.point(*corner, &field("corner"))?;
                    let (u, w) = (v.point(*u, &field("u"))?, v.point(*edge_v, &field("v"))?);
                    v.check(u.cross(w).length() > 0.0, &field("v"), || {
                        "the emitter has zero area (u and v are parallel)".into()
                    })?;
                    let radiance = v.non_negative_rgb(*radiance, &field("radiance"))?;
                    v.sample_count(*samples, &field("samples"))?;
                    let quad = Mesh { name: emitter_name, ..Mesh::quad(c, u, w, 0) };
                    lights.push(add_emitter(&mut meshes, &mut materials, quad, radiance, *samples, i as u64));
                }
                LightSpec::AreaMesh(AreaMeshSpec { file, scale, translate, radiance, samples }) => {
                    v.check(scale.is_finite() && *scale > 0.0, &field("scale"), || {
                        format!("must be finite and > 0, got {scale}")
                    })?;
                    let t = v.point(*translate, &field("translate"))?;
                    let radiance = v.non_negative_rgb(*radiance, &field("radiance"))?;
                    v.sample_count(*samples, &field("samples"))?;
                    let mesh_path = base.join(file);
                    inputs.push(mesh_path.clone());
                    if !mesh_path.is_file() {
                        return Err(v.error(&field("file"), &format!("mesh file '{}' not found", mesh_path.display())));
                    }
                    let mesh = Mesh { name: emitter_name, ..Mesh::load_obj(&mesh_path, *scale, t, 0)? };
                    if let Some(bad) = mesh.positions.iter().position(|p| !within_limits(*p)) {
                        return Err(v.error(
                            &field("file"),
                            &format!("vertex {bad} is outside +/-{MAX_COORDINATE:e} m after scaling"),
                        ));
                    }
                    lights.push(add_emitter(&mut meshes, &mut materials, mesh, radiance, *samples, i as u64));
                }
                LightSpec::Sun(SunSpec { direction, irradiance, angular_radius, samples }) => {
                    let d = v.point(*direction, &field("direction"))?;
                    v.check(d.length() > 0.0, &field("direction"), || "must not be zero".into())?;
                    let irradiance = v.non_negative_rgb(*irradiance, &field("irradiance"))?;
                    v.check(
                        angular_radius.is_finite() && (0.0..=45.0).contains(angular_radius),
                        &field("angular_radius"),
                        || format!("must be between 0 and 45 degrees, got {angular_radius}"),
                    )?;
                    v.sample_count(*samples, &field("samples"))?;
                    lights.push(LightSource::Sun {
                        direction: d,
                        irradiance,
                        angular_radius_degrees: *angular_radius,
                        samples: *samples,
                        seed: i as u64,
                    });
                }
            }
        }

        let mut warnings = Vec::new();
        let gltf_camera = match &spec.gltf {
            None => None,
            Some(g) => {
                let mut light_names = Vec::new();
                let parts = gltf::Parts {
                    meshes: &mut meshes,
                    materials: &mut materials,
                    textures: &mut textures,
                    lights: &mut lights,
                    light_names: &mut light_names,
                    inputs: &mut inputs,
                    warnings: &mut warnings,
                };
                let camera = gltf::import(path, base, g, spec.camera.is_none(), parts)?;
                let matched = groups::apply_rules(path, &g.groups, &light_names)?;
                for (k, group) in matched.into_iter().enumerate() {
                    requested_groups.push((group, format!("gltf.groups (glTF light {k})")));
                }
                camera
            }
        };
        let (camera_spec, aspect_ratio) = match (&spec.camera, gltf_camera) {
            (Some(c), _) => (c.clone(), None),
            (None, Some(c)) => {
                let file = spec.gltf.as_ref().map_or("", |g| g.file.as_str());
                check_camera(&v, &c.spec, &format!("gltf.file ({file}) camera"))?;
                (c.spec, c.aspect_ratio)
            }
            (None, None) => {
                return Err(v.error("camera", "missing: the TOML gives no [camera] and the glTF file has no camera"));
            }
        };
        let film = match &spec.film {
            Some(f) => Film { width: f.width, height: f.height, spp: f.spp },
            // The glTF camera's aspect ratio at 640 pixels wide.
            None => {
                let height =
                    aspect_ratio.map_or(480.0, |a| (DEFAULT_GLTF_WIDTH as f32 / a).round().clamp(1.0, 16384.0));
                Film { width: DEFAULT_GLTF_WIDTH, height: height as u32, spp: 1 }
            }
        };

        let environment = match &spec.environment {
            None => None,
            Some(env) => {
                let field = |f: &str| format!("environment.{f}");
                v.sample_count(env.samples, &field("samples"))?;
                v.check(env.scale.is_finite() && env.scale >= 0.0, &field("scale"), || {
                    format!("must be finite and >= 0, got {}", env.scale)
                })?;
                let map = match (&env.radiance, &env.file) {
                    (Some(_), Some(_)) => return Err(v.error(&field("file"), "give either radiance or file, not both")),
                    (None, None) => return Err(v.error(&field("radiance"), "missing: give radiance or file")),
                    (Some(r), None) => EnvironmentMap::Constant(v.non_negative_rgb(*r, &field("radiance"))?),
                    (None, Some(f)) => {
                        let exr = base.join(f);
                        inputs.push(exr.clone());
                        EnvironmentMap::load_exr(&exr, env.scale).map_err(|e| {
                            SceneError::new(&exr, field("file"), format!("cannot use as an environment: {e}"))
                        })?
                    }
                };
                Some(Environment { map, samples: env.samples })
            }
        };

        let indirect = match &spec.indirect {
            None => None,
            Some(ind) => {
                v.check(ind.paths <= MAX_VPL_PATHS, "indirect.paths", || {
                    format!("must be at most {MAX_VPL_PATHS}, got {}", ind.paths)
                })?;
                v.check((1..=16).contains(&ind.bounces), "indirect.bounces", || {
                    format!("must be between 1 and 16, got {}", ind.bounces)
                })?;
                Some(IndirectSettings { paths: ind.paths as usize, bounces: ind.bounces })
            }
        };
        let groups = LightGroups::assign(
            path,
            &requested_groups,
            spec.environment.as_ref().map(|e| (e.group.clone(), "environment.group".to_string())),
        )?;
        let clamp = spec.render.distance_clamp;
        v.check((0.0..=MAX_COORDINATE).contains(&clamp), "render.distance_clamp", || {
            format!("must be finite and >= 0, got {clamp}")
        })?;

        Ok(Self {
            path: path.to_path_buf(),
            film,
            camera_spec,
            materials,
            textures,
            meshes,
            lights,
            groups,
            max_mirror_depth: spec.render.max_mirror_depth.min(64),
            environment,
            indirect,
            distance_clamp: clamp,
            inputs,
            warnings,
        })
    }

    /// The camera for a film of `width` x `height` pixels (the film's own
    /// size unless the command line overrides it).
    #[must_use]
    pub fn camera(&self, width: u32, height: u32) -> Camera {
        let c = &self.camera_spec;
        Camera::new(Vec3::from(c.eye), Vec3::from(c.look_at), Vec3::from(c.up), c.fov_y, width, height)
    }

    /// Bounds of all geometry: (min, max), infinite when there is none.
    #[must_use]
    pub fn mesh_bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for m in &self.meshes {
            let (a, b) = m.bounds();
            lo = lo.min(a);
            hi = hi.max(b);
        }
        (lo, hi)
    }

    /// At most how many point lights the light sources and the environment
    /// become (without VPLs), known before any is made.
    #[must_use]
    pub fn light_count_bound(&self) -> u64 {
        let sources: u64 = self
            .lights
            .iter()
            .map(|source| match *source {
                LightSource::Point { .. } | LightSource::Spot { .. } => 1,
                LightSource::Grid { count, .. } => u64::from(count[0]) * u64::from(count[1]),
                LightSource::Area { samples, both_sides, .. } => u64::from(samples) * if both_sides { 2 } else { 1 },
                LightSource::Sun { samples, .. } => u64::from(samples),
            })
            .sum();
        sources + self.environment.as_ref().map_or(0, |e| u64::from(e.samples))
    }

    /// The light group of each mesh's emission: an emitter's mesh is in its
    /// light's group (group 0 for a mesh that emits nothing).
    #[must_use]
    pub fn emission_groups(&self) -> Vec<usize> {
        let mut of_mesh = vec![0; self.meshes.len()];
        for (source, &group) in self.lights.iter().zip(&self.groups.of_light) {
            if let LightSource::Area { mesh, .. } = *source {
                of_mesh[mesh] = group;
            }
        }
        of_mesh
    }

    /// A hash of every file the scene read (its `inputs`, in order), as 16
    /// hex digits: what names a render's scene in its EXR (`lightcuts:sceneHash`)
    /// and what `assemble` requires its tiles to share.
    pub fn content_hash(&self) -> Result<String, SceneError> {
        let hashes = self
            .inputs
            .iter()
            .map(|p| {
                crate::util::hash::hash_file(p)
                    .map_err(|e| SceneError::new(p, "file", format!("cannot read it to hash it: {e}")))
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(crate::util::hash::combined_hex(hashes))
    }

    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.meshes.iter().map(|m| m.triangles.len()).sum()
    }
}

/// Whether every coordinate is finite and within [`MAX_COORDINATE`].
fn within_limits(p: Vec3) -> bool {
    p.is_finite() && p.abs().max_element() <= MAX_COORDINATE
}

/// Checks a film size against [`MAX_PIXELS`]; `what` names the field or flag.
pub fn check_resolution(file: &Path, what: &str, width: u32, height: u32) -> Result<(), SceneError> {
    let pixels = u64::from(width) * u64::from(height);
    if pixels > MAX_PIXELS {
        return Err(SceneError::new(
            file,
            what,
            format!("{width} x {height} = {pixels} pixels would not fit in memory (at most {MAX_PIXELS})"),
        ));
    }
    Ok(())
}

fn parse_toml(path: &Path, text: &str) -> Result<SceneFile, SceneError> {
    let de = toml::Deserializer::new(text);
    serde_path_to_error::deserialize(de).map_err(|e| {
        let field = e.path().to_string();
        let inner = e.into_inner();
        let position = inner.span().map(|s| line_column(text, s.start));
        let location = match (field.as_str(), position) {
            (".", Some((l, c))) | ("", Some((l, c))) => format!("line {l}, column {c}"),
            (f, Some((l, c))) => format!("{f} (line {l}, column {c})"),
            (f, None) => f.to_string(),
        };
        SceneError::new(path, location, inner.message())
    })
}

fn parse_json(path: &Path, text: &str) -> Result<SceneFile, SceneError> {
    let mut de = serde_json::Deserializer::from_str(text);
    let spec: SceneFile = serde_path_to_error::deserialize(&mut de).map_err(|e| {
        let field = e.path().to_string();
        let inner = e.into_inner();
        let location = if field == "." || field.is_empty() {
            format!("line {}, column {}", inner.line(), inner.column())
        } else {
            format!("{field} (line {}, column {})", inner.line(), inner.column())
        };
        // serde_json appends " at line L column C" itself; the location has it.
        let message = inner.to_string();
        let message = message.split(" at line ").next().unwrap_or(&message).to_string();
        SceneError::new(path, location, message)
    })?;
    de.end().map_err(|e| {
        SceneError::new(
            path,
            format!("line {}, column {}", e.line(), e.column()),
            "trailing characters after the scene",
        )
    })?;
    Ok(spec)
}

/// 1-based line and column of a byte offset.
fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, column)
}

/// Field checks that produce errors naming the file and field.
struct Validator<'a> {
    file: &'a Path,
}

impl Validator<'_> {
    fn error(&self, field: &str, message: &str) -> SceneError {
        SceneError::new(self.file, field, message)
    }

    fn check(&self, ok: bool, field: &str, message: impl FnOnce() -> String) -> Result<(), SceneError> {
        if ok {
            Ok(())
        } else {
            Err(self.error(field, &message()))
        }
    }

    fn point(&self, p: [f32; 3], field: &str) -> Result<Vec3, SceneError> {
        let v = Vec3::from(p);
        self.check(within_limits(v), field, || format!("must be finite and within +/-{MAX_COORDINATE:e}, got {p:?}"))?;
        Ok(v)
    }

    fn non_negative_rgb(&self, c: [f32; 3], field: &str) -> Result<Vec3, SceneError> {
        let v = Vec3::from(c);
        self.check(v.is_finite() && v.min_element() >= 0.0, field, || format!("must be finite and >= 0, got {c:?}"))?;
        Ok(v)
    }

    fn sample_count(&self, samples: u32, field: &str) -> Result<(), SceneError> {
        self.check((1..=MAX_EMITTER_SAMPLES).contains(&samples), field, || {
            format!("must be between 1 and {MAX_EMITTER_SAMPLES}, got {samples}")
        })
    }

    fn unit_rgb(&self, c: [f32; 3], field: &str) -> Result<Vec3, SceneError> {
        let v = Vec3::from(c);
        self.check(v.is_finite() && v.min_element() >= 0.0 && v.max_element() <= 1.0, field, || {
            format!("must be between 0 and 1, got {c:?}")
        })?;
        Ok(v)
    }
}

#[cfg(test)]
mod tests;
