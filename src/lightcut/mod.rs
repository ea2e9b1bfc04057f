//! Lightcuts ([LC05]): per shading point, a cut through the light
//! trees whose every cluster's error bound is at most `error` times the total
//! estimate, or `max_cut` nodes (docs/design.md, "The bounded cut").
//! `bounds` holds the provable upper bounds of the material and geometric
//! terms over a cluster; `cut` the refinement with representatives fixed
//! when the tree is built ([LC05], "bounded"); `stochastic` the cut whose
//! lights are drawn per sample ([SLC19]); `multidimensional` the cut per
//! pixel through (gather cluster, light cluster) pairs ([MDLC06]). What the
//! three share is here: their settings and result, the policy of which
//! trees are too small for a cut, their exact part, and the dispatch by
//! light group.

pub mod bounds;
pub mod cut;
pub mod multidimensional;
pub mod reconstruction;
pub mod reuse;
pub mod stochastic;

use glam::DVec3;

pub use cut::{evaluate, CutScratch};
pub use stochastic::StochasticScratch;

use crate::embree::Scene as EmbreeScene;
use crate::light::Lights;
use crate::light_tree::layout::CutTree;
use crate::light_tree::LightTrees;
use crate::shading::{BatchBuffers, BatchResult, LightBatch, SurfacePoint};

/// A tree with at most this many lights is evaluated light by light, with
/// the exact renderer's code, in the bounded and stochastic cuts (the
/// multidimensional one builds every tree as a tree): below it, the bounds cost
/// more than the shadow rays they save (docs/notebook/measurements.md, "The
/// exhaustive switch", measures the break-even).
pub const EXHAUSTIVE_LIGHTS: usize = 200;

/// The light trees of `groups` (a light group each) for the cut modes:
/// trees of at most [`EXHAUSTIVE_LIGHTS`] lights are kept as lists.
#[must_use]
pub fn build_trees(groups: &[Lights], seed: u64) -> LightTrees {
    build_trees_with(groups, seed, &CutSettings::default())
}

/// [`build_trees`] with `settings`' switch (`exhaustive_lights`).
#[must_use]
pub fn build_trees_with(groups: &[Lights], seed: u64, settings: &CutSettings) -> LightTrees {
    LightTrees::build_groups(groups, seed, settings.exhaustive_lights)
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CutSettings {
    /// Relative error threshold epsilon (0.02 = 2%, Weber's law).
    pub error: f64,
    /// Largest cut, in nodes (per light group with [`GroupError::Group`]).
    pub max_cut: usize,
    /// What the threshold is relative to when the scene has light groups.
    pub group_error: GroupError,
    /// Trees of at most this many lights are evaluated light by light
    /// ([`EXHAUSTIVE_LIGHTS`]; `lightcuts bench switch` sets it to measure
    /// the break-even).
    pub exhaustive_lights: usize,
    /// The stochastic cut's shadow rays per cut (`--resampled-rays`): 0
    /// traces every cut node's light; N > 0 traces N of them resampled by
    /// their unoccluded contributions (docs/design.md §10.7) when the cut
    /// has more. The other modes ignore it.
    pub resampled_rays: usize,
    /// The bounded mode's reconstruction cuts (`--reconstruct B`): 0 cuts
    /// every camera hit in full; B > 0 cuts in full only at the corners of
    /// B x B pixel blocks and reconstructs the cuts of the camera hits in
    /// between from them (docs/design.md §9.6). The other modes ignore it.
    pub reconstruction_block: u32,
    /// The stochastic cut's cut chosen once per pixel (docs/design.md
    /// §10.9): the cut chosen at a pixel's first sample's camera hit serves
    /// every later sample of the pixel whose camera hit is on the same
    /// surface; false (`--cut-per-sample`) chooses a cut at every shading
    /// point. The other modes ignore it.
    pub pixel_cut: bool,
    /// The stochastic cut's draws per shading point (`--cut-draws M`,
    /// docs/design.md §10.10): 0 walks from every cut node, one light
    /// each ([SLC19]); M > 0 draws M lights over the whole cut, each node
    /// by its importance, one shadow ray each. The other modes ignore it.
    pub cut_draws: usize,
    /// The stochastic cut's reuse between pixels (`--reuse B`,
    /// docs/design.md §10.11): 0 lights each camera hit by its own drawn
    /// lights; B > 0 lights it by the drawn lights of every camera hit of
    /// its B x B pixel block at the same sample index, weighted by
    /// multiple importance sampling. The other modes ignore it.
    pub reuse_block: u32,
}

impl Default for CutSettings {
    fn default() -> Self {
        Self {
            error: 0.02,
            max_cut: 1000,
            group_error: GroupError::Group,
            exhaustive_lights: EXHAUSTIVE_LIGHTS,
            resampled_rays: 0,
            reconstruction_block: 0,
            pixel_cut: false,
            cut_draws: 0,
            reuse_block: 0,
        }
    }
}

/// What a scene with light groups holds each group's error to
/// (`--group-error`). Clusters never span groups either way.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GroupError {
    /// A cut per group, each refined until every node's bound is within
    /// `error` of that group's own total: a dim fill light's layer is as
    /// accurate as the key light's (and the beauty, their sum, at least as
    /// accurate as without groups).
    Group,
    /// One cut through every group's trees, refined against the pixel's
    /// total as without groups; each node's estimate goes to its group's
    /// layer. Cheaper, but a dim group's layer is accurate only relative to
    /// the pixel.
    Pixel,
}

impl GroupError {
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Group => "group",
            Self::Pixel => "pixel",
        }
    }
}

/// What a shading point's direct light came to (or a pixel's, in the
/// multidimensional mode): the radiance, each light group's share of it
/// when the pass splits the radiance by group, the cut's error bound and
/// what it cost. Every mode, and the integrator's parts outside the cut
/// (moving lights), add into one of these; [`CutResult::add_scaled_to`]
/// moves it into a pixel.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CutResult {
    /// Direct radiance towards the viewer, W/(m^2 sr) per channel.
    pub radiance: DVec3,
    /// Each light group's share of `radiance`: one slot per group when the
    /// pass splits the radiance by group, none otherwise.
    pub groups: Vec<DVec3>,
    /// Sum of the error bounds of the final cut's nodes: the design's
    /// guarantee on this point's error in luminance (|L_cut - L_exact| <= it).
    pub error_bound: f64,
    /// Nodes of the final cut, counting each light of a tree evaluated
    /// light by light as one node.
    pub nodes: u64,
    pub shadow_rays: u64,
}

impl CutResult {
    /// Nothing found yet, with `groups` slots (0: the radiance is not split).
    #[must_use]
    pub fn with_groups(groups: usize) -> Self {
        Self { groups: vec![DVec3::ZERO; groups], ..Self::default() }
    }

    /// Credits `value` (already counted in, or about to be added to, the
    /// radiance) to group `group`'s slot; nothing when there are no slots.
    #[inline(always)]
    pub fn credit(&mut self, group: usize, value: DVec3) {
        if let Some(slot) = self.groups.get_mut(group) {
            *slot += value;
        }
    }

    /// The light of a batch of lights of group `group` (its radiance
    /// credited to the group's slot), with what it cost; returns the
    /// batch's radiance, which the caller adds to its running sum.
    #[inline(always)]
    pub fn count_batch(&mut self, group: usize, batch: &BatchResult) -> DVec3 {
        self.credit(group, batch.radiance);
        self.nodes += batch.lights;
        self.shadow_rays += batch.shadow_rays;
        batch.radiance
    }

    /// Adds `scale` times this radiance to `radiance`, and times each
    /// group's share to `groups`' slots (a pixel's sums).
    pub fn add_scaled_to(&self, scale: DVec3, radiance: &mut DVec3, groups: &mut [DVec3]) {
        *radiance += scale * self.radiance;
        for (slot, value) in groups.iter_mut().zip(&self.groups) {
            *slot += scale * *value;
        }
    }
}

/// Every light of the trees too small for a cut, one by one with the exact
/// renderer's code (the same for every cut mode).
#[inline(always)]
pub(crate) fn exhaustive(
    trees: &[CutTree],
    sp: &SurfacePoint<'_>,
    embree: &EmbreeScene,
    batch: &mut BatchBuffers,
) -> BatchResult {
    let mut exhaustive = LightBatch::new(embree, sp, batch);
    for tree in trees {
        for light in &tree.lights {
            exhaustive.add(&light.light(tree.kind));
        }
    }
    exhaustive.finish()
}

/// The exact part of a cut through `trees.trees[range]` (every light of its
/// trees too small for a cut, by [`exhaustive`]): counted into `result`
/// (its nodes and shadow rays; with group slots, group by group, the range
/// holding whole groups' trees, each group's sum credited to its slot).
/// Returns its radiance, where the cut's sum starts.
#[inline(always)]
pub(crate) fn exhaustive_part(
    trees: &LightTrees,
    range: &std::ops::Range<usize>,
    sp: &SurfacePoint<'_>,
    embree: &EmbreeScene,
    batch: &mut BatchBuffers,
    result: &mut CutResult,
) -> DVec3 {
    if result.groups.is_empty() {
        let found = exhaustive(&trees.trees[range.clone()], sp, embree, batch);
        return result.count_batch(0, &found);
    }
    let mut radiance = DVec3::ZERO;
    let inside = |r: &&std::ops::Range<usize>| range.start <= r.start && r.end <= range.end;
    for (g, group) in trees.groups.iter().enumerate().filter(|(_, r)| inside(r)) {
        let found = exhaustive(&trees.trees[group.clone()], sp, embree, batch);
        radiance += result.count_batch(g, &found);
    }
    radiance
}

/// [`by_group`] inlined into the entry point compiled for the CPU's best
/// instruction set (docs/design.md §4): how every cut mode runs its cuts.
#[inline(always)]
pub(crate) fn by_group_at_best(
    trees: &LightTrees,
    groups: usize,
    group_error: GroupError,
    cut: impl FnMut(std::ops::Range<usize>, &mut CutResult),
) -> CutResult {
    crate::util::simd::best(
        #[inline(always)]
        || by_group(trees, groups, group_error, cut),
    )
}

/// Runs `cut` (one cut through the trees of a range, adding what it finds
/// to the result it is given: its radiance, its group slots, its counters)
/// as `group_error` says: through every tree at once when the result has
/// no group slots or with [`GroupError::Pixel`], else once per group.
/// Shared by every cut mode. `groups`: the group slots of the result (0:
/// the radiance is not split by group).
#[inline(always)]
pub(crate) fn by_group(
    trees: &LightTrees,
    groups: usize,
    group_error: GroupError,
    mut cut: impl FnMut(std::ops::Range<usize>, &mut CutResult),
) -> CutResult {
    let mut result = CutResult::with_groups(groups);
    if groups == 0 || group_error == GroupError::Pixel {
        cut(0..trees.trees.len(), &mut result);
    } else {
        for range in &trees.groups {
            cut(range.clone(), &mut result);
        }
    }
    result
}
