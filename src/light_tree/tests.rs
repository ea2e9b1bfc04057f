//! Property tests over random light sets (seeded), for both builders and all
//! three light kinds.
use super::*;

fn random_lights(seed: u64, n: usize, kind: LightKind, clustered: bool) -> Vec<TreeLight> {
    let mut rng = Rng::seeded(seed);
    let centres: Vec<Vec3> = (0..8)
        .map(|_| Vec3::new(rng.range_f32(-10.0, 10.0), rng.range_f32(0.0, 5.0), rng.range_f32(-10.0, 10.0)))
        .collect();
    (0..n)
        .map(|_| {
            let mut position = if clustered {
                centres[rng.below(8) as usize]
                    + Vec3::new(rng.range_f32(-0.5, 0.5), rng.range_f32(-0.5, 0.5), rng.range_f32(-0.5, 0.5))
            } else {
                Vec3::new(rng.range_f32(-10.0, 10.0), rng.range_f32(0.0, 5.0), rng.range_f32(-10.0, 10.0))
            };
            let normal = Vec3::new(rng.range_f32(-1.0, 1.0), rng.range_f32(-1.0, 1.0), rng.range_f32(-1.0, 1.0))
                .normalize_or(Vec3::Y);
            if kind.at_infinity() {
                position = normal;
            }
            let intensity = Vec3::new(rng.range_f32(0.0, 2.0), rng.range_f32(0.0, 2.0), rng.range_f32(0.0, 2.0));
            TreeLight {
                point: position,
                normal,
                intensity,
                spread: if kind == LightKind::Spot { [0.95, 0.7] } else { [0.0; 2] },
                // Area lights are triangles up to 0.5 m across.
                edges: if kind == LightKind::Area {
                    [0; 2].map(|_| Vec3::new(rng.range_f32(-0.5, 0.5), 0.0, rng.range_f32(-0.5, 0.5)))
                } else {
                    [Vec3::ZERO; 2]
                },
            }
        })
        .collect()
}

const KINDS: [LightKind; 6] = LightKind::ALL;

/// Walks the tree checking every structural property; returns the lights
/// below each node visited.
fn check_tree(tree: &LightTree, lights: &[TreeLight]) {
    let n = lights.len();
    if n == 0 {
        assert!(tree.root.is_none());
        return;
    }
    assert_eq!(tree.nodes.len(), n - 1, "a binary tree over n leaves has n - 1 internal nodes");
    let mut seen = vec![0u32; n];
    let root = tree.root.expect("non-empty tree has a root");
    check_node(tree, root, &mut seen);
    assert!(seen.iter().all(|&c| c == 1), "every light is in exactly one leaf");
}

fn check_node(tree: &LightTree, node: NodeRef, seen: &mut [u32]) -> Vec<u32> {
    if node.is_leaf() {
        seen[node.index()] += 1;
        // A leaf's box holds every point its light can be drawn at (an
        // area light's triangle).
        let (lo, hi) = tree.node_bounds(node);
        if let Light::Area(light) = tree.light(node.index()) {
            for u in [[0.0, 0.0], [0.999, 0.0], [0.0, 0.999], [0.3, 0.3], [0.9, 0.8]] {
                let p = light.point_at(u);
                assert!(lo.cmple(p + 1e-6).all() && hi.cmpge(p - 1e-6).all(), "{p} outside the leaf's box");
            }
        }
        return vec![node.index() as u32];
    }
    let [a, b] = tree.node_children(node);
    let mut below = check_node(tree, a, seen);
    below.extend(check_node(tree, b, seen));
    // Intensity is the sum of the children's (to f32 rounding).
    let sum = tree.node_intensity(a) + tree.node_intensity(b);
    assert!((tree.node_intensity(node) - sum).abs().max_element() <= 1e-5 * sum.max_element().max(1.0));
    // The box contains the children's boxes.
    let (lo, hi) = tree.node_bounds(node);
    for child in [a, b] {
        let (clo, chi) = tree.node_bounds(child);
        assert!(lo.cmple(clo).all() && hi.cmpge(chi).all(), "box does not contain a child's box");
    }
    // The cone contains every normal below.
    if tree.kind.has_cone() {
        let cone = tree.node_cone(node);
        for &l in &below {
            assert!(cone.contains(tree.light_normal[l as usize]), "cone misses light {l}'s normal");
        }
    }
    // The representative is a light of the node.
    assert!(below.contains(&tree.node_representative(node)), "representative outside its node");
    below
}

fn same_tree(a: &LightTree, b: &LightTree) -> bool {
    a.root == b.root && a.nodes == b.nodes && a.cones == b.cones
}

#[test]
fn ploc_trees_satisfy_the_structural_properties() {
    for kind in KINDS {
        for (seed, n, clustered) in [(1, 1000, false), (2, 777, true), (3, 33, false), (4, 2, false), (5, 1, true)] {
            let lights = random_lights(seed, n, kind, clustered);
            check_tree(&ploc::build(kind, &lights, seed), &lights);
        }
    }
}

#[test]
fn greedy_trees_satisfy_the_structural_properties() {
    for kind in KINDS {
        for (seed, n) in [(11, 300), (12, 2), (13, 1), (14, 0)] {
            let lights = random_lights(seed, n, kind, seed % 2 == 0);
            check_tree(&greedy::build(kind, &lights, seed), &lights);
        }
    }
}

#[test]
fn degenerate_light_sets_build_valid_trees() {
    for kind in KINDS {
        // Coincident lights, zero-intensity lights, and both together.
        let coincident: Vec<TreeLight> = (0..500)
            .map(|i| TreeLight {
                point: Vec3::ONE,
                normal: Vec3::Y,
                intensity: Vec3::splat(i as f32 % 3.0),
                spread: [0.0; 2],
                edges: [Vec3::ZERO; 2],
            })
            .collect();
        let dark: Vec<TreeLight> =
            random_lights(21, 400, kind, false).into_iter().map(|l| TreeLight { intensity: Vec3::ZERO, ..l }).collect();
        let both: Vec<TreeLight> = (0..300).map(|_| TreeLight::at(Vec3::ZERO, Vec3::Y, Vec3::ZERO)).collect();
        for lights in [&coincident, &dark, &both] {
            check_tree(&ploc::build(kind, lights, 5), lights);
            check_tree(&greedy::build(kind, &lights[..100], 5), &lights[..100]);
        }
        let empty = ploc::build(kind, &[], 1);
        assert!(empty.root.is_none());
    }
}

#[test]
fn the_tree_is_identical_for_one_and_two_threads_and_every_run() {
    for kind in KINDS {
        let lights = random_lights(31, 20_000, kind, true);
        let pool = |t| rayon::ThreadPoolBuilder::new().num_threads(t).build().unwrap();
        let one = pool(1).install(|| ploc::build(kind, &lights, 9));
        let two = pool(2).install(|| ploc::build(kind, &lights, 9));
        let again = pool(2).install(|| ploc::build(kind, &lights, 9));
        assert!(same_tree(&one, &two), "{kind:?}: 1 vs 2 threads");
        assert!(same_tree(&two, &again), "{kind:?}: run to run");
        let other_seed = ploc::build(kind, &lights, 10);
        let structure = |t: &LightTree| t.nodes.iter().map(|n| n.children).collect::<Vec<_>>();
        let representatives = |t: &LightTree| t.nodes.iter().map(|n| n.representative).collect::<Vec<_>>();
        assert_eq!(structure(&one), structure(&other_seed), "the seed changes representatives, not structure");
        assert_ne!(representatives(&one), representatives(&other_seed));
    }
}

#[test]
fn representatives_are_chosen_in_proportion_to_intensity() {
    // Four lights with luminance weights 1 : 2 : 3 : 4, far from each other.
    let lights: Vec<TreeLight> = (0..4)
        .map(|i| TreeLight {
            point: Vec3::new(i as f32 * 3.0, 0.0, 0.0),
            normal: Vec3::Y,
            intensity: Vec3::splat(i as f32 + 1.0),
            spread: [0.0; 2],
            edges: [Vec3::ZERO; 2],
        })
        .collect();
    let runs = 40_000;
    let mut counts = [0u32; 4];
    for seed in 0..runs {
        let tree = ploc::build(LightKind::Omni, &lights, seed);
        counts[tree.node_representative(tree.root.unwrap()) as usize] += 1;
    }
    for (i, &c) in counts.iter().enumerate() {
        let expected = (i as f64 + 1.0) / 10.0;
        let freq = f64::from(c) / runs as f64;
        // 5 standard deviations of a binomial frequency at p <= 0.4: 0.0122.
        assert!((freq - expected).abs() < 0.0122, "light {i}: {freq} vs {expected}");
    }
}

#[test]
fn ploc_is_close_to_greedy_in_total_cluster_size() {
    for kind in KINDS {
        let lights = random_lights(41, 2000, kind, true);
        let ploc = ploc::build(kind, &lights, 1).total_cluster_size();
        let greedy = greedy::build(kind, &lights, 1).total_cluster_size();
        assert!(ploc <= greedy * 1.25, "{kind:?}: PLOC {ploc} vs greedy {greedy}");
    }
}

#[test]
fn memory_stays_under_100_bytes_per_omni_light() {
    let lights = random_lights(51, 10_000, LightKind::Omni, false);
    let tree = ploc::build(LightKind::Omni, &lights, 1);
    assert!(tree.memory_bytes() <= 100 * lights.len(), "{} bytes", tree.memory_bytes());
}

fn depth(tree: &LightTree, node: NodeRef) -> usize {
    if node.is_leaf() {
        1
    } else {
        let [a, b] = tree.node_children(node);
        1 + depth(tree, a).max(depth(tree, b))
    }
}

#[test]
fn coincident_lights_build_a_shallow_tree_not_a_chain() {
    // All pair sizes are 0: ties must not make every cluster pick the same
    // neighbour (one merge per pass, a chain of depth n).
    let lights: Vec<TreeLight> = (0..100_000).map(|_| TreeLight::at(Vec3::ONE, Vec3::Y, Vec3::ONE)).collect();
    let tree = ploc::build(LightKind::Omni, &lights, 1);
    let d = depth(&tree, tree.root.unwrap());
    assert!(d <= 64, "depth {d} for 100,000 coincident lights");
    // Balanced sums keep the f32 total accurate.
    let total = tree.node_intensity(tree.root.unwrap()).x;
    assert!((total - 100_000.0).abs() <= 1e-3, "total {total}");
}

#[test]
fn intensities_near_f32_max_build_a_tree_and_terminate() {
    // Sums overflow to infinity; with coincident lights infinity times a zero
    // diagonal is NaN, which once made a pass merge nothing, forever.
    for kind in KINDS {
        let mut lights = random_lights(61, 5000, kind, true);
        for (i, l) in lights.iter_mut().enumerate() {
            l.intensity = Vec3::splat(3.4e38);
            if i % 2 == 0 {
                l.point = lights_first_position(kind);
            }
        }
        let tree = ploc::build(kind, &lights, 1);
        assert_eq!(tree.nodes.len(), 4999);
        let d = depth(&tree, tree.root.unwrap());
        assert!(d <= 64, "{kind:?}: depth {d} (a chain: one merge per pass)");
    }
}

fn lights_first_position(kind: LightKind) -> Vec3 {
    if kind.at_infinity() {
        Vec3::Y
    } else {
        Vec3::ONE
    }
}
