//! Objects: meshes placed in the world, what the renderer draws and what
//! Cryptomatte names. Most meshes are in world space and drawn once, as
//! themselves; a glTF mesh that several nodes (or EXT_mesh_gpu_instancing)
//! place is kept once in its own space and drawn once per object that
//! places it, as an Embree instance (docs/design.md §4.1).

use glam::{Affine3A, Vec3};

use super::mesh::Mesh;

/// A mesh placed in the world.
#[derive(Debug, Clone, PartialEq)]
pub struct Object {
    /// Index into `Scene::meshes`.
    pub mesh: usize,
    /// From the mesh's space to the world's, when the mesh is not in world
    /// space itself (an instance). Finite and orientation-preserving
    /// (determinant > 0): a mirroring placement is imported as a copy,
    /// whose triangles turn around.
    pub transform: Option<Affine3A>,
    /// What Cryptomatte's object mattes are keyed by (a glTF node's name;
    /// `node[i]` for EXT_mesh_gpu_instancing's instance i).
    pub name: String,
    /// How the object moves over the shutter, from where `transform` (or
    /// the mesh itself) puts it; None: it stands still.
    pub motion: Option<Motion>,
}

/// An object's motion over the shutter (docs/design.md §13.6): its
/// placements at evenly spaced times, the first at the shutter's open
/// (time 0), the last at its close (time 1), each mapping the object's
/// still position to its moved one. Between two steps the matrices are
/// interpolated linearly, as Embree interpolates an instance's transforms,
/// so that shading places a hit exactly where Embree found it.
#[derive(Debug, Clone, PartialEq)]
pub struct Motion {
    pub steps: Vec<Affine3A>,
}

/// Most degrees a step of a rotation turns: between steps the linearly
/// interpolated matrix shrinks the object by 1 - cos(step / 2), 0.015% at 2
/// degrees.
const MAX_STEP_DEGREES: f32 = 2.0;

impl Motion {
    /// A displacement by `translate` and a rotation by `degrees` about
    /// `axis` through `centre`, both growing linearly over the shutter.
    /// `axis` must be non-zero when `degrees` is; at most 129 steps
    /// (Embree's limit).
    #[must_use]
    pub fn rigid(centre: Vec3, translate: Vec3, axis: Vec3, degrees: f32) -> Self {
        let turns = degrees != 0.0;
        let count = if turns {
            ((degrees.abs() / MAX_STEP_DEGREES).ceil() as usize + 1).min(crate::embree::MAX_TIME_STEPS)
        } else {
            2
        };
        let axis = if turns { axis.normalize() } else { Vec3::Y };
        let steps = (0..count)
            .map(|k| {
                let time = k as f32 / (count - 1) as f32;
                let rotation = Affine3A::from_axis_angle(axis, (degrees * time).to_radians());
                Affine3A::from_translation(centre + translate * time) * rotation * Affine3A::from_translation(-centre)
            })
            .collect();
        Self { steps }
    }

    /// The placement at `time` (in [0, 1]): the steps' matrices
    /// interpolated linearly, as Embree does.
    #[must_use]
    pub fn at(&self, time: f32) -> Affine3A {
        let segments = self.steps.len() - 1;
        if segments == 0 {
            return self.steps[0];
        }
        let scaled = time.clamp(0.0, 1.0) * segments as f32;
        let k = (scaled.floor() as usize).min(segments - 1);
        let f = scaled - k as f32;
        let (a, b) = (self.steps[k], self.steps[k + 1]);
        Affine3A {
            matrix3: a.matrix3 * (1.0 - f) + b.matrix3 * f,
            translation: a.translation * (1.0 - f) + b.translation * f,
        }
    }
}

/// The objects of a scene: `instances`, then every mesh they do not
/// place, once, as itself (in mesh order, named as the mesh).
#[must_use]
pub fn place(meshes: &[Mesh], instances: Vec<Object>) -> Vec<Object> {
    let mut instanced = vec![false; meshes.len()];
    for object in &instances {
        instanced[object.mesh] = true;
    }
    let mut objects: Vec<Object> = (0..meshes.len())
        .filter(|&i| !instanced[i])
        .map(|i| Object { mesh: i, transform: None, name: meshes[i].name.clone(), motion: None })
        .collect();
    objects.extend(instances);
    objects
}

/// Bounds of the objects in the world: (min, max), infinite when there are
/// none. An instance's are its mesh's box's eight corners, placed; a moving
/// object's, those of every time step (between steps a point moves on the
/// segment between its placed positions, inside the box).
#[must_use]
pub fn world_bounds(meshes: &[Mesh], objects: &[Object]) -> (Vec3, Vec3) {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for object in objects {
        let (a, b) = meshes[object.mesh].bounds();
        let placed = object.transform.unwrap_or(Affine3A::IDENTITY);
        let still = [Affine3A::IDENTITY];
        let steps = object.motion.as_ref().map_or(&still[..], |m| &m.steps[..]);
        if object.transform.is_none() && object.motion.is_none() {
            lo = lo.min(a);
            hi = hi.max(b);
        } else if a.x <= b.x {
            for step in steps {
                for k in 0..8 {
                    let corner = Vec3::select(glam::BVec3::new(k & 1 != 0, k & 2 != 0, k & 4 != 0), b, a);
                    let p = (*step * placed).transform_point3(corner);
                    lo = lo.min(p);
                    hi = hi.max(p);
                }
            }
        }
    }
    (lo, hi)
}

/// The largest component a ray may reach in an instance's own space: an
/// eighteenth of Embree's bound (`embree::MAX_RAY_COMPONENT`, 1.844e18),
/// which an assertion-enabled Embree (Debian's) enforces by aborting the
/// process, for the rounding of a matrix inverted in `f32`.
pub const MAX_INSTANCE_RAY_COMPONENT: f64 = 1e17;

/// Whether Embree may trace the rays of a scene through an instance placed
/// by `placement`, when every ray starts within `reach` metres of the origin
/// and has a direction no longer than `2 reach`: Embree carries each ray
/// into the instance's space by the inverse placement, and the ray it gets
/// must stay within [`MAX_INSTANCE_RAY_COMPONENT`]. The inverse's Frobenius
/// norm bounds its gain, so |M^-1 (o - t)| <= ||M^-1|| (reach + |t|) and
/// |M^-1 d| <= ||M^-1|| 2 reach (docs/design.md §4.1). Computed in `f64`: a
/// placement that scales by 1e-20 is refused, one that scales by 1e-12 in a
/// scene of a kilometre is not.
#[must_use]
pub fn traceable_instance(placement: Affine3A, reach: f64) -> bool {
    let m = glam::Mat3::from(placement.matrix3).as_dmat3();
    let determinant = m.determinant();
    if !(placement.is_finite() && determinant.is_finite() && determinant > 0.0) {
        return false;
    }
    let inverse = m.inverse();
    let gain = [inverse.x_axis, inverse.y_axis, inverse.z_axis].iter().map(|c| c.length_squared()).sum::<f64>().sqrt();
    let reach = reach.max(1.0);
    let carried = gain * (reach + placement.translation.as_dvec3().length()).max(2.0 * reach);
    carried.is_finite() && carried <= MAX_INSTANCE_RAY_COMPONENT
}

/// What [`make_traceable`] changed: the objects it drew still and those it
/// dropped, by name.
#[derive(Debug, Default, PartialEq, Eq)]
pub struct Untraceable {
    pub drawn_still: Vec<String>,
    pub dropped: Vec<String>,
}

/// Makes every object one Embree can trace in a scene whose rays start
/// within `reach` metres of the origin ([`traceable_instance`]): a moving
/// object with a step it could not trace is drawn still (as the importers
/// draw a motion that scales to nothing), and an instance it could not
/// trace even still is dropped. Such an instance is thinner than about
/// 1e-16 of the scene's extent in some direction, so it covers no pixel:
/// dropping it changes no image, where handing it to Embree would abort
/// the process.
pub fn make_traceable(objects: &mut Vec<Object>, reach: f64) -> Untraceable {
    let mut changed = Untraceable::default();
    objects.retain_mut(|object| {
        let placed = object.transform.unwrap_or(Affine3A::IDENTITY);
        if let Some(motion) = &object.motion {
            if !motion.steps.iter().all(|step| traceable_instance(*step * placed, reach)) {
                changed.drawn_still.push(object.name.clone());
                object.motion = None;
            }
        }
        let keep = object.transform.is_none_or(|t| traceable_instance(t, reach));
        if !keep {
            changed.dropped.push(object.name.clone());
        }
        keep
    });
    changed
}

#[cfg(test)]
mod tests {
    use super::*;

    fn triangle(name: &str) -> Mesh {
        Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            triangles: vec![[0, 1, 2]],
            name: name.to_string(),
            ..Mesh::default()
        }
    }

    #[test]
    fn every_mesh_no_instance_places_is_placed_once_and_bounds_follow_the_instances() {
        let meshes = [triangle("a"), triangle("shared"), triangle("c")];
        let moved = Affine3A::from_translation(Vec3::new(10.0, 0.0, 0.0));
        let instances = vec![
            Object { mesh: 1, transform: Some(moved), name: "n0".into(), motion: None },
            Object {
                mesh: 1,
                transform: Some(Affine3A::from_scale(Vec3::splat(2.0))),
                name: "n1".into(),
                motion: None,
            },
        ];
        let objects = place(&meshes, instances);
        let names: Vec<&str> = objects.iter().map(|o| o.name.as_str()).collect();
        assert_eq!(names, ["a", "c", "n0", "n1"]);
        assert_eq!((objects[1].mesh, objects[1].transform), (2, None));
        // The placed copies reach x = 11 and y = 2; the mesh itself is not drawn.
        let (lo, hi) = world_bounds(&meshes, &objects);
        assert_eq!((lo, hi), (Vec3::ZERO, Vec3::new(11.0, 2.0, 0.0)));
        assert!(world_bounds(&meshes, &[]).0.x.is_infinite());
    }

    #[test]
    fn a_rigid_motion_moves_and_turns_about_the_centre_and_bounds_cover_its_path() {
        let centre = Vec3::new(1.0, 0.0, 0.0);
        let motion = Motion::rigid(centre, Vec3::new(0.0, 2.0, 0.0), Vec3::Z, 90.0);
        assert_eq!(motion.steps.len(), 46, "2 degrees a step");
        assert_eq!(motion.at(0.0), motion.steps[0]);
        assert!(motion.at(0.0).abs_diff_eq(Affine3A::IDENTITY, 1e-6));
        // At the close the centre has moved by translate and a point one
        // unit along x has turned a quarter about z around it.
        let end = motion.at(1.0);
        assert!(end.transform_point3(centre).abs_diff_eq(Vec3::new(1.0, 2.0, 0.0), 1e-5));
        assert!(end.transform_point3(Vec3::new(2.0, 0.0, 0.0)).abs_diff_eq(Vec3::new(1.0, 3.0, 0.0), 1e-5));
        // Halfway: half the displacement, 45 degrees, within the steps'
        // shrinkage (1 - cos 1 degree).
        let p = motion.at(0.5).transform_point3(Vec3::new(2.0, 0.0, 0.0));
        let expected = Vec3::new(1.0, 1.0, 0.0) + Vec3::new(1.0, 1.0, 0.0).normalize();
        assert!(p.distance(expected) < 2e-4, "{p} vs {expected}");
        // A translation alone is two steps; the bounds hold both ends.
        let slide = Motion::rigid(Vec3::ZERO, Vec3::new(5.0, 0.0, 0.0), Vec3::ZERO, 0.0);
        assert_eq!(slide.steps.len(), 2);
        let meshes = [triangle("t")];
        let object = Object { mesh: 0, transform: None, name: "t".into(), motion: Some(slide) };
        assert_eq!(world_bounds(&meshes, &[object]), (Vec3::ZERO, Vec3::new(6.0, 1.0, 0.0)));
        // A full turn is capped at Embree's 129 steps.
        assert_eq!(Motion::rigid(centre, Vec3::ZERO, Vec3::Y, 360.0).steps.len(), 129);
    }

    /// Embree aborted on a glTF node scaled by [1e-20, 1, 1] (its inverse
    /// carried rays to 1e20): such a placement is refused, a merely small
    /// one kept, and the refused instance is dropped or drawn still.
    #[test]
    fn an_instance_embree_cannot_carry_rays_into_is_dropped_and_a_motion_drawn_still() {
        let squashed = Affine3A::from_scale(Vec3::new(1e-20, 1.0, 1.0));
        assert!(!traceable_instance(squashed, 10.0));
        assert!(traceable_instance(Affine3A::from_scale(Vec3::splat(1e-12)), 1000.0));
        assert!(!traceable_instance(Affine3A::from_scale(Vec3::splat(1e-12)), 1e6), "origins at 1e6 m reach 1e18");
        assert!(!traceable_instance(Affine3A::from_scale(Vec3::new(1.0, -1.0, 1.0)), 1.0), "mirroring");
        // Far from the origin, the translation counts: at 1e16 m a scale of 1e-2 carries rays to 1e18.
        let far = Affine3A::from_scale_rotation_translation(Vec3::splat(0.01), glam::Quat::IDENTITY, Vec3::splat(1e16));
        assert!(!traceable_instance(far, 1.0));
        let slide = Motion { steps: vec![Affine3A::IDENTITY, squashed] };
        let mut objects = vec![
            Object { mesh: 0, transform: Some(Affine3A::IDENTITY), name: "kept".into(), motion: None },
            Object { mesh: 0, transform: Some(squashed), name: "flat".into(), motion: None },
            Object { mesh: 0, transform: None, name: "moving".into(), motion: Some(slide) },
        ];
        let changed = make_traceable(&mut objects, 10.0);
        assert_eq!(changed, Untraceable { drawn_still: vec!["moving".into()], dropped: vec!["flat".into()] });
        let names: Vec<&str> = objects.iter().map(|o| o.name.as_str()).collect();
        assert_eq!(names, ["kept", "moving"]);
        assert!(objects[1].motion.is_none());
    }
}
