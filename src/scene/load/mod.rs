//! Reading a scene: the file parsed (TOML, JSON, or a glTF file by
//! itself), then validated section by section into the renderer's model:
//! `settings` (film, camera, environment, indirect light), `materials`,
//! `shapes`, `lights`, and the glTF import (`super::gltf`). Every error names
//! the file and the field path; relative paths resolve against the scene
//! file's directory.

pub(crate) mod additions;
mod lights;
mod materials;
mod settings;
mod shapes;

use std::path::Path;

use glam::Vec3;

use super::file::{self, ImportedCamera, SceneFile};
use super::{
    gltf, groups, object, usd, within_limits, ImportParts, LightGroups, LightSource, Scene, SceneError, MAX_COORDINATE,
    MAX_EMITTER_SAMPLES,
};

/// What the command line overrides in a scene file.
#[derive(Debug, Clone, Copy, Default)]
pub struct LoadOptions<'a> {
    /// `--camera`: the glTF camera by name, or `#N` by node order.
    pub camera: Option<&'a str>,
    /// `--lumens-per-watt`: the glTF import's luminous efficacy.
    pub lumens_per_watt: Option<f32>,
    /// `--shutter OPEN,CLOSE`: the camera's shutter, seconds (the glTF
    /// file's animation is played over it).
    pub shutter: Option<[f32; 2]>,
    /// `--animation NAME`: the glTF file's animation played over the shutter.
    pub animation: Option<&'a str>,
    /// `--time T`: the USD stage's time code everything is read at.
    pub time: Option<f64>,
    /// `--asset-path DIR`: where a USD stage's assets are looked for when
    /// they are not beside the layer naming them (USD's search paths).
    pub asset_paths: &'a [std::path::PathBuf],
    /// `--strict`: what the asset lacks (a missing file or layer, a format
    /// or prim type not read) is an error, not a warning.
    pub strict: bool,
}

impl LoadOptions<'_> {
    /// These options as `lightcuts inspect` takes them on its command line
    /// (what a child process reading the same scene needs).
    #[must_use]
    pub fn flags(&self) -> Vec<String> {
        let mut flags = Vec::new();
        if let Some(camera) = self.camera {
            flags.extend(["--camera".to_string(), camera.to_string()]);
        }
        if let Some(time) = self.time {
            flags.extend(["--time".to_string(), time.to_string()]);
        }
        if let Some([open, close]) = self.shutter {
            flags.extend(["--shutter".to_string(), format!("{open},{close}")]);
        }
        for directory in self.asset_paths {
            flags.extend(["--asset-path".to_string(), directory.display().to_string()]);
        }
        flags
    }
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
        Self::load_with(path, &LoadOptions { camera, ..LoadOptions::default() })
    }

    /// [`Scene::load`] with the command line's overrides of the scene file.
    pub fn load_with(path: &Path, options: &LoadOptions<'_>) -> Result<Self, SceneError> {
        let camera = options.camera;
        let extension = |x: &str| path.extension().is_some_and(|e| e.eq_ignore_ascii_case(x));
        let is_usd = ["usd", "usda", "usdc", "usdz"].into_iter().any(extension);
        let mut spec = if extension("gltf") || extension("glb") {
            let file = path.file_name().map_or_else(String::new, |f| f.to_string_lossy().into_owned());
            SceneFile { gltf: Some(file::GltfSpec::file(file)), ..SceneFile::default() }
        } else if is_usd {
            let file = path.file_name().map_or_else(String::new, |f| f.to_string_lossy().into_owned());
            SceneFile { usd: Some(file::UsdSpec::file(file)), ..SceneFile::default() }
        } else {
            let text = crate::util::file::read_regular(path, crate::util::file::MAX_FILE_BYTES)
                .map_err(|e| SceneError::new(path, "file", format!("cannot read scene: {e}")))?;
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
            if let Some(usd) = spec.usd.as_mut() {
                usd.camera = Some(name.to_string());
            } else {
                let gltf = imported_gltf(path, &mut spec, "--camera", "picks a glTF or USD camera")?;
                gltf.camera = Some(name.to_string());
            }
            // The TOML's own camera would win over the one asked for.
            spec.camera = None;
        }
        if let Some(time) = options.time {
            let usd = spec.usd.as_mut().ok_or_else(|| {
                SceneError::new(path, "--time", "reads a USD stage at a time code, but the scene imports no USD stage")
            })?;
            if !time.is_finite() {
                return Err(SceneError::new(path, "--time", format!("must be finite, got {time}")));
            }
            usd.time = Some(time);
        }
        if let Some(lpw) = options.lumens_per_watt {
            let gltf = imported_gltf(path, &mut spec, "--lumens-per-watt", "converts a glTF file's lights")?;
            if !(lpw.is_finite() && lpw > 0.0) {
                return Err(SceneError::new(path, "--lumens-per-watt", format!("must be finite and > 0, got {lpw}")));
            }
            gltf.lumens_per_watt = lpw;
        }
        if let Some(name) = options.animation {
            let gltf = imported_gltf(path, &mut spec, "--animation", "plays a glTF animation")?;
            gltf.animation = Some(name.to_string());
        }
        if !options.asset_paths.is_empty() {
            let usd = spec.usd.as_mut().ok_or_else(|| {
                SceneError::new(path, "--asset-path", "gives USD's search paths, but the scene imports no USD stage")
            })?;
            usd.search_paths = options.asset_paths.to_vec();
        }
        if let Some(usd) = spec.usd.as_mut() {
            usd.strict = options.strict;
        }
        if let Some([open, close]) = options.shutter {
            if !(open.is_finite() && close.is_finite() && open <= close) {
                return Err(SceneError::new(
                    path,
                    "--shutter",
                    format!("must be OPEN,CLOSE in seconds with open <= close, got {open},{close}"),
                ));
            }
            if let Some(camera) = spec.camera.as_mut() {
                camera.shutter = [open, close];
            }
            if let Some(gltf) = spec.gltf.as_mut() {
                gltf.shutter = Some([open, close]);
            }
            if let Some(usd) = spec.usd.as_mut() {
                usd.shutter = Some([open, close]);
            }
        }
        let imports_itself =
            (spec.gltf.as_ref().is_some_and(|g| path.file_name() == Some(std::ffi::OsStr::new(&g.file)))
                && (extension("gltf") || extension("glb")))
                || (spec.usd.as_ref().is_some_and(|u| path.file_name() == Some(std::ffi::OsStr::new(&u.file)))
                    && is_usd);
        let mut scene = Self::from_spec(path, spec)?;
        if !imports_itself {
            scene.inputs.insert(0, path.to_path_buf());
        }
        if let Some(lpw) = options.lumens_per_watt {
            // Not a file the scene read: part of its hash all the same.
            scene.additions.push(format!("--lumens-per-watt {lpw}"));
        }
        if let Some([open, close]) = options.shutter {
            scene.additions.push(format!("--shutter {open},{close}"));
        }
        if let Some(name) = options.animation {
            scene.additions.push(format!("--animation {name}"));
        }
        if let Some(time) = options.time {
            scene.additions.push(format!("--time {time}"));
        }
        for directory in options.asset_paths {
            scene.additions.push(format!("--asset-path {}", directory.display()));
        }
        if options.strict {
            if let Some(first) = scene.incomplete.first() {
                let more = scene.incomplete.len() - 1;
                let more = if more > 0 { format!(" (and {more} more)") } else { String::new() };
                return Err(SceneError::new(path, "--strict", format!("the scene is incomplete: {first}{more}")));
            }
        }
        Ok(scene)
    }

    /// The USD stage a scene file reads: the file itself when it is one,
    /// else its `[usd]` file (relative to it); None when it reads none, or
    /// cannot be parsed (loading it then says why).
    #[must_use]
    pub fn usd_stage(path: &Path) -> Option<std::path::PathBuf> {
        let extension = |x: &str| path.extension().is_some_and(|e| e.eq_ignore_ascii_case(x));
        if ["usd", "usda", "usdc", "usdz"].into_iter().any(extension) {
            return Some(path.to_path_buf());
        }
        if extension("gltf") || extension("glb") {
            return None;
        }
        let bytes = crate::util::file::read_regular(path, crate::util::file::MAX_FILE_BYTES).ok()?;
        let text = String::from_utf8(bytes).ok()?;
        let spec = if extension("json") { parse_json(path, &text) } else { parse_toml(path, &text) }.ok()?;
        Some(path.parent().unwrap_or(Path::new(".")).join(spec.usd?.file))
    }

    /// Validates a parsed scene file; `path` is used for messages and to
    /// resolve relative mesh and texture paths.
    pub fn from_spec(path: &Path, spec: SceneFile) -> Result<Self, SceneError> {
        let v = Validator { file: path };
        let base = path.parent().unwrap_or(Path::new("."));
        settings::check_film_and_camera(&v, &spec)?;
        let mut inputs = Vec::new();
        let mut textures = Vec::new();
        let (mut materials, material_index) = materials::materials(&v, base, &spec, &mut inputs, &mut textures)?;
        let (mut meshes, shape_motions): (Vec<_>, Vec<_>) =
            shapes::shapes(&v, base, &spec, &material_index, &mut inputs)?.into_iter().unzip();
        let (mut lights, mut requested_groups) =
            lights::lights(&v, base, &spec, &mut meshes, &mut materials, &mut inputs)?;
        // What the glTF and USD imports add to (`ImportParts`) besides the TOML's lists.
        let (mut warnings, mut incomplete, mut instances) = (Vec::new(), Vec::new(), Vec::new());
        let mut animation = None;
        let imported_camera = match &spec.gltf {
            None => None,
            Some(g) => {
                let mut light_names = Vec::new();
                let parts = gltf::Parts {
                    scene: ImportParts {
                        meshes: &mut meshes,
                        instances: &mut instances,
                        materials: &mut materials,
                        textures: &mut textures,
                        lights: &mut lights,
                        inputs: &mut inputs,
                        warnings: &mut warnings,
                        incomplete: &mut incomplete,
                    },
                    light_names: &mut light_names,
                    played: &mut animation,
                };
                // A TOML camera's open shutter, else --shutter's (an
                // instant, open = close, poses the animation then).
                let shutter = spec.camera.as_ref().filter(|c| c.shutter_open()).map(|c| c.shutter).or(g.shutter);
                let camera = gltf::import(path, base, g, spec.camera.is_none(), shutter, parts)?;
                let matched = groups::apply_rules(path, &g.groups, &light_names)?;
                requested_groups
                    .extend(matched.into_iter().enumerate().map(|(k, g)| (g, format!("gltf.groups (glTF light {k})"))));
                camera
            }
        };
        let lights_before_usd = lights.len();
        let mut usd_environment = None;
        let usd_camera = match &spec.usd {
            None => None,
            Some(u) => {
                let mut groups = Vec::new();
                let parts = usd::Parts {
                    scene: ImportParts {
                        meshes: &mut meshes,
                        instances: &mut instances,
                        materials: &mut materials,
                        textures: &mut textures,
                        lights: &mut lights,
                        inputs: &mut inputs,
                        warnings: &mut warnings,
                        incomplete: &mut incomplete,
                    },
                    groups: &mut groups,
                    environment: &mut usd_environment,
                };
                let camera = import_usd(path, base, &spec, u, imported_camera.is_none(), parts)?;
                requested_groups
                    .extend(groups.into_iter().map(|(g, prim)| (g, format!("usd.file ({prim}.lightcuts:group)"))));
                camera
            }
        };
        let mut objects = object::place(&meshes, instances);
        // The shapes are the first meshes, each drawn once as itself; their
        // motion counts only while the shutter is open.
        if spec.camera.as_ref().is_some_and(file::CameraSpec::shutter_open) {
            for (object, motion) in objects.iter_mut().zip(shape_motions) {
                debug_assert!(object.transform.is_none());
                object.motion = motion;
            }
        }
        let (camera_spec, film) = settings::camera_and_film(
            &v,
            &spec,
            imported_camera.or(usd_camera),
            object::world_bounds(&meshes, &objects),
            &incomplete,
            &mut warnings,
        )?;
        untraceable_instances(path, &mut objects, &meshes, &lights, &camera_spec, &mut warnings);
        let ChosenEnvironment { environment, group: environment_group } =
            environment(&v, base, &spec, usd_environment, &mut inputs, &mut warnings)?;
        let indirect = settings::indirect(&v, &spec)?;
        let counts = [spec.lights.len(), lights_before_usd];
        let vpls = matches!(indirect, Some(crate::scene::Indirect::Vpl(_)));
        let emitted_power = emitted_power(&v, &lights, counts, &meshes, &objects, environment.as_ref(), vpls)?;
        let groups = LightGroups::assign(path, &requested_groups, environment_group)?;
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
            objects,
            lights,
            groups,
            max_mirror_depth: spec.render.max_mirror_depth.min(64),
            environment,
            indirect,
            emitted_power,
            distance_clamp: clamp,
            inputs,
            warnings,
            incomplete,
            additions: Vec::new(),
            animation,
        })
    }
}

/// Draws still, or drops, the objects Embree could not trace
/// (`object::make_traceable`), with a warning for each kind: every ray
/// starts within the scene's reach (its geometry, point lights and camera).
fn untraceable_instances(
    path: &Path,
    objects: &mut Vec<super::Object>,
    meshes: &[super::Mesh],
    lights: &[LightSource],
    camera: &file::CameraSpec,
    warnings: &mut Vec<String>,
) {
    let (lo, hi) = object::world_bounds(meshes, objects);
    let points = lights
        .iter()
        .flat_map(LightSource::positions)
        .chain([camera.eye, camera.look_at].map(Vec3::from))
        .chain(camera.eye_end.map(Vec3::from))
        .chain([lo, hi].into_iter().filter(|p| p.is_finite()));
    let reach = points.map(|p| p.as_dvec3().length()).fold(0.0, f64::max) + f64::from(camera.lens_radius.abs());
    let changed = object::make_traceable(objects, reach);
    let list = |names: &[String]| {
        let shown: Vec<&str> = names.iter().take(3).map(String::as_str).collect();
        let more = names.len().saturating_sub(shown.len());
        format!("{}{}", shown.join(", "), if more > 0 { format!(" and {more} more") } else { String::new() })
    };
    if !changed.drawn_still.is_empty() {
        warnings.push(format!(
            "{}: {} moving object(s) drawn still ({}): a step of the motion scales them to under about 1e-16 of the scene's extent, \
             which the ray tracer cannot carry rays into",
            path.display(),
            changed.drawn_still.len(),
            list(&changed.drawn_still)
        ));
    }
    if !changed.dropped.is_empty() {
        warnings.push(format!(
            "{}: {} instance(s) left out ({}): scaled to under about 1e-16 of the scene's extent in some direction, they cover no \
             pixel, and the ray tracer cannot carry rays into them",
            path.display(),
            changed.dropped.len(),
            list(&changed.dropped)
        ));
    }
}

/// The lights' total power, checked (`lights::check_totals`): the TOML's
/// lights are the first `counts[0]`, the glTF file's run up to
/// `counts[1]`, the USD stage's follow.
fn emitted_power(
    v: &Validator<'_>,
    lights: &[LightSource],
    counts: [usize; 2],
    meshes: &[super::Mesh],
    objects: &[super::Object],
    environment: Option<&super::Environment>,
    vpls: bool,
) -> Result<(f64, String), SceneError> {
    let labels: Vec<String> = (0..lights.len())
        .map(|i| match i {
            i if i < counts[0] => format!("lights[{i}]"),
            i if i < counts[1] => "gltf.file".to_string(),
            _ => "usd.file".to_string(),
        })
        .collect();
    // The scene's extent as light paths see it: geometry and point lights.
    let (lo, hi) = lights
        .iter()
        .flat_map(LightSource::positions)
        .fold(object::world_bounds(meshes, objects), |(lo, hi), p| (lo.min(p), hi.max(p)));
    let radius = if lo.is_finite() && hi.is_finite() { 0.5 * (hi - lo).as_dvec3().length() } else { 0.0 };
    lights::check_totals(v, lights, &labels, meshes, environment, vpls, radius)
}

/// The scene's environment and the light group it asks for (with the
/// field that asks, for messages).
struct ChosenEnvironment {
    environment: Option<super::Environment>,
    group: Option<(Option<String>, String)>,
}

/// The TOML's `[environment]`, else the USD stage's dome light (the
/// TOML's wins, with a warning, when both give one).
fn environment(
    v: &Validator<'_>,
    base: &Path,
    spec: &SceneFile,
    dome: Option<(super::Environment, Option<String>)>,
    inputs: &mut Vec<std::path::PathBuf>,
    warnings: &mut Vec<String>,
) -> Result<ChosenEnvironment, SceneError> {
    let environment = settings::environment(v, base, spec, inputs)?;
    let group = spec.environment.as_ref().map(|e| (e.group.clone(), "environment.group".to_string()));
    Ok(match dome {
        Some(_) if environment.is_some() => {
            warnings.push(format!("{}: [environment] is rendered, not the stage's dome light", v.file.display()));
            ChosenEnvironment { environment, group }
        }
        Some((dome, dome_group)) => ChosenEnvironment {
            environment: Some(dome),
            group: Some((dome_group, "usd.file (the dome light's lightcuts:group)".to_string())),
        },
        None => ChosenEnvironment { environment, group },
    })
}

/// The `[usd]` import `u` of `spec`: a TOML camera's open shutter is the
/// stage's (else `--shutter`'s); the stage's camera is wanted when neither
/// the TOML nor a glTF import gives one.
fn import_usd(
    path: &Path,
    base: &Path,
    spec: &SceneFile,
    u: &file::UsdSpec,
    no_imported_camera: bool,
    parts: usd::Parts<'_>,
) -> Result<Option<ImportedCamera>, SceneError> {
    let mut u = u.clone();
    if let Some(camera) = spec.camera.as_ref().filter(|c| c.shutter_open()) {
        u.shutter = Some(camera.shutter);
    }
    usd::import(path, base, &u, spec.camera.is_none() && no_imported_camera, parts)
}

/// The scene's `[gltf]` import, for the command-line `flag` that `does`
/// something to it; an error naming the flag when the scene imports none.
fn imported_gltf<'s>(
    path: &Path,
    spec: &'s mut SceneFile,
    flag: &str,
    does: &str,
) -> Result<&'s mut file::GltfSpec, SceneError> {
    spec.gltf.as_mut().ok_or_else(|| SceneError::new(path, flag, format!("{does}, but the scene imports no glTF file")))
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

    /// A light's intensity, radiance or irradiance: finite, at least 0 and
    /// at most [`lights::MAX_EMISSION`] per channel.
    fn emission(&self, c: [f32; 3], field: &str) -> Result<Vec3, SceneError> {
        let v = Vec3::from(c);
        self.check(v.is_finite() && v.min_element() >= 0.0 && v.max_element() <= lights::MAX_EMISSION, field, || {
            format!("must be finite, >= 0 and at most {:e}, got {c:?}", lights::MAX_EMISSION)
        })?;
        Ok(v)
    }

    fn sample_count(&self, samples: u32, field: &str) -> Result<(), SceneError> {
        self.check((1..=MAX_EMITTER_SAMPLES).contains(&samples), field, || {
            format!("must be between 1 and {MAX_EMITTER_SAMPLES}, got {samples}")
        })
    }

    /// A number between 0 and 1 (`default` where absent), or an error
    /// naming `field`.
    fn unit(&self, value: Option<f32>, default: f32, field: &str) -> Result<f32, SceneError> {
        let value = value.unwrap_or(default);
        self.check(value.is_finite() && (0.0..=1.0).contains(&value), field, || {
            format!("must be between 0 and 1, got {value}")
        })?;
        Ok(value)
    }

    fn unit_rgb(&self, c: [f32; 3], field: &str) -> Result<Vec3, SceneError> {
        let v = Vec3::from(c);
        self.check(v.is_finite() && v.min_element() >= 0.0 && v.max_element() <= 1.0, field, || {
            format!("must be between 0 and 1, got {c:?}")
        })?;
        Ok(v)
    }
}
