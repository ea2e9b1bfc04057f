//! One light's contribution at a shading point ([LC05] eq. 1: M * G * V * I;
//! docs/design.md §5), evaluated four lights at a time (f32x4 lanes), with
//! the shadow ray that decides its visibility (traced by `evaluate`).
//!
//! Every light is evaluated by [`LightEvaluator::terms`], whatever the caller
//! (exact renderer, cut, benchmark), so every mode agrees bit for bit on a
//! light's M * G. Each lane does the same f32 operations in the same order
//! as one light at a time would, and G and the products are f64 (an
//! intensity up to 1e30 W/sr times G up to 1 / epsilon^2 overflows f32).

use std::f32::consts::PI;

use glam::{DVec3, Vec3};
use wide::{f32x4, f64x4, CmpEq, CmpLe};

use super::fibre::Fibre;
use super::lobes::Lobes;
use super::pbr::PbrLanes;
use super::surface::SurfacePoint;
use crate::embree::{Ray, ShadowRay};
use crate::light::{point_on_triangle, triangle_corners, Light, LightKind, SpotLight, TreeLight};
use crate::scene::material::phong_normalisation;
use crate::util::sampling::{mix64, PixelSample};
use crate::util::simd::{dot3, pow, splat3, V3};
use crate::util::triangle;

/// Up to four lights of one kind, one per lane: `point` is the position of
/// an omni, oriented or spot light, the unit direction towards a
/// directional one; `normal` is an oriented light's normal or a spot's
/// direction; `spread` a spot's cosines of its inner and outer angles;
/// `edges` an area light's triangle's edges (its `point` is the
/// triangle's centroid). Lanes past `count` are ignored.
#[derive(Debug, Clone, Copy, Default)]
pub struct Lanes {
    pub point: [[f32; 4]; 3],
    pub normal: [[f32; 4]; 3],
    pub spread: [[f32; 4]; 2],
    pub edges: [[[f32; 4]; 3]; 2],
    pub count: usize,
}

impl Lanes {
    /// Puts a light (a tree leaf's data) in the next lane; false when all
    /// four are taken.
    #[inline(always)]
    pub fn push(&mut self, light: &TreeLight) -> bool {
        let [e0, e1] = light.edges;
        self.put(light.point.to_array(), light.normal.to_array(), [e0.to_array(), e1.to_array()], light.spread)
    }

    /// Puts lane `lane` of `from` in the next lane; false when all four are
    /// taken. Each lane is evaluated on its own, so a light gives the same
    /// value in any lane of any quad.
    #[inline(always)]
    pub fn push_lane(&mut self, from: &Lanes, lane: usize) -> bool {
        let at = |v: &[[f32; 4]; 3]| v.map(|axis| axis[lane]);
        let spread = from.spread.map(|s| s[lane]);
        self.put(at(&from.point), at(&from.normal), [at(&from.edges[0]), at(&from.edges[1])], spread)
    }

    /// Writes one light's data in the next lane; false when all four are
    /// taken.
    #[inline(always)]
    fn put(&mut self, point: [f32; 3], normal: [f32; 3], edges: [[f32; 3]; 2], spread: [f32; 2]) -> bool {
        let k = self.count;
        if k >= 4 {
            return false;
        }
        for axis in 0..3 {
            self.point[axis][k] = point[axis];
            self.normal[axis][k] = normal[axis];
            self.edges[0][axis][k] = edges[0][axis];
            self.edges[1][axis][k] = edges[1][axis];
        }
        self.spread[0][k] = spread[0];
        self.spread[1][k] = spread[1];
        self.count = k + 1;
        true
    }

    /// The lanes' points, each area light's drawn on its triangle as seen
    /// from `p`, with the numbers: for a camera path's point, point `index`
    /// of its pixel's stratified set, rotated by a shift of the pixel and
    /// the triangle's centroid (`PixelSample::point`); otherwise from `key`
    /// and the centroid. The same shading point draws the same point on a
    /// given triangle in every mode (docs/design.md §6.1). A triangle whose
    /// front faces `p` and whose solid angle is within
    /// [`triangle::SOLID_ANGLE_DRAWN`] is drawn uniformly in that solid
    /// angle, and its lane's second value is the solid angle over the
    /// triangle's area (the G that replaces cos / d^2); any other is drawn
    /// uniformly by area (None).
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // lane k of five arrays
    fn points_on_triangles(&self, p: Vec3, key: u64, sample: Option<PixelSample>) -> ([[f32; 4]; 3], [Option<f64>; 4]) {
        let mut point = self.point;
        let mut by_solid_angle = [None; 4];
        for k in 0..self.count {
            let edge = |e: usize| Vec3::new(self.edges[e][0][k], self.edges[e][1][k], self.edges[e][2][k]);
            let edges = [edge(0), edge(1)];
            if edges == [Vec3::ZERO; 2] {
                continue;
            }
            let centroid = Vec3::new(point[0][k], point[1][k], point[2][k]);
            let bits = centroid.to_array().map(|c| u64::from(c.to_bits()));
            let u = match sample {
                // Stratified over the pixel's samples, a shift per part.
                Some(sample) => sample.point(mix64(bits[0] ^ (bits[1] << 32)) ^ bits[2]),
                None => {
                    let h = mix64(mix64(key ^ bits[0] ^ (bits[1] << 32)) ^ bits[2]);
                    [(h >> 40) as f32 * UNIT_24, ((h >> 16) & 0xff_ffff) as f32 * UNIT_24]
                }
            };
            let normal = Vec3::new(self.normal[0][k], self.normal[1][k], self.normal[2][k]);
            let facing = normal.dot(p - centroid) > 0.0;
            let corners = triangle_corners(centroid, edges).map(|c| c.as_dvec3());
            let numbers = u.map(f64::from);
            let drawn = facing.then(|| triangle::sample_spherical_triangle(p.as_dvec3(), corners, numbers)).flatten();
            let at = match drawn {
                Some(draw) => {
                    let area = 0.5 * edges[0].as_dvec3().cross(edges[1].as_dvec3()).length();
                    by_solid_angle[k] = Some(draw.solid_angle / area);
                    draw.point.as_vec3()
                }
                None => point_on_triangle(centroid, edges, u),
            };
            for axis in 0..3 {
                point[axis][k] = at[axis];
            }
        }
        (point, by_solid_angle)
    }
}

/// 2^-24: 24 random bits to a number in [0, 1).
const UNIT_24: f32 = 1.0 / 16_777_216.0;

/// One light's M * G per unit intensity (V not included), and the shadow
/// ray that decides its visibility: None when the light is within the ray
/// offset (nothing can lie between). The ray is meaningless when the term
/// is zero (no ray need be cast).
#[derive(Debug, Clone, Copy, Default)]
pub struct LightTerm {
    pub term: DVec3,
    pub ray: Option<ShadowRay>,
}

/// A shading point's material term M = f_r(wi, wo) cos(theta_i) in four
/// lanes ([LC05] eq. 1; docs/design.md §5.3): what every light's
/// evaluation and the scalar BSDF (`shading::bsdf`) compute it with.
#[derive(Clone, Copy)]
pub struct MaterialLanes {
    n: V3,
    ng: V3,
    r: V3,
    wo: V3,
    /// A metallic-roughness material's BRDF (instead of diffuse + Phong).
    pbr: Option<PbrLanes>,
    /// A fibre's BSDF (instead of any surface's), evaluated lane by lane.
    fibre: Option<Fibre>,
    /// k_d / pi, per channel.
    diffuse: V3,
    /// k_s (n + 2) / (2 pi), and the exponent n, of a Phong lobe.
    phong: Option<(Vec3, f32, f32)>,
}

impl MaterialLanes {
    #[must_use]
    #[inline(always)]
    pub fn new(sp: &SurfacePoint<'_>) -> Self {
        let m = sp.material;
        Self {
            n: splat3(sp.n),
            ng: splat3(sp.ng),
            r: splat3(sp.r),
            wo: splat3(sp.wo),
            pbr: sp.pbr.map(|p| PbrLanes::new(&p, sp.n.dot(sp.wo), sp.coat_n, sp.coat_cos_view())),
            fibre: sp.fibre,
            diffuse: splat3(sp.kd * (1.0 / PI)),
            phong: m.has_specular().then(|| (m.specular, phong_normalisation(m.exponent), m.exponent)),
        }
    }

    /// M = f_r(wi, wo) cos(theta_i) of `lobes` for unit directions wi, per
    /// channel ([LC05] eq. 1); 0 when wi is below the shading or the
    /// geometric surface. A fibre has no below: its f cos is every lobe's
    /// towards any direction (docs/design.md §5.7).
    #[inline(always)]
    pub fn term(&self, wi: &V3, lobes: Lobes) -> V3 {
        let zero = f32x4::ZERO;
        if let Some(fibre) = &self.fibre {
            return fibre_lanes(fibre, wi, lobes);
        }
        let cos_theta = dot3(&self.n, wi);
        let below = cos_theta.cmp_le(zero) | dot3(&self.ng, wi).cmp_le(zero);
        if let Some(pbr) = &self.pbr {
            let f = pbr.f_cos(&self.n, &self.wo, wi, cos_theta, lobes);
            return [below.blend(zero, f[0]), below.blend(zero, f[1]), below.blend(zero, f[2])];
        }
        let mut f = if lobes.diffuse { self.diffuse } else { [zero; 3] };
        if let Some((specular, normalisation, exponent)) = self.phong.filter(|_| lobes.glossy) {
            let cos_alpha = dot3(&self.r, wi).fast_max(zero);
            let lobe = f32x4::splat(normalisation) * pow(cos_alpha, exponent);
            f = [
                f[0] + f32x4::splat(specular.x) * lobe,
                f[1] + f32x4::splat(specular.y) * lobe,
                f[2] + f32x4::splat(specular.z) * lobe,
            ];
        }
        [below.blend(zero, f[0] * cos_theta), below.blend(zero, f[1] * cos_theta), below.blend(zero, f[2] * cos_theta)]
    }
}

/// A fibre's f cos towards four directions, one lane at a time (its
/// lobes' transcendentals have no lane-wise form here). Its lobes are all
/// glossy and diffuse at once: either asks for all of them.
#[inline(never)]
fn fibre_lanes(fibre: &Fibre, wi: &V3, lobes: Lobes) -> V3 {
    if !(lobes.diffuse || lobes.glossy) {
        return [f32x4::ZERO; 3];
    }
    let [x, y, z] = wi.map(f32x4::to_array);
    let f: [Vec3; 4] = std::array::from_fn(|k| fibre.f_cos(Vec3::new(x[k], y[k], z[k])));
    [f32x4::new(f.map(|v| v.x)), f32x4::new(f.map(|v| v.y)), f32x4::new(f.map(|v| v.z))]
}

/// Keeps the points drawn on area lights' triangles apart from other
/// streams keyed by a position.
const TRIANGLE_STREAM: u64 = 0x7a1a_9e5c_0f3d_b2e1;

/// A shading point prepared for evaluating lights four at a time.
pub struct LightEvaluator<'a, 'p> {
    sp: &'a SurfacePoint<'p>,
    p: V3,
    material: MaterialLanes,
    /// Where shadow rays start (lifted off the surface).
    origin: V3,
    origin_point: Vec3,
}

impl<'a, 'p> LightEvaluator<'a, 'p> {
    #[must_use]
    #[inline(always)]
    pub fn new(sp: &'a SurfacePoint<'p>) -> Self {
        let origin = sp.offset_origin();
        Self { sp, p: splat3(sp.p), material: MaterialLanes::new(sp), origin: splat3(origin), origin_point: origin }
    }

    /// The material term of a light of `kind` in directions `wi`: every
    /// lobe, but for the stand-ins of continuous emitters (area lights'
    /// points, the environment's directions) the lobes the shading point
    /// lights them with (`SurfacePoint::emitter_lobes`).
    #[inline(always)]
    fn material(&self, kind: LightKind, wi: &V3) -> V3 {
        let lobes = if kind.stands_in_for_emitter() { self.sp.emitter_lobes } else { Lobes::ALL };
        self.material.term(wi, lobes)
    }

    /// M * G per unit intensity of the lanes' lights, and their shadow rays.
    #[must_use]
    pub fn terms(&self, kind: LightKind, lanes: &Lanes) -> [LightTerm; 4] {
        let mut out = [LightTerm::default(); 4];
        let mut sink = |k: usize, term: DVec3, ray: Option<ShadowRay>| out[k] = LightTerm { term, ray };
        self.each_term(kind, lanes, &[DVec3::ONE; 4], &mut sink);
        out
    }

    /// Calls `sink(lane, value, ray)` for each of the lanes' lights, in lane
    /// order: value = M * G * `weights[lane]` (V not included), and the
    /// shadow ray that decides its visibility (None within the ray offset:
    /// nothing can lie between). A light whose value is 0 gets no ray.
    #[inline(always)]
    pub fn each_term(
        &self,
        kind: LightKind,
        lanes: &Lanes,
        weights: &[DVec3; 4],
        sink: &mut impl FnMut(usize, DVec3, Option<ShadowRay>),
    ) {
        let point = [f32x4::new(lanes.point[0]), f32x4::new(lanes.point[1]), f32x4::new(lanes.point[2])];
        if kind.at_infinity() {
            let m = self.material(kind, &point);
            let m = [m[0].to_array(), m[1].to_array(), m[2].to_array()];
            for (k, w) in weights.iter().enumerate().take(lanes.count) {
                let term = DVec3::new(f64::from(m[0][k]), f64::from(m[1][k]), f64::from(m[2][k]));
                let value = term * *w;
                let ray = (value != DVec3::ZERO).then(|| {
                    let direction = Vec3::new(lanes.point[0][k], lanes.point[1][k], lanes.point[2][k]);
                    ShadowRay::new(Ray {
                        origin: self.origin_point,
                        direction,
                        t_near: self.sp.fibre_exit(direction),
                        t_far: f32::INFINITY,
                        time: self.sp.time,
                    })
                });
                sink(k, value, ray);
            }
            return;
        }
        let (point, by_solid_angle) = if kind == LightKind::Area {
            // The shading point's key for the points drawn on triangles:
            // its position's bits, mixed (here, not per shading point: only
            // area lights need it).
            let bits = self.sp.p.to_array().map(|c| u64::from(c.to_bits()));
            let key = mix64(mix64(bits[0] ^ (bits[1] << 32) ^ TRIANGLE_STREAM) ^ bits[2]);
            let ([x, y, z], by_solid_angle) = lanes.points_on_triangles(self.sp.p, key, self.sp.sample);
            ([f32x4::new(x), f32x4::new(y), f32x4::new(z)], by_solid_angle)
        } else {
            (point, [None; 4])
        };
        let d = [point[0] - self.p[0], point[1] - self.p[1], point[2] - self.p[2]];
        let d2 = dot3(&d, &d);
        let s = d2.sqrt();
        let wi = [d[0] / s, d[1] / s, d[2] / s];
        let m = self.material(kind, &wi);
        // The cosine at an oriented light: its normal against -wi; a spot's
        // falloff at the cosine between its direction and -wi.
        let emitted = kind.has_cone().then(|| {
            let normal = [f32x4::new(lanes.normal[0]), f32x4::new(lanes.normal[1]), f32x4::new(lanes.normal[2])];
            let cosine = dot3(&normal, &[-wi[0], -wi[1], -wi[2]]);
            if kind == LightKind::Spot {
                let cosine = cosine.to_array();
                std::array::from_fn(|k| SpotLight::falloff(cosine[k], lanes.spread[0][k], lanes.spread[1][k]))
            } else {
                cosine.fast_max(f32x4::ZERO).to_array()
            }
        });
        // G = 1 / max(d^2, clamp^2) (times the emitter's cosine), in f64:
        // an intensity up to 1e30 W/sr times G up to 1 / epsilon^2
        // overflows f32. Four lanes at once, the same operations as one at
        // a time.
        let widen = |v: f32x4| f64x4::from(v.to_array().map(f64::from));
        let clamp = self.sp.min_distance_squared();
        let mut g = f64x4::ONE / widen(d2).max(f64x4::splat(clamp));
        if let Some(cosine) = emitted {
            let cosine = cosine.map(f64::from);
            g *= f64x4::from(cosine);
            // A triangle drawn by solid angle: G is its solid angle over its
            // area (the estimate L_e f cos Omega), held within the distance
            // clamp's cos / clamp^2 as the bounds assume (docs/design.md §6.1).
            if by_solid_angle.iter().any(Option::is_some) {
                let mut each = g.to_array();
                for (k, weight) in by_solid_angle.iter().enumerate() {
                    if let Some(weight) = weight {
                        each[k] = weight.min(cosine[k] / clamp);
                    }
                }
                g = f64x4::from(each);
            }
        }
        let terms = [widen(m[0]) * g, widen(m[1]) * g, widen(m[2]) * g].map(f64x4::to_array);
        // The shadow ray from the lifted origin, stopping epsilon short of the light.
        let direction = [point[0] - self.origin[0], point[1] - self.origin[1], point[2] - self.origin[2]];
        let length = dot3(&direction, &direction).sqrt();
        let epsilon = f32x4::splat(self.sp.epsilon);
        let t_far = (f32x4::ONE - epsilon / length).to_array();
        let too_close = length.cmp_le(epsilon + epsilon).to_array();
        // At the light the direction is undefined and it contributes
        // nothing (docs/design.md §5.4); nor does a light M is 0 for.
        let nothing = (d2.cmp_eq(f32x4::ZERO)
            | (m[0].cmp_eq(f32x4::ZERO) & m[1].cmp_eq(f32x4::ZERO) & m[2].cmp_eq(f32x4::ZERO)))
        .to_array();
        let direction = [direction[0].to_array(), direction[1].to_array(), direction[2].to_array()];
        for (k, w) in weights.iter().enumerate().take(lanes.count) {
            if nothing[k] != 0.0 {
                sink(k, DVec3::ZERO, None);
                continue;
            }
            let value = DVec3::new(terms[0][k], terms[1][k], terms[2][k]) * *w;
            let direction = Vec3::new(direction[0][k], direction[1][k], direction[2][k]);
            // Past a fibre's own tube (a light inside it: nothing between).
            let t_near = self.sp.fibre_exit(direction);
            let ray = (value != DVec3::ZERO && too_close[k] == 0.0 && t_near < t_far[k]).then(|| {
                ShadowRay::new(Ray {
                    origin: self.origin_point,
                    direction,
                    t_near,
                    t_far: t_far[k],
                    time: self.sp.time,
                })
            });
            sink(k, value, ray);
        }
    }
}

/// The light's intensity (W/sr), or a directional light's irradiance (W/m^2).
#[must_use]
pub fn light_intensity(light: &Light) -> Vec3 {
    match light {
        Light::Omni(l) => l.intensity,
        Light::Area(l) => l.intensity,
        Light::Oriented(l) => l.intensity,
        Light::Directional(l) | Light::Environment(l) => l.irradiance,
        Light::Spot(l) => l.intensity,
    }
}

/// M * G of one light for the shading point, per unit intensity (V and the
/// light's own intensity not included), in f64.
#[must_use]
pub fn light_term(light: &Light, sp: &SurfacePoint<'_>) -> DVec3 {
    light_sample(light, sp, Vec3::ONE).map_or(DVec3::ZERO, |(value, _)| value)
}

/// One light's unoccluded contribution M * G * `intensity` at `sp` and the
/// shadow ray that decides its visibility: None when the contribution is
/// zero (no ray is cast), and no ray when the light is within the ray offset.
#[must_use]
pub fn light_sample(light: &Light, sp: &SurfacePoint<'_>, intensity: Vec3) -> Option<(DVec3, Option<ShadowRay>)> {
    let mut lanes = Lanes::default();
    lanes.push(&TreeLight::of(light));
    let [found, ..] = LightEvaluator::new(sp).terms(light.kind(), &lanes);
    let value = found.term * intensity.as_dvec3();
    (value != DVec3::ZERO).then_some((value, found.ray))
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI as PI64;

    use glam::DVec3;

    use super::*;
    use crate::light::emitters::{sample_area_light, EmitterTriangle};
    use crate::light::AreaLight;
    use crate::scene::material::{Albedo, Material};

    /// A white Lambertian floor point at `p` (normal +z, seen from above).
    fn floor_point(material: &Material, p: Vec3) -> SurfacePoint<'_> {
        SurfacePoint::bare(material, p, Vec3::Z, Vec3::Z, Vec3::ONE)
    }

    /// Lambert's irradiance at `p` (normal +z) from a polygon of unit
    /// radiance above p's plane: E = 1/2 |sum_i Theta_i (n . unit(r_i x r_i+1))|.
    fn polygon_irradiance(p: DVec3, corners: &[DVec3]) -> f64 {
        let r: Vec<DVec3> = corners.iter().map(|c| (*c - p).normalize()).collect();
        let sum: f64 = (0..r.len())
            .map(|i| {
                let (a, b) = (r[i], r[(i + 1) % r.len()]);
                a.dot(b).clamp(-1.0, 1.0).acos() * DVec3::Z.dot(a.cross(b).normalize())
            })
            .sum();
        0.5 * sum.abs()
    }

    /// A 1 m square of unit radiance 0.1 m above the floor (z = 0), facing
    /// it, as its 18 triangle lights (0.33 m across), and its corners.
    fn square_of_triangle_lights() -> (Vec<AreaLight>, [DVec3; 4]) {
        let corners = [Vec3::new(-0.5, -0.5, 0.1), Vec3::new(-0.5, 0.5, 0.1), Vec3::new(0.5, 0.5, 0.1)];
        let quad = [
            EmitterTriangle { p: [corners[0], corners[1], corners[2]] },
            EmitterTriangle { p: [corners[0], corners[2], Vec3::new(0.5, -0.5, 0.1)] },
        ];
        let square = [[-0.5, -0.5], [-0.5, 0.5], [0.5, 0.5], [0.5, -0.5]].map(|[x, y]| DVec3::new(x, y, 0.1));
        (sample_area_light(&quad, Vec3::ONE, 16, 0.0), square)
    }

    /// The irradiance at `sp` from `lights` (unit radiance): pi times the
    /// floor's radiance under them with albedo 1.
    fn irradiance_at(lights: &[AreaLight], sp: &SurfacePoint<'_>) -> f64 {
        lights.iter().map(|l| light_term(&Light::Area(*l), sp).x * f64::from(l.intensity.x) * PI64).sum()
    }

    /// A floor 0.1 m under a 1 m square of unit radiance split into 18
    /// triangles (0.33 m across, 3 times the height): along a line under
    /// it, the irradiance averaged over 32,768 shading points at each place
    /// (each draws its own point on every triangle) is the square's in
    /// closed form within 0.5% (0.11%; 0.65% when the points were drawn by
    /// area), and one shading point's within 30% (19%, where a draw by area
    /// is 118% off: the triangles are drawn by solid angle). The same
    /// triangles as fixed points at their centroids (what area lights were
    /// before) are off by over 20% there: the floor sees each point as a
    /// spike.
    #[test]
    fn triangle_lights_close_to_a_surface_give_the_polygons_irradiance() {
        let (triangles, square) = square_of_triangle_lights();
        assert_eq!(triangles.len(), 18);
        assert!(triangles.iter().all(|t| t.normal.z < -0.99), "the square faces the floor");
        let points: Vec<AreaLight> = triangles.iter().map(|t| AreaLight { edges: [Vec3::ZERO; 2], ..*t }).collect();
        let material = Material::diffuse("white", Albedo::Constant(Vec3::ONE));
        let irradiance = |lights: &[AreaLight], at: Vec3, jitter: usize| -> f64 {
            let sum: f64 = (0..jitter)
                .map(|k| {
                    // Shading points k units in the last place apart (within
                    // 40 um): each its own key.
                    let y = f32::from_bits(at.y.to_bits() + k as u32);
                    irradiance_at(lights, &floor_point(&material, Vec3::new(at.x, y, at.z)))
                })
                .sum();
            sum / jitter as f64
        };
        let (mut worst_triangles, mut worst_points, mut worst_one) = (0.0f64, 0.0f64, 0.0f64);
        for i in 0..21 {
            let at = Vec3::new(-0.4 + 0.04 * i as f32, 0.013, 0.0);
            let want = polygon_irradiance(at.as_dvec3(), &square);
            worst_triangles = worst_triangles.max((irradiance(&triangles, at, 1 << 15) / want - 1.0).abs());
            worst_points = worst_points.max((irradiance(&points, at, 1) / want - 1.0).abs());
            // One shading point, one point drawn per triangle.
            worst_one = worst_one.max((irradiance(&triangles, at, 1) / want - 1.0).abs());
        }
        eprintln!(
            "worst: triangles {:.2}%, one shading point {:.2}%, fixed points {:.1}%",
            100.0 * worst_triangles,
            100.0 * worst_one,
            100.0 * worst_points
        );
        assert!(worst_triangles < 0.005, "triangles: {:.2}% off", 100.0 * worst_triangles);
        assert!(worst_one < 0.3, "one shading point: {:.2}% off", 100.0 * worst_one);
        assert!(worst_points > 0.2, "fixed points: only {:.2}% off", 100.0 * worst_points);
    }

    /// Points drawn on triangle lights by a camera path's points are
    /// stratified over the pixel's samples (`PixelSample::point`): under the
    /// square above, a pixel's 16 samples at one place average to the
    /// closed-form irradiance over 4,096 pixels (each sample's point is
    /// uniform on its triangle), and the pixels' spread is well below that
    /// of 16 independent draws (a pixel key per sample), which it would
    /// equal if the strata were dropped: 0.061 of it (0.41 when the points
    /// were drawn by area; the draw by solid angle keeps the strata).
    #[test]
    fn points_on_triangle_lights_are_stratified_over_a_pixels_samples() {
        let (triangles, square) = square_of_triangle_lights();
        let material = Material::diffuse("white", Albedo::Constant(Vec3::ONE));
        const PIXELS: u64 = 4096;
        const SPP: u32 = 16;
        let at = Vec3::new(0.13, 0.21, 0.0);
        let want = polygon_irradiance(at.as_dvec3(), &square);
        // Each pixel's mean irradiance over its samples, and the pixels'
        // mean and variance.
        let pixels = |stratified: bool| {
            let means: Vec<f64> = (0..PIXELS)
                .map(|pixel| {
                    let sum: f64 = (0..SPP)
                        .map(|index| {
                            let sample = if stratified {
                                PixelSample { pixel: mix64(pixel), index, count: SPP }
                            } else {
                                PixelSample { pixel: mix64(pixel * 64 + u64::from(index)), index: 0, count: 1 }
                            };
                            irradiance_at(
                                &triangles,
                                &SurfacePoint { sample: Some(sample), ..floor_point(&material, at) },
                            )
                        })
                        .sum();
                    sum / f64::from(SPP)
                })
                .collect();
            let mean = means.iter().sum::<f64>() / PIXELS as f64;
            let variance = means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (PIXELS - 1) as f64;
            (mean, variance)
        };
        let (stratified, independent) = (pixels(true), pixels(false));
        for (mean, variance) in [stratified, independent] {
            let se = (variance / PIXELS as f64).sqrt();
            assert!((mean - want).abs() < 4.0 * se + 1e-6 * want, "mean {mean} against {want} (standard error {se})");
        }
        let ratio = stratified.1 / independent.1;
        eprintln!("pixel variance, stratified over independent samples: {ratio:.3}");
        assert!(ratio < 0.2, "stratified {:e} against independent {:e}", stratified.1, independent.1);
    }
}
