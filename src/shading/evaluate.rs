//! The one evaluate-and-trace step every mode uses (docs/design.md §9.4):
//! a mode only chooses (a light, or a cluster's representative, with the
//! weight its M G V is multiplied by and the slot it is credited to), as
//! pbrt-v4's light samplers only choose; this step evaluates the chosen
//! lights four at a time at the shading point ([`LightEvaluator`]) and
//! traces the shadow rays of those that can contribute as Embree packets.

use glam::DVec3;

use super::direct::{Lanes, LightEvaluator};
use super::surface::SurfacePoint;
use crate::embree::{PacketWidth, Scene as EmbreeScene, ShadowRay};
use crate::light::{Light, LightKind, TreeLight};
use crate::util::color::luminance64;

/// Shadow rays handed to Embree per call: large enough to amortise the FFI
/// crossing, small enough to stay in L1/L2 (256 rays x 32 bytes = 8 KiB).
pub const SHADOW_BATCH: usize = 256;

/// Embree's packets for a batch of shadow rays from one shading point:
/// `lightcuts bench rays` measured packets of 16 at 1.5 times the rate of
/// single-ray calls on the exact renderer's rays (grid10k).
pub const SHADOW_PACKET: PacketWidth = PacketWidth::Sixteen;

/// The lights a mode chose to evaluate at a shading point, in order, each
/// with the weight its M * G * V is multiplied by and the slot it is
/// credited to. Stored four at a time as the evaluation reads them (lights
/// of one kind in each group of four), so that choosing writes each light
/// once, where it is evaluated.
#[derive(Default)]
pub struct Choices {
    /// The quads in use are the first `used`; the others are kept from an
    /// earlier point, so that a new quad is not written twice.
    quads: Vec<Quad>,
    used: usize,
    len: usize,
}

/// Up to four chosen lights of one kind.
#[derive(Clone, Copy)]
struct Quad {
    kind: LightKind,
    lanes: Lanes,
    weights: [DVec3; 4],
    slots: [u32; 4],
}

impl Choices {
    pub fn clear(&mut self) {
        self.used = 0;
        self.len = 0;
    }

    #[must_use]
    pub fn len(&self) -> usize {
        self.len
    }

    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Chooses a light of `kind` with its data as a tree stores it (its
    /// position, or direction for a directional light; its normal, a spot's
    /// axis; a spot's cosines), the weight its M * G * V is multiplied by
    /// (its intensity in W/sr or W/m^2, that over the probability of drawing
    /// it, or 1 for a value per unit intensity), and the slot the value is
    /// credited to (a light group).
    #[inline(always)]
    pub fn push(&mut self, kind: LightKind, light: &TreeLight, weight: DVec3, slot: u32) {
        self.push_with(kind, weight, slot, |lanes| lanes.push(light));
    }

    /// Appends `other`'s lights after these, in order, filling every quad
    /// of one kind before starting the next (as [`Choices::push`] does), so
    /// several points' few draws are evaluated in full quads.
    pub fn append_packed(&mut self, other: &Choices) {
        for quad in &other.quads[..other.used] {
            for k in 0..quad.lanes.count {
                self.push_with(quad.kind, quad.weights[k], quad.slots[k], |lanes| lanes.push_lane(&quad.lanes, k));
            }
        }
    }

    /// [`Choices::push`] with the light's data written by `fill` into the
    /// next lane of the last quad.
    #[inline(always)]
    fn push_with(&mut self, kind: LightKind, weight: DVec3, slot: u32, fill: impl FnOnce(&mut Lanes) -> bool) {
        let full = self.used == 0 || {
            let last = &self.quads[self.used - 1];
            last.lanes.count == 4 || last.kind != kind
        };
        if full {
            if self.used == self.quads.len() {
                self.quads.push(Quad { kind, lanes: Lanes::default(), weights: [DVec3::ZERO; 4], slots: [0; 4] });
            }
            let quad = &mut self.quads[self.used];
            quad.kind = kind;
            quad.lanes.count = 0;
            self.used += 1;
        }
        let quad = &mut self.quads[self.used - 1];
        let k = quad.lanes.count & 3;
        quad.weights[k] = weight;
        quad.slots[k] = slot;
        fill(&mut quad.lanes);
        self.len += 1;
    }

    /// Appends `other`'s lights after these, in order.
    pub fn append(&mut self, other: &Choices) {
        for quad in &other.quads[..other.used] {
            if self.used == self.quads.len() {
                self.quads.push(*quad);
            } else {
                self.quads[self.used] = *quad;
            }
            self.used += 1;
        }
        self.len += other.len;
    }

    /// The kind of each chosen light, in order.
    #[cfg(test)]
    pub(crate) fn kinds(&self) -> impl Iterator<Item = LightKind> + '_ {
        self.quads[..self.used].iter().flat_map(|q| std::iter::repeat_n(q.kind, q.lanes.count))
    }

    /// The slot of each chosen light, in order.
    pub fn slots(&self) -> impl Iterator<Item = u32> + '_ {
        self.quads[..self.used].iter().flat_map(|q| q.slots[..q.lanes.count].iter().copied())
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
    /// [`resample_and_trace`]'s weight of each ray's term, and how many of
    /// its draws took it.
    weights: Vec<f64>,
    picks: Vec<u32>,
}

/// The value of each of `chosen` at `evaluator`'s shading point, in order:
/// M * G * V * weight (0 when occluded, behind the surface or out of
/// reach). The lights are evaluated four at a time; the shadow rays of
/// those whose value is not 0 are traced in one call as packets of `width`.
/// Returns the values and the shadow rays cast.
#[inline(always)]
pub fn evaluate_and_trace<'b>(
    evaluator: &LightEvaluator<'_, '_>,
    embree: &EmbreeScene,
    width: PacketWidth,
    chosen: &Choices,
    buffers: &'b mut Evaluations,
) -> (&'b [DVec3], u64) {
    buffers.clear();
    evaluate_into(evaluator, chosen, buffers);
    trace_evaluations(embree, width, buffers)
}

/// The first half of [`evaluate_and_trace`]: appends the values of
/// `chosen` at `evaluator`'s point to `buffers`, and their shadow rays,
/// untraced. Several points' choices can be appended before one
/// [`trace_evaluations`] (the multidimensional cut's pairs).
#[inline(always)]
pub fn evaluate_into(evaluator: &LightEvaluator<'_, '_>, chosen: &Choices, buffers: &mut Evaluations) {
    let Evaluations { values, rays, ray_entry, .. } = buffers;
    for quad in &chosen.quads[..chosen.used] {
        evaluator.each_term(quad.kind, &quad.lanes, &quad.weights, &mut |_, value, ray| {
            if let Some(ray) = ray {
                rays.push(ray);
                ray_entry.push(values.len() as u32);
            }
            values.push(value);
        });
    }
}

impl Evaluations {
    /// After [`trace_evaluations`]: each traced term's index among the
    /// values, and whether its ray was blocked.
    pub fn traced(&self) -> impl Iterator<Item = (usize, bool)> + '_ {
        self.ray_entry.iter().zip(&self.occluded).map(|(&entry, &blocked)| (entry as usize, blocked))
    }

    /// After [`evaluate_into`]: the values appended, unoccluded (no ray
    /// traced yet).
    #[must_use]
    pub fn values(&self) -> &[DVec3] {
        &self.values
    }

    /// Multiplies each value by `scale(index)`.
    pub fn scale_values(&mut self, scale: impl Fn(usize) -> f64) {
        for (index, value) in self.values.iter_mut().enumerate() {
            *value *= scale(index);
        }
    }

    /// Before [`trace_evaluations`]: drops the shadow rays of the values
    /// for which `keep(index)` is false (their values stay unoccluded).
    pub fn keep_rays(&mut self, mut keep: impl FnMut(usize) -> bool) {
        let mut kept = 0;
        for i in 0..self.rays.len() {
            if keep(self.ray_entry[i] as usize) {
                self.rays[kept] = self.rays[i];
                self.ray_entry[kept] = self.ray_entry[i];
                kept += 1;
            }
        }
        self.rays.truncate(kept);
        self.ray_entry.truncate(kept);
    }

    pub fn clear(&mut self) {
        self.values.clear();
        self.rays.clear();
        self.ray_entry.clear();
        self.picks.clear();
    }
}

/// The second half of [`evaluate_and_trace`]: traces the shadow rays
/// appended to `buffers` as packets of `width` and zeroes the values of
/// those occluded. Returns every value, in the order appended, and the
/// shadow rays cast.
#[inline(always)]
pub fn trace_evaluations<'b>(
    embree: &EmbreeScene,
    width: PacketWidth,
    buffers: &'b mut Evaluations,
) -> (&'b [DVec3], u64) {
    let Evaluations { values, rays, ray_entry, occluded, .. } = buffers;
    embree.occluded_packets(rays, occluded, width);
    for (&entry, &blocked) in ray_entry.iter().zip(occluded.iter()) {
        if blocked {
            values[entry as usize] = DVec3::ZERO;
        }
    }
    (values, rays.len() as u64)
}

/// [`evaluate_and_trace`] with resampled importance sampling over the
/// terms (docs/design.md §10.7; Talbot, Cline and Egbert 2005): when more
/// than R = `rays_kept` of `chosen` need a shadow ray, R draws pick among
/// them in proportion to the luminance w_i of their unoccluded values X_i,
/// stratified by one uniform number `xi` (draw m at (m + xi) / R of the
/// summed w), and only the picked rays are traced. A term picked c_i times
/// is worth X_i V_i c_i W / (R w_i), W the summed w; the others 0. Each
/// draw takes term i with probability w_i / W (a term that can contribute
/// has w_i > 0), so the expected value of every entry is X_i V_i: the sum
/// stays an unbiased estimate of the terms' sum, entry by entry (so of each
/// light group's too), and a term's visibility is all that is sampled.
/// Returns every value, in the order appended, and the shadow rays cast.
#[inline(always)]
pub fn resample_and_trace<'b>(
    evaluator: &LightEvaluator<'_, '_>,
    embree: &EmbreeScene,
    width: PacketWidth,
    chosen: &Choices,
    buffers: &'b mut Evaluations,
    rays_kept: usize,
    xi: f64,
) -> (&'b [DVec3], u64) {
    resample_and_trace_by(evaluator, embree, width, chosen, buffers, rays_kept, xi, |_, value| luminance64(value))
}

/// [`resample_and_trace`] with the resampling weight of the k-th term that
/// needs a ray, of unoccluded value X_k, given as `weight(k, X_k)` (>= 0):
/// the renderer's is X_k's luminance; tests pass wrong ones.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn resample_and_trace_by<'b>(
    evaluator: &LightEvaluator<'_, '_>,
    embree: &EmbreeScene,
    width: PacketWidth,
    chosen: &Choices,
    buffers: &'b mut Evaluations,
    rays_kept: usize,
    xi: f64,
    weight: impl Fn(usize, DVec3) -> f64,
) -> (&'b [DVec3], u64) {
    buffers.clear();
    evaluate_into(evaluator, chosen, buffers);
    let Evaluations { values, rays, ray_entry, weights, picks, .. } = buffers;
    weights.clear();
    weights.extend(ray_entry.iter().enumerate().map(|(k, &e)| weight(k, values[e as usize])));
    let total: f64 = weights.iter().sum();
    if rays.len() <= rays_kept || !(total > 0.0 && total.is_finite()) {
        return trace_evaluations(embree, width, buffers);
    }
    // The stratified draws walk the running sum once.
    picks.clear();
    let (mut below, mut draw) = (0.0, 0usize);
    for &w in weights.iter() {
        below += w;
        let mut count = 0;
        while draw < rays_kept && (draw as f64 + xi) / rays_kept as f64 * total < below {
            count += 1;
            draw += 1;
        }
        picks.push(count);
    }
    // Rounding can leave the last draws past the sum: they take the last
    // term with a weight (its interval ends at the sum).
    if draw < rays_kept {
        let last = weights.iter().rposition(|&w| w > 0.0).expect("the weights sum to more than 0");
        picks[last] += (rays_kept - draw) as u32;
    }
    // Keep the picked rays, each entry scaled by its share of the draws.
    let mut kept = 0;
    for k in 0..rays.len() {
        let entry = ray_entry[k] as usize;
        if picks[k] == 0 {
            values[entry] = DVec3::ZERO;
            continue;
        }
        let share = f64::from(picks[k]) * total / (rays_kept as f64 * weights[k]);
        values[entry] *= share;
        rays[kept] = rays[k];
        ray_entry[kept] = entry as u32;
        kept += 1;
    }
    rays.truncate(kept);
    ray_entry.truncate(kept);
    trace_evaluations(embree, width, buffers)
}

/// Reusable buffers for [`LightBatch`].
#[derive(Default)]
pub struct BatchBuffers {
    chosen: Choices,
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
    #[inline(always)]
    pub fn new(embree: &'a EmbreeScene, sp: &'a SurfacePoint<'p>, buffers: &'a mut BatchBuffers) -> Self {
        buffers.chosen.clear();
        Self { embree, evaluator: LightEvaluator::new(sp), buffers, result: BatchResult::default() }
    }

    /// One light, with its own intensity.
    #[inline(always)]
    pub fn add(&mut self, light: &Light) {
        self.add_tree_light(light.kind(), &TreeLight::of(light));
    }

    /// One light of `kind` as a tree stores it, with its own intensity.
    #[inline(always)]
    pub fn add_tree_light(&mut self, kind: LightKind, light: &TreeLight) {
        self.result.lights += 1;
        self.buffers.chosen.push(kind, light, light.intensity.as_dvec3(), 0);
        if self.buffers.chosen.len() == SHADOW_BATCH {
            self.flush();
        }
    }

    #[inline(always)]
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
    #[inline(always)]
    pub fn finish(mut self) -> BatchResult {
        self.flush();
        self.result
    }
}
