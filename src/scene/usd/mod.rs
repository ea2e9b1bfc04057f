//! USD import (`.usd`, `.usda`, `.usdc`, `.usdz`): the composed stage's
//! meshes and gprims, UsdPreviewSurface materials, UsdLux lights and
//! cameras, instanceable prims and point instancers as Embree instances,
//! and time samples over the shutter, mapped onto the renderer's model as
//! docs/scene-format.md ("USD") tabulates.
//!
//! By job: `stage` is the adapter to the `openusd` crate (the only file
//! that names it); `schema` holds the schemas' fallback values; `xform`
//! composes transforms; `geometry` makes meshes; `materials` reads
//! UsdPreviewSurface networks; `lights` maps UsdLux. This file walks the
//! stage and places what they make.

mod geometry;
mod lights;
mod materials;
mod schema;
mod stage;
mod strands;
mod xform;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{Affine3A, DMat4, DQuat, DVec3, DVec4, Mat4, Vec3};

use self::geometry::Located;
use self::stage::Stage;
use super::environment::{Environment, EnvironmentMap};
use super::file::{CameraSpec, ImportedCamera, UsdSpec};
use super::material::Material;
use super::mesh::Mesh;
use super::object::{Motion, Object};
use super::{within_limits, ImportParts, LightSource, SceneError, MAX_COORDINATE};
use super::{MAX_IMPORT_INSTANCES as MAX_INSTANCES, MAX_IMPORT_TRIANGLES as MAX_TRIANGLES};

/// Deepest prim hierarchy followed (instances and point instancers count
/// their prototypes' depth too).
const MAX_DEPTH: usize = 256;
/// Time steps a moving object's placement is sampled at over an open
/// shutter (as the glTF import's animations are).
const SHUTTER_STEPS: usize = 33;
/// Directional lights a dome light becomes (as a TOML's `[environment]`).
const DOME_SAMPLES: u32 = 4096;
/// Largest dome texture read (1 GiB).
const MAX_DOME_BYTES: u64 = 1 << 30;
/// USD's fallback for an unauthored `metersPerUnit`: centimetres.
const FALLBACK_METERS_PER_UNIT: f64 = 0.01;

/// Where the import's parts go (`ImportParts`), and what only a USD
/// import reports.
pub struct Parts<'a> {
    pub scene: ImportParts<'a>,
    /// Each light's `lightcuts:group` (its own, or its nearest ancestor's)
    /// and the prim it came from, one per light added.
    pub groups: &'a mut Vec<(Option<String>, String)>,
    /// The stage's dome light, as the scene's environment (with its group).
    pub environment: &'a mut Option<(Environment, Option<String>)>,
}

/// Imports `spec.file` (relative to `base`) into `parts`; returns the
/// camera (`spec.camera` by prim path, else the first found) when
/// `want_camera`. With a `shutter` (open < close, time codes) what moves
/// over it blurs; otherwise everything is read at `spec.time`, else the
/// stage's start time code.
pub fn import(
    scene_file: &Path,
    base: &Path,
    spec: &UsdSpec,
    want_camera: bool,
    parts: Parts<'_>,
) -> Result<Option<ImportedCamera>, SceneError> {
    let path = base.join(&spec.file);
    let _ = scene_file;
    parts.scene.inputs.push(path.clone());
    let search_paths: Vec<PathBuf> =
        spec.asset_paths.iter().map(|d| base.join(d)).chain(spec.search_paths.iter().cloned()).collect();
    // The reader is a young library: should it panic on a hostile file,
    // the panic is caught here and reported as the file's error, without
    // the panic's own message on stderr (and without silencing any other
    // thread's: crate::util::panic).
    match crate::util::panic::catch_quietly(|| import_stage(&path, &search_paths, spec, want_camera, parts)) {
        Ok(result) => result,
        Err(panic) => {
            let what = crate::util::panic::message(&*panic);
            Err(SceneError::new(&path, "file", format!("the USD reader failed on this file ({what})")))
        }
    }
}

fn import_stage(
    path: &Path,
    search_paths: &[PathBuf],
    spec: &UsdSpec,
    want_camera: bool,
    parts: Parts<'_>,
) -> Result<Option<ImportedCamera>, SceneError> {
    let error = |(location, message): Located| SceneError::new(path, location, message);
    let size = crate::util::file::open_regular(path)
        .and_then(|file| file.metadata())
        .map_err(|e| SceneError::new(path, "file", format!("cannot read the stage: {e}")))?
        .len();
    if size == 0 {
        return Err(SceneError::new(path, "file", "the file is empty"));
    }
    let stage = Stage::open(path, search_paths).map_err(|e| SceneError::new(path, "file", e))?;
    let up = stage.metadata_token("upAxis").map_err(|e| SceneError::new(path, "upAxis", e))?;
    let up_z = match up.as_deref() {
        None | Some("Y") => false,
        Some("Z") => true,
        Some(other) => return Err(SceneError::new(path, "upAxis", format!("must be Y or Z, got '{other}'"))),
    };
    let meters_per_unit = stage
        .metadata_number("metersPerUnit")
        .map_err(|e| SceneError::new(path, "metersPerUnit", e))?
        .unwrap_or(FALLBACK_METERS_PER_UNIT);
    if !(meters_per_unit.is_finite() && meters_per_unit > 0.0) {
        return Err(SceneError::new(path, "metersPerUnit", format!("must be finite and > 0, got {meters_per_unit}")));
    }
    // The stage's space into the renderer's: metres, +y up (a Z-up stage
    // turned -90 degrees about x, so +z goes to +y).
    let turn = if up_z { DMat4::from_rotation_x(-std::f64::consts::FRAC_PI_2) } else { DMat4::IDENTITY };
    let root = turn * DMat4::from_scale(DVec3::splat(meters_per_unit));
    // Blender's exporter says so in the layer's doc ("Blender v5.0.1"), which
    // the reader calls `documentation`.
    let doc = stage.metadata_token("documentation").map_err(|e| SceneError::new(path, "doc", e))?;
    let blender = doc.as_deref().is_some_and(|d| d.starts_with("Blender v"));
    let time = spec.time.or_else(|| stage.start_time_code()).unwrap_or(0.0);
    if !time.is_finite() {
        return Err(SceneError::new(path, "--time", format!("must be finite, got {time}")));
    }
    let shutter = spec.shutter.filter(|[open, close]| open < close).map(|[o, c]| [f64::from(o), f64::from(c)]);
    let times: Vec<f64> = match shutter {
        Some([open, close]) => {
            (0..SHUTTER_STEPS).map(|k| open + (close - open) * k as f64 / (SHUTTER_STEPS - 1) as f64).collect()
        }
        None => vec![spec.shutter.map_or(time, |[open, _]| f64::from(open))],
    };
    let mut walker = Walker {
        file: path,
        stage: &stage,
        spec,
        times,
        root,
        units: lights::Units { meters_per_unit, distant_scale: if blender { 4.0 } else { 1.0 }, up_z },
        materials: materials::Materials::new(&stage, time),
        material_index: HashMap::new(),
        prototypes: HashMap::new(),
        templates: HashMap::new(),
        parts,
        cameras: Vec::new(),
        triangles: 0,
        emitters: super::EmissiveMeshes::USD,
        still_moving: 0,
        cages: std::collections::BTreeMap::new(),
        skipped: std::collections::BTreeMap::new(),
        primvar_fallbacks: std::collections::BTreeMap::new(),
    };
    walker.materials = materials::Materials::new(&stage, walker.time());
    let roots = stage.root_prims().map_err(|e| SceneError::new(path, "/", e))?;
    let top = Context { worlds: vec![root; walker.times.len()], binding: None, group: None, depth: 0, instance: None };
    for prim in &roots {
        walker.walk(prim, &top).map_err(error)?;
    }
    // What composition could not find (a layer, a format this reader does
    // not read) is left out, as usdview does: the rest renders.
    for error in stage.composition_errors() {
        // Under --strict a piece left out is the error, before anything its
        // absence leads to (no camera, nothing to frame).
        if spec.strict {
            return Err(SceneError::new(path, "--strict", format!("the scene is incomplete: {error}: left out")));
        }
        walker.lacks(format!("{error}: left out"));
    }
    // Every layer read is an input (the root was pushed as given).
    let root = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
    for layer in stage.layer_files() {
        if layer != root && !walker.parts.scene.inputs.contains(&layer) {
            walker.parts.scene.inputs.push(layer);
        }
    }
    walker.summarise();
    if !want_camera {
        return Ok(None);
    }
    walker.camera(spec.camera.as_deref(), stage.default_prim().as_deref()).map_err(error)
}

/// A material as the meshes it is bound to read it: its index in the
/// scene's materials, the primvar holding its texture coordinates, and the
/// primvar (and fallback) its base colour reads as vertex colours.
#[derive(Clone)]
struct Bound {
    material: usize,
    st: String,
    colour: Option<(String, Vec3)>,
    /// The primvars its other inputs read, each with the note of what a
    /// gprim without a constant value of it gets.
    primvars: Vec<(String, String)>,
}

/// An instance being walked. Its prims are walked where they stand for
/// the prototype's (an instanceable prim's instance proxies, a point
/// instancer's prototype itself), under `root`; the same prim of every
/// instance shares one mesh, keyed by `key` + its path below `root`, and is
/// named `name` + that path.
#[derive(Clone)]
struct Instance {
    root: String,
    key: String,
    name: String,
}

impl Instance {
    fn below<'p>(&self, prim: &'p str) -> &'p str {
        prim.strip_prefix(self.root.as_str()).unwrap_or(prim)
    }
}

/// An instanced mesh a prototype's walk placed: the mesh, its name below
/// the instance, its placement relative to the instance's root.
#[derive(Clone)]
struct Placed {
    mesh: usize,
    suffix: String,
    relative: Affine3A,
}

/// What flows down the hierarchy.
#[derive(Clone)]
struct Context {
    /// The parent's world matrix at each of the walker's times.
    worlds: Vec<DMat4>,
    /// The nearest `material:binding` above (a Material's path).
    binding: Option<String>,
    /// The nearest `lightcuts:group` above.
    group: Option<String>,
    depth: usize,
    /// The instance (or point-instancer entry) being walked: its prims are
    /// drawn as instances of meshes kept once per prototype.
    instance: Option<Instance>,
}

struct Walker<'a, 'p> {
    file: &'a Path,
    stage: &'a Stage,
    spec: &'a UsdSpec,
    /// The time codes read: one, or the shutter's steps from open to close.
    times: Vec<f64>,
    root: DMat4,
    units: lights::Units,
    materials: materials::Materials<'a>,
    /// The scene's material of each (Material path or display colour,
    /// culls back faces), and what it reads of a mesh.
    material_index: HashMap<(String, bool), Bound>,
    /// Each prototype prim's meshes (scene mesh, its matrix in the
    /// prototype's space), kept once for all its instances.
    prototypes: HashMap<String, Vec<(usize, DMat4)>>,
    /// What walking an instance of each prototype (by its key) made, for
    /// the next instances to repeat by matrix instead of walking again:
    /// None where a walk made more than instanced meshes (lights, copies).
    templates: HashMap<String, Option<Vec<Placed>>>,
    parts: Parts<'p>,
    /// Cameras found: (prim path, world matrices at the times, stage read time).
    cameras: Vec<(String, Vec<DMat4>)>,
    triangles: usize,
    emitters: super::EmissiveMeshes,
    still_moving: usize,
    /// Subdivision meshes drawn as their control polygons: why, how many, and the first one's path.
    cages: std::collections::BTreeMap<&'static str, (usize, String)>,
    /// The prim types not drawn: how many of each, and the first one's path.
    skipped: std::collections::BTreeMap<String, (usize, String)>,
    /// Primvar readers that read their fallback on some gprims: the note,
    /// how many gprims, and the first one's path.
    primvar_fallbacks: std::collections::BTreeMap<String, (usize, String)>,
}

/// "/First" for one prim, "/First and 2 more" for three: how a warning
/// names the prims of one kind.
fn first_and_more(first: &str, count: usize) -> String {
    if count > 1 {
        format!("{first} and {} more", count - 1)
    } else {
        first.to_string()
    }
}

/// Typed prims that draw nothing themselves: groups, shading, subsets,
/// skeletons (their meshes draw in their bind pose), render settings.
const NOT_DRAWN_BY_DEFINITION: [&str; 16] = [
    "Xform",
    "Scope",
    "Material",
    "Shader",
    "NodeGraph",
    "GeomSubset",
    "SkelRoot",
    "Skeleton",
    "SkelAnimation",
    "BlendShape",
    "RenderSettings",
    "RenderProduct",
    "RenderVar",
    "PhysicsScene",
    "GeomModelAPI",
    "Backdrop",
];

/// Why a prim type is not drawn, for the one line each kind gets.
fn not_drawn_because(type_name: &str) -> &'static str {
    match type_name {
        "NurbsCurves" | "HermiteCurves" => "only BasisCurves are drawn",
        "NurbsPatch" => "NURBS patches are not tessellated",
        "Volume" | "OpenVDBAsset" | "Field3DAsset" => "volumes are not rendered",
        "TetMesh" => "tetrahedral meshes are not drawn",
        _ => "a type this renderer does not draw",
    }
}

/// The gprim types tessellated.
const GPRIMS: [&str; 6] = ["Sphere", "Cube", "Cylinder", "Cone", "Capsule", "Plane"];
/// The UsdLux light types.
const LIGHTS: [&str; 10] = [
    "SphereLight",
    "RectLight",
    "DiskLight",
    "CylinderLight",
    "DistantLight",
    "DomeLight",
    "DomeLight_1",
    "GeometryLight",
    "PortalLight",
    "PluginLight",
];

impl Walker<'_, '_> {
    /// The time everything that does not move is read at: the shutter's open.
    fn time(&self) -> f64 {
        self.times[0]
    }

    fn warn(&mut self, message: String) {
        self.parts.scene.warnings.push(format!("{}: {message}", self.file.display()));
    }

    /// Notes what the stage lacks or holds that is not drawn
    /// (`Scene::incomplete`).
    fn lacks(&mut self, message: String) {
        let line = format!("{}: {message}", self.file.display());
        if !self.parts.scene.incomplete.contains(&line) {
            self.parts.scene.incomplete.push(line);
        }
    }

    fn walk(&mut self, prim: &str, above: &Context) -> Result<(), Located> {
        let stage = self.stage;
        let time = self.time();
        if above.depth > MAX_DEPTH {
            return Err((prim.to_string(), format!("the hierarchy is deeper than {MAX_DEPTH} prims")));
        }
        let info = stage.prim(prim).map_err(|e| (prim.to_string(), e))?;
        if !info.present {
            return Ok(());
        }
        let read = schema::Reader { stage, prim, schema: &info.type_name, time };
        if read.token("visibility")? == "invisible" {
            return Ok(());
        }
        if matches!(read.token("purpose")?.as_str(), "proxy" | "guide") {
            return Ok(());
        }
        let mut here = above.clone();
        here.depth += 1;
        if let Some(group) =
            stage.token(prim, "lightcuts:group", time).map_err(|e| (format!("{prim}.lightcuts:group"), e))?
        {
            here.group = Some(group);
        }
        if let Some(binding) = self.binding(prim)? {
            here.binding = Some(binding);
        }
        here.worlds = self.worlds(prim, &above.worlds)?;
        let type_name = info.type_name.as_str();
        if let Some(prototype) = &info.prototype {
            // An instance: its prototype's prims, read through the
            // instance's proxies (openusd 0.6 composes the proxies of an
            // internal reference's instances, not their prototype's prims).
            let mut inside = here.clone();
            let name = match &here.instance {
                Some(outer) => format!("{}{}", outer.name, outer.below(prim)),
                None => prim.to_string(),
            };
            inside.instance = Some(Instance { root: prim.to_string(), key: prototype.clone(), name });
            let children = stage.children(prim).map_err(|e| (prim.to_string(), e))?;
            return self.walk_instance(prototype, &children, &inside);
        }
        match type_name {
            "Mesh" => self.mesh(prim, &here)?,
            t if GPRIMS.contains(&t) => self.gprim(prim, t, &here)?,
            "BasisCurves" | "Points" => self.strands(prim, type_name, &here)?,
            t if LIGHTS.contains(&t) => self.light(prim, t, &info.api_schemas, &here)?,
            "Camera" if here.instance.is_none() => self.cameras.push((prim.to_string(), here.worlds.clone())),
            "PointInstancer" => return self.point_instancer(prim, &here),
            t if !t.is_empty() && !NOT_DRAWN_BY_DEFINITION.contains(&t) => self.skip(prim, t),
            _ => {}
        }
        for child in stage.children(prim).map_err(|e| (prim.to_string(), e))? {
            self.walk(&child, &here)?;
        }
        Ok(())
    }

    /// The prim's world matrices at the walker's times from its parent's.
    fn worlds(&self, prim: &str, parent: &[DMat4]) -> Result<Vec<DMat4>, Located> {
        let names = xform::op_names(self.stage, prim, self.time())?;
        let moves = self.times.len() > 1
            && names.iter().try_fold(false, |any, op| {
                Ok::<bool, Located>(any || self.stage.varies(prim, op).map_err(|e| (format!("{prim}.{op}"), e))?)
            })?;
        let mut worlds = Vec::with_capacity(self.times.len());
        for (k, &t) in self.times.iter().enumerate() {
            let (local, resets) = if k == 0 || moves {
                xform::local(self.stage, prim, t)?
            } else {
                xform::local(self.stage, prim, self.times[0])?
            };
            let above = if resets { self.root } else { parent[k] };
            worlds.push(above * local);
        }
        Ok(worlds)
    }

    /// The prim's own `material:binding` (the full-purpose one first).
    fn binding(&self, prim: &str) -> Result<Option<String>, Located> {
        for name in ["material:binding:full", "material:binding"] {
            let targets = self.stage.targets(prim, name).map_err(|e| (format!("{prim}.{name}"), e))?;
            if let Some(first) = targets.into_iter().next() {
                return Ok(Some(first));
            }
        }
        Ok(None)
    }

    /// The scene material for a binding (or a display colour), culling back
    /// faces or not; and the primvar its textures read.
    fn material(&mut self, binding: Option<&str>, display: Option<Vec3>, culls: bool) -> Result<Bound, Located> {
        let key = match (binding, display) {
            (Some(b), _) => b.to_string(),
            (None, Some(c)) => format!("displayColor {c}"),
            (None, None) => "default".to_string(),
        };
        if let Some(found) = self.material_index.get(&(key.clone(), culls)) {
            return Ok(found.clone());
        }
        let (mut material, st, colour, primvars) = match binding {
            Some(path) => {
                let imported = self.import_material(path, HashMap::new())?;
                (imported.material, imported.varname, imported.colour_primvar, imported.primvars)
            }
            None => {
                let grey = materials::display_material(&key, display.unwrap_or(materials::DEFAULT_GREY));
                (grey, "st".to_string(), None, Vec::new())
            }
        };
        material.culls_back_faces = culls;
        self.parts.scene.materials.push(material);
        let found = Bound { material: self.parts.scene.materials.len() - 1, st, colour, primvars };
        self.material_index.insert((key, culls), found.clone());
        Ok(found)
    }

    /// The material at `path`, its primvar readers reading `constants` (by
    /// primvar name; empty for the material every gprim shares), with its
    /// warnings and what it lacks reported.
    fn import_material(
        &mut self,
        path: &str,
        constants: HashMap<String, DVec4>,
    ) -> Result<materials::Imported, Located> {
        let mut warnings = Vec::new();
        let imported =
            self.materials.import(path, constants, self.parts.scene.textures, self.parts.scene.inputs, &mut warnings);
        for w in warnings {
            self.warn(w);
        }
        for lacking in self.materials.take_lacking() {
            self.lacks(lacking);
        }
        imported
    }

    /// [`Self::material`] as gprim `prim` sees it: where the material's
    /// primvar readers read primvars the gprim holds constant values of,
    /// the material imported again with those values (one material for
    /// each set of values); a reader whose primvar the gprim lacks, or
    /// varies over its surface, reads its fallback, with a note
    /// (docs/design.md §6.8, "Primvar readers").
    fn material_for(
        &mut self,
        prim: &str,
        binding: Option<&str>,
        display: Option<Vec3>,
        culls: bool,
    ) -> Result<usize, Located> {
        let shared = self.material(binding, display, culls)?;
        let (Some(path), false) = (binding, shared.primvars.is_empty()) else { return Ok(shared.material) };
        let mut constants = HashMap::new();
        for (name, note) in &shared.primvars {
            match self.constant_primvar(prim, name)? {
                Some(value) => {
                    constants.insert(name.clone(), value);
                }
                None => self.primvar_fallbacks.entry(note.clone()).or_insert((0, prim.to_string())).0 += 1,
            }
        }
        if constants.is_empty() {
            return Ok(shared.material);
        }
        let mut values: Vec<_> = constants.iter().map(|(n, v)| format!("{n}={v}")).collect();
        values.sort();
        let key = (format!("{path} {}", values.join(" ")), culls);
        if let Some(found) = self.material_index.get(&key) {
            return Ok(found.material);
        }
        let mut material = self.import_material(path, constants)?.material;
        material.culls_back_faces = culls;
        material.name = format!("{} ({})", material.name, values.join(", "));
        self.parts.scene.materials.push(material);
        let found = Bound { material: self.parts.scene.materials.len() - 1, ..shared };
        self.material_index.insert(key, found.clone());
        Ok(found.material)
    }

    /// The value primvar `name` holds over the whole of gprim `prim`: one
    /// authored on it with `constant` interpolation (or none), or of any
    /// interpolation with every element equal; else a constant one on an
    /// ancestor (constant primvars inherit down the namespace,
    /// UsdGeomPrimvarsAPI's `FindPrimvarWithInheritance`). None where the
    /// gprim's own varies over its surface, or no prim has one (or one of a
    /// type no reader reads). A number reads as grey, a 4-vector as its
    /// first three.
    fn constant_primvar(&self, prim: &str, name: &str) -> Result<Option<DVec4>, Located> {
        let attribute = format!("primvars:{name}");
        let time = self.time();
        let stage = self.stage;
        let at = |p: &str| format!("{p}.{attribute}");
        let mut owner = prim.to_string();
        loop {
            if stage.has_value(&owner, &attribute, time).map_err(|e| (at(&owner), e))? {
                let interpolation = stage.interpolation(&owner, &attribute).map_err(|e| (at(&owner), e))?;
                let constant = matches!(interpolation.as_deref(), None | Some("constant"));
                let values: Vec<DVec4> = if let Some(v) = stage.number(&owner, &attribute, time).ok().flatten() {
                    vec![DVec4::new(v, v, v, 1.0)]
                } else if let Some(v) = stage.vec3(&owner, &attribute, time).ok().flatten() {
                    vec![v.extend(1.0)]
                } else if let Some(v) = stage.vec4(&owner, &attribute, time).ok().flatten() {
                    vec![v]
                } else {
                    // A type no reader's output has (a 2-vector, a string):
                    // no value, so the fallback.
                    let colours = stage.colours(&owner, &attribute, time).ok().flatten();
                    colours.unwrap_or_default().into_iter().map(|c| c.extend(1.0)).collect()
                };
                if let Some(v) = values.iter().find(|v| !v.is_finite()) {
                    return Err((at(&owner), format!("must be finite, got {v:?}")));
                }
                let first = values.first().copied();
                if owner == prim {
                    return Ok(first.filter(|f| constant || values.iter().all(|v| v == f)));
                }
                if constant {
                    return Ok(first);
                }
            }
            match owner.rfind('/') {
                Some(k) if k > 0 => owner.truncate(k),
                _ => return Ok(None),
            }
        }
    }

    fn mesh(&mut self, prim: &str, here: &Context) -> Result<(), Located> {
        let time = self.time();
        let read = schema::Reader { stage: self.stage, prim, schema: "Mesh", time };
        let double_sided = read.boolean("doubleSided")?;
        // The bound material decides which primvars hold the coordinates
        // and the colours.
        let (st, colour) = match here.binding.as_deref() {
            Some(b) => {
                let bound = self.material(Some(b), None, !double_sided)?;
                (bound.st, bound.colour)
            }
            None => ("st".to_string(), None),
        };
        let wanted = geometry::Wanted {
            st: &st,
            colour: colour.as_ref().map(|(name, fallback)| (name.as_str(), fallback.as_dvec3())),
        };
        let (pieces, kept_cage) = geometry::mesh(self.stage, prim, time, &wanted)?;
        if let Some(why) = kept_cage {
            self.cages.entry(why).or_insert((0, prim.to_string())).0 += 1;
        }
        for piece in pieces {
            let binding = match &piece.subset {
                Some(subset) => self.binding(subset)?.or_else(|| here.binding.clone()),
                None => here.binding.clone(),
            };
            self.surface(prim, piece.mesh, binding.as_deref(), double_sided, here)?;
        }
        Ok(())
    }

    fn gprim(&mut self, prim: &str, type_name: &str, here: &Context) -> Result<(), Located> {
        let time = self.time();
        let Some(mesh) = geometry::gprim(self.stage, prim, type_name, time)? else { return Ok(()) };
        let double_sided =
            schema::Reader { stage: self.stage, prim, schema: type_name, time }.boolean("doubleSided")?;
        let display = self
            .stage
            .vec3s(prim, "primvars:displayColor", time)
            .map_err(|e| (format!("{prim}.primvars:displayColor"), e))?;
        let mut mesh = mesh;
        if here.binding.is_none() {
            if let Some(c) = display.and_then(|c| c.first().copied()) {
                mesh.colors = Some(vec![c.as_vec3().max(Vec3::ZERO); mesh.positions.len()]);
            }
        } else if let Some((name, fallback)) = self.material(here.binding.as_deref(), None, !double_sided)?.colour {
            // A material reading a primvar as its colour: the gprim's constant one.
            let value = self.stage.colours(prim, &format!("primvars:{name}"), time).ok().flatten();
            let c = value.and_then(|v| v.first().map(|c| c.as_vec3())).unwrap_or(fallback);
            mesh.colors = Some(vec![c.max(Vec3::ZERO); mesh.positions.len()]);
        }
        self.surface(prim, mesh, here.binding.clone().as_deref(), double_sided, here)
    }

    /// A curves or points prim, drawn as Embree's curves or spheres
    /// (docs/design.md §4.3); its material's colour primvar, or its
    /// display colour, read per point.
    fn strands(&mut self, prim: &str, type_name: &str, here: &Context) -> Result<(), Located> {
        let time = self.time();
        let colour = match here.binding.as_deref() {
            Some(b) => {
                let bound = self.material(Some(b), None, false)?;
                if self.parts.scene.materials[bound.material].emission != Vec3::ZERO {
                    self.warn(format!(
                        "{prim}: curves and points do not emit light: its material's emission is left out"
                    ));
                }
                bound.colour
            }
            None => None,
        };
        let colour = colour.as_ref().map(|(name, fallback)| (name.as_str(), fallback.as_dvec3()));
        let mesh = strands::strands(self.stage, prim, type_name, time, colour)?;
        if mesh.positions.is_empty() {
            return Ok(());
        }
        self.surface(prim, mesh, here.binding.clone().as_deref(), true, here)
    }

    /// A surface (in its prim's space) placed: with its material; as an
    /// area light if it emits; instanced when its prim is in a prototype
    /// or moves, copied into the world otherwise.
    fn surface(
        &mut self,
        prim: &str,
        mut mesh: Mesh,
        binding: Option<&str>,
        double_sided: bool,
        here: &Context,
    ) -> Result<(), Located> {
        mesh.name = prim.to_string();
        // Without a material, a constant display colour is the base colour;
        // with one, display colours are read only where the material reads
        // them (a primvar reader).
        let reads_colours = match binding {
            Some(b) => self.material(Some(b), None, !double_sided)?.colour.is_some(),
            None => false,
        };
        let display = match (&binding, &mesh.colors) {
            (None, Some(colors)) if colors.windows(2).all(|w| w[0] == w[1]) => {
                let c = colors[0];
                mesh.colors = None;
                Some(c)
            }
            (None, Some(_)) => Some(Vec3::ONE),
            (Some(_), _) => {
                if !reads_colours {
                    mesh.colors = None;
                }
                None
            }
            (None, None) => None,
        };
        let material = self.material_for(prim, binding, display, !double_sided)?;
        mesh.material = material;
        if self.parts.scene.materials[material].pbr.as_ref().is_some_and(|p| p.normal_map.is_some())
            && mesh.uvs.is_some()
        {
            geometry::add_tangents(&mut mesh);
        }
        self.triangles += mesh.triangles.len();
        if self.triangles > MAX_TRIANGLES {
            return Err((prim.to_string(), format!("the stage has more than {MAX_TRIANGLES} triangles")));
        }
        let emission = self.parts.scene.materials[material].emission;
        let world = here.worlds[0];
        let moving = here.worlds.windows(2).any(|w| w[0] != w[1]);
        let rigid = world.determinant() > 0.0 && here.worlds.iter().all(|w| w.determinant() > 0.0);
        if emission == Vec3::ZERO && rigid && (here.instance.is_some() || moving) {
            let transform = affine(&world, prim)?;
            let motion = moving.then(|| Motion {
                steps: here.worlds.iter().map(|w| Affine3A::from_mat4(w.as_mat4()) * transform.inverse()).collect(),
            });
            let (name, key) = match &here.instance {
                Some(instance) => (
                    format!("{}{}", instance.name, instance.below(prim)),
                    format!("{}{}#{}", instance.key, instance.below(prim), mesh.material),
                ),
                None => (prim.to_string(), String::new()),
            };
            let index = match self.prototypes.get(&key).and_then(|v| v.first()) {
                Some(&(index, _)) if here.instance.is_some() => index,
                _ => {
                    self.parts.scene.meshes.push(mesh);
                    let index = self.parts.scene.meshes.len() - 1;
                    if here.instance.is_some() {
                        self.prototypes.insert(key, vec![(index, DMat4::IDENTITY)]);
                    }
                    index
                }
            };
            let object = Object { mesh: index, transform: Some(transform), name, motion };
            let (lo, hi) = super::object::world_bounds(self.parts.scene.meshes, std::slice::from_ref(&object));
            if !(within_limits(lo) && within_limits(hi)) {
                return Err((
                    prim.to_string(),
                    format!("is placed at {lo} to {hi}: coordinates must be finite and within +/-{MAX_COORDINATE:e} m"),
                ));
            }
            if self.parts.scene.instances.len() >= MAX_INSTANCES {
                return Err((prim.to_string(), format!("the stage has more than {MAX_INSTANCES} instances")));
            }
            self.parts.scene.instances.push(object);
            return Ok(());
        }
        self.still_moving += usize::from(moving);
        let mesh = lights::placed_mesh(mesh, &world);
        if let Some(p) = mesh.positions.iter().find(|p| !within_limits(**p)) {
            return Err((
                prim.to_string(),
                format!("a point lands at {p}: coordinates must be finite and within +/-{MAX_COORDINATE:e} m"),
            ));
        }
        let has_area = mesh.has_area();
        self.parts.scene.meshes.push(mesh);
        if emission != Vec3::ZERO && has_area {
            let mesh = self.parts.scene.meshes.len() - 1;
            let light = self.emitters.light(mesh, emission, self.spec.emitter_samples, double_sided);
            self.parts.scene.lights.push(light);
            self.parts.scene.materials[material].emits_both_sides = double_sided;
            self.parts.groups.push((here.group.clone(), prim.to_string()));
        }
        Ok(())
    }

    fn light(&mut self, prim: &str, type_name: &str, api_schemas: &[String], here: &Context) -> Result<(), Located> {
        let time = self.time();
        if here.worlds.windows(2).any(|w| w[0] != w[1]) {
            self.still_moving += 1;
        }
        let mut warnings = Vec::new();
        let read = schema::Reader { stage: self.stage, prim, schema: type_name, time };
        let made = lights::light(&read, here.worlds[0], &self.units, api_schemas, &mut warnings)?;
        if type_name == "DistantLight" && self.units.distant_scale != 1.0 {
            warnings.push(format!(
                "{prim}: the stage is Blender's, whose exporter writes a sun's strength / 4: read as 4 x intensity, as \
                 Blender reads it back"
            ));
        }
        for w in warnings {
            self.warn(w);
        }
        match made {
            None => {}
            Some(lights::Made::Light(mut source, mesh)) => {
                if let Some(mesh) = mesh {
                    let LightSource::Area { radiance, .. } = source else {
                        unreachable!("only area lights have meshes")
                    };
                    let mut mesh = mesh;
                    mesh.name = prim.to_string();
                    // Black, emitting from the side its winding faces.
                    self.parts.scene.materials.push(Material {
                        emission: radiance,
                        ..Material::diffuse(prim, super::material::Albedo::Constant(Vec3::ZERO))
                    });
                    mesh.material = self.parts.scene.materials.len() - 1;
                    self.parts.scene.meshes.push(mesh);
                    source = self.emitters.light(
                        self.parts.scene.meshes.len() - 1,
                        radiance,
                        self.spec.emitter_samples,
                        false,
                    );
                }
                if let LightSource::Sun { seed, .. } = &mut source {
                    *seed = 0x05d1_0000 + self.parts.scene.lights.len() as u64;
                }
                for p in source.positions() {
                    if !within_limits(p) {
                        return Err((
                            prim.to_string(),
                            format!(
                                "the light lands at {p}: coordinates must be finite and within +/-{MAX_COORDINATE:e} m"
                            ),
                        ));
                    }
                }
                self.parts.scene.lights.push(source);
                self.parts.groups.push((here.group.clone(), prim.to_string()));
            }
            Some(lights::Made::Dome { radiance, texture, rotation }) => {
                if self.parts.environment.is_some() {
                    self.warn(format!("{prim}: a second dome light is not rendered (the first is the environment)"));
                    return Ok(());
                }
                let map = match texture {
                    None => EnvironmentMap::Constant(radiance),
                    Some(file) => match self.dome_map(prim, &file, radiance, &rotation) {
                        Ok(map) => map,
                        // A texture that cannot be read: the dome's own colour.
                        Err((at, problem)) => {
                            self.lacks(format!("{at}: {problem}: the dome's constant radiance is used"));
                            EnvironmentMap::Constant(radiance)
                        }
                    },
                };
                *self.parts.environment = Some((Environment { map, samples: DOME_SAMPLES }, here.group.clone()));
            }
        }
        Ok(())
    }

    /// A dome's lat-long texture as the renderer's environment map: USD's
    /// (OpenEXR's) lat-long, turned by the dome's rotation, resampled into
    /// the renderer's own convention (docs/scene-format.md) at the same
    /// size.
    fn dome_map(
        &mut self,
        prim: &str,
        file: &stage::Asset,
        radiance: Vec3,
        rotation: &DMat4,
    ) -> Result<EnvironmentMap, Located> {
        let at = format!("{prim}.inputs:texture:file");
        let (read, bytes) = self.stage.asset_bytes(file, MAX_DOME_BYTES).map_err(|e| (at.clone(), e))?;
        if !self.parts.scene.inputs.contains(&read) {
            self.parts.scene.inputs.push(read);
        }
        let image = if bytes.starts_with(&[0x76, 0x2f, 0x31, 0x01]) {
            super::image::decode_radiance_exr(&bytes)
        } else {
            super::image::decode_named(&bytes, &file.authored, super::image::Encoding::Srgb)
                .and_then(|image| super::image::check_radiance(&image).map(|()| image))
        }
        .map_err(|e| (at.clone(), format!("'{}': {e}", file.authored)))?;
        let (width, height) = (image.width, image.height);
        let inverse = rotation.inverse();
        // Each of the renderer's texels averages 4 x 4 nearest lookups of
        // the dome's, so that the map's integral survives the turn.
        const SUB: usize = 4;
        let texels = (0..width * height)
            .map(|p| {
                let (x, y) = (p % width, p / width);
                let mut sum = Vec3::ZERO;
                for k in 0..SUB * SUB {
                    let (sx, sy) = ((k % SUB) as f64 + 0.5, (k / SUB) as f64 + 0.5);
                    let u = (x as f64 + sx / SUB as f64) / width as f64;
                    let v = (y as f64 + sy / SUB as f64) / height as f64;
                    let local = inverse.transform_vector3(our_direction(u, v)).normalize_or_zero();
                    let (u, v) = openexr_latlong(local);
                    let tx = ((u * width as f64) as usize).min(width - 1);
                    let ty = ((v * height as f64) as usize).min(height - 1);
                    sum += image.texels.get(ty * width + tx);
                }
                sum / (SUB * SUB) as f32 * radiance
            })
            .collect();
        Ok(EnvironmentMap::LatLong { width, height, texels, scale: 1.0 })
    }

    fn point_instancer(&mut self, prim: &str, here: &Context) -> Result<(), Located> {
        let time = self.time();
        let at = |a: &str| format!("{prim}.{a}");
        let stage = self.stage;
        let prototypes = stage.targets(prim, "prototypes").map_err(|e| (at("prototypes"), e))?;
        let indices = stage.ints(prim, "protoIndices", time).map_err(|e| (at("protoIndices"), e))?.unwrap_or_default();
        let positions = stage.vec3s(prim, "positions", time).map_err(|e| (at("positions"), e))?.unwrap_or_default();
        let orientations = match stage.quats(prim, "orientations", time).map_err(|e| (at("orientations"), e))? {
            Some(o) => Some(o),
            None => stage.quats(prim, "orientationsf", time).map_err(|e| (at("orientationsf"), e))?,
        };
        let scales = stage.vec3s(prim, "scales", time).map_err(|e| (at("scales"), e))?;
        let invisible: std::collections::HashSet<i64> = stage
            .ints(prim, "invisibleIds", time)
            .map_err(|e| (at("invisibleIds"), e))?
            .unwrap_or_default()
            .into_iter()
            .collect();
        let ids = stage.ints(prim, "ids", time).map_err(|e| (at("ids"), e))?;
        let n = indices.len();
        if positions.len() != n {
            return Err((at("positions"), format!("has {} positions for {n} protoIndices", positions.len())));
        }
        if orientations.as_ref().is_some_and(|o| o.len() != n) {
            return Err((
                at("orientations"),
                format!("has {} entries for {n} protoIndices", orientations.map_or(0, |o| o.len())),
            ));
        }
        if scales.as_ref().is_some_and(|s| s.len() != n) {
            return Err((at("scales"), format!("has {} entries for {n} protoIndices", scales.map_or(0, |s| s.len()))));
        }
        if self.parts.scene.instances.len() + n > MAX_INSTANCES {
            return Err((at("protoIndices"), format!("{n} instances: the stage would have more than {MAX_INSTANCES}")));
        }
        if here.worlds.windows(2).any(|w| w[0] != w[1]) {
            self.still_moving += 1;
        }
        for k in 0..n {
            let id = ids.as_ref().and_then(|ids| ids.get(k).copied()).unwrap_or(k as i64);
            if invisible.contains(&id) {
                continue;
            }
            let index = indices[k];
            let Some(prototype) = usize::try_from(index).ok().and_then(|i| prototypes.get(i)) else {
                return Err((
                    at("protoIndices"),
                    format!("index {index} is outside the {} prototypes", prototypes.len()),
                ));
            };
            let rotation = orientations.as_ref().map_or(DQuat::IDENTITY, |o| o[k]);
            let rotation = if rotation.length() > 0.0 { rotation.normalize() } else { DQuat::IDENTITY };
            let scale = scales.as_ref().map_or(DVec3::ONE, |s| s[k]);
            let placement = DMat4::from_scale_rotation_translation(scale, rotation, positions[k]);
            let mut inside = here.clone();
            inside.depth += 1;
            let parent = prototype.rfind('/').map_or("", |i| &prototype[..i]);
            inside.instance =
                Some(Instance { root: parent.to_string(), key: parent.to_string(), name: format!("{prim}[{k}]") });
            inside.worlds = here.worlds.iter().map(|w| *w * placement).collect();
            self.walk_instance(&format!("{prim} {prototype}"), std::slice::from_ref(prototype), &inside)?;
        }
        Ok(())
    }

    /// Walks `prims` (an instance's, placed by `inside.worlds`) the first
    /// time a prototype `key` is met; after that, when the first walk made
    /// nothing but instanced meshes and nothing moves, places the same
    /// meshes by the new instance's matrix without walking again (a point
    /// instancer's 100,000 entries cost one walk).
    fn walk_instance(&mut self, key: &str, prims: &[String], inside: &Context) -> Result<(), Located> {
        let instance = inside.instance.as_ref().expect("an instance's walk");
        let root = affine(&inside.worlds[0], &instance.root)?;
        if let Some(Some(template)) = self.templates.get(key) {
            if self.parts.scene.instances.len() + template.len() > MAX_INSTANCES {
                return Err((instance.root.clone(), format!("the stage has more than {MAX_INSTANCES} instances")));
            }
            for placed in template {
                let name = format!("{}{}", instance.name, placed.suffix);
                let object = Object { mesh: placed.mesh, transform: Some(root * placed.relative), name, motion: None };
                let (lo, hi) = super::object::world_bounds(self.parts.scene.meshes, std::slice::from_ref(&object));
                if !(within_limits(lo) && within_limits(hi)) {
                    return Err((
                        instance.root.clone(),
                        format!("places a mesh at {lo} to {hi}: beyond +/-{MAX_COORDINATE:e} m"),
                    ));
                }
                self.triangles += self.parts.scene.meshes[placed.mesh].triangles.len();
                self.parts.scene.instances.push(object);
            }
            return Ok(());
        }
        let before = (self.parts.scene.instances.len(), self.parts.scene.meshes.len(), self.parts.scene.lights.len());
        let dome = self.parts.environment.is_some();
        for prim in prims {
            self.walk(prim, inside)?;
        }
        if self.templates.contains_key(key) {
            return Ok(());
        }
        let made = &self.parts.scene.instances[before.0..];
        let only_instances = self.times.len() == 1
            && self.parts.scene.lights.len() == before.2
            && self.parts.environment.is_some() == dome
            && made.iter().all(|o| o.transform.is_some() && o.motion.is_none())
            && (before.1..self.parts.scene.meshes.len()).all(|m| made.iter().any(|o| o.mesh == m));
        let template = only_instances.then(|| {
            let inverse = root.inverse();
            made.iter()
                .map(|o| Placed {
                    mesh: o.mesh,
                    suffix: o.name.strip_prefix(instance.name.as_str()).unwrap_or(&o.name).to_string(),
                    relative: inverse * o.transform.unwrap_or(Affine3A::IDENTITY),
                })
                .collect()
        });
        self.templates.insert(key.to_string(), template);
        Ok(())
    }

    /// The camera asked for (a prim path), else the first found under the
    /// default prim, else the first found.
    fn camera(&self, asked: Option<&str>, default_prim: Option<&str>) -> Result<Option<ImportedCamera>, Located> {
        let chosen = match asked {
            Some(path) => match self.cameras.iter().find(|(p, _)| p == path) {
                Some(c) => Some(c),
                None => {
                    let known: Vec<&str> = self.cameras.iter().map(|(p, _)| p.as_str()).collect();
                    return Err((
                        "--camera".to_string(),
                        format!(
                            "no camera '{path}' on the stage (its cameras: {})",
                            if known.is_empty() { "none".to_string() } else { known.join(", ") }
                        ),
                    ));
                }
            },
            None => {
                let under = default_prim.map(|d| format!("/{d}/"));
                self.cameras
                    .iter()
                    .find(|(p, _)| under.as_ref().is_some_and(|u| p.starts_with(u)))
                    .or_else(|| self.cameras.first())
            }
        };
        let Some((prim, worlds)) = chosen else { return Ok(None) };
        let time = self.time();
        let read = schema::Reader { stage: self.stage, prim, schema: "Camera", time };
        let projection = read.token("projection")?;
        if projection != "perspective" {
            return Err((format!("{prim}.projection"), format!("'{projection}' is not implemented (perspective is)")));
        }
        let focal = read.number("focalLength")?;
        let (horizontal, vertical) = (read.number("horizontalAperture")?, read.number("verticalAperture")?);
        if !(focal > 0.0 && horizontal > 0.0 && vertical > 0.0) {
            return Err((
                format!("{prim}.focalLength"),
                format!("focalLength {focal} and the apertures {horizontal} x {vertical} must be > 0"),
            ));
        }
        if read.number("horizontalApertureOffset")? != 0.0 || read.number("verticalApertureOffset")? != 0.0 {
            return Err((
                format!("{prim}.horizontalApertureOffset"),
                "aperture offsets (a shifted lens) are not implemented".into(),
            ));
        }
        let fov_y = 2.0 * (vertical / (2.0 * focal)).atan();
        let place = |m: &DMat4| {
            let eye = m.transform_point3(DVec3::ZERO);
            let forward = m.transform_vector3(DVec3::NEG_Z).normalize_or_zero();
            let up = m.transform_vector3(DVec3::Y).normalize_or_zero();
            (eye, forward, up)
        };
        let (eye, forward, up) = place(&worlds[0]);
        if forward == DVec3::ZERO || up == DVec3::ZERO {
            return Err((prim.clone(), "the camera's transform is degenerate (zero scale)".into()));
        }
        let scale = worlds[0].transform_vector3(DVec3::NEG_Z).length();
        // Lengths in the camera's space (tenths of a scene unit for the
        // lens) into metres.
        let f_stop = read.number("fStop")?;
        let focus = read.number("focusDistance")? * scale;
        let (lens_radius, focus_distance) = if f_stop > 0.0 && focus > 0.0 {
            (focal / 10.0 * scale / (2.0 * f_stop), Some(focus as f32))
        } else {
            (0.0, None)
        };
        let distance = focus_distance.map_or(1.0, f64::from);
        let mut spec = CameraSpec::pinhole(
            eye.as_vec3().to_array(),
            CameraSpec::aim(eye, forward, distance),
            up.as_vec3().to_array(),
            fov_y.to_degrees() as f32,
        );
        spec.lens_radius = lens_radius as f32;
        spec.focus_distance = focus_distance;
        if worlds.len() > 1 {
            let (eye_end, forward_end, _) = place(&worlds[worlds.len() - 1]);
            if eye_end != eye || forward_end != forward {
                spec.eye_end = Some(eye_end.as_vec3().to_array());
                spec.look_at_end = Some(CameraSpec::aim(eye_end, forward_end, distance));
            }
        }
        Ok(Some(ImportedCamera { spec, aspect_ratio: Some((horizontal / vertical) as f32) }))
    }

    /// Notes a prim of a type this renderer does not draw.
    fn skip(&mut self, prim: &str, type_name: &str) {
        let entry = self.skipped.entry(type_name.to_string()).or_insert_with(|| (0, prim.to_string()));
        entry.0 += 1;
    }

    /// One line each for what the stage asks for that is drawn otherwise.
    fn summarise(&mut self) {
        if let Some(first) = self.materials.undefined.first() {
            let prims = first_and_more(first, self.materials.undefined.len());
            self.lacks(format!(
                "{prims}: bound as materials but defined by no layer read (one is missing, or in a format \
                 this reader does not read): grey"
            ));
        }
        for (type_name, (count, first)) in std::mem::take(&mut self.skipped) {
            let because = not_drawn_because(&type_name);
            self.lacks(format!("{}: {type_name} not drawn ({because})", first_and_more(&first, count)));
        }
        for (note, (count, first)) in std::mem::take(&mut self.primvar_fallbacks) {
            self.lacks(format!("{}: {note}", first_and_more(&first, count)));
        }
        for (why, (count, first)) in std::mem::take(&mut self.cages) {
            let prims = first_and_more(&first, count);
            self.warn(format!("{prims}: subdivision surface drawn as its control polygons ({why})"));
        }
        if self.still_moving > 0 {
            let n = self.still_moving;
            self.warn(format!(
                "{n} moving prim(s) drawn as at the shutter's open (emissive or mirroring surfaces, lights, point instancers)"
            ));
        }
    }
}

/// An f64 matrix as a placement the scene keeps (f32), checked finite.
fn affine(world: &DMat4, prim: &str) -> Result<Affine3A, Located> {
    let m: Mat4 = world.as_mat4();
    if !m.is_finite() {
        return Err((prim.to_string(), "its world transform is not finite".into()));
    }
    Ok(Affine3A::from_mat4(m))
}

/// The direction the renderer's lat-long maps put at (u, v): u = 0.5 +
/// atan2(x, -z) / 2 pi around, v = acos(y) / pi down (scene::environment).
fn our_direction(u: f64, v: f64) -> DVec3 {
    let phi = (u - 0.5) * std::f64::consts::TAU;
    let theta = v * std::f64::consts::PI;
    // x = sin(theta) sin(phi), -z = sin(theta) cos(phi).
    DVec3::new(theta.sin() * phi.sin(), theta.cos(), -theta.sin() * phi.cos())
}

/// Where direction `d` falls in an OpenEXR lat-long map (USD's dome):
/// longitude atan2(x, z) from +pi at the left edge to -pi at the right,
/// latitude from +pi/2 at the top to -pi/2 at the bottom.
fn openexr_latlong(d: DVec3) -> (f64, f64) {
    let longitude = d.x.atan2(d.z);
    let latitude = d.y.clamp(-1.0, 1.0).asin();
    let u = (0.5 - longitude / std::f64::consts::TAU).rem_euclid(1.0);
    let v = 0.5 - latitude / std::f64::consts::PI;
    (u, v)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// OpenEXR's lat-long (USD's dome): longitude 0 is +z and pi/2 is +x,
    /// the top row +y; the renderer's own map is the same image turned by
    /// half its width.
    #[test]
    fn the_openexr_latlong_convention() {
        let close = |a: (f64, f64), b: (f64, f64)| (a.0 - b.0).abs() < 1e-9 && (a.1 - b.1).abs() < 1e-9;
        assert!(close(openexr_latlong(DVec3::Z), (0.5, 0.5)));
        assert!(close(openexr_latlong(DVec3::X), (0.25, 0.5)));
        assert!(close(openexr_latlong(DVec3::NEG_X), (0.75, 0.5)));
        assert!(openexr_latlong(DVec3::Y).1.abs() < 1e-9);
        // Pixel centres of a 1000 x 500 map.
        for (u, v) in [(0.1005, 0.301), (0.6005, 0.701), (0.9505, 0.501)] {
            let d = our_direction(u, v);
            let (x, y) = crate::scene::EnvironmentMap::pixel_of(1000, 500, d.as_vec3());
            assert_eq!((x, y), ((u * 1000.0) as usize, (v * 500.0) as usize), "{u} {v}");
            let (eu, ev) = openexr_latlong(d);
            assert!(((eu - u).rem_euclid(1.0) - 0.5).abs() < 1e-9 && (ev - v).abs() < 1e-9);
        }
    }
}
