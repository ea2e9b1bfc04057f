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
    /// Every hit's draws in one list, and the hit that drew each.
    block: Choices,
    drawn_by: Vec<usize>,
    /// Per hit of the block: every drawn light's value there (unoccluded
    /// until traced) and its shadow ray.
    evaluations: Vec<Evaluations>,
    /// Per hit: the luminance of every drawn light there, unoccluded.
    luminances: Vec<Vec<f64>>,
    /// Per drawn light: its MIS weight, the same at every hit when the
    /// block is one surface (`shared`), and at the hit being lit.
    shared: Vec<f64>,
    weights: Vec<f64>,
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
/// rays too. Deterministic: each hit's sum runs in the order of q, then
/// of q's draws. Inlined into its caller's instruction set (run it under
/// `util::simd::best`), as every hot path is.
#[inline(always)]
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
#[inline(always)]
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
    let ReuseScratch { block, drawn_by, evaluations, luminances, shared, weights, at_hits, masked } = scratch;
    // The block's draws in one list, in the order of q then of q's draws,
    // packed into full quads: each hit evaluates them all in one pass and
    // traces its rays as full packets.
    block.clear();
    drawn_by.clear();
    for (q, lights) in drawn.iter().enumerate() {
        block.append_packed(lights);
        drawn_by.extend(std::iter::repeat_n(q, lights.len()));
    }
    evaluations.resize_with(n, Evaluations::default);
    luminances.resize_with(n, Vec::new);
    for (p, evaluator) in evaluators.iter().enumerate() {
        evaluations[p].clear();
        luminances[p].clear();
        if let Some(evaluator) = evaluator {
            evaluate_into(evaluator, block, &mut evaluations[p]);
            luminances[p].extend(evaluations[p].values().iter().map(|&v| luminance64(v)));
        }
    }
    // Every hit's unoccluded luminance enters the weights of the hits on
    // its surface: one weight per draw for every hit when the block is one
    // surface.
    let one_surface = same_surface.iter().all(|&same| same);
    at_hits.resize(n, 0.0);
    masked.resize(n, 0.0);
    let luminances_of = |entry: usize, at_hits: &mut [f64]| {
        for (l, at) in at_hits.iter_mut().zip(luminances.iter()) {
            *l = at.get(entry).copied().unwrap_or(0.0);
        }
    };
    shared.clear();
    if one_surface {
        for (entry, &q) in drawn_by.iter().enumerate() {
            luminances_of(entry, at_hits);
            shared.push(weight(q, at_hits));
        }
    }
    for (p, result) in results.iter_mut().enumerate() {
        if evaluators[p].is_none() {
            continue;
        }
        // p's weight of each draw: 0 for those of hits off p's surface.
        weights.clear();
        if one_surface {
            weights.extend_from_slice(shared);
        } else {
            let row = &same_surface[p * n..(p + 1) * n];
            for (entry, &q) in drawn_by.iter().enumerate() {
                if !row[q] {
                    weights.push(0.0);
                    continue;
                }
                luminances_of(entry, at_hits);
                for ((m, &l), &same) in masked.iter_mut().zip(at_hits.iter()).zip(row) {
                    *m = if same { l } else { 0.0 };
                }
                weights.push(weight(q, masked));
            }
        }
        let evaluations = &mut evaluations[p];
        evaluations.scale_values(|entry| weights[entry]);
        evaluations.keep_rays(|entry| weights[entry] != 0.0);
        let (values, rays) = trace_evaluations(embree, PacketWidth::Sixteen, evaluations);
        result.shadow_rays += rays;
        for ((value, &m), slot) in values.iter().zip(weights.iter()).zip(block.slots()) {
            if m == 0.0 {
                continue;
            }
            result.radiance += *value;
            result.credit(slot as usize, *value);
        }
    }
}

#[cfg(test)]
mod tests;
