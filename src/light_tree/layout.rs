//! The tree laid out for the cut. Each internal node owns one aligned block
//! holding everything a refinement needs about its two children (box,
//! summed intensity, representative's index, position and, for oriented
//! lights, normal and cone), so refining a node reads one block and never a
//! leaf array. Blocks are in depth-first order with a node's first child
//! right after it (as pbrt-v4's light BVH lays out its nodes), so a cut that
//! refines down one branch walks forward through memory.
//!
//! Boxes are stored as centre and half-extent, widened so that
//! [c - h, c + h] contains the cluster's box in f32 arithmetic; cones as an
//! axis with the cosine and sine of the half-angle, so the bounds need no
//! inverse trigonometric functions (docs/design.md §7.4, pbrt-v4's
//! `CompactLightBounds`).

use glam::Vec3;

use super::{Cone, LightTree, NodeRef};
use crate::light::{LightKind, TreeLight};

/// A child slot: bit 31 set for a leaf (the low bits are its light's index),
/// clear for an internal node (the low bits are its block's index); bit 30
/// set when every light below coincides (same point, and normal for
/// oriented lights), so the representative's estimate is exact and the
/// bound is 0. `EMPTY` marks the unused second slot of the root's block.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Child(u32);

const LEAF: u32 = 1 << 31;
const EXACT: u32 = 1 << 30;
const INDEX: u32 = EXACT - 1;

impl Child {
    pub const EMPTY: Self = Self(u32::MAX);

    /// A leaf: light `light` of the tree.
    #[must_use]
    pub fn leaf(light: u32) -> Self {
        debug_assert!(light <= INDEX);
        Self(LEAF | EXACT | light)
    }

    /// An internal node whose children are in block `block`.
    #[must_use]
    pub fn internal(block: u32, exact: bool) -> Self {
        debug_assert!(block <= INDEX);
        Self(if exact { EXACT | block } else { block })
    }

    #[must_use]
    pub fn is_leaf(self) -> bool {
        self.0 & LEAF != 0
    }

    /// Whether the child's estimate is exact (a leaf, or coincident lights).
    #[must_use]
    pub fn is_exact(self) -> bool {
        self.0 & EXACT != 0
    }

    /// The slot's bits: distinct for every node of a tree.
    #[must_use]
    pub fn bits(self) -> u32 {
        self.0
    }

    /// Light index (leaf) or block index (internal node).
    #[must_use]
    pub fn index(self) -> usize {
        (self.0 & INDEX) as usize
    }
}

/// The two children of a node, structure of arrays over the two slots (for
/// SIMD over both children). 112 bytes, in two cache lines.
#[derive(Debug, Clone, Copy, Default)]
#[repr(C, align(64))]
pub struct Block {
    /// Box centre per axis (positions; directions for directional lights).
    pub centre: [[f32; 2]; 3],
    /// Half-extent per axis (>= 0).
    pub half: [[f32; 2]; 3],
    /// Summed intensity per channel: W/sr, or W/m^2 for directional lights.
    pub intensity: [[f32; 2]; 3],
    /// The representative light's position (its direction for directional lights).
    pub position: [[f32; 2]; 3],
    /// The representative light's index in the tree's lights.
    pub representative: [u32; 2],
    pub child: [Child; 2],
}

/// What oriented lights add to a block: the representative's normal and the
/// cone of normals (axis, cos and sin of the half-angle), with the axis's
/// orthonormal frame (tangent and bitangent, by [`axis_frame`]) that the
/// cone's bound projects the box onto: computed once here rather than at
/// every bound. 112 bytes.
#[derive(Debug, Clone, Copy, Default)]
#[repr(C, align(64))]
pub struct ConeBlock {
    pub normal: [[f32; 2]; 3],
    pub axis: [[f32; 2]; 3],
    pub tangent: [[f32; 2]; 3],
    pub bitangent: [[f32; 2]; 3],
    pub cos_half_angle: [f32; 2],
    pub sin_half_angle: [f32; 2],
}

/// The tangent and bitangent completing unit `a` to an orthonormal frame,
/// without branches (Duff et al. 2017, as glam's `any_orthonormal_pair`),
/// with the same f32 operations in the same order as the bounds' four-lane
/// form of it.
#[must_use]
pub fn axis_frame(a: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(a.z);
    let k = -1.0 / (sign + a.z);
    let b = a.x * a.y * k;
    (Vec3::new(1.0 + sign * a.x * a.x * k, sign * b, -sign * a.x), Vec3::new(b, sign + a.y * a.y * k, -a.y))
}

/// What spot lights add to a block: the representative's cosines of its
/// inner and outer angles, and the widest outer angle below the slot (its
/// smallest cosine), which bounds where the cluster can shine. 24 bytes.
#[derive(Debug, Clone, Copy, Default)]
pub struct SpotBlock {
    pub cos_inner: [f32; 2],
    pub cos_outer: [f32; 2],
    pub min_cos_outer: [f32; 2],
}

/// A block's cone data: its cone block, and a spot tree's spot block.
#[derive(Debug, Clone, Copy)]
pub struct Cones<'a> {
    pub cone: &'a ConeBlock,
    pub spot: Option<&'a SpotBlock>,
}

/// A tree in the cut's layout. `blocks[0]` holds the root in slot 0 (and
/// `Child::EMPTY` in slot 1); `blocks[k]` for k >= 1 holds the children of
/// the internal node whose index is k. Oriented trees have a `cones` entry
/// beside every block. A tree the cut evaluates light by light (see
/// `LightTrees::build`)
/// has no blocks, only its `lights`, which the cut evaluates one by one.
#[derive(Debug, Clone)]
pub struct CutTree {
    pub kind: LightKind,
    pub blocks: Vec<Block>,
    pub cones: Vec<ConeBlock>,
    /// Spot trees: a `spots` entry beside every block.
    pub spots: Vec<SpotBlock>,
    /// The lights of a tree evaluated light by light (empty otherwise).
    pub lights: Vec<TreeLight>,
    /// Area trees: each light's triangle's edges, by light index (a
    /// representative draws its point on its triangle).
    pub edges: Vec<[Vec3; 2]>,
    light_count: usize,
}

/// One slot's data, gathered before it is written into a block.
struct Slot {
    child: Child,
    centre: Vec3,
    half: Vec3,
    intensity: Vec3,
    representative: u32,
    position: Vec3,
    normal: Vec3,
    cone: Cone,
    /// The representative's spread (spots), and the smallest outer cosine below.
    spread: [f32; 2],
    min_cos_outer: f32,
}

/// Centre and half-extent of [lo, hi] such that [c - h, c + h] contains
/// [lo, hi]: whatever c rounds to, h = max(hi - c, c - lo) covers both
/// sides up to the rounding of those subtractions (2^-24 relative), which
/// the factor 1 + 2^-22 covers four times over.
#[must_use]
pub fn centre_half(lo: Vec3, hi: Vec3) -> (Vec3, Vec3) {
    let centre = lo * 0.5 + hi * 0.5;
    let half = (hi - centre).max(centre - lo).max(Vec3::ZERO) * (1.0 + 1.0 / 4_194_304.0);
    // A single point stays a point (0.5 x + 0.5 x is x exactly).
    (centre, Vec3::select(lo.cmpeq(hi), Vec3::ZERO, half))
}

impl CutTree {
    /// Lays out a built tree. The tree's lights, representatives and
    /// intensities are unchanged: only where they are stored changes.
    #[must_use]
    pub fn from_tree(tree: &LightTree) -> Self {
        let oriented = tree.kind.has_cone();
        let spot = tree.kind == LightKind::Spot;
        let mut layout = Self {
            kind: tree.kind,
            blocks: Vec::new(),
            cones: Vec::new(),
            spots: Vec::new(),
            lights: Vec::new(),
            edges: tree.light_edges.clone(),
            light_count: tree.light_count(),
        };
        let Some(root) = tree.root else { return layout };
        let internal = tree.nodes.len();
        // Nodes are created after their children (`TreeBuilder::merge`), so
        // passes in creation order see children first and passes in reverse
        // creation order see parents first: every pass reads the node array
        // in order, and only the block writes scatter.
        let below_count = |below: &[u32], c: NodeRef| if c.is_leaf() { 0 } else { below[c.index()] };
        // Internal nodes in each subtree.
        let mut below = vec![0u32; internal];
        for (n, node) in tree.nodes.iter().enumerate() {
            below[n] = 1 + below_count(&below, node.children[0]) + below_count(&below, node.children[1]);
        }
        // Depth-first block indices: the first child right after its parent,
        // the second after the first's subtree; the root's block is 1.
        let mut index = vec![0u32; internal];
        if !root.is_leaf() {
            index[root.index()] = 1;
        }
        for n in (0..internal).rev() {
            let [a, b] = tree.nodes[n].children;
            if !a.is_leaf() {
                index[a.index()] = index[n] + 1;
            }
            if !b.is_leaf() {
                index[b.index()] = index[n] + 1 + below_count(&below, a);
            }
        }
        drop(below);
        // Each internal node's representative's position and normal, found
        // from its children's (no random reads of the leaf arrays).
        let mut rep_position = vec![Vec3::ZERO; internal];
        let mut rep_normal = vec![Vec3::ZERO; if oriented { internal } else { 0 }];
        // Spots: the representative's spread and the smallest outer cosine.
        let mut rep_spread = vec![([0.0f32; 2], 0.0f32); if spot { internal } else { 0 }];
        let slot = |node: NodeRef, rep_position: &[Vec3], rep_normal: &[Vec3], rep_spread: &[([f32; 2], f32)]| {
            let (lo, hi) = tree.node_bounds(node);
            let (centre, half) = centre_half(lo, hi);
            let representative = tree.node_representative(node);
            let cone = tree.node_cone(node);
            // Coincident spots may differ in their cones' angles: only a
            // single spot is exact.
            let exact = lo == hi && (!oriented || cone.half_angle == 0.0) && !spot;
            let (child, position, normal, (spread, min_cos_outer)) = if node.is_leaf() {
                let spread = tree.light_spread.get(node.index()).copied().unwrap_or([0.0; 2]);
                let point = tree.leaves[node.index()].point;
                (Child::leaf(node.index() as u32), point, tree.light_normal(node.index()), (spread, spread[1]))
            } else {
                let n = node.index();
                let normal = rep_normal.get(n).copied().unwrap_or(Vec3::ZERO);
                let spread = rep_spread.get(n).copied().unwrap_or(([0.0; 2], 0.0));
                (Child::internal(index[n], exact), rep_position[n], normal, spread)
            };
            let intensity = tree.node_intensity(node);
            Slot { child, centre, half, intensity, representative, position, normal, cone, spread, min_cos_outer }
        };
        layout.blocks = vec![Block::default(); internal + 1];
        if oriented {
            layout.cones = vec![ConeBlock::default(); internal + 1];
        }
        if spot {
            layout.spots = vec![SpotBlock::default(); internal + 1];
        }
        for (n, node) in tree.nodes.iter().enumerate() {
            let slots = node.children.map(|c| slot(c, &rep_position, &rep_normal, &rep_spread));
            let shared = if slots[0].representative == node.representative { &slots[0] } else { &slots[1] };
            rep_position[n] = shared.position;
            if oriented {
                rep_normal[n] = shared.normal;
            }
            if spot {
                rep_spread[n] = (shared.spread, slots[0].min_cos_outer.min(slots[1].min_cos_outer));
            }
            let [a, b] = slots;
            layout.write(index[n] as usize, [Some(a), Some(b)]);
        }
        layout.write(0, [Some(slot(root, &rep_position, &rep_normal, &rep_spread)), None]);
        layout
    }

    /// Writes block `b` (and its cone block) from two slots.
    fn write(&mut self, b: usize, slots: [Option<Slot>; 2]) {
        let mut block = Block { child: [Child::EMPTY; 2], ..Block::default() };
        let mut cone = ConeBlock::default();
        let mut spot = SpotBlock::default();
        for (k, slot) in slots.iter().enumerate() {
            let Some(s) = slot else { continue };
            for axis in 0..3 {
                block.centre[axis][k] = s.centre[axis];
                block.half[axis][k] = s.half[axis];
                block.intensity[axis][k] = s.intensity[axis];
                block.position[axis][k] = s.position[axis];
                cone.normal[axis][k] = s.normal[axis];
                cone.axis[axis][k] = s.cone.axis[axis];
            }
            let (tangent, bitangent) = axis_frame(s.cone.axis);
            for axis in 0..3 {
                cone.tangent[axis][k] = tangent[axis];
                cone.bitangent[axis][k] = bitangent[axis];
            }
            block.representative[k] = s.representative;
            block.child[k] = s.child;
            spot.cos_inner[k] = s.spread[0];
            spot.cos_outer[k] = s.spread[1];
            spot.min_cos_outer[k] = s.min_cos_outer;
            let (sin, cos) = s.cone.half_angle.sin_cos();
            // A zero angle is exactly (1, 0): coincident normals stay exact.
            let (sin, cos) = if s.cone.half_angle == 0.0 { (0.0, 1.0) } else { (sin, cos) };
            cone.cos_half_angle[k] = cos;
            cone.sin_half_angle[k] = sin;
        }
        self.blocks[b] = block;
        if let Some(c) = self.cones.get_mut(b) {
            *c = cone;
        }
        if let Some(sb) = self.spots.get_mut(b) {
            *sb = spot;
        }
    }

    /// Block `b`'s cone data, for the kinds with cones.
    #[must_use]
    #[inline]
    pub fn cones_of(&self, b: usize) -> Option<Cones<'_>> {
        self.cones.get(b).map(|cone| Cones { cone, spot: self.spots.get(b) })
    }

    /// A tree too small for a cut to pay: its lights, in order.
    #[must_use]
    pub fn exhaustive(kind: LightKind, lights: Vec<TreeLight>) -> Self {
        let light_count = lights.len();
        Self { kind, blocks: Vec::new(), cones: Vec::new(), spots: Vec::new(), lights, edges: Vec::new(), light_count }
    }

    #[must_use]
    pub fn light_count(&self) -> usize {
        self.light_count
    }

    /// Slot `k` of block `b` as a tree leaf's data: the representative light.
    #[must_use]
    pub fn representative(&self, b: usize, k: usize) -> TreeLight {
        let block = &self.blocks[b];
        let point = Vec3::new(block.position[0][k], block.position[1][k], block.position[2][k]);
        let normal = match self.cones.get(b) {
            Some(c) => Vec3::new(c.normal[0][k], c.normal[1][k], c.normal[2][k]),
            None => Vec3::ZERO,
        };
        let intensity = Vec3::new(block.intensity[0][k], block.intensity[1][k], block.intensity[2][k]);
        let spread = self.spots.get(b).map_or([0.0; 2], |s| [s.cos_inner[k], s.cos_outer[k]]);
        let edges = self.edges.get(block.representative[k] as usize).copied().unwrap_or([Vec3::ZERO; 2]);
        TreeLight { point, normal, intensity, spread, edges }
    }

    /// Heap bytes of the layout.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.blocks.capacity() * std::mem::size_of::<Block>()
            + self.cones.capacity() * std::mem::size_of::<ConeBlock>()
            + self.spots.capacity() * std::mem::size_of::<SpotBlock>()
            + self.lights.capacity() * std::mem::size_of::<TreeLight>()
            + self.edges.capacity() * std::mem::size_of::<[Vec3; 2]>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light_tree::ploc;
    use crate::util::sampling::Rng;

    fn lights(kind: LightKind, n: usize) -> Vec<TreeLight> {
        let mut rng = Rng::seeded(4);
        (0..n)
            .map(|_| {
                let p = Vec3::new(rng.range_f32(-5.0, 5.0), rng.range_f32(0.0, 3.0), rng.range_f32(-5.0, 5.0));
                let normal = Vec3::new(rng.range_f32(-1.0, 1.0), -1.0, rng.range_f32(-1.0, 1.0)).normalize();
                let point = if kind.at_infinity() { -normal } else { p };
                let spread = if kind == LightKind::Spot { [0.9, 0.5 + 0.3 * rng.next_f32()] } else { [0.0; 2] };
                TreeLight { spread, ..TreeLight::at(point, normal, Vec3::new(1.0, rng.next_f32(), 0.5)) }
            })
            .collect()
    }

    /// Walks the layout from the root, checking each slot against the tree
    /// node it was laid out from.
    fn check(tree: &LightTree, layout: &CutTree, b: usize, k: usize, node: NodeRef, seen: &mut [u32]) {
        let block = &layout.blocks[b];
        let child = block.child[k];
        assert_eq!(child.is_leaf(), node.is_leaf());
        let (lo, hi) = tree.node_bounds(node);
        for axis in 0..3 {
            let (c, h) = (block.centre[axis][k], block.half[axis][k]);
            assert!(c - h <= lo[axis] && hi[axis] <= c + h, "box [{lo}, {hi}] not inside centre {c} half {h}");
        }
        assert_eq!(block.representative[k], tree.node_representative(node));
        let light = layout.representative(b, k);
        let rep = tree.node_representative(node) as usize;
        assert_eq!(light.point, tree.leaves[rep].point);
        assert_eq!(light.normal, tree.light_normal(rep));
        assert_eq!(light.intensity, tree.node_intensity(node), "the slot carries the node's summed intensity");
        if node.is_leaf() {
            assert!(child.is_exact());
            seen[node.index()] += 1;
            return;
        }
        let next = child.index();
        let [first, second] = tree.node_children(node);
        check(tree, layout, next, 0, first, seen);
        check(tree, layout, next, 1, second, seen);
    }

    #[test]
    fn the_layout_holds_every_node_in_depth_first_order() {
        for kind in LightKind::ALL {
            for n in [1, 2, 3, 500] {
                let tree = ploc::build(kind, &lights(kind, n), 7);
                let layout = CutTree::from_tree(&tree);
                assert_eq!(layout.blocks.len(), n, "{kind:?}: the root's block plus one per internal node");
                assert_eq!(layout.cones.len(), if kind.has_cone() { n } else { 0 });
                assert_eq!(layout.spots.len(), if kind == LightKind::Spot { n } else { 0 });
                assert_eq!(layout.blocks[0].child[1], Child::EMPTY);
                let mut seen = vec![0; n];
                check(&tree, &layout, 0, 0, tree.root.unwrap(), &mut seen);
                assert!(seen.iter().all(|&s| s == 1), "every light in exactly one leaf slot");
                // Depth-first: a node's first internal child is the next block.
                for (b, block) in layout.blocks.iter().enumerate().skip(1) {
                    if !block.child[0].is_leaf() {
                        assert_eq!(block.child[0].index(), b + 1);
                    }
                }
            }
        }
    }

    #[test]
    fn coincident_lights_are_one_exact_slot_and_boxes_are_widened_only_when_they_have_extent() {
        let same = vec![TreeLight::at(Vec3::ONE, Vec3::Y, Vec3::ONE); 300];
        let layout = CutTree::from_tree(&ploc::build(LightKind::Oriented, &same, 1));
        assert!(layout.blocks[0].child[0].is_exact());
        assert_eq!(layout.blocks[0].half, [[0.0; 2]; 3]);
        let (c, h) = centre_half(Vec3::new(-1.0, 0.1, 1e6), Vec3::new(3.0, 0.1, 1e6 + 1.0));
        assert!(c.x - h.x <= -1.0 && 3.0 <= c.x + h.x && h.y == 0.0 && c.y == 0.1);
        assert!(c.z - h.z <= 1e6 && 1e6 + 1.0 <= c.z + h.z);
    }
}
