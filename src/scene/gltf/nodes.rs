//! The glTF scene's nodes: their world transforms (and over an open
//! shutter, each moving node's at every step), the cameras, where each mesh
//! node puts its mesh (once, or as Embree instances when several nodes or
//! EXT_mesh_gpu_instancing place it: docs/design.md §4.1) and its lights;
//! motion over the shutter, docs/design.md §13.6.

use glam::{Affine3A, Mat4, Vec3};

use super::geometry::Placement;
use super::{Importer, MAX_DEPTH, MAX_INSTANCES};
use crate::scene::file::CameraSpec;
use crate::scene::file::ImportedCamera;
use crate::scene::object::{Motion, Object};
use crate::scene::{within_limits, LightSource, SceneError, MAX_COORDINATE};

/// Times of the shutter a moving node's transform is sampled at, evenly
/// spaced from its open to its close; Embree and shading interpolate
/// linearly between them (docs/design.md §13.6).
pub(super) const SHUTTER_STEPS: usize = 33;

/// Where a mesh node puts its mesh: its world transform (at the shutter's
/// open), whether other nodes place the mesh too, and its world transform
/// at each step of the shutter when it moves.
#[derive(Clone, Copy)]
pub(super) struct MeshPlacement<'a> {
    world: Mat4,
    shared: bool,
    motion: Option<&'a [Mat4]>,
}

/// A node of the scene as the import visits it: its world transform (at
/// the shutter's open, once the shutter is sampled) and its JSON location.
pub(super) struct Visit<'d> {
    node: gltf::Node<'d>,
    world: Mat4,
    location: String,
}

/// A camera node: its camera, its world transform (at the shutter's open),
/// its location, and its world transform at the close when it moves.
struct CameraNode<'d> {
    camera: gltf::Camera<'d>,
    world: Mat4,
    location: String,
    end: Option<Mat4>,
}

impl Importer<'_, '_> {
    /// The scene's nodes depth-first with their world transforms and JSON
    /// locations, each node once (a cycle or a node with two parents is an
    /// error), with an explicit stack (a hostile file cannot overflow ours).
    pub(super) fn visit<'d>(&self, scene: &gltf::Scene<'d>) -> Result<Vec<Visit<'d>>, SceneError> {
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
            visits.push(Visit { node, world, location });
        }
        Ok(visits)
    }

    pub(super) fn import_scene(&mut self, want_camera: bool) -> Result<Option<ImportedCamera>, SceneError> {
        let Some(scene) = self.doc.default_scene().or_else(|| self.doc.scenes().next()) else {
            return Err(self.error("scenes", "the file has no scene to render"));
        };
        self.name_ignored_extensions();
        let mut visits = self.visit(&scene)?;
        // Over an open shutter: each moving node's world transform at every
        // step, and everything posed as at the shutter's open.
        let mut moving = self.shutter_worlds(&visits)?;
        for visit in &mut visits {
            if let Some(steps) = &moving[visit.node.index()] {
                visit.world = steps[0];
            }
        }
        // At an instant (the shutter's open and close the same) everything
        // is posed as the animation has it then, and nothing moves.
        if self.shutter.as_ref().is_some_and(|([open, close], _)| open == close) {
            moving.fill(None);
        }
        // Every node's world transform first: a skin's joints may come
        // after the mesh they pose.
        let mut worlds = vec![None; self.doc.nodes().len()];
        for visit in &visits {
            worlds[visit.node.index()] = Some(visit.world);
        }
        let mut cameras = Vec::new();
        let mut skinned = 0;
        self.placements = self.count_placements(&visits);
        for Visit { node, world, location } in visits {
            let node_name = node.name().map_or_else(|| location.clone(), str::to_string);
            let steps = moving[node.index()].as_deref();
            if let Some(mesh) = node.mesh() {
                skinned += usize::from(node.skin().is_some());
                self.import_node_mesh(&node, &mesh, world, (&location, &node_name), steps, &worlds)?;
            }
            if let Some(camera) = node.camera() {
                let end = steps.and_then(|s| s.last().copied());
                cameras.push(CameraNode { camera, world, location: location.clone(), end });
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
    fn chosen_camera(&self, cameras: &[CameraNode<'_>]) -> Result<Option<ImportedCamera>, SceneError> {
        let chosen = match &self.spec.camera {
            None => cameras.first(),
            Some(name) => {
                // `#N`: the N-th camera in node order (unnamed ones too).
                let found = match name.strip_prefix('#').and_then(|n| n.parse::<usize>().ok()) {
                    Some(i) => cameras.get(i),
                    None => cameras.iter().find(|c| c.camera.name() == Some(name.as_str())),
                };
                if found.is_none() {
                    let names: Vec<String> = cameras
                        .iter()
                        .enumerate()
                        .map(|(i, c)| c.camera.name().map_or_else(|| format!("#{i}"), |n| format!("{n} (#{i})")))
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
        let Some(CameraNode { camera, world, location, end }) = chosen else { return Ok(None) };
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
        let look_at = CameraSpec::aim(eye.as_dvec3(), forward.as_dvec3(), 1.0);
        let mut spec = CameraSpec::pinhole(eye.to_array(), look_at, up.to_array(), fov_y);
        // A moving camera travels in a straight line to where it is at the
        // close, looking along its direction there.
        if let Some(end) = end {
            let (eye_end, forward_end) =
                (end.w_axis.truncate(), end.transform_vector3(Vec3::NEG_Z).normalize_or_zero());
            spec.eye_end = Some(eye_end.to_array());
            spec.look_at_end = Some(CameraSpec::aim(eye_end.as_dvec3(), forward_end.as_dvec3(), 1.0));
        }
        Ok(Some(ImportedCamera { spec, aspect_ratio }))
    }

    /// A mesh node's mesh: posed by its skin, or placed (and moving, with
    /// `steps`, its world transforms over the shutter) once or once per
    /// EXT_mesh_gpu_instancing instance. `at` is the node's location and name.
    pub(super) fn import_node_mesh(
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
    pub(super) fn import_node_light(
        &mut self,
        index: usize,
        world: &Mat4,
        node_name: &str,
        steps: Option<&[Mat4]>,
    ) -> Result<(), SceneError> {
        let before = self.parts.scene.lights.len();
        self.import_light(index, world, node_name)?;
        let Some(steps) = steps else { return Ok(()) };
        // The light this node added, if it added one.
        let added = self.parts.scene.lights.get_mut(before..).and_then(<[LightSource]>::first_mut);
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

    /// How many rigid, orientation-preserving placements each glTF mesh
    /// has among the visited nodes (a node with EXT_mesh_gpu_instancing
    /// counts as two: its mesh is instanced whatever its count).
    fn count_placements(&self, visits: &[Visit<'_>]) -> Vec<usize> {
        let mut placements = vec![0; self.doc.meshes().len()];
        for Visit { node, world, .. } in visits {
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
    pub(super) fn place_mesh(
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
                    let p = if self.parts.scene.materials[material].emission == Vec3::ZERO {
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
            let (lo, hi) = crate::scene::object::world_bounds(self.parts.scene.meshes, std::slice::from_ref(&object));
            if !(within_limits(lo) && within_limits(hi)) {
                return Err(self.error(
                    location,
                    format!("places meshes[{}] at {lo} to {hi} in the world: coordinates must be finite and within +/-{MAX_COORDINATE:e} m", mesh.index()),
                ));
            }
            if self.parts.scene.instances.len() >= MAX_INSTANCES {
                return Err(self.error(location, format!("the scene has more than {MAX_INSTANCES} instances")));
            }
            self.parts.scene.instances.push(object);
        }
        Ok(())
    }

    /// Each visited node's world transform at the shutter's steps, by node
    /// index, for the nodes the animation moves (it drives them or one of
    /// their ancestors); None for the others, and for every node without
    /// a shutter.
    fn shutter_worlds(&self, visits: &[Visit<'_>]) -> Result<Vec<Option<Vec<Mat4>>>, SceneError> {
        let mut moving: Vec<Option<Vec<Mat4>>> = vec![None; self.doc.nodes().len()];
        let Some(([open, close], animation)) = &self.shutter else { return Ok(moving) };
        let mut parent = vec![None; self.doc.nodes().len()];
        for node in self.doc.nodes() {
            for child in node.children() {
                parent[child.index()] = Some(node.index());
            }
        }
        let mut rest = vec![Mat4::IDENTITY; self.doc.nodes().len()];
        for Visit { node, world, .. } in visits {
            rest[node.index()] = *world;
        }
        // One step for an instant.
        let steps = if open < close { SHUTTER_STEPS } else { 1 };
        let times: Vec<f32> =
            (0..steps).map(|k| open + (close - open) * k as f32 / (SHUTTER_STEPS - 1) as f32).collect();
        // Parents come before their children in `visits`.
        for Visit { node, location, .. } in visits {
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

    /// EXT_mesh_gpu_instancing's per-instance transforms (translation x
    /// rotation x scale, each optional), relative to the node.
    pub(super) fn instances(&mut self, value: &serde_json::Value, location: &str) -> Result<Vec<Mat4>, SceneError> {
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

/// The cameras' names, for an error that names none of them.
fn list_or_none(names: &[&str]) -> String {
    if names.is_empty() {
        "no cameras".to_string()
    } else {
        names.join(", ")
    }
}
