//! Lightcuts ([LC05]): per shading point, a cut through the light
//! trees whose every cluster's error bound is at most `error` times the total
//! estimate, or `max_cut` nodes (docs/design.md, "The bounded cut").
//! `bounds` holds the provable upper bounds of the material and geometric
//! terms over a cluster; `cut` the refinement with representatives fixed
//! when the tree is built ([LC05], "bounded"); `stochastic` the cut whose
//! lights are drawn per sample ([SLC19]). What both modes share is here:
//! their settings and result, the policy of which trees are too small for
//! a cut, their exact part, and the dispatch by light group.

pub mod bounds;
pub mod cut;
pub mod multidimensional;
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
/// the exact renderer's code, in both cut modes: below it, the bounds cost
/// more than the shadow rays they save (docs/measurements.md, "The
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
}

impl Default for CutSettings {
    fn default() -> Self {
        Self { error: 0.02, max_cut: 1000, group_error: GroupError::Group, exhaustive_lights: EXHAUSTIVE_LIGHTS }
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

/// Every light of the trees too small for a cut, one by one with the exact
/// renderer's code (the same for both cut modes).
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
/// trees too small for a cut, by [`exhaustive`]) as the start of the cut's
/// result. With `groups`, group by group (the range holds whole groups'
/// trees), each group's sum also added to its slot.
#[inline(always)]
pub(crate) fn exhaustive_part(
    trees: &LightTrees,
    range: &std::ops::Range<usize>,
    sp: &SurfacePoint<'_>,
    embree: &EmbreeScene,
    batch: &mut BatchBuffers,
    groups: Option<&mut [DVec3]>,
) -> CutResult {
    let found = |trees: &[CutTree], batch: &mut BatchBuffers| {
        let f = exhaustive(trees, sp, embree, batch);
        CutResult { radiance: f.radiance, error_bound: 0.0, nodes: f.lights, shadow_rays: f.shadow_rays }
    };
    let Some(groups) = groups else { return found(&trees.trees[range.clone()], batch) };
    let mut total = CutResult::default();
    let inside = |r: &&std::ops::Range<usize>| range.start <= r.start && r.end <= range.end;
    for (g, group) in trees.groups.iter().enumerate().filter(|(_, r)| inside(r)) {
        let part = found(&trees.trees[group.clone()], batch);
        groups[g] += part.radiance;
        total.radiance += part.radiance;
        total.nodes += part.nodes;
        total.shadow_rays += part.shadow_rays;
    }
    total
}

/// Runs `cut` (one cut through the trees of a range, crediting each tree's
/// group's slot when given the slots) as `group_error` says: through every
/// tree at once when there are no slots or with [`GroupError::Pixel`],
/// else once per group, summing the results. Shared by both cut modes.
#[inline(always)]
pub(crate) fn by_group(
    trees: &LightTrees,
    groups: &mut [DVec3],
    group_error: GroupError,
    mut cut: impl FnMut(std::ops::Range<usize>, Option<&mut [DVec3]>) -> CutResult,
) -> CutResult {
    let all = 0..trees.trees.len();
    if groups.is_empty() {
        return cut(all, None);
    }
    match group_error {
        GroupError::Pixel => cut(all, Some(groups)),
        GroupError::Group => {
            let mut total = CutResult::default();
            for range in &trees.groups {
                let found = cut(range.clone(), Some(&mut *groups));
                total.radiance += found.radiance;
                total.error_bound += found.error_bound;
                total.nodes += found.nodes;
                total.shadow_rays += found.shadow_rays;
            }
            total
        }
    }
}
