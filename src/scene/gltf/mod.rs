//! glTF 2.0 import (`.gltf` with external or embedded buffers, and `.glb`):
//! the default scene's meshes, materials, KHR_lights_punctual lights,
//! emissive meshes (as area lights) and cameras, mapped onto the renderer's
//! model as docs/scene-format.md tabulates. Buffers, images and accessors are
//! read by `io` rather than by the `gltf` crate's importer so that every
//! error names the file and the JSON location (`meshes[2].primitives[0].indices`).

mod animation;
mod io;

use std::collections::HashMap;
use std::f32::consts::FRAC_PI_4;
use std::path::{Path, PathBuf};

use glam::{Affine2, Affine3A, Mat2, Mat3, Mat4, Vec2, Vec3, Vec4};
use gltf::json::extensions::scene::khr_lights_punctual::{Light as LightJson, Type as LightType};
use gltf::json::validation::Checked;
use gltf::mesh::Mode;
use gltf::texture::{MagFilter, WrappingMode};

use super::file::{CameraSpec, GltfSpec, DEFAULT_LUMENS_PER_WATT};
use super::groups::GltfLightNames;
use super::image::{Encoding, RgbImage};
use super::material::{Albedo, Cutout, Material, NormalMap, PbrMaterial, TextureRef};
use super::mesh::Mesh;
use super::object::{Motion, Object};
use super::texture::{Filter, Texture, Wrap};
use super::{within_limits, LightSource, SceneError, MAX_COORDINATE, MAX_EMITTER_SAMPLES};

/// Extensions whose absence from the renderer changes nothing it draws
/// (when merely used) and which it implements; anything else listed in
/// `extensionsRequired` is refused by name.
const IMPLEMENTED: [&str; 7] = [
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_materials_specular",
    "KHR_materials_unlit",
    "KHR_mesh_quantization",
    "KHR_texture_transform",
    "EXT_mesh_gpu_instancing",
];

/// Extensions the renderer knows but does not implement, with what a
/// render of a file that uses them does instead (named once on stderr).
const IGNORED: [(&str, &str); 15] = [
    ("KHR_materials_transmission", "surfaces are opaque"),
    ("KHR_materials_volume", "surfaces only, no volume absorption"),
    ("KHR_materials_ior", "the dielectric's IOR is 1.5 (reflectance 0.04)"),
    ("KHR_materials_clearcoat", "the base layer alone, no clear coat"),
    ("KHR_materials_sheen", "no sheen"),
    ("KHR_materials_iridescence", "no thin-film iridescence"),
    ("KHR_materials_anisotropy", "isotropic roughness"),
    ("KHR_materials_dispersion", "no dispersion"),
    ("KHR_materials_diffuse_transmission", "surfaces are opaque"),
    ("KHR_materials_variants", "the default material of each primitive"),
    ("KHR_materials_pbrSpecularGlossiness", "the material's pbrMetallicRoughness (or its defaults)"),
    ("KHR_texture_basisu", "each texture's PNG or JPEG source"),
    ("EXT_texture_webp", "each texture's PNG or JPEG source"),
    ("KHR_draco_mesh_compression", "each primitive's uncompressed attributes"),
    ("EXT_meshopt_compression", "each buffer view's uncompressed fallback"),
];

/// Deepest node hierarchy followed.
const MAX_DEPTH: usize = 1024;

/// Most joints a skin may have.
const MAX_JOINTS: usize = 1 << 16;

/// Most triangles an import may store (2^28): each copy counted, an
/// instanced mesh once.
const MAX_TRIANGLES: usize = 1 << 28;

/// Most instances an import may make (2^24; about 100 bytes each, with
/// Embree's).
const MAX_INSTANCES: usize = 1 << 24;

/// Where the imported parts go: the scene's own lists, which the TOML's
/// parts may already fill (indices are into these lists).
pub struct Parts<'a> {
    pub meshes: &'a mut Vec<Mesh>,
    /// The objects that place the meshes it keeps in their own space
    /// (every other mesh it adds is in world space, drawn as itself).
    pub instances: &'a mut Vec<Object>,
    pub materials: &'a mut Vec<Material>,
    pub textures: &'a mut Vec<Texture>,
    pub lights: &'a mut Vec<LightSource>,
    /// The names each of the lights this import adds is known by (for the
    /// `[[gltf.groups]]` rules), one per light, in order.
    pub light_names: &'a mut Vec<GltfLightNames>,
    pub inputs: &'a mut Vec<PathBuf>,
    pub warnings: &'a mut Vec<String>,
}

/// A perspective camera found in the file.
#[derive(Debug, Clone)]
pub struct GltfCamera {
    pub spec: CameraSpec,
    /// Width over height, when the file gives one.
    pub aspect_ratio: Option<f32>,
}

/// Times of the shutter a moving node's transform is sampled at, evenly
/// spaced from its open to its close; Embree and shading interpolate
/// linearly between them (docs/design.md §13.6).
const SHUTTER_STEPS: usize = 33;

/// Imports `spec.file` (relative to `base`) into `parts`; returns the chosen
/// camera when `want_camera` (the TOML gives none). With a `shutter` (open
/// before close, seconds), the file's animation (`spec.animation`, else
/// its first) is sampled over it: what it moves, moves.
pub fn import(
    scene_file: &Path,
    base: &Path,
    spec: &GltfSpec,
    want_camera: bool,
    shutter: Option<[f32; 2]>,
    parts: Parts<'_>,
) -> Result<Option<GltfCamera>, SceneError> {
    let path = base.join(&spec.file);
    parts.inputs.push(path.clone());
    let check = |ok: bool, field: &str, message: String| {
        if ok {
            Ok(())
        } else {
            Err(SceneError::new(scene_file, format!("gltf.{field}"), message))
        }
    };
    check(
        spec.lumens_per_watt.is_finite() && spec.lumens_per_watt > 0.0,
        "lumens_per_watt",
        format!("must be finite and > 0, got {}", spec.lumens_per_watt),
    )?;
    check(
        (1..=MAX_EMITTER_SAMPLES).contains(&spec.emitter_samples),
        "emitter_samples",
        format!("must be between 1 and {MAX_EMITTER_SAMPLES}, got {}", spec.emitter_samples),
    )?;
    let bytes = std::fs::read(&path)
        .map_err(|e| SceneError::new(scene_file, "gltf.file", format!("cannot read '{}': {e}", path.display())))?;
    let gltf = io::parse(&path, &bytes)?;
    let data = io::Data::load(&path, &gltf.document, gltf.blob.as_deref())?;
    let animation = match shutter {
        Some(_) => animation::Animation::read(&path, &gltf.document, &data, spec.animation.as_deref())?,
        None => None,
    };
    let mut importer = Importer {
        file: &path,
        doc: &gltf.document,
        data,
        materials: HashMap::new(),
        spec,
        parts,
        skipped_primitives: 0,
        emitters: 0,
        triangles: 0,
        placements: Vec::new(),
        prototypes: HashMap::new(),
        punctual: 0,
        shutter: shutter.zip(animation),
        still_moving: 0,
    };
    let camera = importer.import_scene(want_camera)?;
    // The buffer and image files, after the glTF file, in the order read.
    importer.parts.inputs.append(&mut importer.data.inputs);
    Ok(camera)
}

/// Where a mesh node puts its mesh: its world transform (at the shutter's
/// open), whether other nodes place the mesh too, and its world transform
/// at each step of the shutter when it moves.
#[derive(Clone, Copy)]
struct MeshPlacement<'a> {
    world: Mat4,
    shared: bool,
    motion: Option<&'a [Mat4]>,
}

struct Importer<'a, 'p> {
    file: &'a Path,
    doc: &'a gltf::Document,
    data: io::Data<'a>,
    /// The scene's material index of each glTF material (None: the default).
    materials: HashMap<Option<usize>, usize>,
    spec: &'a GltfSpec,
    parts: Parts<'p>,
    skipped_primitives: usize,
    emitters: u64,
    /// Triangles imported so far (every copy counted, an instanced mesh once).
    triangles: usize,
    /// How many rigid, orientation-preserving placements each glTF mesh
    /// has (EXT_mesh_gpu_instancing's nodes count as many): a mesh placed
    /// twice or more is imported once and instanced.
    placements: Vec<usize>,
    /// The scene mesh of each instanced glTF primitive (mesh, primitive),
    /// in the mesh's own space; None for one imported as copies (emissive,
    /// or not triangles).
    prototypes: HashMap<(usize, usize), Option<usize>>,
    /// KHR_lights_punctual lights imported.
    punctual: usize,
    /// The shutter and the animation played over it.
    shutter: Option<([f32; 2], animation::Animation)>,
    /// Moving primitives drawn still (emissive, mirrored or skinned).
    still_moving: usize,
}

impl Importer<'_, '_> {
    fn error(&self, location: impl Into<String>, message: impl Into<String>) -> SceneError {
        SceneError::new(self.file, location, message)
    }

    fn warn(&mut self, location: &str, message: &str) {
        self.parts.warnings.push(format!("{}: {location}: {message}", self.file.display()));
    }

    /// The scene's nodes depth-first with their world transforms and JSON
    /// locations, each node once (a cycle or a node with two parents is an
    /// error), with an explicit stack (a hostile file cannot overflow ours).
    #[allow(clippy::type_complexity)]
    fn visit<'d>(&self, scene: &gltf::Scene<'d>) -> Result<Vec<(gltf::Node<'d>, Mat4, String)>, SceneError> {
        let mut visited = vec![false; self.doc.nodes().len()];
        let mut visits = Vec::new();
        let mut stack: Vec<(gltf::Node<'_>, Mat4, usize)> =
            scene.nodes().map(|n| (n, Mat4::IDENTITY, 0)).collect::<Vec<_>>().into_iter().rev().collect();
        while let Some((node, parent, depth)) = stack.pop() {
            let location = format!("nodes[{}]", node.index());
            if std::mem::replace(&mut visited[node.index()], true) {
                return Err(self
                    .error(&location, "is reached twice in the node hierarchy (a cycle, or a child of two parents)"));
            }
            if depth > MAX_DEPTH {
                return Err(self.error(&location, format!("the node hierarchy is deeper than {MAX_DEPTH}")));
            }
            let local = Mat4::from_cols_array_2d(&node.transform().matrix());
            let field = match node.transform() {
                gltf::scene::Transform::Matrix { .. } => ".matrix",
                gltf::scene::Transform::Decomposed { .. } => " (translation, rotation, scale)",
            };
            if !local.is_finite() {
                return Err(self.error(format!("{location}{field}"), "the transform is not finite"));
            }
            let world = parent * local;
            if !world.is_finite() || !within_limits(world.w_axis.truncate()) {
                return Err(self.error(
                    &location,
                    format!("the world transform places it outside +/-{MAX_COORDINATE:e} m or is not finite"),
                ));
            }
            for child in node.children().collect::<Vec<_>>().into_iter().rev() {
                stack.push((child, world, depth + 1));
            }
            visits.push((node, world, location));
        }
        Ok(visits)
    }

    fn import_scene(&mut self, want_camera: bool) -> Result<Option<GltfCamera>, SceneError> {
        let Some(scene) = self.doc.default_scene().or_else(|| self.doc.scenes().next()) else {
            return Err(self.error("scenes", "the file has no scene to render"));
        };
        self.name_ignored_extensions();
        let mut visits = self.visit(&scene)?;
        // Over an open shutter: each moving node's world transform at every
        // step, and everything posed as at the shutter's open.
        let moving = self.shutter_worlds(&visits)?;
        for (node, world, _) in &mut visits {
            if let Some(steps) = &moving[node.index()] {
                *world = steps[0];
            }
        }
        // Every node's world transform first: a skin's joints may come
        // after the mesh they pose.
        let mut worlds = vec![None; self.doc.nodes().len()];
        for (node, world, _) in &visits {
            worlds[node.index()] = Some(*world);
        }
        let mut cameras = Vec::new();
        let mut skinned = 0;
        self.placements = self.count_placements(&visits);
        for (node, world, location) in visits {
            let node_name = node.name().map_or_else(|| location.clone(), str::to_string);
            let steps = moving[node.index()].as_deref();
            if let Some(mesh) = node.mesh() {
                skinned += usize::from(node.skin().is_some());
                self.import_node_mesh(&node, &mesh, world, (&location, &node_name), steps, &worlds)?;
            }
            if let Some(camera) = node.camera() {
                cameras.push((camera, world, location.clone(), steps.and_then(|s| s.last().copied())));
            }
            if let Some(light) = node.light() {
                self.import_node_light(light.index(), &world, &node_name, steps)?;
            }
        }
        if self.still_moving > 0 {
            let n = self.still_moving;
            self.warn(
                "animations",
                &format!(
                    "{n} moving primitive(s) or light(s) drawn still as at the shutter's open: skinned, emissive, \
                     mirrored or morphed meshes, and lights other than point lights, do not blur"
                ),
            );
        }
        if let Some((_, animation)) = &self.shutter {
            if animation.weight_channels > 0 {
                let n = animation.weight_channels;
                self.warn("animations", &format!("{n} morph-target weight channel(s) not played"));
            }
        }
        self.state_light_units();
        if skinned > 0 {
            self.warn(
                "skins",
                &format!(
                    "{skinned} skinned mesh node(s) posed by their joints' node transforms (no animation is played)"
                ),
            );
        }
        if self.skipped_primitives > 0 {
            let n = self.skipped_primitives;
            self.warn("meshes", &format!("{n} point or line primitive(s) skipped: only triangles are rendered"));
        }
        if !want_camera {
            return Ok(None);
        }
        self.chosen_camera(&cameras)
    }

    /// The camera `[gltf] camera` (or `--camera`) names among `cameras`
    /// (each with its node's world transform at the open, its location
    /// and, when it moves, its world transform at the close), else the
    /// first; None when the file has none.
    #[allow(clippy::type_complexity)]
    fn chosen_camera(
        &self,
        cameras: &[(gltf::Camera<'_>, Mat4, String, Option<Mat4>)],
    ) -> Result<Option<GltfCamera>, SceneError> {
        let chosen = match &self.spec.camera {
            None => cameras.first(),
            Some(name) => {
                // `#N`: the N-th camera in node order (unnamed ones too).
                let found = match name.strip_prefix('#').and_then(|n| n.parse::<usize>().ok()) {
                    Some(i) => cameras.get(i),
                    None => cameras.iter().find(|(c, ..)| c.name() == Some(name.as_str())),
                };
                if found.is_none() {
                    let names: Vec<String> = cameras
                        .iter()
                        .enumerate()
                        .map(|(i, (c, ..))| c.name().map_or_else(|| format!("#{i}"), |n| format!("{n} (#{i})")))
                        .collect();
                    let names: Vec<&str> = names.iter().map(String::as_str).collect();
                    return Err(self.error(
                        "cameras",
                        format!("no camera named '{name}' in the scene (it has: {})", list_or_none(&names)),
                    ));
                }
                found
            }
        };
        let Some((camera, world, location, end)) = chosen else { return Ok(None) };
        let gltf::camera::Projection::Perspective(p) = camera.projection() else {
            return Err(self.error(
                format!("cameras[{}]", camera.index()),
                "orthographic cameras are not supported yet: pick a perspective one (--camera) or give [camera] in a TOML",
            ));
        };
        let eye = world.w_axis.truncate();
        let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
        let up = world.transform_vector3(Vec3::Y).normalize_or_zero();
        let fov_y = p.yfov().to_degrees();
        if forward == Vec3::ZERO || up == Vec3::ZERO || forward.cross(up).length() < 1e-6 {
            return Err(self.error(location, "the camera's transform is degenerate (zero or sheared scale)"));
        }
        if !(fov_y.is_finite() && fov_y > 0.0 && fov_y < 180.0) {
            return Err(self.error(
                format!("cameras[{}].perspective.yfov", camera.index()),
                format!("must be between 0 and pi, got {}", p.yfov()),
            ));
        }
        let aspect_ratio = p.aspect_ratio().filter(|a| a.is_finite() && *a > 0.0);
        let mut spec = CameraSpec::pinhole(eye.to_array(), (eye + forward).to_array(), up.to_array(), fov_y);
        // A moving camera travels in a straight line to where it is at the
        // close, looking along its direction there.
        if let Some(end) = end {
            let (eye_end, forward_end) =
                (end.w_axis.truncate(), end.transform_vector3(Vec3::NEG_Z).normalize_or_zero());
            spec.eye_end = Some(eye_end.to_array());
            spec.look_at_end = Some((eye_end + forward_end).to_array());
        }
        Ok(Some(GltfCamera { spec, aspect_ratio }))
    }

    /// A mesh node's mesh: posed by its skin, or placed (and moving, with
    /// `steps`, its world transforms over the shutter) once or once per
    /// EXT_mesh_gpu_instancing instance. `at` is the node's location and name.
    fn import_node_mesh(
        &mut self,
        node: &gltf::Node<'_>,
        mesh: &gltf::Mesh<'_>,
        world: Mat4,
        (location, node_name): (&str, &str),
        steps: Option<&[Mat4]>,
        worlds: &[Option<Mat4>],
    ) -> Result<(), SceneError> {
        let weights = node.weights().or_else(|| mesh.weights()).unwrap_or(&[]);
        let shared = node.skin().is_none() && node.weights().is_none() && self.placements[mesh.index()] > 1;
        // A node with morph weights of its own keeps its own copy.
        let motion = steps.filter(|_| node.weights().is_none());
        if let Some(skin) = node.skin() {
            self.still_moving += usize::from(steps.is_some());
            let joints = self.joint_matrices(&skin, worlds)?;
            self.import_mesh(mesh, &Placement::Skinned(joints), weights, node_name)
        } else if let Some(value) = node.extension_value("EXT_mesh_gpu_instancing") {
            for (i, instance) in self.instances(value, location)?.into_iter().enumerate() {
                let name = format!("{node_name}[{i}]");
                let motion: Option<Vec<Mat4>> = motion.map(|s| s.iter().map(|w| *w * instance).collect());
                let placed = MeshPlacement { world: world * instance, shared, motion: motion.as_deref() };
                self.place_mesh(mesh, placed, weights, &name, location)?;
            }
            Ok(())
        } else {
            self.still_moving += usize::from(steps.is_some() && motion.is_none());
            self.place_mesh(mesh, MeshPlacement { world, shared, motion }, weights, node_name, location)
        }
    }

    /// A node's punctual light; a point light the animation moves (`steps`)
    /// moves in a straight line from where it is at the open to the close.
    fn import_node_light(
        &mut self,
        index: usize,
        world: &Mat4,
        node_name: &str,
        steps: Option<&[Mat4]>,
    ) -> Result<(), SceneError> {
        let before = self.parts.lights.len();
        self.import_light(index, world, node_name)?;
        let Some(steps) = steps else { return Ok(()) };
        // The light this node added, if it added one.
        let added = self.parts.lights.get_mut(before..).and_then(<[LightSource]>::first_mut);
        if let Some(light) = added {
            if let LightSource::Point { position, intensity } = *light {
                let end = steps[steps.len() - 1].w_axis.truncate();
                *light = LightSource::MovingPoint { start: position, end, intensity };
            } else {
                self.still_moving += 1;
            }
        }
        Ok(())
    }

    /// One line on stderr: how many punctual lights were converted, at
    /// which efficacy, and the viewers' convention's flag.
    fn state_light_units(&mut self) {
        if self.punctual > 0 {
            let lpw = self.spec.lumens_per_watt;
            let convention = if lpw == DEFAULT_LUMENS_PER_WATT {
                format!(
                    "{lpw} lm/W, Blender's convention; a file made for glTF viewers (1 cd taken as 1 W/sr) needs \
                 --lumens-per-watt 1 or [gltf] lumens_per_watt = 1, {:.1} stops brighter",
                    lpw.log2()
                )
            } else {
                format!("{lpw} lm/W as asked ({DEFAULT_LUMENS_PER_WATT}, Blender's convention, is the default)")
            };
            let n = self.punctual;
            self.warn(
                "extensions.KHR_lights_punctual",
                &format!("{n} light(s) in candela and lux converted to W/sr and W/m^2 at {convention}"),
            );
        }
    }

    /// How many rigid, orientation-preserving placements each glTF mesh
    /// has among the visited nodes (a node with EXT_mesh_gpu_instancing
    /// counts as two: its mesh is instanced whatever its count).
    fn count_placements(&self, visits: &[(gltf::Node<'_>, Mat4, String)]) -> Vec<usize> {
        let mut placements = vec![0; self.doc.meshes().len()];
        for (node, world, _) in visits {
            match node.mesh() {
                // Morph weights of the node's own are a pose of its own.
                Some(mesh) if node.skin().is_none() && node.weights().is_none() => {
                    let gpu = node.extension_value("EXT_mesh_gpu_instancing").is_some();
                    if gpu || world.determinant() > 0.0 {
                        placements[mesh.index()] += if gpu { 2 } else { 1 };
                    }
                }
                _ => {}
            }
        }
        placements
    }

    /// A mesh placed rigidly by `world`: as instances of the mesh kept once
    /// in its own space when it is `shared` (placed twice or more) and the
    /// placement keeps orientation; else (and for its emissive primitives,
    /// whose area lights are in world space) as copies.
    fn place_mesh(
        &mut self,
        mesh: &gltf::Mesh<'_>,
        placed: MeshPlacement<'_>,
        weights: &[f32],
        node_name: &str,
        location: &str,
    ) -> Result<(), SceneError> {
        let MeshPlacement { world, shared, motion } = placed;
        // A motion that scales to nothing or mirrors on the way cannot be
        // one instance's: drawn still.
        let motion = match motion {
            Some(steps) if !steps.iter().all(|w| w.determinant() > 0.0) => {
                self.still_moving += 1;
                None
            }
            m => m,
        };
        if !((shared || motion.is_some()) && world.determinant() > 0.0) {
            self.still_moving += usize::from(motion.is_some());
            return self.import_mesh(mesh, &Placement::Rigid(world), weights, node_name);
        }
        for primitive in mesh.primitives() {
            let key = (mesh.index(), primitive.index());
            let prototype = match self.prototypes.get(&key) {
                Some(&p) => p,
                None => {
                    let material = self.material(primitive.material())?;
                    let p = if self.parts.materials[material].emission == Vec3::ZERO {
                        let name = mesh.name().map_or_else(|| format!("meshes[{}]", mesh.index()), str::to_string);
                        self.import_primitive(
                            &primitive,
                            mesh.index(),
                            &Placement::Rigid(Mat4::IDENTITY),
                            weights,
                            &name,
                        )?
                    } else {
                        None
                    };
                    self.prototypes.insert(key, p);
                    p
                }
            };
            let Some(prototype) = prototype else {
                self.still_moving += usize::from(motion.is_some());
                self.import_primitive(&primitive, mesh.index(), &Placement::Rigid(world), weights, node_name)?;
                continue;
            };
            let transform = Affine3A::from_mat4(world);
            // Each step's placement relative to the open's.
            let motion = motion.map(|steps| Motion {
                steps: steps.iter().map(|w| Affine3A::from_mat4(*w) * transform.inverse()).collect(),
            });
            let object = Object { mesh: prototype, transform: Some(transform), name: node_name.to_string(), motion };
            let (lo, hi) = crate::scene::object::world_bounds(self.parts.meshes, std::slice::from_ref(&object));
            if !(within_limits(lo) && within_limits(hi)) {
                return Err(self.error(
                    location,
                    format!("places meshes[{}] at {lo} to {hi} in the world: coordinates must be finite and within +/-{MAX_COORDINATE:e} m", mesh.index()),
                ));
            }
            if self.parts.instances.len() >= MAX_INSTANCES {
                return Err(self.error(location, format!("the scene has more than {MAX_INSTANCES} instances")));
            }
            self.parts.instances.push(object);
        }
        Ok(())
    }

    /// Each visited node's world transform at the shutter's steps, by node
    /// index, for the nodes the animation moves (it drives them or one of
    /// their ancestors); None for the others, and for every node without
    /// a shutter.
    fn shutter_worlds(&self, visits: &[(gltf::Node<'_>, Mat4, String)]) -> Result<Vec<Option<Vec<Mat4>>>, SceneError> {
        let mut moving: Vec<Option<Vec<Mat4>>> = vec![None; self.doc.nodes().len()];
        let Some(([open, close], animation)) = &self.shutter else { return Ok(moving) };
        let mut parent = vec![None; self.doc.nodes().len()];
        for node in self.doc.nodes() {
            for child in node.children() {
                parent[child.index()] = Some(node.index());
            }
        }
        let mut rest = vec![Mat4::IDENTITY; self.doc.nodes().len()];
        for (node, world, _) in visits {
            rest[node.index()] = *world;
        }
        let times: Vec<f32> =
            (0..SHUTTER_STEPS).map(|k| open + (close - open) * k as f32 / (SHUTTER_STEPS - 1) as f32).collect();
        // Parents come before their children in `visits`.
        for (node, _, location) in visits {
            let driven = animation.drives(node.index());
            if !driven && parent[node.index()].is_none_or(|p| moving[p].is_none()) {
                continue;
            }
            let still = Mat4::from_cols_array_2d(&node.transform().matrix());
            let steps: Vec<Mat4> = times
                .iter()
                .enumerate()
                .map(|(k, &t)| {
                    let local = if driven { animation.local(node, t) } else { still };
                    let parent_world = match parent[node.index()] {
                        Some(p) => moving[p].as_ref().map_or(rest[p], |steps| steps[k]),
                        None => Mat4::IDENTITY,
                    };
                    parent_world * local
                })
                .collect();
            if !steps.iter().all(|w| w.is_finite() && within_limits(w.w_axis.truncate())) {
                return Err(self.error(
                    location,
                    format!(
                        "the animation places it outside +/-{MAX_COORDINATE:e} m or makes its transform not finite"
                    ),
                ));
            }
            moving[node.index()] = Some(steps);
        }
        Ok(moving)
    }

    fn import_mesh(
        &mut self,
        mesh: &gltf::Mesh<'_>,
        placement: &Placement,
        weights: &[f32],
        node_name: &str,
    ) -> Result<(), SceneError> {
        for primitive in mesh.primitives() {
            self.import_primitive(&primitive, mesh.index(), placement, weights, node_name)?;
        }
        Ok(())
    }

    /// One primitive as a mesh placed by `placement` (world space; its own
    /// space for the identity) and named `node_name`, an area light when
    /// it emits. Returns the mesh's index, None for a primitive that is
    /// not triangles (skipped).
    fn import_primitive(
        &mut self,
        primitive: &gltf::Primitive<'_>,
        mesh_index: usize,
        placement: &Placement,
        weights: &[f32],
        node_name: &str,
    ) -> Result<Option<usize>, SceneError> {
        let location = format!("meshes[{mesh_index}].primitives[{}]", primitive.index());
        let mode = primitive.mode();
        if matches!(mode, Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip) {
            self.skipped_primitives += 1;
            return Ok(None);
        }
        let (mut positions, mut triangles) = self.read_triangles(primitive, &location)?;
        let count = positions.len();
        let mut normals = self.attribute::<3>(primitive, &location, gltf::Semantic::Normals, "normals", count)?;
        self.morph(primitive, &location, weights, &mut positions, normals.as_mut())?;
        let transforms = self.vertex_transforms(primitive, &location, placement, count)?;
        if transforms.mirrored() {
            // A mirroring transform turns the winding around; keep the
            // front (emitting) side where the file's author saw it.
            for t in &mut triangles {
                t.swap(1, 2);
            }
        }
        let world_positions: Vec<Vec3> =
            positions.iter().enumerate().map(|(i, p)| transforms.point(i, Vec3::from_array(*p))).collect();
        if let Some(bad) = world_positions.iter().position(|p| !within_limits(*p)) {
            return Err(self.error(
                format!("{location}.attributes.POSITION"),
                format!(
                    "vertex {bad} is at {} in the world: coordinates must be finite and within +/-{MAX_COORDINATE:e} m",
                    world_positions[bad]
                ),
            ));
        }
        let normals = match normals {
            None => None,
            Some(normals) => {
                let normals: Vec<Vec3> = normals
                    .iter()
                    .enumerate()
                    .map(|(i, n)| transforms.normal(i, Vec3::from_array(*n)).normalize_or_zero())
                    .collect();
                if normals.iter().any(|n| *n == Vec3::ZERO || !n.is_finite()) {
                    self.warn(&format!("{location}.attributes.NORMAL"), "has zero or non-finite normals: shaded flat");
                    None
                } else {
                    Some(normals)
                }
            }
        };
        let uvs = self.texture_coordinates(primitive, &location, count, 0)?;
        let uvs1 = self.texture_coordinates(primitive, &location, count, 1)?;
        let colors = self.vertex_colors(primitive, &location, count)?;
        let material = self.material(primitive.material())?;
        let normal_set = self.parts.materials[material].pbr.as_ref().and_then(|p| p.normal_map.as_ref()).map(|m| m.set);
        let tangents = if let Some(set) = normal_set {
            // MikkTSpace works in the normal map's own texture coordinates.
            let uvs = if set == 1 { uvs1.as_deref() } else { uvs.as_deref() };
            let frame = Frame { transforms: &transforms, weights, normals: normals.as_deref(), uvs };
            self.tangents(primitive, &location, count, &frame, &world_positions, &triangles)?
        } else {
            None
        };
        let emission = self.parts.materials[material].emission;
        let both_sides = self.parts.materials[material].emits_both_sides;
        let mut mesh = Mesh {
            positions: world_positions,
            normals,
            uvs,
            uvs1,
            colors,
            tangents: None,
            triangles,
            material,
            name: node_name.to_string(),
        };
        match tangents {
            None => {}
            Some(Tangents::PerVertex(tangents)) => mesh.tangents = Some(tangents),
            Some(Tangents::PerCorner(corners)) => mesh.set_corner_tangents(&corners),
        }
        let has_area = mesh.triangles.iter().any(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            (b - a).cross(c - a).length() > 0.0
        });
        self.parts.meshes.push(mesh);
        if emission != Vec3::ZERO && has_area {
            self.emitters += 1;
            self.parts.lights.push(LightSource::Area {
                mesh: self.parts.meshes.len() - 1,
                radiance: emission,
                samples: self.spec.emitter_samples,
                seed: 0x617f_0000 + self.emitters,
                both_sides,
            });
            self.parts.light_names.push(GltfLightNames {
                light: None,
                node: Some(node_name.to_string()),
                material: Some(self.parts.materials[material].name.clone()),
            });
        }
        Ok(Some(self.parts.meshes.len() - 1))
    }

    /// A primitive's POSITIONs (in its mesh's space) and its triangles,
    /// every index checked, the import's triangle count kept under
    /// `MAX_TRIANGLES`.
    #[allow(clippy::type_complexity)]
    fn read_triangles(
        &mut self,
        primitive: &gltf::Primitive<'_>,
        location: &str,
    ) -> Result<(Vec<[f32; 3]>, Vec<[u32; 3]>), SceneError> {
        let Some(positions) = primitive.get(&gltf::Semantic::Positions) else {
            return Err(self.error(format!("{location}.attributes"), "has no POSITION"));
        };
        let positions = self.data.read_floats::<3>(&positions, &format!("{location}.attributes.POSITION"))?;
        let count = positions.len();
        let indices = match primitive.indices() {
            Some(a) => {
                let at = format!("{location}.indices");
                let indices = self.data.read_indices(&a, &at)?;
                if let Some(k) = indices.iter().position(|&i| i as usize >= count) {
                    return Err(self.error(at, format!("index {k} is {}, past the {count} vertices", indices[k])));
                }
                indices
            }
            None => (0..count as u32).collect(),
        };
        let triangles = triangulate(primitive.mode(), &indices);
        self.triangles = self.triangles.saturating_add(triangles.len());
        if self.triangles > MAX_TRIANGLES {
            return Err(self.error(
                location,
                format!(
                    "the scene expands to more than {MAX_TRIANGLES} triangles (copies counted, an instanced mesh once)"
                ),
            ));
        }
        Ok((positions, triangles))
    }

    /// KHR_lights_punctual light `index` placed by `world`: photometric
    /// values over `lumens_per_watt` (candela to W/sr, lux to W/m^2).
    fn import_light(&mut self, index: usize, world: &Mat4, node_name: &str) -> Result<(), SceneError> {
        let location = format!("extensions.KHR_lights_punctual.lights[{index}]");
        let light: &LightJson = self
            .doc
            .as_json()
            .extensions
            .as_ref()
            .and_then(|e| e.khr_lights_punctual.as_ref())
            .and_then(|l| l.lights.get(index))
            .ok_or_else(|| self.error(&location, "a node refers to a light the file does not define"))?;
        let colour = Vec3::from_array(light.color);
        if !colour.is_finite() || colour.min_element() < 0.0 {
            return Err(self.error(format!("{location}.color"), format!("must be finite and >= 0, got {colour}")));
        }
        let value = light.intensity;
        if !value.is_finite() || !(0.0..=1e30).contains(&value) {
            return Err(self.error(format!("{location}.intensity"), format!("must be finite and >= 0, got {value}")));
        }
        let radiometric = colour * (value / self.spec.lumens_per_watt);
        let position = world.w_axis.truncate();
        // Lights shine along their node's -Z.
        let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
        if light.range.is_some() {
            // Physical lights have no range; Cycles ignores it too.
            self.warn(&format!("{location}.range"), "ignored: the light falls off as 1/d^2 to any distance");
        }
        let kind = match &light.type_ {
            Checked::Valid(kind) => kind,
            Checked::Invalid => {
                return Err(self.error(format!("{location}.type"), "must be point, spot or directional"))
            }
        };
        let needs_direction = !matches!(kind, LightType::Point);
        if needs_direction && forward == Vec3::ZERO {
            return Err(self.error(&location, "the light's node has a degenerate (zero-scale) transform"));
        }
        let source = match kind {
            LightType::Point => LightSource::Point { position, intensity: radiometric },
            LightType::Spot => {
                let (inner, outer) =
                    light.spot.as_ref().map_or((0.0, FRAC_PI_4), |s| (s.inner_cone_angle, s.outer_cone_angle));
                if !(outer.is_finite() && outer > 0.0 && outer <= std::f32::consts::FRAC_PI_2) {
                    return Err(self.error(
                        format!("{location}.spot.outerConeAngle"),
                        format!("must be in (0, pi/2], got {outer}"),
                    ));
                }
                if !(inner.is_finite() && inner >= 0.0 && inner < outer) {
                    return Err(self.error(
                        format!("{location}.spot.innerConeAngle"),
                        format!("must be in [0, outerConeAngle), got {inner}"),
                    ));
                }
                LightSource::Spot {
                    position,
                    direction: forward,
                    intensity: radiometric,
                    inner_angle_degrees: inner.to_degrees(),
                    outer_angle_degrees: outer.to_degrees().min(90.0),
                }
            }
            LightType::Directional => LightSource::Sun {
                direction: -forward,
                irradiance: radiometric,
                angular_radius_degrees: 0.0,
                samples: 1,
                seed: 0x6c7f_0000 + index as u64,
            },
        };
        self.parts.lights.push(source);
        self.punctual += 1;
        self.parts.light_names.push(GltfLightNames {
            light: light.name.clone(),
            node: Some(node_name.to_string()),
            material: None,
        });
        Ok(())
    }

    /// The scene's material for a glTF material, made once.
    fn material(&mut self, m: gltf::Material<'_>) -> Result<usize, SceneError> {
        if let Some(&index) = self.materials.get(&m.index()) {
            return Ok(index);
        }
        let location = m.index().map_or("materials (default)".to_string(), |i| format!("materials[{i}]"));
        let pbr = m.pbr_metallic_roughness();
        let base = Vec4::from_array(pbr.base_color_factor());
        let metallic = pbr.metallic_factor();
        let roughness = pbr.roughness_factor();
        for (name, value) in
            [("baseColorFactor", base.min_element()), ("metallicFactor", metallic), ("roughnessFactor", roughness)]
        {
            let max = if name == "baseColorFactor" { base.max_element() } else { value };
            if !(value.is_finite() && max.is_finite() && value >= 0.0 && max <= 1.0) {
                return Err(self.error(format!("{location}.pbrMetallicRoughness.{name}"), "must be between 0 and 1"));
            }
        }
        let base_rgb = base.truncate();
        let (specular, specular_colour, specular_texture, specular_colour_texture) = self.specular(&m, &location)?;
        let mut coverage = None;
        let albedo = match pbr.base_color_texture() {
            None => Albedo::Constant(base_rgb),
            Some(info) => {
                let at = format!("{location}.pbrMetallicRoughness.baseColorTexture");
                let (texture, image) = self.texture(Slot::of(&info), &at, Encoding::Srgb, |t, _| t * base_rgb)?;
                coverage = image.alpha.as_ref().map(|a| {
                    (a.iter().map(|x| x * base.w).collect::<Vec<f32>>(), image.width, image.height, texture.transform)
                });
                Albedo::Texture(texture)
            }
        };
        let metallic_roughness = match pbr.metallic_roughness_texture() {
            None => None,
            Some(info) => {
                let at = format!("{location}.pbrMetallicRoughness.metallicRoughnessTexture");
                Some(self.texture(Slot::of(&info), &at, Encoding::Linear, |t, _| t)?.0)
            }
        };
        let normal_map = match m.normal_texture() {
            None => None,
            Some(info) => {
                let at = format!("{location}.normalTexture");
                if !info.scale().is_finite() {
                    return Err(self.error(format!("{at}.scale"), "must be finite"));
                }
                let slot =
                    Slot::of_normal(&info).map_err(|e| self.error(format!("{at}.extensions.{e}"), "is malformed"))?;
                let (t, _) = self.texture(slot, &at, Encoding::Linear, |t, _| t)?;
                Some(NormalMap { texture: t.texture, transform: t.transform, scale: info.scale(), set: t.set })
            }
        };
        let cutoff = match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => None,
            gltf::material::AlphaMode::Mask => Some(m.alpha_cutoff().unwrap_or(0.5)),
            gltf::material::AlphaMode::Blend => {
                self.warn(&location, "alphaMode BLEND rendered as MASK with a cutoff of 0.5 (no partial transparency)");
                Some(0.5)
            }
        };
        if cutoff.is_some_and(|c| !c.is_finite()) {
            return Err(self.error(format!("{location}.alphaCutoff"), "must be finite"));
        }
        // Only a mask that removes something costs Embree a filter call.
        let cutout = cutoff.and_then(|cutoff| {
            let (alpha, width, height, transform) = coverage.unwrap_or_else(|| (vec![base.w], 1, 1, Affine2::IDENTITY));
            alpha.iter().any(|&a| a < cutoff).then_some(Cutout {
                alpha,
                width: width as u32,
                height: height as u32,
                transform,
                cutoff,
            })
        });
        let (emission, emissive_texture) = self.emission(&m, &location)?;
        let index = self.parts.materials.len();
        let name = m.name().map_or_else(|| location.clone(), str::to_string);
        self.parts.materials.push(Material {
            emission,
            emissive_texture,
            emits_both_sides: m.double_sided(),
            cutout,
            pbr: Some(PbrMaterial {
                metallic,
                roughness,
                specular,
                specular_colour,
                metallic_roughness,
                specular_texture,
                specular_colour_texture,
                normal_map,
            }),
            unlit: m.unlit(),
            culls_back_faces: !m.double_sided(),
            ..Material::diffuse(name, albedo)
        });
        self.materials.insert(m.index(), index);
        Ok(index)
    }

    /// KHR_materials_specular's factor, colour and their textures (1,
    /// white and none without the extension): the dielectric's reflectance
    /// at normal incidence is 0.04 (IOR 1.5) times the colour, times the
    /// factor.
    #[allow(clippy::type_complexity)]
    fn specular(
        &mut self,
        m: &gltf::Material<'_>,
        location: &str,
    ) -> Result<(f32, Vec3, Option<TextureRef>, Option<TextureRef>), SceneError> {
        let (specular, specular_colour) = m
            .specular()
            .map_or((1.0, Vec3::ONE), |s| (s.specular_factor(), Vec3::from_array(s.specular_color_factor())));
        if !(specular.is_finite()
            && specular_colour.is_finite()
            && specular >= 0.0
            && specular_colour.min_element() >= 0.0)
        {
            return Err(self.error(format!("{location}.extensions.KHR_materials_specular"), "must be finite and >= 0"));
        }
        let at = format!("{location}.extensions.KHR_materials_specular");
        // The extension's schema caps the factor at 1: above it the
        // diffuse weight 1 - max(F) would be negative.
        let specular = if specular > 1.0 {
            self.warn(&format!("{at}.specularFactor"), &format!("{specular} clamped to 1, the extension's maximum"));
            1.0
        } else {
            specular
        };
        let specular_texture = match m.specular().and_then(|s| s.specular_texture()) {
            None => None,
            // The factor is the texture's alpha channel (linear).
            Some(info) => Some(
                self.texture(Slot::of(&info), &format!("{at}.specularTexture"), Encoding::Linear, |_, a| {
                    Vec3::splat(a)
                })?
                .0,
            ),
        };
        let specular_colour_texture = match m.specular().and_then(|s| s.specular_color_texture()) {
            None => None,
            Some(info) => {
                Some(self.texture(Slot::of(&info), &format!("{at}.specularColorTexture"), Encoding::Srgb, |t, _| t)?.0)
            }
        };
        Ok((specular, specular_colour, specular_texture, specular_colour_texture))
    }

    /// The emitted radiance (emissiveFactor x KHR_materials_emissive_strength,
    /// W/(m^2 sr)) and the emissive texture multiplying it.
    fn emission(&mut self, m: &gltf::Material<'_>, location: &str) -> Result<(Vec3, Option<TextureRef>), SceneError> {
        let strength = m.emissive_strength().unwrap_or(1.0);
        let emission = Vec3::from_array(m.emissive_factor()) * strength;
        if !emission.is_finite() || emission.min_element() < 0.0 {
            return Err(self.error(
                format!("{location}.emissiveFactor"),
                format!("emission must be finite and >= 0, got {emission}"),
            ));
        }
        let emissive_texture = match m.emissive_texture() {
            Some(info) if emission != Vec3::ZERO => {
                let at = format!("{location}.emissiveTexture");
                Some(self.texture(Slot::of(&info), &at, Encoding::Srgb, |t, _| t)?.0)
            }
            // A texture times a zero factor emits nothing: not read.
            _ => None,
        };
        Ok((emission, emissive_texture))
    }
}

/// Where a mesh's vertices go: one node transform, or (a skin) each
/// vertex's blend of its joints' matrices.
enum Placement {
    Rigid(Mat4),
    /// Each joint's world transform times its inverse bind matrix.
    Skinned(Vec<Mat4>),
}

/// A primitive's object-to-world transform, for all its vertices or one
/// per vertex (skinned), with the inverse transposes for normals.
enum VertexTransforms {
    Rigid { matrix: Mat4, normal: Mat3 },
    PerVertex { matrices: Vec<Mat4>, normals: Vec<Mat3> },
}

impl VertexTransforms {
    fn of(matrices: Vec<Mat4>) -> Self {
        let normals = matrices.iter().map(|m| Mat3::from_mat4(*m).inverse().transpose()).collect();
        Self::PerVertex { matrices, normals }
    }

    fn rigid(matrix: Mat4) -> Self {
        Self::Rigid { matrix, normal: Mat3::from_mat4(matrix).inverse().transpose() }
    }

    fn matrix(&self, vertex: usize) -> &Mat4 {
        match self {
            Self::Rigid { matrix, .. } => matrix,
            Self::PerVertex { matrices, .. } => &matrices[vertex],
        }
    }

    fn point(&self, vertex: usize, p: Vec3) -> Vec3 {
        self.matrix(vertex).transform_point3(p)
    }

    fn vector(&self, vertex: usize, v: Vec3) -> Vec3 {
        self.matrix(vertex).transform_vector3(v)
    }

    fn normal(&self, vertex: usize, n: Vec3) -> Vec3 {
        match self {
            Self::Rigid { normal, .. } => *normal * n,
            Self::PerVertex { normals, .. } => normals[vertex] * n,
        }
    }

    /// Whether the transform mirrors (a skin: its first vertex's does).
    fn mirrored(&self) -> bool {
        match self {
            Self::Rigid { matrix, .. } => Mat3::from_mat4(*matrix).determinant() < 0.0,
            Self::PerVertex { matrices, .. } => {
                matrices.first().is_some_and(|m| Mat3::from_mat4(*m).determinant() < 0.0)
            }
        }
    }
}

impl Importer<'_, '_> {
    /// Names, once each, the extensions the file uses but the renderer does
    /// not implement, with what the render does instead (a required one was
    /// refused in `io::parse`).
    fn name_ignored_extensions(&mut self) {
        let used: Vec<String> = self.doc.extensions_used().map(str::to_string).collect();
        for name in used {
            if IMPLEMENTED.contains(&name.as_str()) {
                continue;
            }
            let instead = IGNORED
                .iter()
                .find(|(n, _)| *n == name)
                .map_or("ignored: the render is what the file gives without it", |(_, instead)| instead);
            self.warn("extensionsUsed", &format!("{name} is not implemented: {instead}"));
        }
    }

    /// glTF's morph targets at `weights` (the node's, else the mesh's; 0
    /// where none is given): POSITION and NORMAL displaced by the weighted
    /// sum of the targets' (the specification's section 3.7.2.2), in the mesh's
    /// own space.
    fn morph(
        &mut self,
        primitive: &gltf::Primitive<'_>,
        location: &str,
        weights: &[f32],
        positions: &mut [[f32; 3]],
        mut normals: Option<&mut Vec<[f32; 3]>>,
    ) -> Result<(), SceneError> {
        for (k, target) in primitive.morph_targets().enumerate() {
            let weight = weights.get(k).copied().unwrap_or(0.0);
            if !weight.is_finite() {
                return Err(self.error(format!("{location} (weights[{k}])"), "morph target weights must be finite"));
            }
            if weight == 0.0 {
                continue;
            }
            self.add_deltas(target.positions(), &format!("{location}.targets[{k}].POSITION"), weight, positions)?;
            if let Some(normals) = normals.as_deref_mut() {
                self.add_deltas(target.normals(), &format!("{location}.targets[{k}].NORMAL"), weight, normals)?;
            }
        }
        Ok(())
    }

    /// Adds `weight` times a morph target's displacements (`accessor`, at
    /// JSON location `at`; nothing when absent) to `into`, one per vertex.
    fn add_deltas(
        &self,
        accessor: Option<gltf::Accessor<'_>>,
        at: &str,
        weight: f32,
        into: &mut [[f32; 3]],
    ) -> Result<(), SceneError> {
        let Some(a) = accessor else { return Ok(()) };
        let deltas = self.data.read_floats::<3>(&a, at)?;
        if deltas.len() != into.len() {
            return Err(self.error(at, format!("has {} elements for {} vertices", deltas.len(), into.len())));
        }
        for (v, d) in into.iter_mut().zip(&deltas) {
            for c in 0..3 {
                v[c] += weight * d[c];
            }
        }
        Ok(())
    }

    /// The transforms that place a primitive's vertices: the node's, or
    /// for a skin each vertex's JOINTS_0 matrices blended by its WEIGHTS_0
    /// (the specification's section 3.7.3: the skinned node's own transform is
    /// not applied).
    fn vertex_transforms(
        &mut self,
        primitive: &gltf::Primitive<'_>,
        location: &str,
        placement: &Placement,
        count: usize,
    ) -> Result<VertexTransforms, SceneError> {
        let joints = match placement {
            Placement::Rigid(matrix) => return Ok(VertexTransforms::rigid(*matrix)),
            Placement::Skinned(joints) => joints,
        };
        let (Some(indices), Some(weights)) =
            (primitive.get(&gltf::Semantic::Joints(0)), primitive.get(&gltf::Semantic::Weights(0)))
        else {
            return Err(self.error(format!("{location}.attributes"), "is skinned but has no JOINTS_0 and WEIGHTS_0"));
        };
        let at_joints = format!("{location}.attributes.JOINTS_0");
        let indices = self.data.read_floats::<4>(&indices, &at_joints)?;
        let at_weights = format!("{location}.attributes.WEIGHTS_0");
        let weights = self.data.read_floats::<4>(&weights, &at_weights)?;
        if indices.len() != count || weights.len() != count {
            return Err(
                self.error(at_joints, format!("JOINTS_0 and WEIGHTS_0 must have {count} elements, one a vertex"))
            );
        }
        let mut matrices = Vec::with_capacity(count);
        for (v, (j, w)) in indices.iter().zip(&weights).enumerate() {
            let mut m = Mat4::ZERO;
            for k in 0..4 {
                if w[k] == 0.0 {
                    continue;
                }
                let Some(joint) = joints.get(j[k] as usize) else {
                    return Err(self.error(
                        &at_joints,
                        format!("vertex {v} names joint {}, but the skin has {}", j[k], joints.len()),
                    ));
                };
                if !w[k].is_finite() {
                    return Err(self.error(&at_weights, format!("vertex {v}'s weights are not finite")));
                }
                m += *joint * w[k];
            }
            matrices.push(m);
        }
        Ok(VertexTransforms::of(matrices))
    }

    /// A skin's joint matrices: each joint node's world transform times its
    /// inverse bind matrix (identity without them).
    fn joint_matrices(&mut self, skin: &gltf::Skin<'_>, worlds: &[Option<Mat4>]) -> Result<Vec<Mat4>, SceneError> {
        let location = format!("skins[{}]", skin.index());
        let joints: Vec<gltf::Node<'_>> = skin.joints().collect();
        if joints.is_empty() || joints.len() > MAX_JOINTS {
            return Err(self.error(
                format!("{location}.joints"),
                format!("has {} joints: a skin has 1 to {MAX_JOINTS}", joints.len()),
            ));
        }
        let inverse_binds = match skin.inverse_bind_matrices() {
            None => vec![Mat4::IDENTITY; joints.len()],
            Some(a) => {
                let at = format!("{location}.inverseBindMatrices");
                let m = self.data.read_floats::<16>(&a, &at)?;
                if m.len() < joints.len() {
                    return Err(self.error(at, format!("has {} matrices for {} joints", m.len(), joints.len())));
                }
                m.iter().map(Mat4::from_cols_array).collect()
            }
        };
        let mut matrices = Vec::with_capacity(joints.len());
        for (k, (joint, inverse_bind)) in joints.iter().zip(&inverse_binds).enumerate() {
            let Some(world) = worlds[joint.index()] else {
                return Err(self.error(
                    format!("{location}.joints[{k}]"),
                    format!("nodes[{}] is not in the rendered scene", joint.index()),
                ));
            };
            let m = world * *inverse_bind;
            if !m.is_finite() {
                return Err(self.error(format!("{location}.inverseBindMatrices"), format!("matrix {k} is not finite")));
            }
            matrices.push(m);
        }
        Ok(matrices)
    }

    /// EXT_mesh_gpu_instancing's per-instance transforms (translation x
    /// rotation x scale, each optional), relative to the node.
    fn instances(&mut self, value: &serde_json::Value, location: &str) -> Result<Vec<Mat4>, SceneError> {
        let at = format!("{location}.extensions.EXT_mesh_gpu_instancing.attributes");
        let attributes = value.get("attributes").and_then(serde_json::Value::as_object);
        let Some(attributes) = attributes else { return Err(self.error(at, "missing")) };
        let accessor = |name: &str| -> Result<Option<gltf::Accessor<'_>>, SceneError> {
            let Some(index) = attributes.get(name) else { return Ok(None) };
            let found = index.as_u64().and_then(|i| self.doc.accessors().nth(i as usize));
            found.map(Some).ok_or_else(|| self.error(format!("{at}.{name}"), format!("{index} is not an accessor")))
        };
        let (t, r, sc) = (accessor("TRANSLATION")?, accessor("ROTATION")?, accessor("SCALE")?);
        let read3 = |a: &Option<gltf::Accessor<'_>>, name: &str| {
            a.as_ref().map(|a| self.data.read_floats::<3>(a, &format!("{at}.{name}"))).transpose()
        };
        let translations = read3(&t, "TRANSLATION")?;
        let scales = read3(&sc, "SCALE")?;
        let rotations = r.as_ref().map(|a| self.data.read_floats::<4>(a, &format!("{at}.ROTATION"))).transpose()?;
        let counts =
            [translations.as_ref().map(Vec::len), scales.as_ref().map(Vec::len), rotations.as_ref().map(Vec::len)];
        let count = counts.iter().flatten().copied().max().unwrap_or(0);
        if counts.iter().flatten().any(|&n| n != count) {
            return Err(self.error(at, "TRANSLATION, ROTATION and SCALE must have one element an instance each"));
        }
        let mut matrices = Vec::with_capacity(count);
        for i in 0..count {
            let t = translations.as_ref().map_or(Vec3::ZERO, |v| Vec3::from_array(v[i]));
            let s = scales.as_ref().map_or(Vec3::ONE, |v| Vec3::from_array(v[i]));
            let q = rotations.as_ref().map_or(glam::Quat::IDENTITY, |v| glam::Quat::from_array(v[i]).normalize());
            let m = Mat4::from_scale_rotation_translation(s, q, t);
            if !m.is_finite() {
                return Err(self.error(at, format!("instance {i}'s transform is not finite")));
            }
            matrices.push(m);
        }
        Ok(matrices)
    }
}

/// What a primitive's tangents are made from: its node's transform, its
/// morph weights, and its world-space normals and (glTF) texture
/// coordinates.
struct Frame<'a> {
    transforms: &'a VertexTransforms,
    weights: &'a [f32],
    normals: Option<&'a [Vec3]>,
    uvs: Option<&'a [Vec2]>,
}

impl Importer<'_, '_> {
    /// A normal-mapped primitive's tangents in world space: its `TANGENT`s
    /// (displaced by its morph targets' at the weights, transformed by the
    /// node's matrix; w flipped by a mirroring one),
    /// or MikkTSpace's from its normals and texture coordinates, as the
    /// specification asks. None, with a warning, without normals or
    /// texture coordinates (the normal map is then not used).
    fn tangents(
        &mut self,
        primitive: &gltf::Primitive<'_>,
        location: &str,
        count: usize,
        frame: &Frame<'_>,
        positions: &[Vec3],
        triangles: &[[u32; 3]],
    ) -> Result<Option<Tangents>, SceneError> {
        let (Some(normals), Some(uvs)) = (frame.normals, frame.uvs) else {
            self.warn(location, "normalTexture unused: the primitive has no NORMAL or not the TEXCOORD it reads");
            return Ok(None);
        };
        let Some(mut tangents) =
            self.attribute::<4>(primitive, location, gltf::Semantic::Tangents, "tangents", count)?
        else {
            return Ok(mikktspace_tangents(positions, normals, uvs, triangles));
        };
        // Morph targets displace the tangent's xyz (glTF section 3.7.2.2); w stays.
        let mut xyz: Vec<[f32; 3]> = tangents.iter().map(|t| [t[0], t[1], t[2]]).collect();
        for (k, target) in primitive.morph_targets().enumerate() {
            let weight = frame.weights.get(k).copied().unwrap_or(0.0);
            if weight != 0.0 {
                self.add_deltas(target.tangents(), &format!("{location}.targets[{k}].TANGENT"), weight, &mut xyz)?;
            }
        }
        for (t, v) in tangents.iter_mut().zip(&xyz) {
            t[..3].copy_from_slice(v);
        }
        let sign = if frame.transforms.mirrored() { -1.0 } else { 1.0 };
        let tangents: Vec<Vec4> = tangents
            .iter()
            .enumerate()
            .map(|(i, t)| {
                frame.transforms.vector(i, Vec3::new(t[0], t[1], t[2])).normalize_or_zero().extend(sign * t[3].signum())
            })
            .collect();
        if tangents.iter().any(|t| !t.is_finite() || t.truncate() == Vec3::ZERO) {
            self.warn(
                &format!("{location}.attributes.TANGENT"),
                "has zero or non-finite tangents: MikkTSpace's are used",
            );
            return Ok(mikktspace_tangents(positions, normals, uvs, triangles));
        }
        Ok(Some(Tangents::PerVertex(tangents)))
    }

    /// A primitive's float attribute `semantic` of N components, one per
    /// vertex (`noun` names its elements in the error); None when absent.
    fn attribute<const N: usize>(
        &self,
        primitive: &gltf::Primitive<'_>,
        location: &str,
        semantic: gltf::Semantic,
        noun: &str,
        count: usize,
    ) -> Result<Option<Vec<[f32; N]>>, SceneError> {
        let Some(a) = primitive.get(&semantic) else { return Ok(None) };
        let at = format!("{location}.attributes.{}", semantic.to_string());
        let values = self.data.read_floats::<N>(&a, &at)?;
        if values.len() != count {
            return Err(self.error(at, format!("has {} {noun} for {count} vertices", values.len())));
        }
        Ok(Some(values))
    }

    /// A primitive's `TEXCOORD_<set>`, finite, one per vertex.
    fn texture_coordinates(
        &mut self,
        primitive: &gltf::Primitive<'_>,
        location: &str,
        count: usize,
        set: u32,
    ) -> Result<Option<Vec<Vec2>>, SceneError> {
        let semantic = gltf::Semantic::TexCoords(set);
        let Some(uvs) = self.attribute::<2>(primitive, location, semantic, "coordinates", count)? else {
            return Ok(None);
        };
        if uvs.iter().flatten().any(|x| !x.is_finite()) {
            return Err(
                self.error(format!("{location}.attributes.TEXCOORD_{set}"), "has non-finite texture coordinates")
            );
        }
        Ok(Some(uvs.iter().map(|uv| Vec2::from_array(*uv)).collect()))
    }

    /// A primitive's `COLOR_0` (VEC3 or VEC4 of floats or normalized
    /// integers, linear; the alpha is not used): the colours that multiply
    /// its base colour.
    fn vertex_colors(
        &mut self,
        primitive: &gltf::Primitive<'_>,
        location: &str,
        count: usize,
    ) -> Result<Option<Vec<Vec3>>, SceneError> {
        let Some(a) = primitive.get(&gltf::Semantic::Colors(0)) else { return Ok(None) };
        let at = format!("{location}.attributes.COLOR_0");
        let colors: Vec<Vec3> = if a.dimensions() == gltf::accessor::Dimensions::Vec4 {
            self.data.read_floats::<4>(&a, &at)?.iter().map(|c| Vec3::new(c[0], c[1], c[2])).collect()
        } else {
            self.data.read_floats::<3>(&a, &at)?.iter().map(|c| Vec3::from_array(*c)).collect()
        };
        if colors.len() != count {
            return Err(self.error(at, format!("has {} colours for {count} vertices", colors.len())));
        }
        if colors.iter().any(|c| !c.is_finite() || c.min_element() < 0.0) {
            return Err(self.error(at, "has colours that are not finite and >= 0"));
        }
        // A float colour may exceed 1, but it multiplies the base colour, a
        // reflectance the BRDF (and its bound: docs/design.md §8.3) needs
        // within [0, 1].
        let brightest = colors.iter().map(|c| c.max_element()).fold(0.0, f32::max);
        if brightest > 1.0 {
            self.warn(
                &at,
                &format!(
                    "colours above 1 (up to {brightest}) clamped to 1: they multiply the base colour, a reflectance"
                ),
            );
            return Ok(Some(colors.iter().map(|c| c.min(Vec3::ONE)).collect()));
        }
        Ok(Some(colors))
    }

    /// A texture of the file as the renderer's: its image decoded as
    /// `encoding` says and mapped texel by texel through `map` (colour and
    /// alpha, 1 where the image has none), read with its sampler's wrap
    /// modes and magnification filter, through the slot's texture
    /// coordinates and KHR_texture_transform. Returns the reference and the
    /// decoded image.
    fn texture(
        &mut self,
        slot: Slot<'_>,
        at: &str,
        encoding: Encoding,
        map: impl Fn(Vec3, f32) -> Vec3,
    ) -> Result<(TextureRef, RgbImage), SceneError> {
        // KHR_texture_transform's texCoord overrides the texture info's.
        let tex_coord = slot.transform.and_then(|t| t.tex_coord).unwrap_or(slot.tex_coord);
        let set = if tex_coord <= 1 {
            tex_coord as usize
        } else {
            self.warn(at, &format!("uses TEXCOORD_{tex_coord}: read with TEXCOORD_0 (sets 0 and 1 are read)"));
            0
        };
        let transform = uv_transform(slot.transform);
        if !(transform.matrix2.is_finite() && transform.translation.is_finite()) {
            return Err(self.error(format!("{at}.extensions.KHR_texture_transform"), "must be finite"));
        }
        let texture = slot.texture;
        let image = self.data.image(&texture.source(), at, encoding)?;
        let sampler = texture.sampler();
        let wrap = |mode: WrappingMode| match mode {
            WrappingMode::Repeat => Wrap::Repeat,
            WrappingMode::ClampToEdge => Wrap::ClampToEdge,
            WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        };
        let filter = match sampler.mag_filter() {
            Some(MagFilter::Nearest) => Filter::Nearest,
            Some(MagFilter::Linear) | None => Filter::Linear,
        };
        let texels = match &image.alpha {
            Some(alpha) => image.texels.iter().zip(alpha).map(|(t, a)| map(*t, *a)).collect(),
            None => image.texels.iter().map(|t| map(*t, 1.0)).collect(),
        };
        let texture = Texture::from_texels(image.width, image.height, texels)
            .with_sampler([wrap(sampler.wrap_s()), wrap(sampler.wrap_t())], filter);
        self.parts.textures.push(texture);
        Ok((TextureRef { texture: self.parts.textures.len() - 1, transform, set }, image))
    }
}

/// A primitive's tangents: the file's, one per vertex, or MikkTSpace's,
/// one per triangle corner (`Mesh::set_corner_tangents` splits the
/// vertices whose corners disagree).
enum Tangents {
    PerVertex(Vec<Vec4>),
    PerCorner(Vec<[Vec4; 3]>),
}

/// MikkTSpace tangents of a triangle mesh, one per triangle corner, from
/// glTF's texture coordinates with v turned up, so that the bitangent
/// points up the image as glTF's normal maps expect. None if MikkTSpace
/// fails.
fn mikktspace_tangents(positions: &[Vec3], normals: &[Vec3], uvs: &[Vec2], triangles: &[[u32; 3]]) -> Option<Tangents> {
    struct Faces<'a> {
        positions: &'a [Vec3],
        normals: &'a [Vec3],
        uvs: &'a [Vec2],
        triangles: &'a [[u32; 3]],
        tangents: Vec<[Vec4; 3]>,
    }
    impl bevy_mikktspace::Geometry for Faces<'_> {
        fn num_faces(&self) -> usize {
            self.triangles.len()
        }
        fn num_vertices_of_face(&self, _face: usize) -> usize {
            3
        }
        fn position(&self, face: usize, vert: usize) -> [f32; 3] {
            self.positions[self.triangles[face][vert] as usize].to_array()
        }
        fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
            self.normals[self.triangles[face][vert] as usize].to_array()
        }
        fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
            let uv = self.uvs[self.triangles[face][vert] as usize];
            [uv.x, 1.0 - uv.y]
        }
        fn set_tangent_encoded(&mut self, tangent: [f32; 4], face: usize, vert: usize) {
            self.tangents[face][vert] = Vec4::from_array(tangent);
        }
    }
    let mut faces = Faces {
        positions,
        normals,
        uvs,
        triangles,
        tangents: vec![[Vec4::new(1.0, 0.0, 0.0, 1.0); 3]; triangles.len()],
    };
    bevy_mikktspace::generate_tangents(&mut faces).then_some(Tangents::PerCorner(faces.tangents))
}

/// Triangles of a primitive: lists as they are, strips and fans converted
/// (alternate strip triangles reversed to keep one winding).
fn triangulate(mode: Mode, indices: &[u32]) -> Vec<[u32; 3]> {
    match mode {
        Mode::TriangleStrip => (2..indices.len())
            .map(|i| {
                let (a, b, c) = (indices[i - 2], indices[i - 1], indices[i]);
                if i % 2 == 0 {
                    [a, b, c]
                } else {
                    [b, a, c]
                }
            })
            .collect(),
        Mode::TriangleFan => (2..indices.len()).map(|i| [indices[0], indices[i - 1], indices[i]]).collect(),
        _ => indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
    }
}

/// The map from a mesh's glTF uv to `Texture::lookup`'s: KHR_texture_transform
/// (translation x rotation x scale, as the extension defines it), then v
/// flipped (glTF's v = 0 is the image's top row, the lookup's its bottom).
fn uv_transform(transform: Option<KhrTextureTransform>) -> Affine2 {
    let flip = Affine2::from_mat2_translation(Mat2::from_diagonal(Vec2::new(1.0, -1.0)), Vec2::new(0.0, 1.0));
    let Some(t) = transform else { return flip };
    let (sin, cos) = t.rotation.sin_cos();
    let rotation = Mat2::from_cols(Vec2::new(cos, -sin), Vec2::new(sin, cos));
    let khr = Affine2::from_mat2_translation(
        rotation * Mat2::from_diagonal(Vec2::from_array(t.scale)),
        Vec2::from_array(t.offset),
    );
    flip * khr
}

/// KHR_texture_transform's fields (the extension's defaults where absent).
#[derive(Debug, Clone, Copy)]
struct KhrTextureTransform {
    offset: [f32; 2],
    rotation: f32,
    scale: [f32; 2],
    tex_coord: Option<u32>,
}

impl From<&gltf::json::extensions::texture::TextureTransform> for KhrTextureTransform {
    fn from(t: &gltf::json::extensions::texture::TextureTransform) -> Self {
        Self { offset: t.offset.0, rotation: t.rotation.0, scale: t.scale.0, tex_coord: t.tex_coord }
    }
}

/// Where a material reads a texture: the texture, its `texCoord`, and its
/// KHR_texture_transform.
struct Slot<'a> {
    texture: gltf::Texture<'a>,
    tex_coord: u32,
    transform: Option<KhrTextureTransform>,
}

impl<'a> Slot<'a> {
    fn of(info: &gltf::texture::Info<'a>) -> Self {
        let transform = info.texture_transform().map(|t| KhrTextureTransform {
            offset: t.offset(),
            rotation: t.rotation(),
            scale: t.scale(),
            tex_coord: t.tex_coord(),
        });
        Self { texture: info.texture(), tex_coord: info.tex_coord(), transform }
    }

    /// A normal texture's slot: the `gltf` crate models no transform on
    /// it, so the extension's JSON is read here. Err names the extension
    /// when its JSON is malformed.
    fn of_normal(info: &gltf::material::NormalTexture<'a>) -> Result<Self, &'static str> {
        const KHR: &str = "KHR_texture_transform";
        let transform = match info.extension_value(KHR) {
            None => None,
            Some(value) => {
                let t: gltf::json::extensions::texture::TextureTransform =
                    serde_json::from_value(value.clone()).map_err(|_| KHR)?;
                Some(KhrTextureTransform::from(&t))
            }
        };
        Ok(Self { texture: info.texture(), tex_coord: info.tex_coord(), transform })
    }
}

fn list_or_none(names: &[&str]) -> String {
    if names.is_empty() {
        "no cameras".to_string()
    } else {
        names.join(", ")
    }
}

#[cfg(test)]
mod tests;
