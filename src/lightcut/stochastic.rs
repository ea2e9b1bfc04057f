//! Stochastic lightcuts ([SLC19] Yuksel, "Stochastic Lightcuts", HPG 2019;
//! docs/design.md §10 has the mathematics): per sample, a cut is
//! chosen from the bounds alone (no shadow ray), then each cut node's light
//! is drawn by walking down its subtree, taking each child with probability
//! proportional to its importance (its bound: an upper bound of its
//! unoccluded contribution), and weighted by one over the path's
//! probability. One shadow ray per cut node.
//!
//! Unbiased: the cut does not depend on the sample's random numbers, and a
//! child's importance is 0 only when none of its lights can reach the point
//! (every cosine bound, or the intensity, is 0), so every light that can
//! contribute has a non-zero probability. E[estimate of node C] = sum over
//! C's lights of M G V I. The error falls as 1 / sqrt(samples), or faster
//! where a pixel's samples share cut nodes (below).
//!
//! Deterministic: every choice comes from the caller's random stream (the
//! sample's) and the shading point's pixel sample, so images are
//! bit-identical for any thread count and window.
//!
//! Stratified over a pixel's samples (docs/design.md §10.8): a walk is
//! driven by one uniform number, rescaled at each step (inversion of the
//! subtree's distribution), and the numbers a cut node gets at a pixel's
//! samples fall one in each of as many strata as the pixel has samples.
//!
//! One cut per pixel (docs/design.md §10.9): by default a pixel's later
//! samples walk the cut chosen at its first, each with its own point's
//! importance (any cut is unbiased; only the walks need the point).

use std::collections::BinaryHeap;

use glam::{DVec3, Vec3};

use super::bounds::PointBounds;
use super::{by_group_at_best, exhaustive_part, CutResult, CutSettings, GroupError};
use crate::embree::{PacketWidth, Scene as EmbreeScene};
use crate::light_tree::layout::{Child, CutTree};
use crate::light_tree::{LightTrees, TreeIndex};
use crate::shading::{
    evaluate_and_trace, resample_and_trace, BatchBuffers, Choices, Evaluations, LightEvaluator, SurfaceKey,
    SurfacePoint,
};
use crate::util::color::luminance;
use crate::util::sampling::{PixelSample, Rng, ONE_BELOW};

/// The stochastic mode's default cut settings (chosen by measurement: see
/// the README's "Stochastic lightcuts" section).
pub const STOCHASTIC_DEFAULTS: CutSettings = CutSettings {
    error: 0.05,
    max_cut: 1000,
    group_error: GroupError::Group,
    exhaustive_lights: super::EXHAUSTIVE_LIGHTS,
    resampled_rays: 0,
    reconstruction_block: 0,
    reuse_block: 0,
    pixel_cut: true,
    cut_draws: 0,
};

/// From this many samples per pixel on, a render without `--method` is
/// stochastic: at 16 spp the stochastic cut (its draws stratified over the
/// pixel's samples) had the smaller error on every scene measured, at
/// about the bounded cut's time; at 4 the bounded cut still won on the
/// atrium (docs/notebook/measurements.md, "Stratified over a pixel's samples").
pub const STOCHASTIC_FROM_SPP: u32 = 16;

/// A cut node's key for [`PixelSample::number`]: the same node of the
/// same tree at every sample of a pixel.
#[inline(always)]
fn node_key(tree: TreeIndex, block: u32, slot: u8) -> u64 {
    (u64::from(tree) << 40) | (u64::from(block) << 8) | u64::from(slot)
}

/// The key of the number a cut through the trees from `trees_from` draws
/// its lights over the cut by ([`PixelSample::number`], design §10.10): apart
/// from every node's (a tree index sits in lower bits).
#[inline(always)]
fn cut_key(trees_from: usize) -> u64 {
    u64::MAX ^ trees_from as u64
}

/// The key of the sequence of numbers the `c`-th cut a pixel keeps draws
/// its lights by ([`PixelSample::in_turn`], design §10.10): apart from
/// [`cut_key`]'s and every node's.
#[inline(always)]
fn kept_cut_key(trees_from: usize, c: usize) -> u64 {
    cut_key(trees_from) ^ ((c as u64 + 1) << 48)
}

/// One node of the cut being chosen: slot `slot` of block `block`.
#[derive(Debug, Clone, Copy)]
struct Node {
    /// Normalised upper bound of the node's unoccluded contribution.
    importance: f32,
    block: u32,
    slot: u8,
    tree: TreeIndex,
    in_cut: bool,
}

/// A light drawn for a cut node, waiting for its evaluation.
#[derive(Debug, Clone, Copy)]
struct Drawn {
    /// The light's intensity over the probability of drawing it (W/sr, or
    /// W/m^2 for directional lights): the estimate is M G V times this.
    weight: DVec3,
    block: u32,
    slot: u8,
    tree: TreeIndex,
}

/// Per-thread buffers reused across shading points.
#[derive(Default)]
pub struct StochasticScratch {
    batch: BatchBuffers,
    nodes: Vec<Node>,
    heap: BinaryHeap<u64>,
    walks: Vec<Walk>,
    drawn: Vec<Drawn>,
    chosen: Choices,
    evaluations: Evaluations,
    pixel_cuts: PixelCuts,
    /// A cut of its own's nodes and their cumulative probabilities, when
    /// lights are drawn over the cut.
    cut: Vec<Node>,
    cdf: Vec<f64>,
}

impl StochasticScratch {
    /// Forgets the pixel's cuts (design §10.9): called where a tile starts,
    /// so that a cut never outlives the render and the pixels it was chosen
    /// for.
    pub fn forget_pixel_cuts(&mut self) {
        self.pixel_cuts.pixel = None;
    }
}

/// The most surfaces a pixel keeps cuts for (design §10.9): a pixel whose
/// samples see several surfaces (a silhouette, a moving object, a blurred
/// foreground) chooses a cut at the first sample on each and reuses it at
/// the later ones on that surface. On the motion scene's window at 256 spp
/// 8 left twice as many cuts to choose as 16 did, and 32 no fewer than 16.
const PIXEL_SURFACES: usize = 16;

/// The least cosine between the normals of a kept cut's point and a later
/// sample's for the sample to use the cut (design §10.9): with lights
/// drawn over the cut, its distribution is the kept point's. On the motion
/// scene's window at 256 spp (a sphere sliding over the floor) four draws
/// gave 1.5% mean error at cos 0.9, 1.1% at 0.97, 0.86% at 0.99 and 0.74%
/// at 0.995, for about the same time (docs/notebook/measurements.md, "A pixel's
/// cuts kept per surface").
const PIXEL_CUT_NORMAL_COS: f32 = 0.995;

/// How far a later sample's glossy lobe may fall, towards a light at the
/// peak of the kept point's lobe, before the kept cut's distribution no
/// longer serves its draws ([`SurfacePoint::lobe_turn_cos`], design §10.9,
/// "The lobe's turn"): past it the kept nodes are weighed again at the
/// sample's own point. A normal within [`PIXEL_CUT_NORMAL_COS`] turns the
/// mirror direction by up to 11.5 degrees, far past a sharp lobe's width
/// (a chrome of roughness 0.08 falls 4x within 0.7 degrees), where the
/// kept distribution gives the lights the sample reflects the uniform
/// share alone. On `scenes/shiny.toml`'s chrome sphere at 16 spp, three
/// draws: 13.3% mean error without the test, 4.0% past a fall of 16,
/// 3.2% past 4, 3.1% past 2 and weighed again at every sample; 4 leaves
/// the Phong scenes measured (the motion and dof windows, grid10k, the
/// atrium) as they were, bit for bit (docs/notebook/measurements.md, "A sharp
/// lobe's turn between a pixel's samples").
const LOBE_TURN_RATIO: f32 = 4.0;

/// The cuts a pixel keeps for its later samples (design §10.9): one per
/// surface its samples saw (up to [`PIXEL_SURFACES`]) and per cut through
/// a range of trees (one per light group, or one for all).
#[derive(Default)]
struct PixelCuts {
    /// The pixel sample's key they were chosen for ([`PixelSample::pixel`])
    /// and the index of the latest sample that used them: a sample of
    /// another pixel, or an earlier index (the pixel rendered again),
    /// starts afresh.
    pixel: Option<(u64, u32)>,
    /// The surfaces of the points the cuts were chosen at (each point's
    /// material by address): a later sample uses the first that holds it.
    surfaces: Vec<SurfaceKey>,
    cuts: Vec<KeptCut>,
    nodes: Vec<Node>,
    /// With lights drawn over the cut (`cut_draws` > 0): each node's
    /// cumulative probability ([`cut_distribution`]), beside `nodes`.
    cdf: Vec<f64>,
}

/// A cut a pixel keeps: the surface it serves, the range of trees it cuts,
/// its nodes, and the mirror direction of the point its distribution was
/// weighed at (with lights drawn over the cut).
struct KeptCut {
    /// Index in `PixelCuts::surfaces`.
    surface: usize,
    /// The range's first tree.
    trees_from: usize,
    /// The cut's nodes in `PixelCuts::nodes` (and their `cdf`).
    nodes: std::ops::Range<usize>,
    /// `SurfacePoint::r` of the point the cut was chosen at.
    mirror: Vec3,
    /// The samples that have drawn by its distribution so far: the next
    /// takes that number of the cut's sequence ([`PixelSample::in_turn`]).
    uses: u32,
}

/// What a sample's lights are drawn over when they are drawn over the
/// cut (`cut_draws` > 0), the cut's nodes and their probabilities.
enum DrawnOver {
    /// `StochasticScratch::nodes`' `in_cut` nodes, weighed at this point:
    /// the cut chosen here, or a kept cut copied there (without draws over
    /// the cut, or where the point's glossy lobe has turned too far from
    /// the kept point's, [`LOBE_TURN_RATIO`]).
    Here,
    /// A kept cut's nodes and cumulative probabilities (`PixelCuts::nodes`
    /// and `PixelCuts::cdf`, this range of both), and the sample's number
    /// for its draws: the next of the cut's sequence.
    Kept(std::ops::Range<usize>, f64),
}

impl PixelCuts {
    /// Starts afresh unless `sample` follows the samples the cuts were kept
    /// at (the same pixel, an index no earlier).
    fn follow(&mut self, sample: PixelSample) {
        if !self.pixel.is_some_and(|(pixel, index)| pixel == sample.pixel && index <= sample.index) {
            self.surfaces.clear();
            self.cuts.clear();
            self.nodes.clear();
            self.cdf.clear();
        }
        self.pixel = Some((sample.pixel, sample.index));
    }
}

/// How a walk down a subtree chooses between two children: the weights of
/// the two slots of each of two blocks of a tree (non-negative; a child of
/// weight 0 is never taken). The renderer uses [`walk_importance`]; tests
/// also pass deliberately wrong ones.
pub trait Importance: Fn(&CutTree, [usize; 2]) -> [[f32; 2]; 2] {}
impl<F: Fn(&CutTree, [usize; 2]) -> [[f32; 2]; 2]> Importance for F {}

/// The walk's importance at a shading point, as the renderer uses it: each
/// slot's [`PointBounds::importance_quad`] (the bound with G estimated at
/// the box's centre). A block's weights do not depend on the block it is
/// paired with (each lane is computed on its own).
pub fn walk_importance(bounds: &PointBounds) -> impl Importance + '_ {
    // Inlined into the walks, so compiled in their instruction set
    // (util::simd::best).
    #[inline(always)]
    move |tree: &CutTree, [a, b]: [usize; 2]| {
        let cones = tree.cones_of(a).zip(tree.cones_of(b)).map(|(x, y)| [x, y]);
        let [a0, a1, b0, b1] = bounds.importance_quad(tree.kind, [&tree.blocks[a], &tree.blocks[b]], cones);
        [[a0, a1], [b0, b1]]
    }
}

/// Direct light at `sp` from every tree, by a stochastic lightcut whose
/// random choices come from `rng`. `settings.error` and `settings.max_cut`
/// choose the cut: a node is split while its bound is above `error` times
/// the cut's summed bounds and the cut has fewer than `max_cut` nodes.
/// With `groups` slots (one per light group), every drawn light's
/// contribution is also credited to its group's slot, so each group's sum
/// is an unbiased estimate of that group's light; the cut is chosen per
/// group or through every group's trees as `settings.group_error` says.
pub fn evaluate(
    trees: &LightTrees,
    sp: &SurfacePoint<'_>,
    embree: &EmbreeScene,
    settings: &CutSettings,
    rng: &mut Rng,
    scratch: &mut StochasticScratch,
    groups: usize,
) -> CutResult {
    let bounds = PointBounds::new(sp, trees.scale);
    let importance = walk_importance(&bounds);
    let at = AtPoint { trees, sp, embree, settings, bounds: &bounds, importance: &importance };
    evaluate_with(&at, rng, scratch, groups)
}

/// What a shading point's stochastic cut reads: the trees, the point and
/// its bounds, the settings, and the walks' importance there.
pub(crate) struct AtPoint<'a, 'p, I> {
    pub trees: &'a LightTrees,
    pub sp: &'a SurfacePoint<'p>,
    pub embree: &'a EmbreeScene,
    pub settings: &'a CutSettings,
    pub bounds: &'a PointBounds,
    pub importance: &'a I,
}

/// The stochastic cut's lights at `sp`, drawn as [`evaluate`] draws them
/// but not evaluated, appended to `into` after clearing it (each with its
/// weight, the light's intensity over the probability of drawing it, and
/// its group's slot), for an estimator that evaluates them at other points
/// too (reuse between pixels, `lightcut::reuse`). The result holds what
/// needs no draw (the trees summed light by light, their radiance and
/// credits) and the cut's node count.
#[allow(clippy::too_many_arguments)]
pub fn draw_lights(
    trees: &LightTrees,
    sp: &SurfacePoint<'_>,
    embree: &EmbreeScene,
    settings: &CutSettings,
    rng: &mut Rng,
    scratch: &mut StochasticScratch,
    groups: usize,
    into: &mut Choices,
) -> CutResult {
    let bounds = PointBounds::new(sp, trees.scale);
    let importance = walk_importance(&bounds);
    let at = AtPoint { trees, sp, embree, settings, bounds: &bounds, importance: &importance };
    into.clear();
    by_group_at_best(
        trees,
        groups,
        settings.group_error,
        #[inline(always)]
        |range, result| {
            let drawn = draw_through(&at, range, rng, scratch, result);
            if let Some(fixed) = drawn {
                result.radiance += fixed;
                into.append(&scratch.chosen);
            }
        },
    )
}

/// [`evaluate`] with the walks' importance given (for tests of bias).
pub(crate) fn evaluate_with(
    at: &AtPoint<'_, '_, impl Importance>,
    rng: &mut Rng,
    scratch: &mut StochasticScratch,
    groups: usize,
) -> CutResult {
    by_group_at_best(
        at.trees,
        groups,
        at.settings.group_error,
        #[inline(always)]
        |range, result| cut_through(at, range, rng, scratch, result),
    )
}

/// One stochastic cut through `trees.trees[range]`, its threshold relative
/// to their summed bounds, added to `result`: each drawn light's
/// contribution is also credited to its tree's group's slot.
#[inline(always)]
fn cut_through(
    at: &AtPoint<'_, '_, impl Importance>,
    range: std::ops::Range<usize>,
    rng: &mut Rng,
    scratch: &mut StochasticScratch,
    result: &mut CutResult,
) {
    let Some(fixed) = draw_through(at, range, rng, scratch, result) else {
        return;
    };
    let AtPoint { sp, embree, settings, .. } = *at;
    let evaluator = LightEvaluator::new(sp);
    let (values, rays) = if settings.resampled_rays > 0 {
        // The stratified draws' number comes after the walks' numbers.
        let xi = rng.next_f64();
        let (chosen, evaluations) = (&scratch.chosen, &mut scratch.evaluations);
        resample_and_trace(&evaluator, embree, PacketWidth::Sixteen, chosen, evaluations, settings.resampled_rays, xi)
    } else {
        evaluate_and_trace(&evaluator, embree, PacketWidth::Sixteen, &scratch.chosen, &mut scratch.evaluations)
    };
    result.shadow_rays += rays;
    let mut radiance = fixed;
    for (slot, value) in scratch.chosen.slots().zip(values) {
        radiance += *value;
        result.credit(slot as usize, *value);
    }
    result.radiance += radiance;
}

/// The first half of [`cut_through`]: the cut through `trees.trees[range]`
/// and its drawn lights, into `scratch.chosen` (unevaluated); the trees
/// summed light by light are added to `result` and their radiance returned,
/// or None when no tree of the range has a cut (`result` then has it all).
#[inline(always)]
fn draw_through(
    at: &AtPoint<'_, '_, impl Importance>,
    range: std::ops::Range<usize>,
    rng: &mut Rng,
    scratch: &mut StochasticScratch,
    result: &mut CutResult,
) -> Option<DVec3> {
    let AtPoint { trees, sp, embree, settings, bounds, importance } = *at;
    let range_start = range.start;
    let fixed = exhaustive_part(trees, &range, sp, embree, &mut scratch.batch, result);
    if trees.trees[range.clone()].iter().all(|t| t.blocks.is_empty()) {
        result.radiance += fixed;
        return None;
    }
    let (cut_nodes, drawn_over) = match sp.sample.filter(|_| settings.pixel_cut) {
        Some(sample) => pixel_cut(at, range, scratch, sample),
        None => (choose_cut(trees, range, settings, bounds, scratch), DrawnOver::Here),
    };
    result.nodes += cut_nodes as u64;

    let sample = sp.sample.unwrap_or(PixelSample::ALONE);
    if settings.cut_draws > 0 {
        // One number for the cut's draws: a kept cut's is the next of its
        // own sequence (design §10.10); a cut weighed here takes the pixel
        // sample's, keyed by its first tree. `xi` is drawn either way, so
        // the sample's later numbers do not depend on which.
        let xi = rng.next_f64();
        let StochasticScratch { nodes, cut, cdf, pixel_cuts, walks, drawn, .. } = scratch;
        let (over, u) = match drawn_over {
            DrawnOver::Kept(r, u) => ((&pixel_cuts.nodes[r.clone()], &pixel_cuts.cdf[r]), u),
            DrawnOver::Here => {
                cut.clear();
                cut.extend(nodes.iter().filter(|n| n.in_cut));
                cdf.clear();
                cut_distribution(trees, importance, cut, cdf);
                ((&cut[..], &cdf[..]), sample.number(cut_key(range_start), xi))
            }
        };
        draw_over_cut(trees, over, u, settings.cut_draws, walks, drawn);
        // Walks of one tree next to each other, to step in pairs.
        walks.sort_by_key(|w| w.tree);
        run_walks(trees, scratch, importance);
    } else {
        draw(trees, rng, sample, scratch, importance);
    }
    // Group the draws by tree (the walks finish in any order).
    scratch.drawn.sort_by_key(|d| d.tree);
    // Evaluated by the evaluate-and-trace step, each credited to its tree's group.
    scratch.chosen.clear();
    for d in &scratch.drawn {
        let tree = &trees.trees[d.tree as usize];
        let light = tree.representative(d.block as usize, d.slot as usize);
        scratch.chosen.push(tree.kind, &light, d.weight, trees.group_of_tree[d.tree as usize] as u32);
    }
    Some(fixed)
}

/// Draws one light per cut node of `scratch.nodes` into `scratch.drawn`,
/// its weight the light's intensity over the probability of drawing it:
/// all walks step down together, level by level, so that their reads of
/// the tree overlap in memory. Each walk is driven by one number: the
/// pixel sample's for its node, from the next of `rng`'s in the order of
/// the cut's nodes.
#[inline(always)]
fn draw(
    trees: &LightTrees,
    rng: &mut Rng,
    sample: PixelSample,
    scratch: &mut StochasticScratch,
    importance: &impl Importance,
) {
    scratch.drawn.clear();
    scratch.walks.clear();
    for node in scratch.nodes.iter().filter(|n| n.in_cut) {
        let tree = &trees.trees[node.tree as usize];
        let child = tree.blocks[node.block as usize].child[node.slot as usize];
        if child.is_exact() {
            // An exact node is its own representative with probability 1
            // (all its lights have the same M G V).
            let intensity = slot_intensity(tree, node.block as usize, node.slot as usize);
            scratch.drawn.push(Drawn {
                weight: intensity.as_dvec3(),
                block: node.block,
                slot: node.slot,
                tree: node.tree,
            });
        } else {
            let u = sample.number(node_key(node.tree, node.block, node.slot), rng.next_f64());
            scratch.walks.push(Walk { below: child.index() as u32, inverse_probability: 1.0, u, tree: node.tree });
        }
    }
    run_walks(trees, scratch, importance);
}

/// Draws `draws` lights per shading point over the whole cut (design
/// §10.10) instead of one per node: node k of `cut` is taken with the
/// probability q_k that `cdf` accumulates (its walks' weight at the point the
/// cut was chosen for, mixed with a uniform share), at `draws` numbers
/// u_m = (m + u) / draws that stratify [0, 1) (systematic sampling: each
/// u_m is uniform on its stratum, so the mean of the draws' estimates is
/// unbiased), u the pixel sample's number for the cut. Each draw then
/// walks down from its node as [`draw`]'s walks do, driven by its u_m
/// rescaled into the node's interval, its path's probability starting at
/// draws q_k: the estimate is (1 / draws) sum_m X_m / q_{k_m}.
#[inline(always)]
fn draw_over_cut(
    trees: &LightTrees,
    (cut, cdf): (&[Node], &[f64]),
    u: f64,
    draws: usize,
    walks: &mut Vec<Walk>,
    drawn: &mut Vec<Drawn>,
) {
    drawn.clear();
    walks.clear();
    if cut.is_empty() {
        return;
    }
    for m in 0..draws {
        let u_m = (m as f64 + u) / draws as f64;
        // The first node whose interval [cdf[k - 1], cdf[k]) holds u_m.
        let k = cdf.partition_point(|&c| c <= u_m).min(cut.len() - 1);
        let low = if k == 0 { 0.0 } else { cdf[k - 1] };
        let q = cdf[k] - low;
        let node = cut[k];
        let probability = draws as f64 * q;
        let tree = &trees.trees[node.tree as usize];
        let child = tree.blocks[node.block as usize].child[node.slot as usize];
        if child.is_exact() {
            let intensity = slot_intensity(tree, node.block as usize, node.slot as usize);
            drawn.push(Drawn {
                weight: intensity.as_dvec3() / probability,
                block: node.block,
                slot: node.slot,
                tree: node.tree,
            });
        } else {
            let u = ((u_m - low) / q).clamp(0.0, ONE_BELOW);
            walks.push(Walk {
                below: child.index() as u32,
                inverse_probability: 1.0 / probability,
                u,
                tree: node.tree,
            });
        }
    }
}

/// The share of the probability of drawing a cut node that is spread
/// evenly over the cut's nodes when lights are drawn over the whole cut
/// (design §10.10): every node stays possible at a later sample of the
/// pixel whose point sees a node the first sample's weights gave 0.
/// 0.02, 0.1 and 0.3 measured alike on `scenes/dof.toml` at 256 spp; with
/// the walks' weights, 0.03 and 0.1 alike on the motion window and 0.3
/// worse (docs/notebook/measurements.md, "A cut's draws by the walks' weights").
const UNIFORM_SHARE: f64 = 0.1;

/// The cumulative probabilities of drawing each of `cut`'s nodes, appended
/// to `cdf`: q_k = (1 - s) W_k / sum W + s / n, s = [`UNIFORM_SHARE`]
/// (uniform where every W is 0); the last is exactly 1. W_k is the walks'
/// weight of node k at the point (`importance`, design §10.5: G at the
/// box's centre), not the bound that chose the cut: a bound's 1 / d_min^2
/// is far above the contribution of a node near the point, which then
/// took draws from the nodes that light it (design §10.10).
#[inline(always)]
fn cut_distribution(trees: &LightTrees, importance: &impl Importance, cut: &[Node], cdf: &mut Vec<f64>) {
    let start = cdf.len();
    // Two nodes of one tree weighed in one evaluation (a block's weights
    // do not depend on the block it is paired with).
    let mut k = 0;
    while k < cut.len() {
        let (a, b) = (cut[k], cut.get(k + 1).copied().filter(|b| b.tree == cut[k].tree));
        let tree = &trees.trees[a.tree as usize];
        let blocks = [a.block, b.unwrap_or(a).block].map(|block| block as usize);
        let [wa, wb] = importance(tree, blocks);
        let finite = |w: f32| f64::from(if w.is_finite() { w } else { f32::MAX });
        cdf.push(finite(wa[a.slot as usize]));
        if let Some(b) = b {
            cdf.push(finite(wb[b.slot as usize]));
        }
        k += 1 + usize::from(b.is_some());
    }
    let n = cut.len() as f64;
    let total: f64 = cdf[start..].iter().sum();
    let mut sum = 0.0;
    for w in &mut cdf[start..] {
        sum += if total > 0.0 { (1.0 - UNIFORM_SHARE) * *w / total + UNIFORM_SHARE / n } else { 1.0 / n };
        *w = sum;
    }
    if let Some(last) = cdf.last_mut() {
        *last = 1.0;
    }
}

/// Runs the walks of `scratch.walks` down to their lights, into `scratch.drawn`.
#[inline(always)]
fn run_walks(trees: &LightTrees, scratch: &mut StochasticScratch, importance: &impl Importance) {
    while !scratch.walks.is_empty() {
        // Touch every walk's next block first: the reads miss the cache
        // together instead of one after another. (A block is two cache
        // lines: one read in each.) Measured: grid100k's full frame, one
        // thread, takes 7.4 s without this pass and 5.5 s with it.
        let touched = scratch.walks.iter().fold(0u32, |t, w| {
            let block = &trees.trees[w.tree as usize].blocks[w.below as usize];
            t ^ block.centre[0][0].to_bits() ^ block.representative[0]
        });
        std::hint::black_box(touched);
        // Two walks of one tree step together: their four children's
        // weights in one evaluation. The walks that go on are compacted in
        // place, in order (linear in the walks per level).
        let (mut k, mut kept) = (0, 0);
        while k < scratch.walks.len() {
            let paired = k + 1 < scratch.walks.len() && scratch.walks[k + 1].tree == scratch.walks[k].tree;
            let tree = &trees.trees[scratch.walks[k].tree as usize];
            let blocks = [k, if paired { k + 1 } else { k }].map(|i| scratch.walks[i].below as usize);
            let weights = importance(tree, blocks);
            let count = if paired { 2 } else { 1 };
            let mut went_on = [false; 2];
            // The second walk's draw first (the order the sum adds them in).
            for i in (0..count).rev() {
                match step(tree, &mut scratch.walks[k + i], weights[i]) {
                    Step::Down => went_on[i] = true,
                    Step::Drawn(drawn) => scratch.drawn.push(drawn),
                    Step::Nothing => {}
                }
            }
            for i in (0..count).filter(|&i| went_on[i]) {
                scratch.walks.swap(kept, k + i);
                kept += 1;
            }
            k += count;
        }
        scratch.walks.truncate(kept);
    }
}

/// The heap key of a node: its bound's bits above the complement of its
/// index (largest bound first, ties to the earlier node).
fn key(bound: f32, node: usize) -> u64 {
    (u64::from(bound.to_bits()) << 32) | u64::from(!(node as u32))
}

/// Chooses the cut from the bounds alone, into `scratch.nodes` (those with
/// `in_cut`): from the roots, split the node with the largest error bound
/// while that bound exceeds `error` times the cut's summed importance and
/// the cut is smaller than `max_cut`. Returns the cut's size.
#[inline(always)]
fn choose_cut(
    trees: &LightTrees,
    range: std::ops::Range<usize>,
    settings: &CutSettings,
    bounds: &PointBounds,
    scratch: &mut StochasticScratch,
) -> usize {
    scratch.nodes.clear();
    scratch.heap.clear();
    // The cut's summed importance and size.
    let mut total = 0.0f64;
    let mut size = 0usize;
    for i in range {
        if !trees.trees[i].blocks.is_empty() {
            (total, size) = add_slots(trees, bounds, scratch, i as TreeIndex, 0, &[0], (total, size));
        }
    }
    while size < settings.max_cut {
        let Some(&top) = scratch.heap.peek() else { break };
        let bound = f32::from_bits((top >> 32) as u32);
        if f64::from(bound) <= settings.error * total {
            break;
        }
        scratch.heap.pop();
        let node = &mut scratch.nodes[!(top as u32) as usize];
        node.in_cut = false;
        let (tree, b, k) = (node.tree, node.block as usize, node.slot as usize);
        let (total_after, size_after) = (total - f64::from(node.importance), size - 1);
        let child = trees.trees[tree as usize].blocks[b].child[k];
        (total, size) = add_slots(trees, bounds, scratch, tree, child.index(), &[0, 1], (total_after, size_after));
    }
    size
}

/// The cut of a pixel's sample (design §10.9): the cut the pixel kept for
/// the surface of the sample's point, when an earlier sample on that
/// surface kept one for these trees; otherwise the cut [`choose_cut`]
/// chooses, kept for the surface while the pixel keeps fewer than
/// [`PIXEL_SURFACES`]. Any cut gives an unbiased estimate (design §10.4):
/// the cut decides only how the lights are shared out among walks, and
/// each walk draws by the importance at its own point. Returns the cut's
/// size, and what lights drawn over the cut (`cut_draws` > 0) are drawn
/// over: a kept cut's nodes with the kept distribution, unless the point's
/// glossy lobe has turned too far from the kept point's
/// ([`LOBE_TURN_RATIO`]); otherwise the cut is `scratch.nodes`' `in_cut`
/// nodes, weighed here.
#[inline(always)]
fn pixel_cut(
    at: &AtPoint<'_, '_, impl Importance>,
    range: std::ops::Range<usize>,
    scratch: &mut StochasticScratch,
    sample: PixelSample,
) -> (usize, DrawnOver) {
    let AtPoint { trees, sp, settings, bounds, importance, .. } = *at;
    let trees_from = range.start;
    let kept = &mut scratch.pixel_cuts;
    kept.follow(sample);
    let material = sp.material_address();
    let surface = kept.surfaces.iter().position(|key| key.holds_within(material, sp, PIXEL_CUT_NORMAL_COS));
    if let Some(s) = surface {
        if let Some(c) = kept.cuts.iter().position(|cut| cut.surface == s && cut.trees_from == trees_from) {
            let cut = &mut kept.cuts[c];
            let nodes = cut.nodes.clone();
            if settings.cut_draws > 0 && sp.r.dot(cut.mirror) >= sp.lobe_turn_cos(LOBE_TURN_RATIO) {
                let u = sample.in_turn(kept_cut_key(trees_from, c), cut.uses);
                cut.uses += 1;
                return (nodes.len(), DrawnOver::Kept(nodes, u));
            }
            scratch.nodes.clear();
            scratch.nodes.extend_from_slice(&kept.nodes[nodes]);
            return (scratch.nodes.len(), DrawnOver::Here);
        }
    }
    let size = choose_cut(trees, range, settings, bounds, scratch);
    let kept = &mut scratch.pixel_cuts;
    let s = match surface {
        Some(s) => s,
        None if kept.surfaces.len() < PIXEL_SURFACES => {
            kept.surfaces.push(SurfaceKey::of(material, sp));
            kept.surfaces.len() - 1
        }
        None => return (size, DrawnOver::Here),
    };
    let start = kept.nodes.len();
    kept.nodes.extend(scratch.nodes.iter().filter(|n| n.in_cut));
    let nodes = start..kept.nodes.len();
    let c = kept.cuts.len();
    kept.cuts.push(KeptCut { surface: s, trees_from, nodes: nodes.clone(), mirror: sp.r, uses: 1 });
    if settings.cut_draws == 0 {
        return (size, DrawnOver::Here);
    }
    cut_distribution(trees, importance, &kept.nodes[nodes.clone()], &mut kept.cdf);
    // The first number of the cut's sequence: this sample is its first use.
    (size, DrawnOver::Kept(nodes, sample.in_turn(kept_cut_key(trees_from, c), 0)))
}

/// Adds slots `slots` of block `b` of tree `tree` to the cut; returns the
/// cut's summed importance and size after.
#[inline(always)]
fn add_slots(
    trees: &LightTrees,
    bounds: &PointBounds,
    scratch: &mut StochasticScratch,
    tree: TreeIndex,
    b: usize,
    slots: &[usize],
    (mut total, mut size): (f64, usize),
) -> (f64, usize) {
    let t = &trees.trees[tree as usize];
    let block = &t.blocks[b];
    let importance = bounds.importance(t.kind, block, t.cones_of(b));
    for &k in slots {
        let index = scratch.nodes.len();
        scratch.nodes.push(Node { importance: importance[k], block: b as u32, slot: k as u8, tree, in_cut: true });
        total += f64::from(importance[k]);
        size += 1;
        // An exact node (a leaf, or coincident lights) is never split.
        if !block.child[k].is_exact() && importance[k] > 0.0 {
            scratch.heap.push(key(importance[k], index));
        }
    }
    (total, size)
}

/// A walk down a cut node's subtree, drawing one of its lights.
#[derive(Debug, Clone)]
struct Walk {
    /// The block holding the children of the node the walk is at.
    below: u32,
    /// One over the probability of the path so far.
    inverse_probability: f64,
    /// The number that drives the walk, uniform on [0, 1) given the path
    /// so far (rescaled at each step).
    u: f64,
    tree: TreeIndex,
}

enum Step {
    /// The walk moved down a level.
    Down,
    /// The walk reached an exact node: its light, weighted.
    Drawn(Drawn),
    /// No light below can reach the point.
    Nothing,
}

/// One step of a walk: takes child k with probability w_k / (w_0 + w_1),
/// the weights of the block the walk is at: child 0 when u < w_0 / (w_0 +
/// w_1), compared as u (w_0 + w_1) < w_0 so that the choice waits on no
/// division. Given that choice u is uniform on the child's interval, so
/// mapped back onto [0, 1) it drives the next step (design §10.8): the walk
/// inverts the subtree's distribution with one number. One division a step
/// (1 / w_k), where p_0 = w_0 / (w_0 + w_1) and u / p_k took two (design
/// §10.4).
#[inline(always)]
fn step(tree: &CutTree, walk: &mut Walk, weights: [f32; 2]) -> Step {
    let b = walk.below as usize;
    let Some((k, sum, weights)) = choose_child(tree, b, weights, walk.u) else { return Step::Nothing };
    let w = weights[k];
    let inverse = 1.0 / w;
    walk.inverse_probability *= sum * inverse;
    walk.u = ((walk.u * sum - [0.0, weights[0]][k]) * inverse).clamp(0.0, ONE_BELOW);
    let child = tree.blocks[b].child[k];
    if child.is_exact() {
        let weight = slot_intensity(tree, b, k).as_dvec3() * walk.inverse_probability;
        return Step::Drawn(Drawn { weight, block: b as u32, slot: k as u8, tree: walk.tree });
    }
    walk.below = child.index() as u32;
    Step::Down
}

/// The child a walk at block `b` with number `u` takes, the weights' sum
/// and the weights ([`child_weights`]): child 1 when u (w_0 + w_1) >= w_0
/// and w_1 > 0 (u < 1, but u w_0 may round up to w_0).
#[inline(always)]
fn choose_child(tree: &CutTree, b: usize, weights: [f32; 2], u: f64) -> Option<(usize, f64, [f64; 2])> {
    let (sum, [w0, w1]) = child_weights(tree, b, weights)?;
    Some((usize::from(u * sum >= w0 && w1 > 0.0), sum, [w0, w1]))
}

/// Block `b`'s two weights as the walk uses them ([`finite_weights`], in
/// f64) and their sum; None when both are 0 (no child can be taken).
#[inline(always)]
fn child_weights(tree: &CutTree, b: usize, weights: [f32; 2]) -> Option<(f64, [f64; 2])> {
    let [w0, w1] = finite_weights(tree, b, weights).map(f64::from);
    let sum = w0 + w1;
    (sum > 0.0).then_some((sum, [w0, w1]))
}

/// The probability that a walk started below a cut node (at block `below`,
/// which holds the node's children) ends at slot `target` = (block, slot),
/// a leaf or an exact node, with the weights `importance` gives: the
/// product of w_k / (w_0 + w_1) on the way down, the probabilities [`step`]
/// takes (it keeps their product's inverse, which rounds differently, well
/// within the tests' 1e-12). pbrt-v4's `PMF` of its light samplers; for
/// tests and diagnostics (it searches the subtree: time linear in its
/// size). 0 when the walk cannot reach `target` or `target` is not below
/// the node.
pub fn pmf(tree: &CutTree, importance: &impl Importance, below: usize, target: (usize, usize)) -> f64 {
    let [weights, _] = importance(tree, [below, below]);
    let Some((sum, weights)) = child_weights(tree, below, weights) else { return 0.0 };
    (0..2)
        .map(|k| {
            let p = weights[k] / sum;
            let child = tree.blocks[below].child[k];
            if (below, k) == target {
                p
            } else if child.is_exact() || child == Child::EMPTY || p == 0.0 {
                0.0
            } else {
                p * pmf(tree, importance, child.index(), target)
            }
        })
        .sum()
}

/// The weights, or the slots' intensities' luminance where a weight is not
/// finite (a box with the point inside and a clamp too small for f32): both
/// children of a reachable node then stay possible.
#[inline(always)]
fn finite_weights(tree: &CutTree, b: usize, weights: [f32; 2]) -> [f32; 2] {
    if weights.iter().all(|x| x.is_finite()) {
        return weights;
    }
    [0, 1].map(|k| luminance(slot_intensity(tree, b, k)).max(0.0))
}

#[inline(always)]
fn slot_intensity(tree: &CutTree, b: usize, k: usize) -> Vec3 {
    let block = &tree.blocks[b];
    Vec3::new(block.intensity[0][k], block.intensity[1][k], block.intensity[2][k])
}

#[cfg(test)]
pub(super) mod tests;
