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
        .map(|i| Object { mesh: i, transform: None, name: meshes[i].name.clone() })
        .collect();
    objects.extend(instances);
    objects
}

/// Bounds of the objects in the world: (min, max), infinite when there are
/// none. An instance's are its mesh's box's eight corners, placed.
#[must_use]
pub fn world_bounds(meshes: &[Mesh], objects: &[Object]) -> (Vec3, Vec3) {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for object in objects {
        let (a, b) = meshes[object.mesh].bounds();
        match object.transform {
            None => {
                lo = lo.min(a);
                hi = hi.max(b);
            }
            Some(t) if a.x <= b.x => {
                for k in 0..8 {
                    let corner = Vec3::select(glam::BVec3::new(k & 1 != 0, k & 2 != 0, k & 4 != 0), b, a);
                    let p = t.transform_point3(corner);
                    lo = lo.min(p);
                    hi = hi.max(p);
                }
            }
            Some(_) => {}
        }
    }
    (lo, hi)
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
            Object { mesh: 1, transform: Some(moved), name: "n0".into() },
            Object { mesh: 1, transform: Some(Affine3A::from_scale(Vec3::splat(2.0))), name: "n1".into() },
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
}
