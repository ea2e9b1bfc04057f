//! Radiance along camera paths: direct light from every point light
//! ([LC05] eq. 1) or from a lightcut, plus perfect mirror bounces.
//!
//! Radiance is accumulated in f64: a product M * G * I with intensities up to
//! 1e30 W/sr and G up to 1/epsilon^2 overflows f32. Values are clamped to
//! finite f32 only when a pixel is stored (see `film_value`).

use glam::{DVec3, Vec3};

use super::geometry::{Geometry, SurfacePoint};
use crate::embree::ShadowRay;
use crate::light::Lights;

/// Shadow rays handed to Embree per call: large enough to amortise the FFI
/// crossing, small enough to stay in L1/L2 (256 rays x 32 bytes = 8 KiB).
pub const SHADOW_BATCH: usize = 256;

/// How direct light is computed at each shading point.
#[derive(Clone, Copy)]
pub enum DirectLighting {
    /// Every light, one shadow ray each: the reference.
    Exact,
}

/// Reusable per-thread buffers (no allocation per shading point).
#[derive(Default)]
pub struct Scratch {
    rays: Vec<ShadowRay>,
    values: Vec<DVec3>,
    occluded: Vec<bool>,
}

/// Counters for one shading point or summed over many.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ShadingStats {
    pub shadow_rays: u64,
    pub shading_points: u64,
    /// Sum of cut sizes over shading points (the exact mode's cut is every light).
    pub cut_nodes: u64,
    pub max_cut: u64,
}

impl ShadingStats {
    pub fn add(&mut self, other: &Self) {
        self.shadow_rays += other.shadow_rays;
        self.shading_points += other.shading_points;
        self.cut_nodes += other.cut_nodes;
        self.max_cut = self.max_cut.max(other.max_cut);
    }
}

/// What the first hit of a camera sample reports to the AOVs.
#[derive(Debug, Clone, Copy)]
pub struct FirstHit {
    pub albedo: Vec3,
    pub normal: Vec3,
    pub distance: f32,
}

pub struct SampleResult {
    pub radiance: DVec3,
    pub first_hit: Option<FirstHit>,
    pub stats: ShadingStats,
}

pub struct Integrator<'a> {
    pub geometry: &'a Geometry<'a>,
    pub lights: &'a Lights,
    pub direct: DirectLighting,
    pub max_mirror_depth: u32,
}

impl Integrator<'_> {
    /// Radiance arriving at the camera along `ray` (camera paths bounce only
    /// off mirrors; every other surface is shaded by direct light).
    pub fn trace(&self, mut ray: crate::embree::Ray, scratch: &mut Scratch) -> SampleResult {
        let mut result = SampleResult {
            radiance: DVec3::ZERO,
            first_hit: None,
            stats: ShadingStats::default(),
        };
        let mut throughput = DVec3::ONE;
        for depth in 0..=self.max_mirror_depth {
            let Some(hit) = self.geometry.embree.intersect(&ray) else {
                break;
            };
            let sp = self.geometry.surface(&ray, &hit);
            if depth == 0 {
                result.first_hit = Some(FirstHit {
                    albedo: sp.kd,
                    normal: sp.n,
                    distance: sp.distance,
                });
            }
            let direct = self.direct_light(&sp, scratch, &mut result.stats);
            result.radiance += throughput * direct;
            if !sp.material.has_mirror() || depth == self.max_mirror_depth {
                break;
            }
            throughput *= sp.material.mirror.as_dvec3();
            ray = sp.mirror_ray();
        }
        result
    }

    fn direct_light(
        &self,
        sp: &SurfacePoint<'_>,
        scratch: &mut Scratch,
        stats: &mut ShadingStats,
    ) -> DVec3 {
        stats.shading_points += 1;
        match self.direct {
            DirectLighting::Exact => {
                let n = self.lights.len() as u64;
                stats.cut_nodes += n;
                stats.max_cut = stats.max_cut.max(n);
                exact_direct(self.geometry, self.lights, sp, scratch, stats)
            }
        }
    }
}

/// The unoccluded contribution M * G * I of a point light at `y` with
/// intensity `intensity` ([LC05] eq. 1 without V), in f64.
#[must_use]
pub fn omni_contribution(sp: &SurfacePoint<'_>, y: Vec3, intensity: Vec3) -> DVec3 {
    let d = y - sp.p;
    let d2 = d.length_squared();
    if d2 == 0.0 {
        // The shading point is at the light: its direction is undefined and the
        // light contributes nothing here (documented in docs/scene-format.md).
        return DVec3::ZERO;
    }
    let wi = d / d2.sqrt();
    let m = sp.material_term(wi);
    if m == Vec3::ZERO {
        return DVec3::ZERO;
    }
    let g = 1.0 / f64::from(d2).max(sp.min_distance_squared());
    m.as_dvec3() * g * intensity.as_dvec3()
}

/// Every light, one shadow ray each, in batches.
fn exact_direct(
    geometry: &Geometry<'_>,
    lights: &Lights,
    sp: &SurfacePoint<'_>,
    scratch: &mut Scratch,
    stats: &mut ShadingStats,
) -> DVec3 {
    let mut sum = DVec3::ZERO;
    for chunk in lights.omni.chunks(SHADOW_BATCH) {
        scratch.rays.clear();
        scratch.values.clear();
        for light in chunk {
            let value = omni_contribution(sp, light.position, light.intensity);
            if value == DVec3::ZERO {
                continue;
            }
            match sp.shadow_ray_to(light.position) {
                Some(ray) => {
                    scratch.rays.push(ray);
                    scratch.values.push(value);
                }
                None => sum += value,
            }
        }
        geometry
            .embree
            .occluded_batch(&scratch.rays, &mut scratch.occluded);
        stats.shadow_rays += scratch.rays.len() as u64;
        for (value, &occluded) in scratch.values.iter().zip(&scratch.occluded) {
            if !occluded {
                sum += *value;
            }
        }
    }
    sum
}

/// A finite f32 for the film: NaN becomes 0 and magnitudes beyond f32's
/// range are clamped to the largest finite value, so no NaN or Inf ever
/// reaches a pixel.
#[must_use]
pub fn film_value(x: f64) -> f32 {
    if x.is_nan() {
        0.0
    } else {
        x.clamp(f64::from(f32::MIN), f64::from(f32::MAX)) as f32
    }
}
