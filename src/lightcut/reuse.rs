//! Reuse between neighbouring pixels (docs/design.md §10.11): the camera
//! hits of a B x B pixel block at one sample index each draw their
//! stochastic cut's lights (`stochastic::draw_lights`), and every hit is
//! lit by all of the block's draws, each weighted by multiple importance
//! sampling, so that each hit's estimate has B^2 cuts' draws for the price
//! of one cut's choosing and B^2 cuts' shadow rays.
//!
//! Hit q's draws are a stratified estimator of the sum over every light:
//! each drawn light c carries its intensity over the probability q drew it
//! with (its weight in [`Choices`]), so sum_c X_p(c) V_p(c) (its value at
//! any point p) is unbiased for p's sum wherever q could draw every light
//! that reaches p. With MIS weights m_q(c) that sum to 1 over the hits
//! that can draw c, sum_q sum_c m_q(c) X_p(c) V_p(c) is unbiased for p's
//! sum over all lights (Veach and Guibas's multi-sample model, SIGGRAPH
//! 1995; pairwise and generalised forms in Lin et al., "Generalized
//! Resampled Importance Sampling", SIGGRAPH 2022). The renderer's m_q(c) is the balance
//! heuristic with each hit's unoccluded luminance of c standing for its
//! probability of drawing it: lum X_q(c) / sum_j lum X_j(c). A hit whose
//! X_q(c) is 0 gets weight 0 (its walk may not reach c), and the weights
//! sum to 1 wherever some hit's X_j(c) > 0, in particular wherever
//! X_p(c) > 0.
//!
//! The weights are p's own: the sums run over the hits on p's surface
//! ([`same_surfaces`]), p among them, and the other hits' draws do not
//! light p. Any set of techniques that holds p's own gives p an unbiased
//! estimate, and luminance stands for probability only between points
//! whose cuts are alike: a sphere point beside a floor point (a moving
//! object's blur mixes them over whole blocks) drew from a cut of
//! another shape, and its draws came into the floor with large weights.
use glam::DVec3;

use super::CutResult;
use crate::embree::{PacketWidth, Scene as EmbreeScene};
use crate::shading::evaluate::{evaluate_into, trace_evaluations};
use crate::shading::{Choices, Evaluations, LightEvaluator, SurfaceKey, SurfacePoint};
use crate::util::color::luminance64;
use crate::util::sampling::PixelSample;

/// The pixel sample of hit `k` of a block of `hits` camera hits at sample
/// `index` of `spp` (design §10.11): the block's samples are one
/// stratified set keyed by `block_key`, in which hit k takes index
/// index x hits + k of spp x hits, so that the hits' draws of a cut node
/// they share fall in different strata. Each hit's numbers stay uniform
/// ([`PixelSample::number`]), so each hit's draws keep their distribution
/// and the block's estimate its mean.
#[must_use]
pub fn block_sample(block_key: u64, hits: usize, k: usize, index: u32, spp: u32) -> PixelSample {
    let n = hits as u32;
    PixelSample { pixel: block_key, index: index * n + k as u32, count: spp.max(1) * n }
}

/// Which hits of a block light which (design §10.11): entry p n + q is
/// whether hit q's draws light hit p, true where both are on one surface
/// ([`SurfaceKey::holds`]: the same material, normals within 0.9 in
/// cosine, distances from the viewer within 1.1), so a hit on the sliding
/// sphere lights no floor hit beside it. Symmetric, and true from a hit to
/// itself; false where a pixel hit nothing.
#[must_use]
pub fn same_surfaces(points: &[Option<&SurfacePoint<'_>>]) -> Vec<bool> {
    let keys: Vec<_> = points.iter().map(|p| p.map(|sp| SurfaceKey::of(sp.material_address(), sp))).collect();
    let mut same = Vec::with_capacity(points.len() * points.len());
    for point in points {
        same.extend(keys.iter().map(|key| match (point, key) {
            (Some(sp), Some(key)) => key.holds(sp.material_address(), sp),
            _ => false,
        }));
    }
    same
}

/// Reusable buffers of [`estimate`].
#[derive(Default)]
pub struct ReuseScratch {
    evaluations: Evaluations,
    /// Per hit of the block: the luminance of each of one hit's drawn
    /// lights there, unoccluded, and its value there with visibility.
    luminances: Vec<Vec<f64>>,
    values: Vec<Vec<DVec3>>,
    /// One drawn light's luminance at every hit.
    at_hits: Vec<f64>,
    /// `at_hits` at the hits on a receiver's surface (0 elsewhere).
    masked: Vec<f64>,
}

/// The renderer's MIS weight of hit q's drawn light given its unoccluded
/// luminance at every hit of the block (0 where a pixel hit nothing): the
/// balance heuristic, lum_q / sum_j lum_j.
#[must_use]
pub fn balance(q: usize, luminances: &[f64]) -> f64 {
    let total: f64 = luminances.iter().sum();
    if total > 0.0 {
        luminances[q] / total
    } else {
        0.0
    }
}

/// Lights every hit of a block by the draws of the hits on its surface:
/// `drawn[q]` are hit q's drawn lights (weights included), `evaluators[p]`
/// hit p's evaluator (None: the pixel's camera ray hit nothing to shade),
/// `same_surface` is [`same_surfaces`]' matrix, and each drawn light's
/// value at p, times its MIS weight over the hits on p's surface, is added
/// to `results[p]`'s radiance and credited to its group's slot; p's shadow
/// rays too. Deterministic: the sums run in the order of q, then of q's
/// draws.
pub fn estimate(
    evaluators: &[Option<LightEvaluator<'_, '_>>],
    same_surface: &[bool],
    drawn: &[Choices],
    embree: &EmbreeScene,
    results: &mut [CutResult],
    scratch: &mut ReuseScratch,
) {
    estimate_with(evaluators, same_surface, drawn, embree, results, scratch, balance);
}

/// [`estimate`] with the MIS weight given as `weight(q, luminances)` (the
/// renderer's is [`balance`]; tests pass wrong ones).
pub(crate) fn estimate_with(
    evaluators: &[Option<LightEvaluator<'_, '_>>],
    same_surface: &[bool],
    drawn: &[Choices],
    embree: &EmbreeScene,
    results: &mut [CutResult],
    scratch: &mut ReuseScratch,
    weight: impl Fn(usize, &[f64]) -> f64,
) {
    let n = evaluators.len();
    let ReuseScratch { evaluations, luminances, values, at_hits, masked } = scratch;
    masked.resize(n, 0.0);
    let one_surface = same_surface.iter().all(|&same| same);
    luminances.resize_with(n, Vec::new);
    values.resize_with(n, Vec::new);
    at_hits.resize(n, 0.0);
    for (q, lights) in drawn.iter().enumerate() {
        if lights.is_empty() {
            continue;
        }
        for (p, evaluator) in evaluators.iter().enumerate() {
            luminances[p].clear();
            values[p].clear();
            let Some(evaluator) = evaluator else { continue };
            evaluations.clear();
            evaluate_into(evaluator, lights, evaluations);
            luminances[p].extend(evaluations.values().iter().map(|&v| luminance64(v)));
            // Every hit's unoccluded luminance enters the weights of the
            // hits on its surface; only a hit on q's surface traces q's draws.
            if same_surface[p * n + q] {
                let (traced, rays) = trace_evaluations(embree, PacketWidth::Sixteen, evaluations);
                values[p].extend_from_slice(traced);
                results[p].shadow_rays += rays;
            }
        }
        for (c, slot) in lights.slots().enumerate() {
            for (l, at) in at_hits.iter_mut().zip(luminances.iter()) {
                *l = at.get(c).copied().unwrap_or(0.0);
            }
            // One weight for every hit when the block is one surface.
            let shared = one_surface.then(|| weight(q, at_hits));
            // p has values of q's draws only when q is on its surface.
            for (p, (result, at)) in results.iter_mut().zip(values.iter()).enumerate() {
                let Some(&value) = at.get(c) else { continue };
                let m = shared.unwrap_or_else(|| {
                    let row = &same_surface[p * n..(p + 1) * n];
                    for ((m, &l), &same) in masked.iter_mut().zip(at_hits.iter()).zip(row) {
                        *m = if same { l } else { 0.0 };
                    }
                    weight(q, masked)
                });
                if m == 0.0 {
                    continue;
                }
                let value = value * m;
                result.radiance += value;
                result.credit(slot as usize, value);
            }
        }
    }
}

#[cfg(test)]
mod tests;
