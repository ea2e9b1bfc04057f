//! The bounded cut per shading point ([LC05]; docs/design.md §9).
//!
//! Start from the roots of the trees present; keep the cut in a max-heap on
//! error bound; replace the node with the largest bound by its children while
//! that bound exceeds `error` times the total estimate and the cut is smaller
//! than `max_cut`. The child that shares its parent's representative reuses
//! the parent's M * G * V (no new shadow ray); the other costs one shadow ray.
//!
//! Shadow rays go to Embree in batches: each step pops up to
//! `REFINE_BATCH` nodes that are above the threshold, refines them all, and
//! traces their new rays in one call. Refining a node the one-at-a-time
//! algorithm would have kept only tightens the result.
//!
//! A refinement reads one block of the tree's layout (both children's boxes,
//! intensities, cones and representatives), bounds both children at once
//! (`bounds`), and keys the heap with integers: the bound's f32 bits (a
//! non-negative float orders like its bits) above the entry's index. Only
//! nodes whose bounds are above the threshold are kept in the heap; the
//! others wait in a list and join it if the threshold falls below them
//! (`Cut::set_threshold`), so the nodes refined are the same, in the same
//! order, as with every node in one heap.
//!
//! Bounds and estimates are compared on luminance. Estimates are f64: the
//! representative's M G V, exactly the exact renderer's, times the node's
//! intensity. The final radiance is the sum of the cut's estimates in
//! creation order, so it is deterministic and free of the cancellation a
//! running total accumulates.

use glam::{DVec3, Vec3};
use std::collections::BinaryHeap;

use super::bounds::PointBounds;
use super::reconstruction::{AnchorCut, AnchorNode, Visibility};
use super::{by_group_at_best, exhaustive_part, CutResult, CutSettings};
use crate::embree::{PacketWidth, Scene as EmbreeScene};
use crate::light_tree::layout::{Child, CutTree};
use crate::light_tree::{LightTrees, TreeIndex, MAX_TREES};
use crate::shading::{evaluate_and_trace, BatchBuffers, Choices, Evaluations, LightEvaluator, SurfacePoint};
use crate::util::color::luminance64;

/// Nodes refined per batch of shadow rays (each refinement needs one ray:
/// one child shares its parent's representative).
pub const REFINE_BATCH: usize = 8;

/// One node of the cut (or one that was in it and has been refined).
#[derive(Debug, Clone, Copy)]
struct Entry {
    /// M * G * V of the node's representative, per unit intensity.
    unit: DVec3,
    /// The node's summed intensity: its estimate is unit * intensity.
    intensity: Vec3,
    /// Normalised error bound (0 for an exact node).
    bound: f32,
    child: Child,
    representative: u32,
    tree: TreeIndex,
    in_cut: bool,
    /// What the representative's shadow ray found (reconstruction cuts'
    /// anchors read it: docs/design.md §9.6).
    seen: Seen,
}

/// What a cut node's shadow ray found at a shading point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Seen {
    /// No ray was traced: the representative's M * G was 0.
    Untraced,
    Visible,
    Occluded,
}

impl Entry {
    /// What a child sharing this node's representative reuses.
    #[inline(always)]
    fn shared(&self) -> (u32, DVec3, Seen) {
        (self.representative, self.unit, self.seen)
    }

    /// The node's estimate, M * G * V of the representative times the
    /// node's intensity ([LC05] eq. 2); f64, the same bits every time.
    #[inline]
    fn estimate(&self) -> DVec3 {
        self.unit * self.intensity.as_dvec3()
    }
}

/// An entry whose representative's M * G * V is still to be found (the
/// child of a refined node that does not share its parent's
/// representative): where its representative is, slot `slot` of block
/// `block` of its tree.
#[derive(Debug, Clone, Copy)]
struct Pending {
    entry: u32,
    block: u32,
    slot: u8,
}

/// Bits of the heap key that hold an entry's index, below the tree's 9
/// (`light_tree::MAX_TREES`).
const ENTRY_BITS: u32 = 23;
const ENTRY_MASK: u32 = (1 << ENTRY_BITS) - 1;

/// Most entries one cut may make: the heap key holds an entry's index in
/// 23 bits. A cut stops refining before it would exceed it (a cut of 4
/// million nodes, where `max_cut` is 1000 by default).
const MAX_ENTRIES: usize = 1 << ENTRY_BITS;

const _: () = assert!(MAX_TREES << ENTRY_BITS == 1 << 32, "tree and entry fill the key's low 32 bits");

/// The heap key of an entry: its bound's bits (a non-negative f32 orders
/// like its bits), its tree, and the complement of its index, so the largest
/// bound comes first, ties go to the earlier entry, and the key alone says
/// which tree a node is in.
#[inline]
fn key(bound: f32, tree: TreeIndex, entry: usize) -> u64 {
    debug_assert!(entry < MAX_ENTRIES && usize::from(tree) < MAX_TREES);
    (u64::from(bound.to_bits()) << 32) | (u64::from(tree) << ENTRY_BITS) | u64::from(!(entry as u32) & ENTRY_MASK)
}

#[inline]
fn key_entry(key: u64) -> usize {
    (!(key as u32) & ENTRY_MASK) as usize
}

#[inline]
fn key_tree(key: u64) -> TreeIndex {
    ((key as u32) >> ENTRY_BITS) as TreeIndex
}

#[inline]
fn key_bound(key: u64) -> f32 {
    f32::from_bits((key >> 32) as u32)
}

/// Per-thread buffers reused across shading points.
#[derive(Default)]
pub struct CutScratch {
    batch: BatchBuffers,
    entries: Vec<Entry>,
    heap: BinaryHeap<u64>,
    /// The keys of entries in the cut whose bound was at most the threshold
    /// when they joined it (see [`Cut::admit`]).
    below: Vec<u64>,
    pending: Vec<Pending>,
    chosen: Choices,
    evaluations: Evaluations,
}

struct Cut<'a, 'p> {
    /// The trees cut through (a group's, or every group's); entries number
    /// their tree by its index here.
    trees: &'a [CutTree],
    evaluator: LightEvaluator<'a, 'p>,
    bounds: PointBounds,
    embree: &'a EmbreeScene,
    scratch: &'a mut CutScratch,
    /// The threshold the refinements in progress compare bounds with (-inf
    /// before the first): every entry of the cut whose bound is above it is
    /// in the heap, the others may wait in `below`.
    threshold: f32,
    /// The largest bound in `below` (or 0): a threshold at or above it
    /// moves nothing.
    below_max: f32,
    /// The luminance of the cut's total estimate (what the threshold is
    /// relative to): each entry's estimate's luminance added when it joins
    /// the cut and taken away when it is refined.
    total: f64,
    cut_nodes: usize,
    shadow_rays: u64,
}

impl Cut<'_, '_> {
    /// Adds both children of the node whose block is `b` (the roots: slot 0
    /// of block 0). `parent` is the refined node's representative and its
    /// M * G * V, which the child that shares the representative reuses; the
    /// other child waits in `pending` for its representative's evaluation.
    #[inline(always)]
    fn add_children(&mut self, tree: TreeIndex, b: usize, parent: Option<(u32, DVec3, Seen)>) {
        let t = &self.trees[tree as usize];
        let bounds = self.bounds.pair(t.kind, &t.blocks[b], t.cones_of(b));
        self.add_slots(tree, b, bounds, parent);
    }

    /// [`Cut::add_children`] of two refined nodes of one tree, their four
    /// children bounded at once.
    #[inline(always)]
    fn add_children_of_two(&mut self, tree: TreeIndex, parents: [&Entry; 2]) {
        let t = &self.trees[tree as usize];
        let [b0, b1] = parents.map(|p| p.child.index());
        let cones = t.cones_of(b0).zip(t.cones_of(b1)).map(|(x, y)| [x, y]);
        let [a0, a1, c0, c1] = self.bounds.quad(t.kind, [&t.blocks[b0], &t.blocks[b1]], cones);
        self.add_slots(tree, b0, [a0, a1], Some(parents[0].shared()));
        self.add_slots(tree, b1, [c0, c1], Some(parents[1].shared()));
    }

    /// Makes the entries of block `b`'s children: the one that shares the
    /// refined node's representative (`parent`) joins the cut with its M * G
    /// * V; the other waits for its representative's evaluation.
    #[inline(always)]
    fn add_slots(&mut self, tree: TreeIndex, b: usize, bounds: [f32; 2], parent: Option<(u32, DVec3, Seen)>) {
        let block = &self.trees[tree as usize].blocks[b];
        let (shared, unit, seen) = parent.unwrap_or((u32::MAX, DVec3::ZERO, Seen::Untraced));
        for (k, &bound) in bounds.iter().enumerate() {
            let child = block.child[k];
            if child == Child::EMPTY {
                continue;
            }
            let representative = block.representative[k];
            let intensity = Vec3::new(block.intensity[0][k], block.intensity[1][k], block.intensity[2][k]);
            let index = self.scratch.entries.len();
            if representative == shared && parent.is_some() {
                self.scratch.entries.push(Entry {
                    unit,
                    intensity,
                    bound,
                    child,
                    representative,
                    tree,
                    in_cut: true,
                    seen,
                });
                self.admit(index);
            } else {
                let seen = Seen::Untraced;
                let entry =
                    Entry { unit: DVec3::ZERO, intensity, bound, child, representative, tree, in_cut: true, seen };
                self.scratch.entries.push(entry);
                self.scratch.pending.push(Pending { entry: index as u32, block: b as u32, slot: k as u8 });
            }
        }
    }

    /// Takes the node with the largest bound out of the cut, if that bound
    /// exceeds the threshold (the one the heap holds every node above:
    /// [`Cut::set_threshold`]): the node to refine.
    #[inline(always)]
    fn pop_above(&mut self) -> Option<Entry> {
        let &top = self.scratch.heap.peek()?;
        if key_bound(top) <= self.threshold {
            return None;
        }
        self.scratch.heap.pop();
        let entry = &mut self.scratch.entries[key_entry(top)];
        entry.in_cut = false;
        let entry = *entry;
        self.total -= luminance64(entry.estimate());
        self.cut_nodes -= 1;
        Some(entry)
    }

    /// Counts entry `index` into the cut: its estimate into the total, its
    /// bound into the heap, or, when the bound is not above the threshold,
    /// into `below`: most of the cut's nodes are never refined, and a heap
    /// of only the nodes that may be is smaller and cheaper to keep.
    #[inline(always)]
    fn admit(&mut self, index: usize) {
        let entry = &self.scratch.entries[index];
        self.total += luminance64(entry.estimate());
        self.cut_nodes += 1;
        // An exact node (bound 0) is never refined: it goes in neither.
        if entry.bound > 0.0 {
            let key = key(entry.bound, entry.tree, index);
            if entry.bound > self.threshold {
                self.scratch.heap.push(key);
            } else {
                self.scratch.below.push(key);
                self.below_max = self.below_max.max(entry.bound);
            }
        }
    }

    /// Sets the threshold of the next refinements. When it falls, the
    /// entries waiting in `below` whose bounds are now above it join the
    /// heap, so that the heap's largest key above the threshold is the
    /// cut's: the nodes refined, and their order, are those of one heap of
    /// every entry.
    #[inline(always)]
    fn set_threshold(&mut self, threshold: f32) {
        if threshold < self.below_max {
            let CutScratch { heap, below, .. } = &mut *self.scratch;
            let mut below_max = 0.0f32;
            below.retain(|&k| {
                let bound = key_bound(k);
                if bound > threshold {
                    heap.push(k);
                    false
                } else {
                    below_max = below_max.max(bound);
                    true
                }
            });
            self.below_max = below_max;
        }
        self.threshold = threshold;
    }

    /// Evaluates the pending entries' representatives (M * G * V per unit
    /// intensity) by the evaluate-and-trace step, and admits the entries.
    #[inline(always)]
    fn flush(&mut self) {
        if self.scratch.pending.is_empty() {
            return;
        }
        let CutScratch { pending, entries, chosen, evaluations, .. } = &mut *self.scratch;
        chosen.clear();
        for p in pending.iter() {
            let tree = &self.trees[entries[p.entry as usize].tree as usize];
            chosen.push(tree.kind, &tree.representative(p.block as usize, p.slot as usize), DVec3::ONE, 0);
        }
        let (units, rays) = evaluate_and_trace(&self.evaluator, self.embree, PacketWidth::Eight, chosen, evaluations);
        self.shadow_rays += rays;
        for (p, &unit) in pending.iter().zip(units) {
            entries[p.entry as usize].unit = unit;
        }
        for (k, occluded) in evaluations.traced() {
            entries[pending[k].entry as usize].seen = if occluded { Seen::Occluded } else { Seen::Visible };
        }
        for i in 0..self.scratch.pending.len() {
            let entry = self.scratch.pending[i].entry as usize;
            self.admit(entry);
        }
        self.scratch.pending.clear();
    }
}

/// Direct light at `sp` from every tree, by a lightcut. With `groups`
/// slots (a scene with light groups whose pass splits the radiance by
/// group), each group's share of the radiance is credited to its slot, and
/// the cut controls the error as `settings.group_error` says.
pub fn evaluate(
    trees: &LightTrees,
    sp: &SurfacePoint<'_>,
    embree: &EmbreeScene,
    settings: &CutSettings,
    scratch: &mut CutScratch,
    groups: usize,
) -> CutResult {
    evaluate_recording(trees, sp, embree, settings, scratch, groups, None)
}

/// [`evaluate`] at an anchor of reconstruction cuts (docs/design.md §9.6):
/// the same cut, and what it found recorded in `anchor` (each cut's total,
/// each node's visibility) for the samples around it.
pub fn evaluate_anchor(
    trees: &LightTrees,
    sp: &SurfacePoint<'_>,
    embree: &EmbreeScene,
    settings: &CutSettings,
    scratch: &mut CutScratch,
    groups: usize,
    anchor: &mut AnchorCut,
) -> CutResult {
    anchor.clear();
    evaluate_recording(trees, sp, embree, settings, scratch, groups, Some(anchor))
}

/// [`evaluate`], each cut recorded in `anchor` when there is one.
#[inline(always)]
fn evaluate_recording(
    trees: &LightTrees,
    sp: &SurfacePoint<'_>,
    embree: &EmbreeScene,
    settings: &CutSettings,
    scratch: &mut CutScratch,
    groups: usize,
    mut anchor: Option<&mut AnchorCut>,
) -> CutResult {
    by_group_at_best(
        trees,
        groups,
        settings.group_error,
        #[inline(always)]
        |range, result| cut_through(trees, range, sp, embree, settings, scratch, result, anchor.as_deref_mut()),
    )
}

/// One cut through `trees.trees[range]`, its threshold relative to their
/// total, added to `result`: every node's estimate is also credited to the
/// slot of its tree's group. With `anchor`, the cut is recorded there.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn cut_through(
    all: &LightTrees,
    range: std::ops::Range<usize>,
    sp: &SurfacePoint<'_>,
    embree: &EmbreeScene,
    settings: &CutSettings,
    scratch: &mut CutScratch,
    result: &mut CutResult,
    anchor: Option<&mut AnchorCut>,
) {
    let trees = &all.trees[range.clone()];
    // Small trees first, light by light with the exact renderer's code; their
    // sum is exact and counts in the total the threshold is relative to.
    let fixed = exhaustive_part(all, &range, sp, embree, &mut scratch.batch, result);
    if trees.iter().all(|t| t.blocks.is_empty()) {
        result.radiance += fixed;
        if let Some(anchor) = anchor {
            anchor.totals.push(luminance64(fixed));
        }
        return;
    }

    scratch.entries.clear();
    scratch.heap.clear();
    scratch.below.clear();
    scratch.pending.clear();
    let scale = all.scale;
    let mut cut = Cut {
        trees,
        evaluator: LightEvaluator::new(sp),
        bounds: PointBounds::new(sp, scale),
        embree,
        scratch,
        threshold: f32::NEG_INFINITY,
        below_max: 0.0,
        total: luminance64(fixed),
        cut_nodes: 0,
        shadow_rays: 0,
    };
    for (i, tree) in trees.iter().enumerate() {
        if !tree.blocks.is_empty() {
            cut.add_children(i as TreeIndex, 0, None);
        }
    }
    cut.flush();
    loop {
        // In the bounds' normalised units.
        cut.set_threshold((settings.error * cut.total.max(0.0) * f64::from(scale)) as f32);
        let mut refined = 0;
        // Only internal nodes have bounds above 0, so a popped entry has a block.
        let max_cut = settings.max_cut.min(MAX_ENTRIES / 2 - REFINE_BATCH);
        while refined < REFINE_BATCH && cut.cut_nodes + refined < max_cut {
            let Some(first) = cut.pop_above() else { break };
            refined += 1;
            // The next largest too, when it is of the same tree and the batch
            // and the cut have room: both nodes' children are bounded at once.
            let room = refined < REFINE_BATCH && cut.cut_nodes + refined + 1 < max_cut;
            let same_tree = cut.scratch.heap.peek().is_some_and(|&k| key_tree(k) == first.tree);
            match (room && same_tree).then(|| cut.pop_above()).flatten() {
                Some(second) => {
                    refined += 1;
                    cut.add_children_of_two(first.tree, [&first, &second]);
                }
                None => cut.add_children(first.tree, first.child.index(), Some(first.shared())),
            }
        }
        if refined == 0 {
            break;
        }
        cut.flush();
    }
    // The cut's sum, in the order its entries were made (after the exact part).
    let (mut radiance, mut bound) = (fixed, 0.0f64);
    for entry in cut.scratch.entries.iter().filter(|e| e.in_cut) {
        radiance += entry.estimate();
        bound += f64::from(entry.bound);
        result.credit(all.group_of_tree[range.start + entry.tree as usize], entry.estimate());
    }
    if let Some(anchor) = anchor {
        record(trees, range.start, &cut.scratch.entries, luminance64(radiance), anchor);
    }
    result.radiance += radiance;
    result.error_bound += bound / f64::from(scale);
    // The exhaustive part's lights are in the point's cut too (counted there).
    result.nodes += cut.cut_nodes as u64;
    result.shadow_rays += cut.shadow_rays;
}

/// Records a finished cut through `trees` (the scene's trees from
/// `first_tree` on) in `anchor`: its total's luminance, and every node it
/// made: a node of the cut with what its ray saw, a refined node with what
/// its cut descendants saw, all alike or [`Visibility::Mixed`]. Children
/// are made after their parents, so a reverse walk meets them first.
fn record(trees: &[CutTree], first_tree: usize, entries: &[Entry], total: f64, anchor: &mut AnchorCut) {
    anchor.totals.push(total);
    for entry in entries.iter().rev() {
        let tree = first_tree + entry.tree as usize;
        let visibility = if entry.in_cut {
            match entry.seen {
                Seen::Visible => Visibility::Visible,
                Seen::Occluded => Visibility::Occluded,
                Seen::Untraced => Visibility::Mixed,
            }
        } else {
            let block = &trees[entry.tree as usize].blocks[entry.child.index()];
            let mut children = block.child.iter().filter(|&&c| c != Child::EMPTY);
            let first = children.next().and_then(|&c| anchor.node(tree, c)).map_or(Visibility::Mixed, |n| n.visibility);
            children.fold(first, |v, &c| {
                let other = anchor.node(tree, c).map_or(Visibility::Mixed, |n| n.visibility);
                if other == v {
                    v
                } else {
                    Visibility::Mixed
                }
            })
        };
        anchor.insert(tree, entry.child, AnchorNode { visibility, refined: !entry.in_cut });
    }
}

#[cfg(test)]
pub(crate) mod tests;
