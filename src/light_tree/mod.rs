//! The light tree ([LC05]; docs/design.md §7): a binary tree per light type whose leaves
//! are lights and whose internal nodes are clusters with summed intensity,
//! bounds, and a representative light chosen with probability proportional
//! to intensity. Built as flat arrays of leaves and nodes (a node stores only
//! what its type needs), then laid out for the cut (`layout`).
//!
//! Built by locally-ordered agglomerative clustering ([FAC08], in the parallel
//! form of [PLOC18]: `ploc`), or by the exact greedy algorithm (`greedy`, for
//! tests and the quality benchmark). Both are deterministic: the same lights
//! and seed give the same tree for every thread count.

pub mod cluster;
pub mod greedy;
pub mod layout;
pub mod ploc;

use std::time::{Duration, Instant};

use glam::Vec3;

pub use cluster::Cone;
use cluster::{Cluster, Metric};

use crate::light::{Light, LightKind, Lights, TreeLight};
use crate::util::color::luminance;
use crate::util::sampling::Rng;

/// A node: a leaf (one light, by index into the tree's lights) or an internal
/// cluster (by index into the node arrays). The top bit tells which.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct NodeRef(u32);

const LEAF_BIT: u32 = 1 << 31;

impl NodeRef {
    #[must_use]
    pub fn leaf(light: u32) -> Self {
        debug_assert!(light < LEAF_BIT);
        Self(light | LEAF_BIT)
    }

    #[must_use]
    pub fn internal(node: u32) -> Self {
        debug_assert!(node < LEAF_BIT);
        Self(node)
    }

    #[must_use]
    pub fn is_leaf(self) -> bool {
        self.0 & LEAF_BIT != 0
    }

    /// Light index (leaf) or node index (internal).
    #[must_use]
    pub fn index(self) -> usize {
        (self.0 & !LEAF_BIT) as usize
    }
}

/// A leaf: one light.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Leaf {
    /// The point clustered: a position, or a directional light's direction
    /// (see [`TreeLight::point`]).
    pub point: Vec3,
    /// W/sr, or a directional light's irradiance (W/m^2).
    pub intensity: Vec3,
}

/// An internal node as the builders make it, 48 bytes. The cut does not
/// read these: it reads the tree laid out for it (`layout`: one block per
/// node holding both children's data).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Node {
    /// Box of positions (omni, oriented) or of directions (directional).
    pub min: Vec3,
    pub max: Vec3,
    /// Summed RGB intensity.
    pub intensity: Vec3,
    /// Index of the representative light.
    pub representative: u32,
    pub children: [NodeRef; 2],
}

/// A built light tree. Leaves are the lights in input order.
#[derive(Debug, Clone)]
pub struct LightTree {
    pub kind: LightKind,
    pub leaves: Vec<Leaf>,
    /// Oriented only: each light's unit normal.
    pub light_normal: Vec<Vec3>,
    /// Spot trees only: each light's cosines of its inner and outer angles.
    pub light_spread: Vec<[f32; 2]>,
    /// Area trees only: each light's triangle's edges (`AreaLight::edges`).
    pub light_edges: Vec<[Vec3; 2]>,
    /// Internal nodes (n - 1 of them for n lights).
    pub nodes: Vec<Node>,
    /// Oriented only: each internal node's cone of normals.
    pub cones: Vec<Cone>,
    pub root: Option<NodeRef>,
}

impl LightTree {
    #[must_use]
    pub fn light_count(&self) -> usize {
        self.leaves.len()
    }

    /// A light's normal (oriented trees), or zero.
    #[must_use]
    pub fn light_normal(&self, light: usize) -> Vec3 {
        self.light_normal.get(light).copied().unwrap_or(Vec3::ZERO)
    }

    /// Light `i` of the tree (its leaf `i`).
    #[must_use]
    pub fn light(&self, i: usize) -> Light {
        let leaf = &self.leaves[i];
        let spread = self.light_spread.get(i).copied().unwrap_or([0.0; 2]);
        let edges = self.light_edges.get(i).copied().unwrap_or([Vec3::ZERO; 2]);
        TreeLight { point: leaf.point, normal: self.light_normal(i), intensity: leaf.intensity, spread, edges }
            .light(self.kind)
    }

    #[must_use]
    pub fn node_intensity(&self, node: NodeRef) -> Vec3 {
        if node.is_leaf() {
            self.leaves[node.index()].intensity
        } else {
            self.nodes[node.index()].intensity
        }
    }

    /// (min, max) of the node's box (for a leaf, its light's point, or an
    /// area light's triangle: wherever its drawn points can be).
    #[must_use]
    pub fn node_bounds(&self, node: NodeRef) -> (Vec3, Vec3) {
        if node.is_leaf() {
            let (i, leaf) = (node.index(), &self.leaves[node.index()]);
            let edges = self.light_edges.get(i).copied().unwrap_or([Vec3::ZERO; 2]);
            TreeLight { edges, ..TreeLight::at(leaf.point, Vec3::ZERO, leaf.intensity) }.bounds()
        } else {
            let n = &self.nodes[node.index()];
            (n.min, n.max)
        }
    }

    /// Cone of normals; omni and directional trees store none, and report a
    /// zero-angle cone (their bounds and metric ignore it).
    #[must_use]
    pub fn node_cone(&self, node: NodeRef) -> Cone {
        if !self.kind.has_cone() {
            Cone::of_direction(Vec3::Z)
        } else if node.is_leaf() {
            Cone::of_direction(self.light_normal[node.index()])
        } else {
            self.cones[node.index()]
        }
    }

    #[must_use]
    pub fn node_representative(&self, node: NodeRef) -> u32 {
        if node.is_leaf() {
            node.index() as u32
        } else {
            self.nodes[node.index()].representative
        }
    }

    /// Children of an internal node.
    #[must_use]
    pub fn node_children(&self, node: NodeRef) -> [NodeRef; 2] {
        debug_assert!(!node.is_leaf());
        self.nodes[node.index()].children
    }

    /// Heap bytes the finished tree holds (leaf and node arrays).
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        fn bytes<T>(v: &Vec<T>) -> usize {
            v.capacity() * std::mem::size_of::<T>()
        }
        bytes(&self.leaves)
            + bytes(&self.light_normal)
            + bytes(&self.light_spread)
            + bytes(&self.light_edges)
            + bytes(&self.nodes)
            + bytes(&self.cones)
    }

    /// Sum of [LC05]'s cluster size over internal nodes: the quantity the
    /// builders minimise greedily (smaller is a better tree).
    #[must_use]
    pub fn total_cluster_size(&self) -> f64 {
        let metric = metric_for(self.kind, self.leaves.iter().map(|l| l.point));
        self.nodes
            .iter()
            .enumerate()
            .map(|(i, n)| {
                let c = Cluster {
                    min: n.min,
                    max: n.max,
                    cone: self.node_cone(NodeRef::internal(i as u32)),
                    intensity: n.intensity,
                    weight: luminance(n.intensity),
                    node: NodeRef::internal(i as u32),
                };
                metric.size(&c)
            })
            .sum()
    }
}

/// A tree's index among a scene's trees, as the cuts store it.
pub type TreeIndex = u16;

/// Most trees a scene has: one per light group and kind. The bounded cut's
/// heap key holds a tree's index in 9 bits (`lightcut::cut`), which every
/// scene the loader accepts fits: 63 groups x 6 kinds = 378 (checked below).
pub const MAX_TREES: usize = 1 << 9;

const _: () = assert!(crate::scene::groups::MAX_LIGHT_GROUPS * LightKind::ALL.len() <= MAX_TREES);

/// The light trees of a scene, laid out for the cut: one per light group
/// and light kind the scene has, no more (clusters never span groups).
pub struct LightTrees {
    /// Group by group (in the order of the scene's groups), kind by kind.
    pub trees: Vec<layout::CutTree>,
    /// The trees of group g: `trees[groups[g].clone()]`.
    pub groups: Vec<std::ops::Range<usize>>,
    /// The group of each tree, in the order of `trees`.
    pub group_of_tree: Vec<usize>,
    /// Build time of each tree (clustering and layout), in the order of `trees`.
    pub build_times: Vec<Duration>,
    /// 1 / the total luminance of every light (1 when that is 0 or not
    /// finite): the cut's bounds are computed on intensities times this, so
    /// that they stay within f32's range.
    pub scale: f32,
}

impl LightTrees {
    /// Builds a tree for each kind of light present (on the current rayon
    /// pool; the trees do not depend on its thread count); a kind of at
    /// most `exhaustive_lights` lights is kept as a list of lights for the
    /// cut to evaluate one by one (the cut's policy: see
    /// `lightcut::EXHAUSTIVE_LIGHTS`).
    #[must_use]
    pub fn build(lights: &Lights, seed: u64, exhaustive_lights: usize) -> Self {
        Self::build_groups(std::slice::from_ref(lights), seed, exhaustive_lights)
    }

    /// Builds a tree for each light group (`groups[g]`: group g's lights)
    /// and each kind present in it.
    #[must_use]
    pub fn build_groups(groups: &[Lights], seed: u64, exhaustive_lights: usize) -> Self {
        let mut trees = Vec::new();
        let mut ranges = Vec::with_capacity(groups.len());
        let mut build_times = Vec::new();
        let mut total = 0.0f64;
        for lights in groups {
            let first = trees.len();
            for kind in LightKind::ALL {
                if lights.count(kind) == 0 {
                    continue;
                }
                let start = Instant::now();
                let leaves = lights.tree_lights(kind);
                total += leaves.iter().map(|l| f64::from(luminance(l.intensity))).sum::<f64>();
                trees.push(if leaves.len() <= exhaustive_lights {
                    layout::CutTree::exhaustive(kind, leaves)
                } else {
                    layout::CutTree::from_tree(&ploc::build(kind, &leaves, seed))
                });
                build_times.push(start.elapsed());
            }
            ranges.push(first..trees.len());
        }
        assert!(trees.len() <= MAX_TREES, "{} trees: the loader allows at most {MAX_TREES}", trees.len());
        let group_of_tree = ranges.iter().enumerate().flat_map(|(g, r)| r.clone().map(move |_| g)).collect();
        let scale = (1.0 / total) as f32;
        let scale = if scale.is_finite() && scale > 0.0 { scale } else { 1.0 };
        Self { trees, groups: ranges, group_of_tree, build_times, scale }
    }

    /// The trees of one built tree each (benchmarks of other builders).
    #[must_use]
    pub fn of(tree: &LightTree) -> Self {
        let total: f64 = tree.leaves.iter().map(|l| f64::from(luminance(l.intensity))).sum();
        let scale = (1.0 / total) as f32;
        let scale = if scale.is_finite() && scale > 0.0 { scale } else { 1.0 };
        Self {
            trees: vec![layout::CutTree::from_tree(tree)],
            groups: std::iter::once(0..1).collect(),
            group_of_tree: vec![0],
            build_times: vec![Duration::ZERO],
            scale,
        }
    }

    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.trees.iter().map(layout::CutTree::memory_bytes).sum()
    }
}

/// The metric's constants for a set of light positions.
fn metric_for(kind: LightKind, positions: impl Iterator<Item = Vec3>) -> Metric {
    let c_squared = if kind.has_cone() {
        let (lo, hi) = positions.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| (lo.min(p), hi.max(p)));
        (hi - lo).as_dvec3().length_squared()
    } else {
        0.0
    };
    Metric { kind, c_squared }
}

/// Shared by both builders: the leaf arrays and the node arrays being filled,
/// and the one place where two clusters merge.
pub(crate) struct TreeBuilder {
    tree: LightTree,
    metric: Metric,
    seed: u64,
}

impl TreeBuilder {
    fn new(kind: LightKind, lights: &[TreeLight], seed: u64) -> Self {
        let n = lights.len();
        let metric = metric_for(kind, lights.iter().map(|l| l.point));
        let oriented = kind.has_cone();
        let tree = LightTree {
            kind,
            leaves: lights.iter().map(|l| Leaf { point: l.point, intensity: l.intensity }).collect(),
            light_normal: if oriented {
                lights.iter().map(|l| l.normal.normalize_or_zero()).collect()
            } else {
                Vec::new()
            },
            light_spread: if kind == LightKind::Spot { lights.iter().map(|l| l.spread).collect() } else { Vec::new() },
            light_edges: if kind == LightKind::Area { lights.iter().map(|l| l.edges).collect() } else { Vec::new() },
            nodes: Vec::with_capacity(n.saturating_sub(1)),
            cones: Vec::with_capacity(if oriented { n.saturating_sub(1) } else { 0 }),
            root: None,
        };
        Self { tree, metric, seed }
    }

    fn leaf_cluster(&self, light: usize) -> Cluster {
        let leaf = self.tree.leaves[light];
        let (min, max) = self.tree.node_bounds(NodeRef::leaf(light as u32));
        Cluster {
            min,
            max,
            cone: self.tree.node_cone(NodeRef::leaf(light as u32)),
            intensity: leaf.intensity,
            weight: luminance(leaf.intensity),
            node: NodeRef::leaf(light as u32),
        }
    }

    /// Creates the internal node for A u B. The representative is A's with
    /// probability w_A / (w_A + w_B), drawn from a stream keyed by (seed,
    /// node index): node indices are assigned in a fixed order, so the choice
    /// does not depend on thread timing. By induction every light is its
    /// node's representative with probability w_light / w_node ([LC05]; docs/design.md §7.1).
    fn merge(&mut self, a: &Cluster, b: &Cluster) -> Cluster {
        let index = self.tree.nodes.len() as u32;
        let node = NodeRef::internal(index);
        let total = f64::from(a.weight) + f64::from(b.weight);
        let u = Rng::from_key(&[self.seed, u64::from(index)]).next_f64();
        // Zero total weight (all lights black): pick evenly.
        let pick_a = if total > 0.0 { u * total < f64::from(a.weight) } else { u < 0.5 };
        let representative =
            if pick_a { self.tree.node_representative(a.node) } else { self.tree.node_representative(b.node) };
        let merged = Cluster {
            min: a.min.min(b.min),
            max: a.max.max(b.max),
            cone: if self.metric.kind.has_cone() { a.cone.union(b.cone) } else { a.cone },
            intensity: a.intensity + b.intensity,
            weight: a.weight + b.weight,
            node,
        };
        self.tree.nodes.push(Node {
            min: merged.min,
            max: merged.max,
            intensity: merged.intensity,
            representative,
            children: [a.node, b.node],
        });
        if self.metric.kind.has_cone() {
            self.tree.cones.push(merged.cone);
        }
        merged
    }

    fn finish(mut self, root: Option<NodeRef>) -> LightTree {
        self.tree.root = root;
        self.tree
    }
}

#[cfg(test)]
mod tests;
