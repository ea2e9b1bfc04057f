//! Multidimensional lightcuts ([MDLC06]; docs/design.md §13): a pixel's
//! whole integral at once. Its gather points (every camera sample's
//! shading points over the pixel's area and the lens, with the mirror
//! paths' points, each with its strength) are clustered into a gather tree
//! per pixel; the cut runs through the implicit product graph of (gather
//! cluster, light cluster) pairs, starting from (gather root, each light
//! tree's root), and refines the pair with the largest error bound, on the
//! gather side or the light side, until every pair's bound is at most
//! `error` times the pixel's total estimate. A pair's estimate is the
//! representative pair's M G V (one shadow ray) times the gather cluster's
//! summed strength times the light cluster's summed intensity, the pair
//! drawn per pair (docs/design.md §13.4); its bound is the same product
//! with M, G and V replaced by their upper bounds over the two clusters
//! (`bounds::GatherBounds`, docs/design.md §13.3).

use std::collections::BinaryHeap;

use glam::{DVec3, Vec3};

use super::bounds::{min_distance_squared_f32, GatherBounds, PointBounds};
use super::{by_group_at_best, CutResult, CutSettings};
use crate::embree::Scene as EmbreeScene;
use crate::light_tree::layout::{Child, CutTree};
use crate::light_tree::{LightTrees, TreeIndex};
use crate::shading::{evaluate_into, trace_evaluations, Choices, Evaluations, LightEvaluator, SurfacePoint};
use crate::util::color::luminance64;
use crate::util::sampling::mix64;
use crate::util::streams::Stream;

/// Pairs refined per batch of shadow rays.
const REFINE_BATCH: usize = 32;

/// Most pairs one pixel's cut may make (the heap key holds a pair's index
/// in 32 bits; a cut stops refining well before).
const MAX_PAIRS: usize = 1 << 28;

/// The defaults of `render --multidimensional`: the threshold is relative to
/// the pixel's whole direct light, and a pixel's cut holds all its gather
/// points' pairs, so its largest cut is larger than one point's.
pub const MULTIDIMENSIONAL_DEFAULTS: CutSettings = CutSettings {
    error: 0.02,
    max_cut: 8192,
    group_error: super::GroupError::Group,
    exhaustive_lights: 0,
    resampled_rays: 0,
    reconstruction_block: 0,
    reuse_block: 0,
    pixel_cut: false,
    cut_draws: 0,
};

/// One shading point of a pixel's camera paths, with its strength: the
/// throughput of the path that reached it (mirror reflectances), the
/// weight its direct light enters the pixel's sum with.
#[derive(Debug, Clone)]
pub struct GatherPoint<'s> {
    pub sp: SurfacePoint<'s>,
    pub strength: DVec3,
}

/// A node of a pixel's gather tree: its bounds' inputs, its summed
/// strength, and what is below it.
#[derive(Debug, Clone, Copy)]
struct GatherNode {
    bounds: GatherBounds,
    strength: DVec3,
    below: Below,
}

/// One (gather cluster, light cluster) pair of the cut, or one that has
/// been refined. The light cluster is slot `slot` of block `block` of tree
/// `tree`.
#[derive(Debug, Clone, Copy)]
struct Pair {
    /// M * G * V of the representative pair, per unit strength and intensity.
    unit: DVec3,
    /// The gather cluster's strength times the light cluster's intensity.
    weight: DVec3,
    bound: f32,
    gather: u32,
    /// The representative pair ([`ProductCut::representatives`]): its
    /// gather point, and its light (slot `light_slot` of block
    /// `light_block`, a leaf or coincident lights).
    gather_representative: u32,
    light_block: u32,
    block: u32,
    light_slot: u8,
    slot: u8,
    tree: TreeIndex,
    in_cut: bool,
}

/// What is below a gather node.
#[derive(Debug, Clone, Copy)]
enum Below {
    /// One gather point (its index).
    Point(u32),
    /// Two nodes (their indices).
    Children([u32; 2]),
}

impl Below {
    fn children(self) -> Option<[u32; 2]> {
        match self {
            Self::Point(_) => None,
            Self::Children(c) => Some(c),
        }
    }
}

impl Pair {
    fn estimate(&self) -> DVec3 {
        self.unit * self.weight
    }
}

/// Per-thread buffers reused across pixels.
#[derive(Default)]
pub struct GatherScratch {
    nodes: Vec<GatherNode>,
    bounds: Vec<PointBounds>,
    order: Vec<u32>,
    pairs: Vec<Pair>,
    heap: BinaryHeap<u64>,
    pending: Vec<u32>,
    chosen: Choices,
    evaluations: Evaluations,
    batch: crate::shading::BatchBuffers,
}

impl GatherScratch {
    /// The bounds of gather node `g` against both slots of block `b` of
    /// `tree`: a point's own bound (exact slots 0) times its strength's
    /// largest channel, or the cluster's (docs/design.md §13.3).
    pub(crate) fn pair_bounds(&self, g: u32, tree: &CutTree, b: usize) -> [f32; 2] {
        let node = &self.nodes[g as usize];
        let bounds = &self.bounds[g as usize];
        if let Below::Children(_) = node.below {
            return bounds.importance(tree.kind, &tree.blocks[b], tree.cones_of(b));
        }
        let strength = node.bounds.strength.max_element() * (1.0 + 1.0 / 1_048_576.0);
        bounds.pair(tree.kind, &tree.blocks[b], tree.cones_of(b)).map(|x| x * strength)
    }

    /// The gather points below node `g`, and the node's summed strength.
    #[cfg(test)]
    pub(crate) fn points_below(&self, g: u32) -> (Vec<u32>, DVec3) {
        let mut out = Vec::new();
        let mut stack = vec![g];
        while let Some(n) = stack.pop() {
            match self.nodes[n as usize].below {
                Below::Point(i) => out.push(i),
                Below::Children(c) => stack.extend(c),
            }
        }
        (out, self.nodes[g as usize].strength)
    }

    #[cfg(test)]
    pub(crate) fn node_count(&self) -> usize {
        self.nodes.len()
    }
}

/// What a pixel's cut found, beside the radiance: its gather tree's size.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PixelCut {
    pub cut: CutResult,
    pub gather_nodes: u64,
}

/// The direct light of a pixel's gather points, summed with their
/// strengths (Σ S_g L_g), by a multidimensional lightcut per light group
/// as `settings.group_error` says; each group's share is added to
/// its slot when there are `groups` slots. `key` is (seed, pixel x, pixel y): it
/// draws the gather clusters' representatives.
pub fn evaluate(
    trees: &LightTrees,
    points: &[GatherPoint<'_>],
    embree: &EmbreeScene,
    settings: &CutSettings,
    key: [u64; 3],
    scratch: &mut GatherScratch,
    groups: usize,
) -> PixelCut {
    if points.is_empty() {
        return PixelCut::default();
    }
    let salt = Stream::Gather.rng(&key).next_u64();
    let root = build_gather_tree(points, trees.scale, scratch);
    let cut = by_group_at_best(
        trees,
        groups,
        settings.group_error,
        #[inline(always)]
        |range, result| {
            let gathered = Gathered { points, root, salt };
            product_cut(trees, range, &gathered, embree, settings, scratch, result);
        },
    );
    PixelCut { cut, gather_nodes: scratch.nodes.len() as u64 }
}

/// The pixel's gather tree in `scratch.nodes` (and each node's bounds in
/// `scratch.bounds`), built top down: a node's points are split at the
/// median of the coordinate (position, or normal) with the largest
/// relative spread. Returns the root's index.
pub(crate) fn build_gather_tree(points: &[GatherPoint<'_>], scale: f32, scratch: &mut GatherScratch) -> u32 {
    scratch.nodes.clear();
    scratch.bounds.clear();
    scratch.order.clear();
    scratch.order.extend(0..points.len() as u32);
    let mut order = std::mem::take(&mut scratch.order);
    let root = build_node(points, &mut order, scale, scratch);
    scratch.order = order;
    root
}

/// One point's leaf node and bounds.
fn leaf(points: &[GatherPoint<'_>], i: u32, scale: f32) -> (GatherNode, PointBounds) {
    let g = &points[i as usize];
    let bounds = PointBounds::new(&g.sp, scale);
    let (diffuse, glossy) = bounds.gather_terms(g.sp.kd);
    let node = GatherNode {
        bounds: GatherBounds {
            lo: g.sp.p,
            hi: g.sp.p,
            axis: g.sp.n,
            cos_cone: 1.0,
            strength: g.strength.as_vec3(),
            diffuse,
            glossy,
            min_distance_squared: min_distance_squared_f32(&g.sp),
        },
        strength: g.strength,
        below: Below::Point(i),
    };
    (node, bounds)
}

fn build_node(points: &[GatherPoint<'_>], order: &mut [u32], scale: f32, scratch: &mut GatherScratch) -> u32 {
    if let [i] = *order {
        let (node, bounds) = leaf(points, i, scale);
        scratch.nodes.push(node);
        scratch.bounds.push(bounds);
        return (scratch.nodes.len() - 1) as u32;
    }
    split(points, order);
    let (left, right) = order.split_at_mut(order.len() / 2);
    let a = build_node(points, left, scale, scratch);
    let b = build_node(points, right, scale, scratch);
    let (na, nb) = (scratch.nodes[a as usize], scratch.nodes[b as usize]);
    let (ga, gb) = (&na.bounds, &nb.bounds);
    let (lo, hi) = (ga.lo.min(gb.lo), ga.hi.max(gb.hi));
    // The normal cone: the mean normal's direction, and the widest angle
    // from it to any point's normal (a little wider: rounding).
    let sum: Vec3 = order.iter().map(|&i| points[i as usize].sp.n).sum();
    let (axis, cos_cone) = if sum.length_squared() > 1e-12 {
        let axis = sum.normalize();
        let widest = order.iter().map(|&i| points[i as usize].sp.n.dot(axis)).fold(1.0f32, f32::min);
        (axis, widest - 1e-5)
    } else {
        (Vec3::Z, -1.0)
    };
    let bounds = GatherBounds {
        lo,
        hi,
        axis,
        cos_cone,
        strength: ga.strength + gb.strength,
        diffuse: ga.diffuse.max(gb.diffuse),
        glossy: ga.glossy.max(gb.glossy),
        min_distance_squared: ga.min_distance_squared.min(gb.min_distance_squared),
    };
    scratch.nodes.push(GatherNode { bounds, strength: na.strength + nb.strength, below: Below::Children([a, b]) });
    scratch.bounds.push(PointBounds::gather_cluster(&bounds, scale));
    (scratch.nodes.len() - 1) as u32
}

/// Orders `order` so that its two halves are the split: by the position
/// coordinate with the largest spread relative to the box's diagonal, or
/// the normal coordinate with the largest spread relative to 2, whichever
/// is larger (ties to the index, so the order is deterministic).
fn split(points: &[GatherPoint<'_>], order: &mut [u32]) {
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    let (mut nlo, mut nhi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for &i in order.iter() {
        let sp = &points[i as usize].sp;
        (lo, hi) = (lo.min(sp.p), hi.max(sp.p));
        (nlo, nhi) = (nlo.min(sp.n), nhi.max(sp.n));
    }
    let diagonal = (hi - lo).length().max(f32::MIN_POSITIVE);
    let spreads = [(hi - lo) / diagonal, (nhi - nlo) * 0.5];
    let spread = |c: usize| spreads[c / 3][c % 3];
    // Coordinates 0-2: the position's x, y, z; 3-5: the normal's.
    let widest = (1..6).fold(0, |best, c| if spread(c) > spread(best) { c } else { best });
    let coordinate = |i: u32| {
        let sp = &points[i as usize].sp;
        if widest < 3 {
            sp.p[widest]
        } else {
            sp.n[widest - 3]
        }
    };
    order.sort_by(|&a, &b| coordinate(a).total_cmp(&coordinate(b)).then(a.cmp(&b)));
}

/// The heap key of a pair: its bound's bits above the complement of its
/// index (the largest bound first, ties to the earlier pair).
fn key(bound: f32, pair: usize) -> u64 {
    (u64::from(bound.to_bits()) << 32) | u64::from(!(pair as u32))
}

struct ProductCut<'a, 'p> {
    trees: &'a [CutTree],
    /// The pixel's key for drawing gather representatives.
    salt: u64,
    points: &'a [GatherPoint<'p>],
    embree: &'a EmbreeScene,
    scratch: &'a mut GatherScratch,
    total: f64,
    pairs: usize,
    shadow_rays: u64,
}

impl ProductCut<'_, '_> {
    fn bounds(&self, g: u32, t: TreeIndex, b: usize) -> [f32; 2] {
        self.scratch.pair_bounds(g, &self.trees[t as usize], b)
    }

    /// Adds the pair (gather node `g`, slot `k` of block `b` of tree `t`)
    /// with its bound: it shares its parent's M G V when both
    /// representatives are the parent's (`parent`), else it waits for its
    /// representative pair's evaluation.
    fn add(&mut self, g: u32, t: TreeIndex, b: usize, k: usize, bound: f32, parent: Option<&Pair>) {
        let block = &self.trees[t as usize].blocks[b];
        let child = block.child[k];
        if child == Child::EMPTY {
            return;
        }
        let (gather_representative, (light_block, light_slot)) = self.representatives(g, t, b, k);
        let node = &self.scratch.nodes[g as usize];
        let intensity = DVec3::new(
            f64::from(block.intensity[0][k]),
            f64::from(block.intensity[1][k]),
            f64::from(block.intensity[2][k]),
        );
        let shared = parent.filter(|p| {
            (p.gather_representative, p.light_block, p.light_slot) == (gather_representative, light_block, light_slot)
        });
        let pair = Pair {
            unit: shared.map_or(DVec3::ZERO, |p| p.unit),
            weight: node.strength * intensity,
            bound,
            gather: g,
            gather_representative,
            light_block,
            block: b as u32,
            light_slot,
            slot: k as u8,
            tree: t,
            in_cut: true,
        };
        let index = self.scratch.pairs.len();
        self.scratch.pairs.push(pair);
        if shared.is_some() {
            self.admit(index);
        } else {
            self.scratch.pending.push(index as u32);
        }
    }

    /// The representative pair of (gather node `g`, slot `k` of block `b`
    /// of tree `t`), drawn per pair so that a coarse pair's error is
    /// independent of its neighbours' in both dimensions (docs/design.md
    /// §13.4, "Representatives"): the gather point by a descent from `g` that takes each child
    /// in proportion to its strength, keyed by the light cluster; the light
    /// by a descent from the slot that takes each child in proportion to
    /// its intensity's luminance, keyed by that gather point. One draw
    /// per pair from S_g I_l / (S_sum I_sum) makes the pair's estimate
    /// unbiased. A gather split's child that holds the parent's gather
    /// point draws the same pair, and reuses the parent's M G V.
    fn representatives(&self, g: u32, t: TreeIndex, b: usize, k: usize) -> (u32, (u32, u8)) {
        let draw = |key: u64| (mix64(self.salt ^ mix64(key)) >> 11) as f64 * (1.0 / 9_007_199_254_740_992.0);
        let cluster = (u64::from(t) << 32) ^ ((b as u64) << 1) ^ k as u64;
        let nodes = &self.scratch.nodes;
        let mut n = g;
        let point = loop {
            match nodes[n as usize].below {
                Below::Point(i) => break i,
                Below::Children([a, c]) => {
                    let (la, lc) = (luminance64(nodes[a as usize].strength), luminance64(nodes[c as usize].strength));
                    n = if la + lc <= 0.0 || draw((u64::from(n) << 40) ^ cluster) * (la + lc) < la { a } else { c };
                }
            }
        };
        let tree = &self.trees[t as usize];
        let (mut b, mut k) = (b, k);
        loop {
            let child = tree.blocks[b].child[k];
            // A leaf, or lights at one point: its representative stands for all.
            if child.is_exact() {
                return (point, (b as u32, k as u8));
            }
            let block = &tree.blocks[child.index()];
            let weight = |j: usize| {
                let i = Vec3::new(block.intensity[0][j], block.intensity[1][j], block.intensity[2][j]);
                if block.child[j] == Child::EMPTY {
                    0.0
                } else {
                    f64::from(crate::util::color::luminance(i))
                }
            };
            let (l0, l1) = (weight(0), weight(1));
            let key = (u64::from(t) << 56) ^ ((child.index() as u64) << 28) ^ u64::from(point) ^ (1 << 63);
            let j = usize::from(!(l0 + l1 <= 0.0 || draw(key) * (l0 + l1) < l0));
            (b, k) = (child.index(), j);
        }
    }

    fn admit(&mut self, index: usize) {
        let pair = &self.scratch.pairs[index];
        self.total += luminance64(pair.estimate());
        self.pairs += 1;
        if pair.bound > 0.0 {
            self.scratch.heap.push(key(pair.bound, index));
        }
    }

    /// Replaces `pair` by its two children on the side the refinement
    /// chooses: the gather side when the light side cannot split (a leaf
    /// or coincident lights), the light side when the gather side cannot
    /// (one gather point), else the side whose two children's bounds sum
    /// to less (docs/design.md §13.4: where [MDLC06] compares the two
    /// clusters' sizes, this also sees a pixel's points on two faces of an
    /// edge, whose normal cone a size does not measure).
    fn refine(&mut self, pair: &Pair) {
        let (t, b, k) = (pair.tree, pair.block as usize, pair.slot as usize);
        let child = self.trees[t as usize].blocks[b].child[k];
        let children = self.scratch.nodes[pair.gather as usize].below.children();
        let gather_split = children.map(|[g0, g1]| [self.bounds(g0, t, b)[k], self.bounds(g1, t, b)[k]]);
        let light_split = (!child.is_exact()).then(|| self.bounds(pair.gather, t, child.index()));
        match (children, gather_split, light_split) {
            (Some(gs), Some(gather), light) if light.is_none_or(|l| gather[0] + gather[1] < l[0] + l[1]) => {
                for (g, bound) in gs.into_iter().zip(gather) {
                    self.add(g, t, b, k, bound, Some(pair));
                }
            }
            (_, _, Some(light)) => {
                for (slot, bound) in light.into_iter().enumerate() {
                    self.add(pair.gather, t, child.index(), slot, bound, Some(pair));
                }
            }
            // A point against an exact slot has bound 0 and is never refined.
            _ => {}
        }
    }

    /// Evaluates the pending pairs' representative pairs (M G V per unit,
    /// one shadow ray each where it can contribute), gather point by gather
    /// point, and admits the pairs.
    fn flush(&mut self) {
        let GatherScratch { pending, pairs, chosen, evaluations, .. } = &mut *self.scratch;
        pending.sort_by_key(|&p| (pairs[p as usize].gather_representative, p));
        // Every pending pair's term, gather point by gather point, then all
        // their shadow rays in one call.
        evaluations.clear();
        let mut start = 0;
        while start < pending.len() {
            let point = pairs[pending[start] as usize].gather_representative;
            let run =
                pending[start..].iter().take_while(|&&p| pairs[p as usize].gather_representative == point).count();
            let evaluator = LightEvaluator::new(&self.points[point as usize].sp);
            chosen.clear();
            for &p in &pending[start..start + run] {
                let pair = &pairs[p as usize];
                let tree = &self.trees[pair.tree as usize];
                let light = tree.representative(pair.light_block as usize, pair.light_slot as usize);
                chosen.push(tree.kind, &light, DVec3::ONE, 0);
            }
            evaluate_into(&evaluator, chosen, evaluations);
            start += run;
        }
        let (units, rays) = trace_evaluations(self.embree, crate::embree::PacketWidth::Eight, evaluations);
        self.shadow_rays += rays;
        for (&p, &unit) in pending.iter().zip(units) {
            pairs[p as usize].unit = unit;
        }
        // Admitted in creation order, so the total's sums do not depend on
        // the evaluation's grouping.
        pending.sort_unstable();
        let admitted = std::mem::take(&mut self.scratch.pending);
        for &p in &admitted {
            self.admit(p as usize);
        }
        self.scratch.pending = admitted;
        self.scratch.pending.clear();
    }
}

/// A pixel's gather points, the root of their tree, and the key of its
/// representatives' draws.
#[derive(Clone, Copy)]
struct Gathered<'g, 'p> {
    points: &'g [GatherPoint<'p>],
    root: u32,
    salt: u64,
}

/// One product-graph cut through `trees.trees[range]` for the pixel's
/// gather tree (root `root`), its threshold relative to the pixel's total
/// through those trees, added to `result`: every pair's estimate is also
/// credited to the slot of its tree's group.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn product_cut(
    all: &LightTrees,
    range: std::ops::Range<usize>,
    gathered: &Gathered<'_, '_>,
    embree: &EmbreeScene,
    settings: &CutSettings,
    scratch: &mut GatherScratch,
    result: &mut CutResult,
) {
    let Gathered { points, root, salt } = *gathered;
    let trees = &all.trees[range.clone()];
    let fixed = exhaustive_trees(all, &range, points, embree, scratch, result);
    scratch.pairs.clear();
    scratch.heap.clear();
    scratch.pending.clear();
    let mut cut =
        ProductCut { trees, salt, points, embree, scratch, total: luminance64(fixed), pairs: 0, shadow_rays: 0 };
    for t in (0..trees.len()).filter(|&t| !trees[t].blocks.is_empty()) {
        let bound = cut.bounds(root, t as TreeIndex, 0)[0];
        cut.add(root, t as TreeIndex, 0, 0, bound, None);
    }
    cut.flush();
    let max_cut = settings.max_cut.min(MAX_PAIRS);
    let scale = f64::from(all.scale);
    loop {
        let threshold = (settings.error * cut.total.max(0.0) * scale) as f32;
        let mut refined = 0;
        while refined < REFINE_BATCH && cut.pairs + refined < max_cut {
            let Some(&top) = cut.scratch.heap.peek() else { break };
            if f32::from_bits((top >> 32) as u32) <= threshold {
                break;
            }
            cut.scratch.heap.pop();
            let index = !(top as u32) as usize;
            let pair = cut.scratch.pairs[index];
            cut.scratch.pairs[index].in_cut = false;
            cut.total -= luminance64(pair.estimate());
            cut.pairs -= 1;
            cut.refine(&pair);
            refined += 1;
        }
        if refined == 0 {
            break;
        }
        cut.flush();
    }
    let (mut radiance, mut bound) = (fixed, 0.0f64);
    for pair in cut.scratch.pairs.iter().filter(|p| p.in_cut) {
        radiance += pair.estimate();
        bound += f64::from(pair.bound);
        result.credit(all.group_of_tree[range.start + pair.tree as usize], pair.estimate());
    }
    result.radiance += radiance;
    result.error_bound += bound / scale;
    result.nodes += cut.pairs as u64;
    result.shadow_rays += cut.shadow_rays;
}

/// The trees laid out light by light (none when built for this mode, which
/// builds every tree as a tree): each light at each gather point, times
/// the point's strength, counted into `result` (each value credited to its
/// group's slot); returns their radiance.
fn exhaustive_trees(
    all: &LightTrees,
    range: &std::ops::Range<usize>,
    points: &[GatherPoint<'_>],
    embree: &EmbreeScene,
    scratch: &mut GatherScratch,
    result: &mut CutResult,
) -> DVec3 {
    let mut radiance = DVec3::ZERO;
    for t in range.clone().filter(|&t| !all.trees[t].lights.is_empty()) {
        let tree = &all.trees[t];
        for g in points {
            let found = super::exhaustive(std::slice::from_ref(tree), &g.sp, embree, &mut scratch.batch);
            let value = found.radiance * g.strength;
            radiance += value;
            result.nodes += found.lights;
            result.shadow_rays += found.shadow_rays;
            result.credit(all.group_of_tree[t], value);
        }
    }
    radiance
}
