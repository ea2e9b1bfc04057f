//! Parallel locally-ordered clustering [PLOC18] of lights, the parallel form
//! of [FAC08]'s locally-ordered agglomerative clustering.
//!
//! Clusters are kept in Morton order of their lights' positions (directions
//! for directional lights). Each pass: (1) for every cluster, the size of its
//! union with each of the next `RADIUS` clusters, in parallel (each pair is
//! computed once); (2) every cluster's nearest neighbour within `RADIUS` on
//! either side; (3) mutual nearest neighbours merge, in one ordered scan that
//! also assigns node indices. A pass costs O(n * RADIUS) and removes a
//! constant fraction of the clusters, so the build is near-linear.
//!
//! Deterministic: pair sizes do not depend on the thread that computes them,
//! ties are broken by index, and merges happen in index order, so the tree is
//! identical for every thread count.

use glam::Vec3;
use rayon::prelude::*;

use super::cluster::{Cluster, Cone, Metric};
use super::{Leaf, LightTree, NodeRef, TreeBuilder};
use crate::light::{LightKind, TreeLight};

/// Neighbours searched on each side. [PLOC18] finds 8 to 16 close to the
/// greedy tree's quality; 16 keeps our cut sizes within a few percent of the
/// greedy tree's (see `lightcuts bench tree`).
pub const RADIUS: usize = 16;

/// While more than 1 / EARLY_DIVISOR of the lights are still separate
/// clusters, search only EARLY_RADIUS neighbours: these passes hold most of
/// the work and build the bottom of the tree, which cuts rarely reach
/// (measured with `lightcuts bench tree`: 1M omni lights in about half the
/// time, average cut within 5% of the greedy tree's). Omni lights only:
/// oriented lights' Morton order ignores their normals, and directional
/// lights' cut grew 6-7% over the greedy tree's with it (same benchmark), so
/// both keep the full radius.
const EARLY_RADIUS: usize = 2;
const EARLY_DIVISOR: usize = 16;

/// Clusters per rayon task when computing pair sizes.
const CHUNK: usize = 4096;

/// A cluster as the passes see it: 32 bytes, so a search window of 2 x 16
/// neighbours is 16 cache lines. Oriented trees keep cones beside it.
#[derive(Debug, Clone, Copy)]
struct Slim {
    min: Vec3,
    max: Vec3,
    weight: f32,
    node: NodeRef,
}

impl Slim {
    fn of(c: &Cluster) -> Self {
        Self { min: c.min, max: c.max, weight: c.weight, node: c.node }
    }
}

/// The clusters of a pass and what travels beside them: their cones
/// (oriented trees only; empty otherwise) and their intensities (read only by
/// merges, so the neighbour search does not carry them).
struct Working {
    clusters: Vec<Slim>,
    cones: Vec<Cone>,
    intensities: Vec<Vec3>,
}

impl Working {
    fn full(&self, k: usize) -> Cluster {
        let c = &self.clusters[k];
        Cluster {
            min: c.min,
            max: c.max,
            cone: self.cones.get(k).copied().unwrap_or(Cone::of_direction(Vec3::Z)),
            intensity: self.intensities[k],
            weight: c.weight,
            node: c.node,
        }
    }

    fn set(&mut self, k: usize, c: &Cluster) {
        self.clusters[k] = Slim::of(c);
        self.intensities[k] = c.intensity;
        if let Some(cone) = self.cones.get_mut(k) {
            *cone = c.cone;
        }
    }

    fn copy(&mut self, from: usize, to: usize) {
        self.clusters[to] = self.clusters[from];
        self.intensities[to] = self.intensities[from];
        if !self.cones.is_empty() {
            self.cones[to] = self.cones[from];
        }
    }

    fn truncate(&mut self, n: usize) {
        self.clusters.truncate(n);
        self.intensities.truncate(n);
        self.cones.truncate(n);
    }
}

/// Builds a light tree (on the current rayon pool).
#[must_use]
pub fn build(kind: LightKind, lights: &[TreeLight], seed: u64) -> LightTree {
    build_with_radius(kind, lights, seed, RADIUS)
}

/// As [`build`], with a chosen search radius (>= 1).
#[must_use]
pub fn build_with_radius(kind: LightKind, lights: &[TreeLight], seed: u64, radius: usize) -> LightTree {
    let radius = radius.max(1);
    let mut builder = TreeBuilder::new(kind, lights, seed);
    if lights.len() <= 1 {
        let root = (!lights.is_empty()).then(|| builder.leaf_cluster(0).node);
        return builder.finish(root);
    }
    let order = morton_order(&builder.tree.leaves);
    let mut work = Working {
        clusters: order.iter().map(|&i| Slim::of(&builder.leaf_cluster(i as usize))).collect(),
        cones: if kind.has_cone() {
            order.iter().map(|&i| builder.leaf_cluster(i as usize).cone).collect()
        } else {
            Vec::new()
        },
        intensities: order.iter().map(|&i| builder.tree.leaves[i as usize].intensity).collect(),
    };
    drop(order);
    let metric = builder.metric;
    let mut nearest: Vec<u32> = Vec::new();
    while work.clusters.len() > 1 {
        let n = work.clusters.len();
        let early = kind == LightKind::Omni && n * EARLY_DIVISOR > lights.len();
        let pass_radius = if early { EARLY_RADIUS.min(radius) } else { radius };
        nearest_neighbours(&metric, &work.clusters, &work.cones, pass_radius, &mut nearest);
        // Compaction in place: a merge writes to the lower index i of its pair
        // and the write index never passes the read index, so cluster j > i
        // is still unread when i is processed.
        let mut write = 0;
        for i in 0..n {
            let j = nearest[i] as usize;
            let mutual = nearest[j] as usize == i;
            if !mutual {
                work.copy(i, write);
                write += 1;
            } else if i < j {
                let merged = builder.merge(&work.full(i), &work.full(j));
                work.set(write, &merged);
                write += 1;
            }
        }
        if write == n {
            // Unreachable while the pair order is strict (see `pair_size`);
            // kept so that no floating-point surprise can loop forever: merge
            // the first two clusters.
            debug_assert!(false, "a pass merged nothing");
            let merged = builder.merge(&work.full(0), &work.full(1));
            work.set(0, &merged);
            for k in 2..n {
                work.copy(k, k - 1);
            }
            write = n - 1;
        }
        work.truncate(write);
    }
    let clusters = work.clusters;
    let root = Some(clusters[0].node);
    builder.finish(root)
}

/// size(C_i u C_j) by [LC05]'s metric, in f32 for omni and directional
/// lights (f64 for oriented ones, then rounded): only the order of sizes
/// matters, and a size beyond f32's range is infinity either way, with ties
/// broken by index like any other. Symmetric to the bit (min, max and + are
/// commutative), so i and j agree on their pair.
#[inline]
fn pair_size(metric: &Metric, clusters: &[Slim], cones: &[Cone], i: usize, j: usize) -> f32 {
    let (ci, cj) = (&clusters[i], &clusters[j]);
    let diagonal = ci.max.max(cj.max) - ci.min.min(cj.min);
    let weight = ci.weight + cj.weight;
    let size = if metric.kind.has_cone() {
        let angular = 1.0 - f64::from(cones[i].union_half_angle(cones[j]).cos());
        (f64::from(weight) * (diagonal.as_dvec3().length_squared() + metric.c_squared * angular * angular)) as f32
    } else {
        weight * diagonal.length_squared()
    };
    // Summed intensities can overflow to infinity (lights near f32::MAX), and
    // infinity times a zero diagonal is NaN, which compares false with
    // everything and would break the strict order that guarantees a merge
    // every pass: NaN counts as infinity (whose ties the hash breaks).
    if size.is_nan() {
        f32::INFINITY
    } else {
        size
    }
}

/// Tie-break of a pair with equal sizes: a hash of its indices. Ranking
/// ties by index instead makes every cluster of a run of equal sizes (100,000
/// coincident lights, say) choose the same neighbour, so each pass merges one
/// pair and the tree degenerates into a chain; hashed ties give many mutual
/// pairs per pass.
#[inline]
fn tie_break(a: usize, b: usize) -> u64 {
    crate::util::sampling::mix64(((a as u64) << 32) ^ b as u64)
}

/// nearest[i] = the j within `radius` of i minimising (size(i u j),
/// tie_break(i, j), min(i,j), max(i,j)): a strict total order on pairs, so
/// the globally smallest pair is always mutual and every pass makes progress.
///
/// Each chunk walks its rows i in increasing order and computes size(i, i+k)
/// for k = 1..=radius once, offering it to both ends; it starts `radius` rows
/// early so its first clusters also see their backward neighbours. Every
/// cluster thus receives its candidates in increasing j, i.e. increasing
/// (min, max) order, so keeping the first strictly smaller (size, tie-break)
/// implements the order. No n x radius table is written or read back.
fn nearest_neighbours(metric: &Metric, clusters: &[Slim], cones: &[Cone], radius: usize, nearest: &mut Vec<u32>) {
    let n = clusters.len();
    nearest.resize(n, 0);
    nearest.par_chunks_mut(CHUNK).enumerate().for_each(|(chunk, out)| {
        let (start, end) = (chunk * CHUNK, chunk * CHUNK + out.len());
        let mut best_size = vec![f32::INFINITY; out.len()];
        let mut best_tie = vec![u64::MAX; out.len()];
        let mut best = vec![usize::MAX; out.len()];
        let mut offer = |target: usize, candidate: usize, size: f32, tie: u64| {
            let t = target - start;
            let better = size < best_size[t] || (size == best_size[t] && tie < best_tie[t]);
            if better || best[t] == usize::MAX {
                best_size[t] = size;
                best_tie[t] = tie;
                best[t] = candidate;
            }
        };
        for i in start.saturating_sub(radius)..end {
            for j in i + 1..(i + radius + 1).min(n) {
                if j >= end && i < start {
                    break;
                }
                let size = pair_size(metric, clusters, cones, i, j);
                let tie = tie_break(i, j);
                if i >= start {
                    offer(i, j, size, tie);
                }
                if (start..end).contains(&j) {
                    offer(j, i, size, tie);
                }
            }
        }
        for (slot, b) in out.iter_mut().zip(best) {
            *slot = b as u32;
        }
    });
}

/// Light indices sorted by the 63-bit Morton code of their position in the
/// lights' bounding box (ties by index, so the order is total).
fn morton_order(leaves: &[Leaf]) -> Vec<u32> {
    let (lo, hi) =
        leaves.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), l| (lo.min(l.point), hi.max(l.point)));
    let extent = (hi - lo).max(Vec3::splat(f32::MIN_POSITIVE));
    let scale = 2_097_151.0 / extent; // 2^21 - 1 cells per axis
    let mut keyed: Vec<(u64, u32)> = leaves
        .par_iter()
        .enumerate()
        .map(|(i, leaf)| {
            let p = leaf.point;
            let q = ((p - lo) * scale).clamp(Vec3::ZERO, Vec3::splat(2_097_151.0));
            (morton3(q.x as u64) | (morton3(q.y as u64) << 1) | (morton3(q.z as u64) << 2), i as u32)
        })
        .collect();
    keyed.par_sort_unstable();
    keyed.into_iter().map(|(_, i)| i).collect()
}

/// Spreads the low 21 bits of x so that two zero bits follow each.
fn morton3(x: u64) -> u64 {
    let mut x = x & 0x1f_ffff;
    x = (x | (x << 32)) & 0x001f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x001f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn morton_interleaves_bits() {
        assert_eq!(morton3(0b1), 0b1);
        assert_eq!(morton3(0b10), 0b1000);
        assert_eq!(morton3(0b11), 0b1001);
        assert_eq!(morton3(0x1f_ffff).count_ones(), 21);
    }
}
