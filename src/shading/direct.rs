//! One light's contribution at a shading point ([LC05] eq. 1: M * G * V * I),
//! and a batch that sums many lights with one shadow ray each: the exact
//! renderer, and lightcuts' evaluation of trees too small for a cut to pay.
//! Shadow rays go to Embree in batches.

use glam::{DVec3, Vec3};

use super::surface::SurfacePoint;
use crate::embree::{Scene as EmbreeScene, ShadowRay};
use crate::light::Light;

/// Shadow rays handed to Embree per call: large enough to amortise the FFI
/// crossing, small enough to stay in L1/L2 (256 rays x 32 bytes = 8 KiB).
pub const SHADOW_BATCH: usize = 256;

/// M * G of one light for the shading point, per unit intensity (V and the
/// light's own intensity not included), in f64.
#[must_use]
pub fn light_term(light: &Light, sp: &SurfacePoint<'_>) -> DVec3 {
    let (position, normal) = match *light {
        Light::Directional(l) => return sp.material_term(l.direction).as_dvec3(),
        Light::Omni(l) => (l.position, None),
        Light::Oriented(l) => (l.position, Some(l.normal)),
    };
    let d = position - sp.p;
    let d2 = d.length_squared();
    if d2 == 0.0 {
        // The shading point is at the light: the direction is undefined
        // and the light contributes nothing here (docs/scene-format.md).
        return DVec3::ZERO;
    }
    let wi = d / d2.sqrt();
    let m = sp.material_term(wi);
    if m == Vec3::ZERO {
        return DVec3::ZERO;
    }
    let mut g = 1.0 / f64::from(d2).max(sp.min_distance_squared());
    if let Some(normal) = normal {
        g *= f64::from(normal.dot(-wi).max(0.0));
    }
    m.as_dvec3() * g
}

/// The light's intensity (W/sr), or a directional light's irradiance (W/m^2).
#[must_use]
pub fn light_intensity(light: &Light) -> Vec3 {
    match light {
        Light::Omni(l) => l.intensity,
        Light::Oriented(l) => l.intensity,
        Light::Directional(l) => l.irradiance,
    }
}

/// One light's unoccluded contribution M * G * `intensity` at `sp` and the
/// shadow ray that decides its visibility: None when the contribution is
/// zero (no ray is cast), and no ray when the light is within the ray offset
/// (nothing can lie between). The exact renderer casts exactly these rays.
#[must_use]
pub fn light_sample(light: &Light, sp: &SurfacePoint<'_>, intensity: Vec3) -> Option<(DVec3, Option<ShadowRay>)> {
    let value = light_term(light, sp) * intensity.as_dvec3();
    if value == DVec3::ZERO {
        return None;
    }
    let ray = match *light {
        Light::Directional(l) => Some(sp.shadow_ray_towards(l.direction)),
        Light::Omni(l) => sp.shadow_ray_to(l.position),
        Light::Oriented(l) => sp.shadow_ray_to(l.position),
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

/// What a batch found: the sum, and what it cost.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BatchResult {
    /// Sum of M * G * V * I over the lights added.
    pub radiance: DVec3,
    /// Lights added (each evaluated exactly).
    pub lights: u64,
    pub shadow_rays: u64,
}

/// Sums M * G * V * I over the lights added, casting their shadow rays in
/// batches of [`SHADOW_BATCH`]. The sum is in the order lights are added.
pub struct LightBatch<'a, 'p> {
    embree: &'a EmbreeScene,
    sp: &'a SurfacePoint<'p>,
    buffers: &'a mut BatchBuffers,
    result: BatchResult,
}

impl<'a, 'p> LightBatch<'a, 'p> {
    pub fn new(embree: &'a EmbreeScene, sp: &'a SurfacePoint<'p>, buffers: &'a mut BatchBuffers) -> Self {
        buffers.rays.clear();
        buffers.values.clear();
        Self { embree, sp, buffers, result: BatchResult::default() }
    }

    /// One light, with its own intensity.
    pub fn add(&mut self, light: &Light) {
        self.result.lights += 1;
        let Some((value, ray)) = light_sample(light, self.sp, light_intensity(light)) else { return };
        match ray {
            Some(ray) => {
                self.buffers.rays.push(ray);
                self.buffers.values.push(value);
                if self.buffers.rays.len() == SHADOW_BATCH {
                    self.flush();
                }
            }
            None => self.result.radiance += value,
        }
    }

    fn flush(&mut self) {
        let b = &mut *self.buffers;
        self.embree.occluded_batch(&b.rays, &mut b.occluded);
        self.result.shadow_rays += b.rays.len() as u64;
        for (value, &occluded) in b.values.iter().zip(&b.occluded) {
            if !occluded {
                self.result.radiance += *value;
            }
        }
        b.rays.clear();
        b.values.clear();
    }

    /// Traces what is left and returns the sum and the counts.
    pub fn finish(mut self) -> BatchResult {
        self.flush();
        self.result
    }
}
