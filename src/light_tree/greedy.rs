//! The exact greedy agglomerative build: always merge the pair whose union has
//! the smallest cluster size ([LC05]; docs/design.md §7.2). O(n^2) time with cached
//! nearest neighbours; for tests and the quality benchmark only.

use super::cluster::Cluster;
use super::{LightTree, TreeBuilder};
use crate::light::{LightKind, TreeLight};

/// Builds the greedy tree (single-threaded, deterministic: ties go to the
/// lower index).
#[must_use]
pub fn build(kind: LightKind, lights: &[TreeLight], seed: u64) -> LightTree {
    let mut builder = TreeBuilder::new(kind, lights, seed);
    let mut clusters: Vec<Option<Cluster>> = (0..lights.len()).map(|i| Some(builder.leaf_cluster(i))).collect();
    let n = clusters.len();
    if n <= 1 {
        let root = clusters.first().and_then(|c| c.map(|c| c.node));
        return builder.finish(root);
    }
    let metric = builder.metric;
    // nearest[i] = (size of i's best union, partner).
    let nearest_of = |clusters: &[Option<Cluster>], i: usize| -> (f64, usize) {
        let ci = clusters[i].as_ref().expect("live cluster");
        let mut best = (f64::INFINITY, usize::MAX);
        for (j, c) in clusters.iter().enumerate() {
            if let (true, Some(cj)) = (j != i, c) {
                let d = metric.merged_size(ci, cj);
                if d < best.0 || best.1 == usize::MAX {
                    best = (d, j);
                }
            }
        }
        best
    };
    let mut nearest: Vec<(f64, usize)> = (0..n).map(|i| nearest_of(&clusters, i)).collect();
    let mut live = n;
    let mut last = 0;
    while live > 1 {
        // The globally smallest union (ties: lowest index).
        let mut i = usize::MAX;
        for k in 0..n {
            if clusters[k].is_some() && (i == usize::MAX || nearest[k].0 < nearest[i].0) {
                i = k;
            }
        }
        let j = nearest[i].1;
        let (a, b) = (clusters[i].take().expect("live"), clusters[j].take().expect("live"));
        let merged = builder.merge(&a, &b);
        let slot = i.min(j);
        clusters[slot] = Some(merged);
        live -= 1;
        last = slot;
        for k in 0..n {
            if clusters[k].is_none() || k == slot {
                continue;
            }
            if nearest[k].1 == i || nearest[k].1 == j {
                nearest[k] = nearest_of(&clusters, k);
            } else {
                let d = metric.merged_size(clusters[k].as_ref().expect("live"), &merged);
                if d < nearest[k].0 {
                    nearest[k] = (d, slot);
                }
            }
        }
        if live > 1 {
            nearest[slot] = nearest_of(&clusters, slot);
        }
    }
    let root = clusters[last].map(|c| c.node);
    builder.finish(root)
}
