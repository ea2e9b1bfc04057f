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

use super::cluster::{Cluster, Metric};
use super::{LightKind, LightTree, TreeBuilder, TreeLight};

/// Neighbours searched on each side. [PLOC18] finds 8 to 16 close to the
/// greedy tree's quality; 16 keeps our cut sizes within a few percent of the
/// greedy tree's (see `lightcuts bench tree`).
pub const RADIUS: usize = 16;

/// Clusters per rayon task when computing pair sizes.
const CHUNK: usize = 4096;

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
    let positions: Vec<Vec3> = builder.tree.leaves.iter().map(|l| l.position).collect();
    let order = morton_order(&positions);
    let mut clusters: Vec<Cluster> = order.iter().map(|&i| builder.leaf_cluster(i as usize)).collect();
    let metric = builder.metric;
    let mut sizes: Vec<f32> = Vec::new();
    let mut nearest: Vec<u32> = Vec::new();
    let mut next: Vec<Cluster> = Vec::with_capacity(clusters.len());
    while clusters.len() > 1 {
        let n = clusters.len();
        pair_sizes(&metric, &clusters, radius, &mut sizes);
        nearest_neighbours(&sizes, n, radius, &mut nearest);
        next.clear();
        for i in 0..n {
            let j = nearest[i] as usize;
            let mutual = nearest[j] as usize == i;
            if !mutual {
                next.push(clusters[i]);
            } else if i < j {
                // The merged cluster takes the lower position; j's slot empties.
                next.push(builder.merge(&clusters[i], &clusters[j]));
            }
        }
        debug_assert!(next.len() < n, "every pass merges at least the globally closest pair");
        std::mem::swap(&mut clusters, &mut next);
    }
    let root = Some(clusters[0].node);
    builder.finish(root)
}

/// sizes[i * radius + (k - 1)] = size(C_i u C_{i+k}) for k in 1..=radius
/// (infinity past the end). Computed in f64 and stored as f32 (half the
/// memory traffic; values beyond f32's range become infinity, whose ties
/// are broken by index like any other). Parallel, each pair once.
fn pair_sizes(metric: &Metric, clusters: &[Cluster], radius: usize, sizes: &mut Vec<f32>) {
    let n = clusters.len();
    sizes.resize(n * radius, f32::INFINITY);
    sizes.par_chunks_mut(CHUNK * radius).enumerate().for_each(|(chunk, out)| {
        let first = chunk * CHUNK;
        for (local, row) in out.chunks_mut(radius).enumerate() {
            let i = first + local;
            let ci = &clusters[i];
            for (k, slot) in row.iter_mut().enumerate() {
                let j = i + k + 1;
                *slot = if j < n { metric.merged_size(ci, &clusters[j]) as f32 } else { f32::INFINITY };
            }
        }
    });
}

/// nearest[i] = the j within `radius` of i minimising (size(i u j), min(i,j),
/// max(i,j)): a strict total order on pairs, so the globally smallest pair is
/// always mutual and every pass makes progress. Candidates are visited in
/// increasing j, which is increasing (min, max) order, so keeping the first
/// strictly smaller size implements the tie-break. NaN never wins.
fn nearest_neighbours(sizes: &[f32], n: usize, radius: usize, nearest: &mut Vec<u32>) {
    nearest.resize(n, 0);
    nearest.par_chunks_mut(CHUNK).enumerate().for_each(|(chunk, out)| {
        for (local, slot) in out.iter_mut().enumerate() {
            let i = chunk * CHUNK + local;
            let mut best_size = f32::INFINITY;
            let mut best = usize::MAX;
            for j in i.saturating_sub(radius)..i {
                let size = sizes[j * radius + (i - j - 1)];
                if size < best_size || best == usize::MAX {
                    best_size = size;
                    best = j;
                }
            }
            let row = &sizes[i * radius..i * radius + radius.min(n - 1 - i)];
            for (k, &size) in row.iter().enumerate() {
                if size < best_size || best == usize::MAX {
                    best_size = size;
                    best = i + k + 1;
                }
            }
            *slot = best as u32;
        }
    });
}

/// Light indices sorted by the 63-bit Morton code of their position in the
/// lights' bounding box (ties by index, so the order is total).
fn morton_order(positions: &[Vec3]) -> Vec<u32> {
    let (lo, hi) = positions.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    let extent = (hi - lo).max(Vec3::splat(f32::MIN_POSITIVE));
    let scale = 2_097_151.0 / extent; // 2^21 - 1 cells per axis
    let mut keyed: Vec<(u64, u32)> = positions
        .par_iter()
        .enumerate()
        .map(|(i, &p)| {
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
