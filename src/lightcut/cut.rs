//! The cut per shading point ([LC05] sec. 4; ../shared/LIGHTCUTS.md section 5).
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
//! Bounds and estimates are compared on luminance. The final radiance is the
//! sum of the cut's estimates in creation order, so it is deterministic and
//! free of the cancellation a running total accumulates.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use glam::DVec3;

use super::bounds::{error_bound, PointBounds};
use crate::embree::{Scene as EmbreeScene, ShadowRay};
use crate::light_tree::{LightTree, NodeRef};
use crate::shading::{light_sample, BatchBuffers, LightBatch, SurfacePoint};
use crate::util::color::luminance64;

/// A tree with at most this many lights is evaluated light by light: for so
/// few lights the bounds cannot save a shadow ray worth their cost, and the
/// renderer must never be slower than `--exact` (measured: few4 in the README).
pub const EXHAUSTIVE_LIGHTS: usize = 200;

/// Nodes refined per batch of shadow rays.
pub const REFINE_BATCH: usize = 8;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CutSettings {
    /// Relative error threshold epsilon (0.02 = 2%, Weber's law).
    pub error: f64,
    /// Largest cut, in nodes.
    pub max_cut: usize,
}

impl Default for CutSettings {
    fn default() -> Self {
        Self { error: 0.02, max_cut: 1000 }
    }
}

/// What one shading point's cut found.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CutResult {
    /// Direct radiance towards the viewer, W/(m^2 sr) per channel.
    pub radiance: DVec3,
    /// Sum of the error bounds of the final cut's nodes: the design's
    /// guarantee on this point's error in luminance (|L_cut - L_exact| <= it).
    pub error_bound: f64,
    /// Nodes of the final cut, counting each light of a tree evaluated
    /// light by light as one node.
    pub nodes: u64,
    pub shadow_rays: u64,
}

/// One node of the cut (or one that was in it and has been refined).
#[derive(Debug, Clone, Copy)]
struct Entry {
    tree: u8,
    node: NodeRef,
    /// M * G * V of the node's representative, per unit intensity.
    unit: DVec3,
    estimate: DVec3,
    /// The node's error bound (0 for a leaf, which is exact).
    bound: f64,
    in_cut: bool,
}

/// A node whose representative still needs its shadow ray.
#[derive(Debug, Clone, Copy)]
struct Pending {
    tree: u8,
    node: NodeRef,
    unoccluded: DVec3,
    /// Index into the ray batch, or None when no ray is needed.
    ray: Option<u32>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct HeapItem {
    bound: f64,
    entry: u32,
}

impl Eq for HeapItem {}

impl Ord for HeapItem {
    fn cmp(&self, other: &Self) -> Ordering {
        // Largest bound first; ties go to the earlier entry (deterministic).
        self.bound.total_cmp(&other.bound).then_with(|| other.entry.cmp(&self.entry))
    }
}

impl PartialOrd for HeapItem {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

/// Per-thread buffers reused across shading points.
#[derive(Default)]
pub struct CutScratch {
    batch: BatchBuffers,
    entries: Vec<Entry>,
    heap: BinaryHeap<HeapItem>,
    pending: Vec<Pending>,
    rays: Vec<ShadowRay>,
    occluded: Vec<bool>,
}

struct Cut<'a, 'p> {
    trees: &'a [LightTree],
    sp: &'a SurfacePoint<'p>,
    bounds: PointBounds<'a, 'p>,
    embree: &'a EmbreeScene,
    scratch: &'a mut CutScratch,
    total: DVec3,
    cut_nodes: usize,
    shadow_rays: u64,
}

impl Cut<'_, '_> {
    /// Queues a node whose representative is new to the cut.
    fn add_new(&mut self, tree: u8, node: NodeRef) {
        let t = &self.trees[tree as usize];
        let representative = t.light(t.node_representative(node) as usize);
        // M * G per unit intensity of the representative, and its shadow ray.
        let (unoccluded, ray) = light_sample(&representative, self.sp, glam::Vec3::ONE).unwrap_or((DVec3::ZERO, None));
        let ray = ray.map(|r| {
            self.scratch.rays.push(r);
            (self.scratch.rays.len() - 1) as u32
        });
        self.scratch.pending.push(Pending { tree, node, unoccluded, ray });
    }

    /// Adds a node whose M * G * V is known (it shares its parent's representative).
    fn add_known(&mut self, tree: u8, node: NodeRef, unit: DVec3) {
        let t = &self.trees[tree as usize];
        let intensity = t.node_intensity(node);
        let estimate = unit * intensity.as_dvec3();
        let bound = if node.is_leaf() {
            0.0
        } else {
            let (lo, hi) = t.node_bounds(node);
            let cone = t.node_cone(node);
            // Lights at one position (omni), or one direction (directional),
            // or one position and one normal (oriented) have identical M, G
            // and V: the representative's estimate is exact, the error 0.
            if lo == hi && cone.half_angle == 0.0 {
                0.0
            } else {
                error_bound(self.bounds.cluster(t.kind, lo, hi, cone), intensity)
            }
        };
        let index = self.scratch.entries.len() as u32;
        self.scratch.entries.push(Entry { tree, node, unit, estimate, bound, in_cut: true });
        self.total += estimate;
        self.cut_nodes += 1;
        if bound > 0.0 {
            self.scratch.heap.push(HeapItem { bound, entry: index });
        }
    }

    /// Traces the queued shadow rays in one batch and adds their nodes.
    fn flush(&mut self) {
        if self.scratch.pending.is_empty() {
            return;
        }
        self.embree.occluded_batch(&self.scratch.rays, &mut self.scratch.occluded);
        self.shadow_rays += self.scratch.rays.len() as u64;
        let pending = std::mem::take(&mut self.scratch.pending);
        for p in &pending {
            let visible = p.ray.is_none_or(|r| !self.scratch.occluded[r as usize]);
            let unit = if visible { p.unoccluded } else { DVec3::ZERO };
            self.add_known(p.tree, p.node, unit);
        }
        self.scratch.pending = pending;
        self.scratch.pending.clear();
        self.scratch.rays.clear();
    }
}

/// Direct light at `sp` from every tree, by a lightcut.
pub fn evaluate(
    trees: &[LightTree],
    sp: &SurfacePoint<'_>,
    embree: &EmbreeScene,
    settings: &CutSettings,
    scratch: &mut CutScratch,
) -> CutResult {
    // Small trees first, light by light with the exact renderer's code; their
    // sum is exact and counts in the total the threshold is relative to.
    let mut exhaustive = LightBatch::new(embree, sp, &mut scratch.batch);
    for tree in trees.iter().filter(|t| t.light_count() <= EXHAUSTIVE_LIGHTS) {
        for i in 0..tree.light_count() {
            exhaustive.add(&tree.light(i));
        }
    }
    let fixed = exhaustive.finish();
    let mut result =
        CutResult { radiance: fixed.radiance, error_bound: 0.0, nodes: fixed.lights, shadow_rays: fixed.shadow_rays };
    if fixed.lights as usize == trees.iter().map(LightTree::light_count).sum::<usize>() {
        return result;
    }

    scratch.entries.clear();
    scratch.heap.clear();
    scratch.pending.clear();
    scratch.rays.clear();
    let mut cut = Cut {
        trees,
        sp,
        bounds: PointBounds::new(sp),
        embree,
        scratch,
        total: fixed.radiance,
        cut_nodes: 0,
        shadow_rays: 0,
    };
    for (i, tree) in trees.iter().enumerate() {
        if tree.light_count() > EXHAUSTIVE_LIGHTS {
            cut.add_new(i as u8, tree.root.expect("a tree with lights has a root"));
        }
    }
    cut.flush();
    loop {
        let threshold = settings.error * luminance64(cut.total).max(0.0);
        let mut refined = 0;
        while refined < REFINE_BATCH && cut.cut_nodes + refined < settings.max_cut {
            let Some(top) = cut.scratch.heap.peek().copied() else { break };
            if top.bound <= threshold {
                break;
            }
            cut.scratch.heap.pop();
            let entry = cut.scratch.entries[top.entry as usize];
            cut.scratch.entries[top.entry as usize].in_cut = false;
            cut.total -= entry.estimate;
            cut.cut_nodes -= 1;
            let tree = &trees[entry.tree as usize];
            let representative = tree.node_representative(entry.node);
            for child in tree.node_children(entry.node) {
                if tree.node_representative(child) == representative {
                    cut.add_known(entry.tree, child, entry.unit);
                } else {
                    cut.add_new(entry.tree, child);
                }
            }
            refined += 1;
        }
        if refined == 0 {
            break;
        }
        cut.flush();
    }
    let in_cut = || cut.scratch.entries.iter().filter(|e| e.in_cut);
    result.radiance = in_cut().fold(fixed.radiance, |sum, e| sum + e.estimate);
    result.error_bound = in_cut().map(|e| e.bound).sum();
    // The exhaustive part's lights are in the point's cut too.
    result.nodes += cut.cut_nodes as u64;
    result.shadow_rays += cut.shadow_rays;
    result
}

#[cfg(test)]
mod tests;
