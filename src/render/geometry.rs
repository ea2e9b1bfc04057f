//! The scene's triangles in Embree, and the surface point a hit describes.

use glam::{Vec2, Vec3};

use crate::embree::{self, Device, EmbreeError, Hit, MeshError, Ray, ShadowRay};
use crate::scene::material::{reflect, Material};
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
}

impl<'s> Geometry<'s> {
    pub fn try_new(device: &Device, scene: &'s Scene) -> Result<Self, GeometryError> {
        let mut builder = device.try_new_scene()?;
        let mut mesh_of_geometry = Vec::new();
        for (i, mesh) in scene.meshes.iter().enumerate() {
            let id = builder
                .attach_triangles(&mesh.positions, &mesh.triangles)
                .map_err(|source| GeometryError::Mesh { shape: i, source })?;
            debug_assert_eq!(id as usize, mesh_of_geometry.len(), "Embree assigns ids in order");
            mesh_of_geometry.push(i);
        }
        let embree = builder.commit()?;
        let (lo, hi) = scene.bounds();
        let magnitude = if lo.is_finite() && hi.is_finite() { lo.abs().max(hi.abs()).max_element() } else { 0.0 };
        // The floor keeps the offset positive for a scene of a single point at the origin.
        let ray_epsilon = (magnitude * (1.0 / 65536.0)).max(1e-30);
        Ok(Self { scene, embree, mesh_of_geometry, ray_epsilon, distance_clamp: scene.distance_clamp })
    }

    /// The surface point of a hit along `ray`, with normals facing the ray's origin.
    #[must_use]
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
        let kd = material.albedo_at(uv, &self.scene.textures);
        SurfacePoint {
            p,
            n,
            ng,
            wo,
            r: reflect(wo, n),
            kd,
            material,
            distance: hit.t * ray.direction.length(),
            emitted: if front { material.emission } else { Vec3::ZERO },
            epsilon: self.ray_epsilon,
            min_distance: self.ray_epsilon.max(self.distance_clamp),
        }
    }
}

/// A shading point: position, normals (facing the viewer), outgoing direction.
#[derive(Debug, Clone)]
pub struct SurfacePoint<'s> {
    pub p: Vec3,
    /// Shading normal, unit, on the viewer's side.
    pub n: Vec3,
    /// Geometric normal, unit, on the viewer's side.
    pub ng: Vec3,
    /// Unit direction towards the viewer.
    pub wo: Vec3,
    /// Mirror direction of wo about n.
    pub r: Vec3,
    /// Diffuse albedo here (texture evaluated).
    pub kd: Vec3,
    pub material: &'s Material,
    /// Distance from the ray origin, metres.
    pub distance: f32,
    /// Radiance the surface emits towards the viewer (area-light emitters).
    pub emitted: Vec3,
    pub(crate) epsilon: f32,
    /// The distance below which 1/d^2 is clamped: the ray offset, or the
    /// scene's `render.distance_clamp` when larger.
    pub(crate) min_distance: f32,
}

impl SurfacePoint<'_> {
    /// The material term M = f_r(wi, wo) cos(theta_i) for a unit direction wi
    /// ([LC05] eq. 1); 0 when wi is below the shading or the geometric
    /// surface (light cannot reach this side through the surface).
    #[must_use]
    pub fn material_term(&self, wi: Vec3) -> Vec3 {
        let cos_theta = self.n.dot(wi);
        if cos_theta <= 0.0 || self.ng.dot(wi) <= 0.0 {
            return Vec3::ZERO;
        }
        crate::scene::material::brdf(self.kd, self.material, self.r, wi) * cos_theta
    }

    /// Origin for rays leaving the surface on the viewer's side.
    #[must_use]
    pub fn offset_origin(&self) -> Vec3 {
        self.p + self.ng * self.epsilon
    }

    /// The shadow ray from here to a point light at `y`, stopping `epsilon`
    /// short of it so a light lying on a surface is not hidden by that surface.
    /// `None` when the light is within `epsilon`: nothing can lie between.
    #[must_use]
    pub fn shadow_ray_to(&self, y: Vec3) -> Option<ShadowRay> {
        let origin = self.offset_origin();
        let direction = y - origin;
        let length = direction.length();
        if length <= 2.0 * self.epsilon {
            return None;
        }
        Some(ShadowRay::new(Ray { origin, direction, t_near: 0.0, t_far: 1.0 - self.epsilon / length }))
    }

    /// The shadow ray towards a light at infinity in unit direction `d`.
    #[must_use]
    pub fn shadow_ray_towards(&self, d: Vec3) -> ShadowRay {
        ShadowRay::new(Ray { origin: self.offset_origin(), direction: d, t_near: 0.0, t_far: f32::INFINITY })
    }

    /// The mirror-reflected ray.
    #[must_use]
    pub fn mirror_ray(&self) -> Ray {
        Ray { origin: self.offset_origin(), direction: self.r, t_near: 0.0, t_far: f32::INFINITY }
    }

    /// The distance clamp for point-light singularities: squared distances
    /// below min_distance^2 count as min_distance^2 (the ray offset, or the
    /// scene's larger `render.distance_clamp`), so a light on a surface gives
    /// a large but finite value. Applied identically by every render mode and
    /// by the bounds.
    #[must_use]
    pub fn min_distance_squared(&self) -> f64 {
        // f64: the offset may be as small as 1e-30, whose square underflows f32.
        f64::from(self.min_distance) * f64::from(self.min_distance)
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
