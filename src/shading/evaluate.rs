//! The one evaluate-and-trace step every mode uses (docs/design.md §9.4):
//! a mode only chooses (a light, or a cluster's representative, with the
//! weight its M G V is multiplied by and the slot it is credited to), as
//! pbrt-v4's light samplers only choose; this step evaluates the chosen
//! lights four at a time at the shading point ([`LightEvaluator`]) and
//! traces the shadow rays of those that can contribute as Embree packets.

use glam::{DVec3, Vec3};

use super::direct::{Lanes, LightEvaluator};
use super::surface::SurfacePoint;
use crate::embree::{PacketWidth, Scene as EmbreeScene, ShadowRay};
use crate::light::{Light, LightKind, TreeLight};

/// Shadow rays handed to Embree per call: large enough to amortise the FFI
/// crossing, small enough to stay in L1/L2 (256 rays x 32 bytes = 8 KiB).
pub const SHADOW_BATCH: usize = 256;

/// Embree's packets for a batch of shadow rays from one shading point:
/// `lightcuts bench rays` measured packets of 16 at 1.5 times the rate of
/// single-ray calls on the exact renderer's rays (grid10k).
pub const SHADOW_PACKET: PacketWidth = PacketWidth::Sixteen;

/// A light a mode chose to evaluate at a shading point.
#[derive(Debug, Clone, Copy)]
pub struct Chosen {
    pub kind: LightKind,
    /// A tree leaf's data: the light's position (its direction for a
    /// directional light), its normal (oriented lights; a spot's axis) and
    /// a spot's cosines of its inner and outer angles.
    pub point: Vec3,
    pub normal: Vec3,
    pub spread: [f32; 2],
    /// What the light's M * G * V is multiplied by: its intensity (W/sr,
    /// or W/m^2 for a directional light), its intensity over the
    /// probability of drawing it, or 1 for the unit value a bounded cut
    /// multiplies by a cluster's intensity.
    pub weight: DVec3,
    /// Where the caller credits the value (a light group).
    pub slot: u32,
}

impl Chosen {
    /// `light` of `kind` with weight `weight`, credited to `slot`.
    #[must_use]
    pub fn new(kind: LightKind, light: &TreeLight, weight: DVec3, slot: u32) -> Self {
        Self { kind, point: light.point, normal: light.normal, spread: light.spread, weight, slot }
    }
}

/// Reusable buffers of [`evaluate_and_trace`]: the values found, and the
/// shadow rays in flight with the entry each belongs to.
#[derive(Default)]
pub struct Evaluations {
    values: Vec<DVec3>,
    rays: Vec<ShadowRay>,
    ray_entry: Vec<u32>,
    occluded: Vec<bool>,
}

/// The value of each of `chosen` at `evaluator`'s shading point, in order:
/// M * G * V * weight (0 when occluded, behind the surface or out of
/// reach). The lights are evaluated four at a time (consecutive lights of
/// one kind share lanes); the shadow rays of those whose value is not 0 are
/// traced in one call as packets of `width`. Returns the values and the
/// shadow rays cast.
pub fn evaluate_and_trace<'b>(
    evaluator: &LightEvaluator<'_, '_>,
    embree: &EmbreeScene,
    width: PacketWidth,
    chosen: &[Chosen],
    buffers: &'b mut Evaluations,
) -> (&'b [DVec3], u64) {
    let Evaluations { values, rays, ray_entry, occluded } = buffers;
    values.clear();
    rays.clear();
    ray_entry.clear();
    for run in chosen.chunk_by(|a, b| a.kind == b.kind) {
        for quad in run.chunks(4) {
            let mut lanes = Lanes::default();
            for c in quad {
                lanes.push_point(c.point, c.normal, c.spread);
            }
            for (c, found) in quad.iter().zip(evaluator.terms(quad[0].kind, &lanes)) {
                let value = found.term * c.weight;
                // No ray for a light that contributes nothing here, nor for
                // one within the ray offset (nothing can lie between).
                if value != DVec3::ZERO {
                    if let Some(ray) = found.ray {
                        rays.push(ray);
                        ray_entry.push(values.len() as u32);
                    }
                }
                values.push(value);
            }
        }
    }
    embree.occluded_packets(rays, occluded, width);
    for (&entry, &blocked) in ray_entry.iter().zip(occluded.iter()) {
        if blocked {
            values[entry as usize] = DVec3::ZERO;
        }
    }
    (values, rays.len() as u64)
}

/// Reusable buffers for [`LightBatch`].
#[derive(Default)]
pub struct BatchBuffers {
    chosen: Vec<Chosen>,
    evaluations: Evaluations,
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

/// Sums M * G * V * I over the lights added, in the order added, by the
/// evaluate-and-trace step ([`evaluate_and_trace`]) in batches of
/// [`SHADOW_BATCH`] lights: the exact renderer, and the cut modes' trees too
/// small for a cut.
pub struct LightBatch<'a, 'p> {
    embree: &'a EmbreeScene,
    evaluator: LightEvaluator<'a, 'p>,
    buffers: &'a mut BatchBuffers,
    result: BatchResult,
}

impl<'a, 'p> LightBatch<'a, 'p> {
    pub fn new(embree: &'a EmbreeScene, sp: &'a SurfacePoint<'p>, buffers: &'a mut BatchBuffers) -> Self {
        buffers.chosen.clear();
        Self { embree, evaluator: LightEvaluator::new(sp), buffers, result: BatchResult::default() }
    }

    /// One light, with its own intensity.
    pub fn add(&mut self, light: &Light) {
        self.add_tree_light(light.kind(), &TreeLight::of(light));
    }

    /// One light of `kind` as a tree stores it, with its own intensity.
    pub fn add_tree_light(&mut self, kind: LightKind, light: &TreeLight) {
        self.result.lights += 1;
        self.buffers.chosen.push(Chosen::new(kind, light, light.intensity.as_dvec3(), 0));
        if self.buffers.chosen.len() == SHADOW_BATCH {
            self.flush();
        }
    }

    fn flush(&mut self) {
        let b = &mut *self.buffers;
        let (values, rays) =
            evaluate_and_trace(&self.evaluator, self.embree, SHADOW_PACKET, &b.chosen, &mut b.evaluations);
        self.result.shadow_rays += rays;
        for value in values {
            self.result.radiance += *value;
        }
        b.chosen.clear();
    }

    /// Traces what is left and returns the sum and the counts.
    pub fn finish(mut self) -> BatchResult {
        self.flush();
        self.result
    }
}
