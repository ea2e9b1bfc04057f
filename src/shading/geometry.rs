//! The scene's triangles in Embree, and the surface point a hit describes.

use glam::{Vec2, Vec3};

use super::pbr::Pbr;
use super::surface::SurfacePoint;
use crate::embree::{self, AlphaMask, Device, EmbreeError, Hit, MeshError, Ray};
use crate::light::Lights;
use crate::scene::material::reflect;
use crate::scene::Scene;

/// Embree's view of a scene plus what shading needs to interpret its hits.
pub struct Geometry<'s> {
    pub scene: &'s Scene,
    pub embree: embree::Scene,
    /// Mesh index of each Embree geometry id.
    mesh_of_geometry: Vec<usize>,
    /// Offset that lifts ray origins off the surface they leave, in metres.
    /// It scales with the scene: 2^-16 of the largest coordinate magnitude,
    /// i.e. about 500 f32 ulps of the coordinates, far above the few ulps of
    /// error in a barycentric hit point, far below any feature size.
    pub ray_epsilon: f32,
    /// The scene's distance clamp for 1/d^2 (metres).
    pub distance_clamp: f32,
    /// Bounds of the geometry and the omni lights: (min, max), infinite when
    /// there are neither.
    pub bounds: (Vec3, Vec3),
}

impl<'s> Geometry<'s> {
    /// Hands the scene's meshes to Embree. `lights` are the scene's lights:
    /// with the geometry they set the scale of the ray offset.
    pub fn try_new(device: &Device, scene: &'s Scene, lights: &[Lights]) -> Result<Self, GeometryError> {
        let mut builder = device.try_new_scene()?;
        let mut mesh_of_geometry = Vec::new();
        for (i, mesh) in scene.meshes.iter().enumerate() {
            let mask = scene.materials[mesh.material].cutout.as_ref().map(|c| AlphaMask {
                uvs: mesh.uvs.clone().unwrap_or_else(|| vec![Vec2::ZERO; mesh.positions.len()]),
                alpha: c.alpha.clone(),
                width: c.width,
                height: c.height,
                transform: c.transform,
                cutoff: c.cutoff,
            });
            let id = builder
                .attach_masked_triangles(&mesh.positions, &mesh.triangles, mask)
                .map_err(|source| GeometryError::Mesh { shape: i, source })?;
            debug_assert_eq!(id as usize, mesh_of_geometry.len(), "Embree assigns ids in order");
            mesh_of_geometry.push(i);
        }
        let embree = builder.commit()?;
        let (lo, hi) = lights
            .iter()
            .flat_map(|group| &group.omni)
            .fold(scene.mesh_bounds(), |(lo, hi), l| (lo.min(l.position), hi.max(l.position)));
        let magnitude = if lo.is_finite() && hi.is_finite() { lo.abs().max(hi.abs()).max_element() } else { 0.0 };
        // The floor keeps the offset positive for a scene of a single point at the origin.
        let ray_epsilon = (magnitude * (1.0 / 65536.0)).max(1e-30);
        Ok(Self {
            scene,
            embree,
            mesh_of_geometry,
            ray_epsilon,
            distance_clamp: scene.distance_clamp,
            bounds: (lo, hi),
        })
    }

    /// The surface point of a hit along `ray`, with normals facing the ray's origin.
    /// The index into the scene's meshes of the mesh `hit` is on.
    #[must_use]
    pub fn mesh_of(&self, hit: &Hit) -> usize {
        self.mesh_of_geometry[hit.geometry as usize]
    }

    pub fn surface(&self, ray: &Ray, hit: &Hit) -> SurfacePoint<'s> {
        let mesh = &self.scene.meshes[self.mesh_of_geometry[hit.geometry as usize]];
        let tri = mesh.triangles[hit.primitive as usize];
        let (u, v) = (hit.u, hit.v);
        let w = 1.0 - u - v;
        let [p0, p1, p2] = tri.map(|i| mesh.positions[i as usize]);
        // Barycentric interpolation is more accurate than origin + t * direction.
        let p = w * p0 + u * p1 + v * p2;
        let wo = (-ray.direction).normalize();
        let mut ng = (p1 - p0).cross(p2 - p0).normalize_or_zero();
        // Emitters emit from the side their winding faces.
        let front = ng.dot(wo) > 0.0;
        if ng == Vec3::ZERO {
            // A degenerate triangle Embree still reported: face the viewer.
            ng = wo;
        }
        if ng.dot(wo) < 0.0 {
            ng = -ng;
        }
        let mut n = match &mesh.normals {
            Some(normals) => {
                let [n0, n1, n2] = tri.map(|i| normals[i as usize]);
                (w * n0 + u * n1 + v * n2).normalize_or_zero()
            }
            None => ng,
        };
        if n == Vec3::ZERO || !n.is_finite() {
            n = ng;
        }
        if n.dot(ng) < 0.0 {
            n = -n;
        }
        let uv = match &mesh.uvs {
            Some(uvs) => {
                let [t0, t1, t2] = tri.map(|i| uvs[i as usize]);
                w * t0 + u * t1 + v * t2
            }
            None => Vec2::new(u, v),
        };
        let material = &self.scene.materials[mesh.material];
        let mut base = material.albedo_at(uv, &self.scene.textures);
        if let Some(colors) = &mesh.colors {
            let [c0, c1, c2] = tri.map(|i| colors[i as usize]);
            base *= w * c0 + u * c1 + v * c2;
        }
        let pbr = material.pbr.as_ref().map(|m| Pbr::of(m, base, uv, &self.scene.textures));
        let kd = pbr.map_or(base, |p| p.diffuse_albedo());
        SurfacePoint {
            p,
            n,
            ng,
            wo,
            r: reflect(wo, n),
            kd,
            material,
            pbr,
            distance: hit.t * ray.direction.length(),
            emitted: if front || material.emits_both_sides { material.emission } else { Vec3::ZERO },
            epsilon: self.ray_epsilon,
            min_distance: self.ray_epsilon.max(self.distance_clamp),
        }
    }
}

/// Failure to hand the scene to Embree.
#[derive(Debug, thiserror::Error)]
pub enum GeometryError {
    /// A shape's triangles were rejected (malformed generated or loaded mesh).
    #[error("shapes[{shape}]: {source}")]
    Mesh { shape: usize, source: MeshError },
    /// Embree failed (out of memory, unsupported CPU).
    #[error(transparent)]
    Embree(#[from] EmbreeError),
}
