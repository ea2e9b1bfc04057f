//! Reconstruction cuts ([LC05] section 6; docs/design.md §9.6): full bounded cuts
//! at a sparse set of anchors (the corners of pixel blocks, fixed by the
//! image), and at every other camera hit a cut reconstructed from its
//! block's four anchors. The reconstruction walks the trees from the top:
//!
//! - a node whose bound at the point is above `error` times the anchors'
//!   mean total is split, as the bounded cut splits it (the anchors' total
//!   stands in for the point's, which is not known before its cut is);
//! - a node the anchors agree on is estimated without a shadow ray: all
//!   saw it occluded (every one of their cut nodes at or below it, or the
//!   cut node above it), it is dropped; all saw it visible, its
//!   representative's M * G at the point counts with V = 1;
//! - where they disagree, a node some anchor refined is split, to find
//!   where the disagreement is; one no anchor refined is traced, as the
//!   bounded cut traces it.
//!
//! What is interpolated is visibility only: the material and geometric
//! terms are the point's own, and every node kept has the bounded cut's
//! error bound at the point. A node's estimate and its exact sum both lie
//! between 0 and its bound whatever visibility is assumed, so the point's
//! error stays within the sum of its nodes' bounds. A node whose
//! representative an anchor did not trace (M * G was 0 there) counts as a
//! disagreement. At `error` 0 nothing is assumed: every node is traced,
//! and the cut is the exact sum.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use glam::DVec3;

use super::bounds::PointBounds;
use super::{by_group_at_best, exhaustive_part, CutResult, CutSettings};
use crate::embree::{PacketWidth, Scene as EmbreeScene};
use crate::light_tree::layout::Child;
use crate::light_tree::{LightTrees, TreeIndex};
use crate::shading::{
    evaluate_and_trace, evaluate_into, BatchBuffers, Choices, Evaluations, LightEvaluator, SurfacePoint,
};

/// The anchors a reconstructed cut reads: the corners of its pixel block.
pub const ANCHORS: usize = 4;

/// What an anchor's cut saw of a node's lights.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Visibility {
    /// Every shadow ray under the node (or the one above it) was unblocked.
    Visible,
    /// Every one was blocked.
    Occluded,
    /// Some of each, or a representative that was not traced.
    Mixed,
}

/// One node of an anchor's cut, or one it refined.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AnchorNode {
    pub visibility: Visibility,
    /// Whether the anchor split it (its cut is below the node).
    pub refined: bool,
}

/// The hasher of node keys: the keys are already distinct integers, mixed
/// once (SplitMix's finaliser).
#[derive(Default)]
pub struct NodeHasher(u64);

impl Hasher for NodeHasher {
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = crate::util::sampling::mix64(self.0 ^ u64::from(b));
        }
    }

    fn write_u64(&mut self, key: u64) {
        self.0 = crate::util::sampling::mix64(key);
    }
}

/// What one anchor's full cut found: per cut through a range of trees (in
/// [`super::by_group`]'s order), the luminance of its total; per node it made,
/// what it saw.
#[derive(Debug, Clone, Default)]
pub struct AnchorCut {
    pub(crate) totals: Vec<f64>,
    nodes: HashMap<u64, AnchorNode, BuildHasherDefault<NodeHasher>>,
}

impl AnchorCut {
    pub fn clear(&mut self) {
        self.totals.clear();
        self.nodes.clear();
    }

    /// The key of the node `child` of the scene's tree `tree`.
    fn key(tree: usize, child: Child) -> u64 {
        ((tree as u64) << 32) | u64::from(child.bits())
    }

    pub(crate) fn insert(&mut self, tree: usize, child: Child, node: AnchorNode) {
        self.nodes.insert(Self::key(tree, child), node);
    }

    /// What the anchor's cut made of node `child` of tree `tree`; None for
    /// a node below its cut.
    #[must_use]
    pub fn node(&self, tree: usize, child: Child) -> Option<AnchorNode> {
        self.nodes.get(&Self::key(tree, child)).copied()
    }

    /// Nodes recorded (the anchor's cut and the nodes it refined).
    #[must_use]
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }
}

/// A node's views by the four anchors of a block, a nibble each (anchor a
/// in bits 4a to 4a + 3): bit 0 set when the anchor made the node, bit 1
/// when it refined it, bits 2 and 3 its [`Visibility`] (0 visible, 1
/// occluded, 2 mixed).
type Views = u16;

const MADE: Views = 0x1111;
const REFINED: Views = 0x2222;

fn nibble(node: AnchorNode) -> Views {
    let visibility = match node.visibility {
        Visibility::Visible => 0,
        Visibility::Occluded => 1,
        Visibility::Mixed => 2,
    };
    1 | (Views::from(node.refined) << 1) | (visibility << 2)
}

/// The four anchors of a pixel block merged for the walk: per cut through
/// a range of trees, their mean total; per node any of them made, each
/// one's view of it ([`Views`]), so that a node costs one look-up.
#[derive(Debug, Clone, Default)]
pub struct AnchorBlock {
    totals: Vec<f64>,
    nodes: HashMap<u64, Views, BuildHasherDefault<NodeHasher>>,
}

impl AnchorBlock {
    #[must_use]
    pub fn merge(anchors: [&AnchorCut; ANCHORS]) -> Self {
        let calls = anchors.iter().map(|a| a.totals.len()).max().unwrap_or(0);
        let totals = (0..calls)
            .map(|i| anchors.iter().map(|a| a.totals.get(i).copied().unwrap_or(0.0)).sum::<f64>() / ANCHORS as f64)
            .collect();
        let mut nodes: HashMap<u64, Views, BuildHasherDefault<NodeHasher>> = HashMap::default();
        for (a, anchor) in anchors.iter().enumerate() {
            for (&key, &node) in &anchor.nodes {
                *nodes.entry(key).or_insert(0) |= nibble(node) << (4 * a);
            }
        }
        Self { totals, nodes }
    }

    /// The views of node `child` of the scene's tree `tree`, whose parent's
    /// are `parent`: an anchor that did not make the node (it is below its
    /// cut) sees it as it saw the parent, unrefined.
    #[inline(always)]
    fn views(&self, tree: usize, child: Child, parent: Views) -> Views {
        let made = self.nodes.get(&AnchorCut::key(tree, child)).copied().unwrap_or(0);
        // Each nibble whose bit 0 is set, all four bits set (no carries).
        let mask = (made & MADE) * 0xF;
        (made & mask) | (parent & !mask & !REFINED) | MADE
    }
}

/// What the anchors agree a node's visibility is, and whether any refined it.
#[inline(always)]
fn agreement(views: Views) -> (Visibility, bool) {
    let visibility = (views >> 2) & 0x3333;
    let agreed = if visibility == (visibility & 3) * 0x1111 {
        match visibility & 3 {
            0 => Visibility::Visible,
            1 => Visibility::Occluded,
            _ => Visibility::Mixed,
        }
    } else {
        Visibility::Mixed
    };
    (agreed, views & REFINED != 0)
}

/// A node waiting in the walk: slot `slot` of block `block` of tree
/// `tree`, its bound at the point, and the anchors' views of it.
#[derive(Clone, Copy)]
struct Node {
    tree: TreeIndex,
    block: u32,
    slot: u8,
    bound: f32,
    views: Views,
}

/// Per-thread buffers reused across shading points.
#[derive(Default)]
pub struct ReconstructionScratch {
    batch: BatchBuffers,
    stack: Vec<Node>,
    /// The cut's nodes estimated with V = 1 and those traced: their
    /// representatives, and each one's tree and intensity.
    interpolated: Choices,
    interpolated_nodes: Vec<(TreeIndex, DVec3)>,
    traced: Choices,
    traced_nodes: Vec<(TreeIndex, DVec3)>,
    evaluations: Evaluations,
}

/// Direct light at `sp` by a cut reconstructed from `anchors` (the full
/// cuts at the corners of the point's pixel block, with the same settings
/// and `groups`, merged).
pub fn evaluate(
    trees: &LightTrees,
    sp: &SurfacePoint<'_>,
    embree: &EmbreeScene,
    settings: &CutSettings,
    anchors: &AnchorBlock,
    scratch: &mut ReconstructionScratch,
    groups: usize,
) -> CutResult {
    let mut call = 0;
    by_group_at_best(
        trees,
        groups,
        settings.group_error,
        #[inline(always)]
        |range, result| {
            reconstruct(trees, range, call, sp, embree, settings, anchors, scratch, result);
            call += 1;
        },
    )
}

/// One reconstructed cut through `all.trees[range]`, the `call`-th of the
/// point (the anchors' `call`-th cut is through the same trees).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn reconstruct(
    all: &LightTrees,
    range: std::ops::Range<usize>,
    call: usize,
    sp: &SurfacePoint<'_>,
    embree: &EmbreeScene,
    settings: &CutSettings,
    anchors: &AnchorBlock,
    scratch: &mut ReconstructionScratch,
    result: &mut CutResult,
) {
    let trees = &all.trees[range.clone()];
    let fixed = exhaustive_part(all, &range, sp, embree, &mut scratch.batch, result);
    if trees.iter().all(|t| t.blocks.is_empty()) {
        result.radiance += fixed;
        return;
    }
    // The bounded cut's rule (docs/design.md §9.1), relative to the
    // anchors' mean total: each anchor's total is its radiance's luminance.
    let total = anchors.totals.get(call).copied().unwrap_or(0.0);
    let scale = all.scale;
    let threshold = (settings.error * total.max(0.0) * f64::from(scale)) as f32;
    let bounds = PointBounds::new(sp, scale);
    let ReconstructionScratch { stack, interpolated, interpolated_nodes, traced, traced_nodes, evaluations, .. } =
        scratch;
    stack.clear();
    interpolated.clear();
    interpolated_nodes.clear();
    traced.clear();
    traced_nodes.clear();

    // Pushes both children of block `b` of tree `t`, each anchor's view of
    // a child it made is its own; of one below its cut, the parent's.
    let push_children = |stack: &mut Vec<Node>, t: usize, b: usize, parent: Views| {
        let tree = &trees[t];
        let block = &tree.blocks[b];
        let pair = bounds.pair(tree.kind, block, tree.cones_of(b));
        for (k, &bound) in pair.iter().enumerate() {
            let child = block.child[k];
            if child == Child::EMPTY {
                continue;
            }
            let views = anchors.views(range.start + t, child, parent);
            stack.push(Node { tree: t as TreeIndex, block: b as u32, slot: k as u8, bound, views });
        }
    };
    // A root no anchor made (it cannot happen with the anchors' settings)
    // is a disagreement: it is traced.
    let unknown: Views = 0x8888;
    for t in (0..trees.len()).rev() {
        if !trees[t].blocks.is_empty() {
            push_children(stack, t, 0, unknown);
        }
    }
    let max_cut = settings.max_cut.max(1);
    let (mut nodes, mut bound) = (0usize, 0.0f64);
    while let Some(node) = stack.pop() {
        let tree = &trees[node.tree as usize];
        let block = &tree.blocks[node.block as usize];
        let (k, child) = (node.slot as usize, block.child[node.slot as usize]);
        let (mut agreed, refined_by_some) = agreement(node.views);
        if settings.error <= 0.0 {
            // `--error 0` asks for the exact sum: nothing is assumed seen.
            agreed = Visibility::Mixed;
        }
        // Both children join the cut in this node's place.
        let room = nodes + stack.len() + 2 <= max_cut;
        let split = node.bound > threshold || (agreed == Visibility::Mixed && refined_by_some);
        if !child.is_leaf() && room && split {
            push_children(stack, node.tree as usize, child.index(), node.views);
            continue;
        }
        nodes += 1;
        bound += f64::from(node.bound);
        let intensity = DVec3::new(
            f64::from(block.intensity[0][k]),
            f64::from(block.intensity[1][k]),
            f64::from(block.intensity[2][k]),
        );
        let light = tree.representative(node.block as usize, k);
        match agreed {
            Visibility::Occluded => {}
            Visibility::Visible => {
                interpolated.push(tree.kind, &light, DVec3::ONE, 0);
                interpolated_nodes.push((node.tree, intensity));
            }
            Visibility::Mixed => {
                traced.push(tree.kind, &light, DVec3::ONE, 0);
                traced_nodes.push((node.tree, intensity));
            }
        }
    }

    let evaluator = LightEvaluator::new(sp);
    let mut radiance = fixed;
    evaluations.clear();
    evaluate_into(&evaluator, interpolated, evaluations);
    for (&unit, &(tree, intensity)) in evaluations.values().iter().zip(interpolated_nodes.iter()) {
        let estimate = unit * intensity;
        radiance += estimate;
        result.credit(all.group_of_tree[range.start + tree as usize], estimate);
    }
    let (units, rays) = evaluate_and_trace(&evaluator, embree, PacketWidth::Eight, traced, evaluations);
    for (&unit, &(tree, intensity)) in units.iter().zip(traced_nodes.iter()) {
        let estimate = unit * intensity;
        radiance += estimate;
        result.credit(all.group_of_tree[range.start + tree as usize], estimate);
    }
    result.radiance += radiance;
    result.error_bound += bound / f64::from(scale);
    result.nodes += nodes as u64;
    result.shadow_rays += rays;
}

#[cfg(test)]
mod tests;
