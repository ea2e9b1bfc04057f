//! The scene's triangles in Embree, and the surface point a hit describes.

use std::collections::HashMap;
use std::sync::Arc;

use glam::{Affine3A, Mat3A, Vec2, Vec3, Vec4};

use super::fibre::{self, Fibre};
use super::pbr::{Interface, Pbr};
use super::surface::SurfacePoint;
use crate::embree::{self, AlphaMask, Device, EmbreeError, Hit, MeshError, Ray};
use crate::light::Lights;
use crate::scene::material::{reflect, Material, NormalMap, TexCoords};
use crate::scene::mesh::{Mesh, StrandKind, Strands};
use crate::scene::texture::Texture;
use crate::scene::{PixelFootprint, Scene};

/// Embree's view of a scene plus what shading needs to interpret its hits.
pub struct Geometry<'s> {
    pub scene: &'s Scene,
    pub embree: embree::Scene,
    /// Object index (into `Scene::objects`) of each Embree geometry id.
    object_of_geometry: Vec<usize>,
    /// Each object's placement, for shading its hits.
    placements: Vec<Placing>,
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
        let mut object_of_geometry = Vec::with_capacity(scene.objects.len());
        // One committed scene per instanced mesh, shared by its instances.
        let mut instanced: HashMap<usize, Arc<embree::Scene>> = HashMap::new();
        let placements: Vec<Placing> = scene.objects.iter().map(Placing::of).collect();
        for (i, (object, placing)) in scene.objects.iter().zip(&placements).enumerate() {
            let shape = |source| GeometryError::Mesh { shape: object.mesh, source };
            let mut child = || -> Result<Arc<embree::Scene>, GeometryError> {
                if let Some(child) = instanced.get(&object.mesh) {
                    return Ok(Arc::clone(child));
                }
                let mut child = device.try_new_scene()?;
                attach_mesh(&mut child, scene, object.mesh).map_err(shape)?;
                let child = Arc::new(child.commit()?);
                instanced.insert(object.mesh, Arc::clone(&child));
                Ok(child)
            };
            let id = match placing {
                Placing::World => attach_mesh(&mut builder, scene, object.mesh),
                Placing::Still(p) => builder.attach_instance(&child()?, p.to_world),
                Placing::Moving(motion) => builder.attach_moving_instance(&child()?, &motion.steps),
            }
            .map_err(shape)?;
            debug_assert_eq!(id as usize, object_of_geometry.len(), "Embree assigns ids in order");
            object_of_geometry.push(i);
        }
        let embree = builder.commit()?;
        let (lo, hi) = lights
            .iter()
            .flat_map(|group| {
                group.omni.iter().map(|l| l.position).chain(group.moving.iter().flat_map(|l| [l.start, l.end]))
            })
            .fold(scene.mesh_bounds(), |(lo, hi), p| (lo.min(p), hi.max(p)));
        let magnitude = if lo.is_finite() && hi.is_finite() { lo.abs().max(hi.abs()).max_element() } else { 0.0 };
        // The floor keeps the offset positive for a scene of a single point at the origin.
        let ray_epsilon = (magnitude * (1.0 / 65536.0)).max(1e-30);
        Ok(Self {
            scene,
            embree,
            object_of_geometry,
            placements,
            ray_epsilon,
            distance_clamp: scene.distance_clamp,
            bounds: (lo, hi),
        })
    }

    /// The index into the scene's objects of the object `hit` is on.
    #[must_use]
    pub fn object_of(&self, hit: &Hit) -> usize {
        self.object_of_geometry[hit.geometry as usize]
    }

    /// The index into the scene's meshes of the mesh `hit` is on.
    #[must_use]
    pub fn mesh_of(&self, hit: &Hit) -> usize {
        self.scene.objects[self.object_of(hit)].mesh
    }

    /// The world-space corners of triangle `primitive` of the object `hit`
    /// is on, at time `time` of the shutter, and that object's placement then.
    fn triangle(&self, hit: &Hit, time: f32) -> ([Vec3; 3], Option<Placement>) {
        let object = self.object_of(hit);
        let mesh = &self.scene.meshes[self.scene.objects[object].mesh];
        let corners = mesh.triangles[hit.primitive as usize].map(|i| mesh.positions[i as usize]);
        let placement = self.placement(object, time);
        (placement.map_or(corners, |p| corners.map(|c| p.to_world.transform_point3(c))), placement)
    }

    /// Object `object`'s placement at time `time` of the shutter (`None`
    /// for a mesh in world space).
    fn placement(&self, object: usize, time: f32) -> Option<Placement> {
        match &self.placements[object] {
            Placing::World => None,
            Placing::Still(p) => Some(*p),
            Placing::Moving(motion) => Some(Placement::of(motion.at(time))),
        }
    }

    /// Whether a camera (or mirror) ray passes through `hit`: the back of
    /// a triangle whose material culls back faces (glTF's `doubleSided:
    /// false`).
    #[must_use]
    pub fn culls(&self, ray: &Ray, hit: &Hit) -> bool {
        let mesh = &self.scene.meshes[self.mesh_of(hit)];
        let material = &self.scene.materials[mesh.material];
        // A transmitting solid's inside is where its refracted rays go.
        if !material.culls_back_faces || mesh.strands.is_some() || material.bounds_a_solid() {
            return false;
        }
        let ([p0, p1, p2], _) = self.triangle(hit, ray.time);
        (p1 - p0).cross(p2 - p0).dot(ray.direction) > 0.0
    }

    /// The surface point of a hit along `ray`, in the world, with normals
    /// facing the ray's origin; its textures read unfiltered.
    pub fn surface(&self, ray: &Ray, hit: &Hit) -> SurfacePoint<'s> {
        self.surface_seen(ray, hit, None)
    }

    /// The surface point of a hit along `ray`, its textures filtered over
    /// the `footprint` of a camera's pixel there (docs/design.md §5.3, "MIP
    /// maps"), if one is given.
    pub fn surface_seen(&self, ray: &Ray, hit: &Hit, footprint: Option<&PixelFootprint>) -> SurfacePoint<'s> {
        let mesh = &self.scene.meshes[self.mesh_of(hit)];
        if let Some(strands) = &mesh.strands {
            return self.strand_surface(ray, hit, mesh, strands);
        }
        let tri = mesh.triangles[hit.primitive as usize];
        let (u, v) = (hit.u, hit.v);
        let w = 1.0 - u - v;
        let ([p0, p1, p2], placement) = self.triangle(hit, ray.time);
        // Barycentric interpolation is more accurate than origin + t * direction.
        let p = w * p0 + u * p1 + v * p2;
        let wo = (-ray.direction).normalize();
        let mut ng = crate::util::triangle::normal([p0, p1, p2]);
        // Emitters emit from the side their winding faces.
        let front = ng.dot(wo) > 0.0;
        if ng == Vec3::ZERO {
            // A degenerate triangle Embree still reported: face the viewer.
            ng = wo;
        }
        if ng.dot(wo) < 0.0 {
            ng = -ng;
        }
        let mut uvs = mesh.tex_coords(hit.primitive as usize, u, v);
        if let Some(footprint) = footprint {
            let dp_dxy = footprint.dp_dxy(p, ng, ray.time);
            let corners = mesh.corner_tex_coords(hit.primitive as usize);
            for (set, corners) in corners.into_iter().enumerate() {
                let [dx, dy] = uv_differentials([p0, p1, p2], corners, dp_dxy);
                (uvs.duv_dx[set], uvs.duv_dy[set]) = (dx, dy);
            }
        }
        let material = &self.scene.materials[mesh.material];
        let pbr = material.pbr.as_ref();
        let coat_map = pbr.and_then(|p| p.clearcoat.as_ref()).and_then(|c| c.normal_map.as_ref());
        let (mut n, mut coat_n) = match &mesh.normals {
            Some(normals) => {
                let [n0, n1, n2] = tri.map(|i| normals[i as usize]);
                let n = w * n0 + u * n1 + v * n2;
                let n = placement.map_or(n, |p| p.normal * n).normalize_or_zero();
                // Seen from behind, the whole frame turns to the viewer's
                // side (decided on the interpolated normal, so that a
                // perturbed normal dipping below the surface is not turned).
                let side = if n.dot(ng) < 0.0 { -1.0 } else { 1.0 };
                // The base's normal map, and a clear coat's own (without
                // one the coat keeps the interpolated normal, docs/design.md §5.10).
                let mapped = |map: Option<&NormalMap>| match (map, &mesh.tangents) {
                    (Some(map), Some(tangents)) if n != Vec3::ZERO => {
                        let [t0, t1, t2] = tri.map(|i| tangents[i as usize]);
                        let tangent = (w * t0 + u * t1 + v * t2).truncate();
                        let tangent = placement.map_or(tangent, |p| p.to_world.matrix3 * tangent);
                        perturbed(n, tangent, t0.w, map, uvs.uv[map.set.min(1)], &self.scene.textures)
                    }
                    _ => n,
                };
                (side * mapped(pbr.and_then(|p| p.normal_map.as_ref())), side * mapped(coat_map))
            }
            None => (ng, ng),
        };
        if n == Vec3::ZERO || !n.is_finite() {
            n = ng;
        }
        if coat_n == Vec3::ZERO || !coat_n.is_finite() || pbr.is_none_or(|p| p.clearcoat.is_none()) {
            coat_n = if pbr.is_some_and(|p| p.clearcoat.is_some()) { ng } else { n };
        }
        let colour = mesh.colors.as_ref().map(|colors| {
            let [c0, c1, c2] = tri.map(|i| colors[i as usize]);
            w * c0 + u * c1 + v * c2
        });
        let emits = front || material.emits_both_sides;
        self.shaded(ray, hit, Frame { p, n, ng, coat_n, wo, uvs, colour, emits, back: !front }, material)
    }

    /// The surface point of a hit on curves or spheres (docs/design.md
    /// §4.3). Embree reports the normal of a tube or a sphere (in the
    /// instanced object's space) but a flat ribbon's tangent: the ribbon's
    /// normal is the direction to the viewer made square to it. Colours
    /// are interpolated along the segment; texture coordinates are the
    /// hit's (u along the segment, v across it); strands emit nothing
    /// (they are not light sources, docs/design.md §4.3).
    fn strand_surface(&self, ray: &Ray, hit: &Hit, mesh: &'s Mesh, strands: &Strands) -> SurfacePoint<'s> {
        let placement = self.placement(self.object_of(hit), ray.time);
        let wo = (-ray.direction).normalize();
        let p = ray.origin + hit.t * ray.direction;
        let mut ng = if matches!(strands.kind, StrandKind::Curves { ribbon: true, .. }) {
            let tangent = placement.map_or(hit.ng, |p| p.to_world.matrix3 * hit.ng).normalize_or_zero();
            (wo - tangent * tangent.dot(wo)).normalize_or_zero()
        } else {
            placement.map_or(hit.ng, |p| p.normal * hit.ng).normalize_or_zero()
        };
        if ng == Vec3::ZERO || !ng.is_finite() {
            ng = wo;
        }
        if ng.dot(wo) < 0.0 {
            ng = -ng;
        }
        let uv = Vec2::new(hit.u, hit.v);
        let colour = mesh.colors.as_ref().map(|colors| strands.interpolate(colors, hit.primitive as usize, hit.u));
        let uvs = TexCoords::at([uv, uv]);
        let frame = Frame { p, n: ng, ng, coat_n: ng, wo, uvs, colour, emits: false, back: false };
        let mut sp = self.shaded(ray, hit, frame, &self.scene.materials[mesh.material]);
        if matches!(strands.kind, StrandKind::Curves { ribbon: false, .. }) && !sp.material.unlit {
            let primitive = hit.primitive as usize;
            let to_world = |v: Vec3| placement.map_or(v, |p| p.to_world.matrix3 * v);
            let tangent = strands.tangent(&mesh.positions, primitive, hit.u).map(to_world);
            // The radius in world units: the object's scale across the tube.
            let scale = to_world(hit.ng.normalize_or_zero()).length();
            let radius = strands.interpolate(&strands.radii, primitive, hit.u) * scale;
            make_fibre(&mut sp, tangent, radius);
        }
        sp
    }

    /// The surface point of `frame`, shaded with `material`.
    fn shaded(&self, ray: &Ray, hit: &Hit, frame: Frame, material: &'s Material) -> SurfacePoint<'s> {
        let Frame { p, n, ng, coat_n, wo, uvs, colour, emits, back } = frame;
        let mut base = material.albedo_at(&uvs, &self.scene.textures);
        if let Some(colour) = colour {
            base *= colour;
        }
        // An unlit surface shows its base colour and reflects nothing.
        let pbr =
            material.pbr.as_ref().filter(|_| !material.unlit).map(|m| Pbr::of(m, base, &uvs, &self.scene.textures));
        let kd = if material.unlit { Vec3::ZERO } else { pbr.map_or(base, |p| p.diffuse_albedo()) };
        let distance = hit.t * ray.direction.length();
        // A transmitting dielectric's delta lobes, and what the ray kept
        // crossing its solid from the inside (docs/design.md §5.8).
        let transmitting = material.pbr.as_ref().and_then(|m| m.transmission.as_ref()).zip(pbr);
        let coat_cos_view = coat_n.dot(wo);
        let interface = transmitting.map(|(t, _)| Interface::of(t.thin_walled, back));
        let delta = transmitting.zip(interface).map(|((_, p), i)| p.delta_lobes(n, wo, i, coat_cos_view));
        let interior_transmittance =
            transmitting.filter(|_| back).map_or(Vec3::ONE, |(t, _)| t.interior_transmittance(distance));
        SurfacePoint {
            p,
            n,
            ng,
            coat_n,
            wo,
            r: reflect(wo, n),
            kd,
            material,
            pbr,
            fibre: None,
            fibre_radius: 0.0,
            distance,
            time: ray.time,
            emitted: if material.unlit {
                base
            } else if emits {
                material.emission_at(&uvs, &self.scene.textures)
            } else {
                Vec3::ZERO
            },
            epsilon: self.ray_epsilon,
            min_distance: self.ray_epsilon.max(self.distance_clamp),
            emitter_lobes: super::Lobes::ALL,
            sample: None,
            mirror: match (delta, pbr) {
                (Some(delta), _) => delta.mirror,
                (None, Some(p)) => p.mirror(n.dot(wo), coat_cos_view),
                _ => material.mirror,
            },
            transmission: delta.map_or(Vec3::ZERO, |d| d.transmission),
            transmitted: delta.map_or(-wo, |d| d.transmitted),
            interface,
            interior_transmittance,
        }
    }
}

/// Makes a tube's hit a fibre's (docs/design.md §5.7): the fibre BSDF of
/// the material's colour (a metallic-roughness material's base colour, or
/// the diffuse albedo) and roughness (0.3 for a material without one)
/// takes the place of its lobes and of any mirror.
fn make_fibre(sp: &mut SurfacePoint<'_>, tangent: Option<Vec3>, radius: f32) {
    let colour = sp.pbr.map_or(sp.kd, |p| p.base);
    let roughness = sp.pbr.map_or(fibre::DEFAULT_BETA, |p| p.alpha.sqrt());
    let Some(bsdf) = tangent.and_then(|t| Fibre::new(t, sp.ng, sp.wo, colour, roughness)) else { return };
    sp.fibre = Some(bsdf);
    sp.fibre_radius = if radius.is_finite() { radius.max(0.0) } else { 0.0 };
    sp.pbr = None;
    sp.mirror = Vec3::ZERO;
    sp.transmission = Vec3::ZERO;
    sp.interface = None;
    sp.interior_transmittance = Vec3::ONE;
}

/// How texture coordinates change from one pixel to the next along the
/// film's x and y on a triangle of world corners `p` and texture
/// coordinates `uv`, the point seen moving by `dp_dxy` (pbrt-v4's
/// `Triangle::InteractionFromIntersection` for dp/du and dp/dv, then
/// `SurfaceInteraction::ComputeDifferentials`: the least-squares uv step
/// whose dp/du du + dp/dv dv is nearest each step, each change clamped to
/// ±1e8). A triangle whose uvs or corners are degenerate gets none (its
/// textures read unfiltered).
fn uv_differentials(p: [Vec3; 3], uv: [Vec2; 3], dp_dxy: [Vec3; 2]) -> [Vec2; 2] {
    let (duv02, duv12) = (uv[0] - uv[2], uv[1] - uv[2]);
    let (dp02, dp12) = (p[0] - p[2], p[1] - p[2]);
    let determinant = duv02.x * duv12.y - duv02.y * duv12.x;
    let dpdu = (duv12.y * dp02 - duv02.y * dp12) / determinant;
    let dpdv = (duv02.x * dp12 - duv12.x * dp02) / determinant;
    let (a00, a01, a11) = (dpdu.dot(dpdu), dpdu.dot(dpdv), dpdv.dot(dpdv));
    let inverse = 1.0 / (a00 * a11 - a01 * a01);
    if !(inverse.is_finite() && dpdu.is_finite() && dpdv.is_finite()) {
        return [Vec2::ZERO; 2];
    }
    dp_dxy.map(|step| {
        let (b0, b1) = (dpdu.dot(step), dpdv.dot(step));
        let duv = Vec2::new(a11 * b0 - a01 * b1, a00 * b1 - a01 * b0) * inverse;
        let clamp = |x: f32| if x.is_finite() { x.clamp(-1e8, 1e8) } else { 0.0 };
        Vec2::new(clamp(duv.x), clamp(duv.y))
    })
}

/// Where a hit is and how it faces: what shading needs of the geometry.
struct Frame {
    p: Vec3,
    /// The shading normal and the geometric one, both facing `wo`, and a
    /// clear coat's shading normal (`SurfacePoint::coat_n`).
    n: Vec3,
    ng: Vec3,
    coat_n: Vec3,
    /// Towards the ray's origin, unit length.
    wo: Vec3,
    uvs: TexCoords,
    /// Interpolated vertex colours, multiplying the base colour.
    colour: Option<Vec3>,
    /// Whether the side seen is one that emits.
    emits: bool,
    /// Whether the side seen is the back of the winding (the inside of
    /// a closed mesh whose triangles wind outwards).
    back: bool,
}

/// How an object's hits are placed in the world.
enum Placing {
    /// Its mesh is in world space.
    World,
    /// An instance that stands still.
    Still(Placement),
    /// A moving object: from its mesh's space to the world's at each time
    /// (docs/design.md §13.6), the steps Embree is given.
    Moving(crate::scene::object::Motion),
}

impl Placing {
    /// How `object` is placed: its motion's steps after its own transform.
    fn of(object: &crate::scene::object::Object) -> Self {
        match (object.transform, &object.motion) {
            (None, None) => Self::World,
            (Some(t), None) => Self::Still(Placement::of(t)),
            (t, Some(motion)) => Self::Moving(crate::scene::object::Motion {
                steps: motion.steps.iter().map(|s| *s * t.unwrap_or(Affine3A::IDENTITY)).collect(),
            }),
        }
    }
}

/// An instance's map from its mesh's space to the world's, and the
/// inverse transpose that carries normals (docs/design.md §4.1).
#[derive(Clone, Copy)]
struct Placement {
    to_world: Affine3A,
    normal: Mat3A,
}

impl Placement {
    fn of(to_world: Affine3A) -> Self {
        Self { to_world, normal: to_world.matrix3.inverse().transpose() }
    }
}

/// Attaches mesh `mesh` of `scene` to `builder` as it is, with its cut-out.
fn attach_mesh(
    builder: &mut embree::SceneBuilder,
    scene: &Scene,
    mesh: usize,
) -> Result<embree::GeometryId, MeshError> {
    let mesh = &scene.meshes[mesh];
    if let Some(strands) = &mesh.strands {
        let points: Vec<Vec4> = mesh.positions.iter().zip(&strands.radii).map(|(p, &r)| p.extend(r)).collect();
        return match &strands.kind {
            StrandKind::Spheres => builder.attach_spheres(&points),
            StrandKind::Curves { basis, ribbon, segments } => {
                let shape = if *ribbon { embree::CurveShape::Flat } else { embree::CurveShape::Round };
                builder.attach_curves(*basis, shape, &points, segments)
            }
        };
    }
    let mask = scene.materials[mesh.material].cutout.as_ref().map(|c| AlphaMask {
        uvs: mesh.uvs.clone().unwrap_or_else(|| vec![Vec2::ZERO; mesh.positions.len()]),
        alpha: c.alpha.clone(),
        width: c.width,
        height: c.height,
        transform: c.transform,
        cutoff: c.cutoff,
    });
    builder.attach_masked_triangles(&mesh.positions, &mesh.triangles, mask)
}

/// The shading normal `n` perturbed by a tangent-space normal map (glTF
/// 2.0's normalTexture): the texel's (2 t - 1), x and y scaled by the map's
/// scale, in the frame (tangent, w (n x tangent), n) with the tangent made
/// orthogonal to n. `n` itself where the frame or the result degenerates.
fn perturbed(n: Vec3, tangent: Vec3, w: f32, map: &NormalMap, uv: Vec2, textures: &[Texture]) -> Vec3 {
    let t = (tangent - n * n.dot(tangent)).normalize_or_zero();
    if t == Vec3::ZERO {
        return n;
    }
    let b = n.cross(t) * w.signum();
    let texel = textures[map.texture].lookup(map.transform.transform_point2(uv)) * 2.0 - Vec3::ONE;
    let local = Vec3::new(texel.x * map.scale, texel.y * map.scale, texel.z);
    let perturbed = (t * local.x + b * local.y + n * local.z).normalize_or_zero();
    if perturbed == Vec3::ZERO || !perturbed.is_finite() {
        n
    } else {
        perturbed
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

#[cfg(test)]
mod tests {
    use glam::Affine2;

    use super::*;

    /// On a triangle whose texture coordinates are (x / 2, z / 4), a step
    /// of the point seen is that step in uv; a step off the plane counts
    /// by its part in the plane; degenerate uvs give no footprint.
    #[test]
    fn uv_differentials_are_the_steps_in_texture_space() {
        let p = [Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 4.0)];
        let uv = [Vec2::ZERO, Vec2::X, Vec2::Y];
        let [dx, dy] = uv_differentials(p, uv, [Vec3::new(0.2, 0.0, 0.0), Vec3::new(0.1, 3.0, 0.4)]);
        assert!((dx - Vec2::new(0.1, 0.0)).length() < 1e-6, "{dx}");
        assert!((dy - Vec2::new(0.05, 0.1)).length() < 1e-6, "{dy}");
        let flat = [Vec2::ZERO, Vec2::X, Vec2::X * 2.0];
        assert_eq!(uv_differentials(p, flat, [Vec3::X, Vec3::Z]), [Vec2::ZERO; 2]);
    }

    /// A map of one texel encoding the tangent-space normal `local`.
    fn map_of(local: Vec3, scale: f32) -> (NormalMap, Vec<Texture>) {
        let texel = (local + Vec3::ONE) * 0.5;
        let map = NormalMap { texture: 0, transform: Affine2::IDENTITY, scale, set: 0 };
        (map, vec![Texture::from_texels(1, 1, vec![texel])])
    }

    /// glTF's convention: +X along the tangent (increasing u), +Y along w (n
    /// x tangent) (up the texture), +Z the normal; x and y scaled.
    #[test]
    fn a_normal_map_tilts_the_normal_in_the_tangent_frame() {
        let (n, t) = (Vec3::Z, Vec3::X);
        let close = |a: Vec3, b: Vec3| (a - b).length() < 1e-5;
        let at = |local: Vec3, w: f32, scale: f32| {
            let (map, textures) = map_of(local, scale);
            perturbed(n, t, w, &map, Vec2::ZERO, &textures)
        };
        assert!(close(at(Vec3::Z, 1.0, 1.0), n), "a flat texel keeps the normal");
        assert!(close(at(Vec3::new(0.6, 0.0, 0.8), 1.0, 1.0), Vec3::new(0.6, 0.0, 0.8)));
        assert!(close(at(Vec3::new(0.0, 0.6, 0.8), 1.0, 1.0), Vec3::new(0.0, 0.6, 0.8)), "+Y is n x t");
        assert!(close(at(Vec3::new(0.0, 0.6, 0.8), -1.0, 1.0), Vec3::new(0.0, -0.6, 0.8)), "w flips +Y");
        assert!(close(at(Vec3::new(0.6, 0.0, 0.8), 1.0, 0.0), n), "scale 0 flattens the map");
        let half = Vec3::new(0.3, 0.0, 0.8).normalize();
        assert!(close(at(Vec3::new(0.6, 0.0, 0.8), 1.0, 0.5), half), "scale 0.5 halves x");
        // A tangent not orthogonal to n is made so first.
        let (map, textures) = map_of(Vec3::new(0.6, 0.0, 0.8), 1.0);
        assert!(close(
            perturbed(n, Vec3::new(1.0, 0.0, 1.0), 1.0, &map, Vec2::ZERO, &textures),
            Vec3::new(0.6, 0.0, 0.8)
        ));
        // A tangent along n has no frame: the normal stays.
        assert_eq!(perturbed(n, n, 1.0, &map, Vec2::ZERO, &textures), n);
    }
}
