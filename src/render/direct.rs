//! Direct light from a list of lights, every light with its own shadow ray
//! ([LC05] eq. 1): the exact renderer, and lightcuts' evaluation of trees too
//! small for a cut to pay. Shadow rays go to Embree in batches.

use glam::{DVec3, Vec3};

use super::geometry::SurfacePoint;
use super::integrator::ShadingStats;
use crate::embree::{Scene as EmbreeScene, ShadowRay};
use crate::light_tree::LightKind;
use crate::lightcut::bounds::light_term;

/// Shadow rays handed to Embree per call: large enough to amortise the FFI
/// crossing, small enough to stay in L1/L2 (256 rays x 32 bytes = 8 KiB).
pub const SHADOW_BATCH: usize = 256;

/// One light's unoccluded contribution M * G * I at `sp` and the shadow ray
/// that decides its visibility: None when the contribution is zero (no ray
/// is cast), and no ray when the light is within the ray offset (nothing can
/// lie between). The exact renderer casts exactly these rays.
#[must_use]
pub fn light_sample(
    kind: LightKind,
    sp: &SurfacePoint<'_>,
    position: Vec3,
    normal: Vec3,
    intensity: Vec3,
) -> Option<(DVec3, Option<ShadowRay>)> {
    let value = light_term(kind, sp, position, normal) * intensity.as_dvec3();
    if value == DVec3::ZERO {
        return None;
    }
    let ray = match kind {
        LightKind::Directional => Some(sp.shadow_ray_towards(position)),
        _ => sp.shadow_ray_to(position),
    };
    Some((value, ray))
}

/// Reusable buffers for [`LightBatch`].
#[derive(Default)]
pub struct BatchBuffers {
    rays: Vec<ShadowRay>,
    values: Vec<DVec3>,
    occluded: Vec<bool>,
}

/// Sums M * G * V * I over the lights added, casting their shadow rays in
/// batches of [`SHADOW_BATCH`]. The sum is in the order lights are added.
pub struct LightBatch<'a, 'p> {
    embree: &'a EmbreeScene,
    sp: &'a SurfacePoint<'p>,
    buffers: &'a mut BatchBuffers,
    sum: DVec3,
    shadow_rays: u64,
    lights: u64,
}

impl<'a, 'p> LightBatch<'a, 'p> {
    pub fn new(embree: &'a EmbreeScene, sp: &'a SurfacePoint<'p>, buffers: &'a mut BatchBuffers) -> Self {
        buffers.rays.clear();
        buffers.values.clear();
        Self { embree, sp, buffers, sum: DVec3::ZERO, shadow_rays: 0, lights: 0 }
    }

    /// One light: `position` is the direction towards it for a directional
    /// light; `normal` is used by oriented lights only.
    pub fn add(&mut self, kind: LightKind, position: Vec3, normal: Vec3, intensity: Vec3) {
        self.lights += 1;
        let Some((value, ray)) = light_sample(kind, self.sp, position, normal, intensity) else { return };
        match ray {
            Some(ray) => {
                self.buffers.rays.push(ray);
                self.buffers.values.push(value);
                if self.buffers.rays.len() == SHADOW_BATCH {
                    self.flush();
                }
            }
            None => self.sum += value,
        }
    }

    fn flush(&mut self) {
        let b = &mut *self.buffers;
        self.embree.occluded_batch(&b.rays, &mut b.occluded);
        self.shadow_rays += b.rays.len() as u64;
        for (value, &occluded) in b.values.iter().zip(&b.occluded) {
            if !occluded {
                self.sum += *value;
            }
        }
        b.rays.clear();
        b.values.clear();
    }

    /// Traces what is left, records the counters, and returns the sum.
    pub fn finish(mut self, stats: &mut ShadingStats) -> DVec3 {
        self.flush();
        stats.shadow_rays += self.shadow_rays;
        stats.cut_nodes += self.lights;
        stats.max_cut = stats.max_cut.max(self.lights);
        self.sum
    }
}
