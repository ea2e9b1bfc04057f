//! `lightcuts bench tree`: build time, peak memory and bytes per light of the
//! PLOC light tree over seeded random lights, and its quality against the
//! exact greedy tree (sum of cluster sizes, average cut size at 2%).

use std::time::Instant;

use glam::Vec3;
use serde::Serialize;

use crate::cli::process;
use crate::embree::Device;
use crate::light::{LightKind, TreeLight};
use crate::light_tree::layout::CutTree;
use crate::light_tree::{greedy, ploc, LightTree, LightTrees};
use crate::lightcut::{evaluate, CutScratch, CutSettings};
use crate::scene::material::{Albedo, Material};
use crate::shading::SurfacePoint;
use crate::util::sampling::Rng;

/// How the benchmark's lights are spread.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Distribution {
    /// Uniform in a 20 x 5 x 20 m box.
    Uniform,
    /// 64 clumps of 0.5 m radius in that box.
    Clustered,
}

/// Seeded random lights of one kind. Directional lights point into the upper
/// hemisphere; oriented lights face mostly downwards.
#[must_use]
pub fn random_lights(kind: LightKind, n: usize, distribution: Distribution, seed: u64) -> Vec<TreeLight> {
    let mut rng = Rng::from_key(&[seed, n as u64, distribution as u64]);
    let box_point =
        |rng: &mut Rng| Vec3::new(rng.range_f32(-10.0, 10.0), rng.range_f32(3.0, 8.0), rng.range_f32(-10.0, 10.0));
    let centres: Vec<Vec3> = (0..64).map(|_| box_point(&mut rng)).collect();
    let unit = |rng: &mut Rng| loop {
        let v = Vec3::new(rng.range_f32(-1.0, 1.0), rng.range_f32(-1.0, 1.0), rng.range_f32(-1.0, 1.0));
        let l = v.length_squared();
        if l > 1e-4 && l <= 1.0 {
            break v / l.sqrt();
        }
    };
    (0..n)
        .map(|_| {
            let position = match distribution {
                Distribution::Uniform => box_point(&mut rng),
                Distribution::Clustered => centres[rng.below(64) as usize] + 0.5 * unit(&mut rng) * rng.next_f32(),
            };
            let mut direction = unit(&mut rng);
            let intensity =
                Vec3::splat(rng.range_f32(0.5, 1.5)) * Vec3::new(1.0, rng.range_f32(0.8, 1.0), rng.range_f32(0.6, 1.0));
            match kind {
                LightKind::Omni => TreeLight::at(position, Vec3::ZERO, intensity),
                LightKind::Area | LightKind::Oriented | LightKind::Spot => {
                    if direction.y > 0.0 {
                        direction.y = -direction.y;
                    }
                    // Spots: outer half-angles of 20 to 60 degrees, inner 80% of them.
                    let spread = if kind == LightKind::Spot {
                        let outer = rng.range_f32(20.0, 60.0).to_radians();
                        [(0.8 * outer).cos(), outer.cos()]
                    } else {
                        [0.0; 2]
                    };
                    TreeLight { spread, ..TreeLight::at(position, direction, intensity) }
                }
                LightKind::Directional | LightKind::Environment => {
                    direction.y = direction.y.abs();
                    TreeLight::at(direction, Vec3::ZERO, intensity)
                }
            }
        })
        .collect()
}

#[derive(Debug, Clone, Serialize)]
pub struct BuildFigure {
    pub kind: &'static str,
    pub distribution: Distribution,
    pub lights: usize,
    pub build_seconds: f64,
    /// Resident memory the build added at its peak (Linux VmHWM after
    /// resetting it, minus VmRSS before), in MiB; None where /proc is missing.
    pub peak_build_mib: Option<f64>,
    pub tree_bytes_per_light: f64,
    /// The tree laid out for the cut (`light_tree::layout`): the time to lay
    /// it out, and its bytes per light (what a render keeps).
    pub layout_seconds: f64,
    pub layout_bytes_per_light: f64,
    /// build time per light over the previous size's (1.0 = linear).
    pub growth_per_light: Option<f64>,
    /// build time over the previous size's.
    pub growth: Option<f64>,
}

#[derive(Debug, Clone, Serialize)]
pub struct QualityFigure {
    pub kind: &'static str,
    pub distribution: Distribution,
    pub lights: usize,
    pub shading_points: usize,
    pub ploc_total_cluster_size: f64,
    pub greedy_total_cluster_size: f64,
    pub ploc_average_cut: f64,
    pub greedy_average_cut: f64,
    /// ploc_average_cut / greedy_average_cut - 1.
    pub cut_excess: f64,
    pub greedy_build_seconds: f64,
}

/// Builds a PLOC tree over `lights` and reports time and memory.
pub fn measure_build(
    kind: LightKind,
    distribution: Distribution,
    lights: &[TreeLight],
    seed: u64,
) -> (BuildFigure, LightTree) {
    let reset = process::reset_peak_resident();
    let before = process::memory().map(|m| m.resident_mib);
    let start = Instant::now();
    let tree = ploc::build(kind, lights, seed);
    let build_seconds = start.elapsed().as_secs_f64();
    let peak = process::memory().map(|m| m.peak_resident_mib);
    let start = Instant::now();
    let layout = CutTree::from_tree(&tree);
    let layout_seconds = start.elapsed().as_secs_f64();
    let peak_build_mib = match (reset, before, peak) {
        (true, Some(b), Some(p)) => Some((p - b).max(0.0)),
        _ => None,
    };
    let figure = BuildFigure {
        kind: kind.name(),
        distribution,
        lights: lights.len(),
        build_seconds,
        peak_build_mib,
        tree_bytes_per_light: tree.memory_bytes() as f64 / lights.len().max(1) as f64,
        layout_seconds,
        layout_bytes_per_light: layout.memory_bytes() as f64 / lights.len().max(1) as f64,
        growth_per_light: None,
        growth: None,
    };
    (figure, tree)
}

/// Fixed shading points on the floor y = 0 under the lights (diffuse,
/// normal up), seen from random directions above.
fn shading_points(material: &Material, count: usize) -> Vec<SurfacePoint<'_>> {
    let mut rng = Rng::seeded(0x5eed);
    (0..count)
        .map(|_| {
            let p = Vec3::new(rng.range_f32(-12.0, 12.0), 0.0, rng.range_f32(-12.0, 12.0));
            let wo = Vec3::new(rng.range_f32(-1.0, 1.0), rng.range_f32(0.2, 1.0), rng.range_f32(-1.0, 1.0)).normalize();
            SurfacePoint::bare(material, p, Vec3::Y, wo, Vec3::splat(0.5))
        })
        .collect()
}

/// Average cut size at 2% over the fixed shading points (no occluders).
pub fn average_cut(tree: &LightTree, points: &[SurfacePoint<'_>], embree: &crate::embree::Scene) -> f64 {
    let settings = CutSettings { error: 0.02, max_cut: 1_000_000, ..CutSettings::default() };
    let mut scratch = CutScratch::default();
    let trees = LightTrees::of(tree);
    let nodes: u64 = points.iter().map(|sp| evaluate(&trees, sp, embree, &settings, &mut scratch, 0).nodes).sum();
    nodes as f64 / points.len().max(1) as f64
}

/// PLOC against greedy on `n` lights: cluster sizes and average cut size.
pub fn measure_quality(
    kind: LightKind,
    distribution: Distribution,
    n: usize,
    seed: u64,
) -> Result<QualityFigure, crate::embree::EmbreeError> {
    let lights = random_lights(kind, n, distribution, seed);
    let ploc_tree = ploc::build(kind, &lights, seed);
    let start = Instant::now();
    let greedy_tree = greedy::build(kind, &lights, seed);
    let greedy_build_seconds = start.elapsed().as_secs_f64();
    let material = Material::diffuse("bench", Albedo::Constant(Vec3::splat(0.5)));
    let points = shading_points(&material, 1000);
    let device = Device::try_new()?;
    let empty = device.try_new_scene()?.commit()?;
    let ploc_cut = average_cut(&ploc_tree, &points, &empty);
    let greedy_cut = average_cut(&greedy_tree, &points, &empty);
    Ok(QualityFigure {
        kind: kind.name(),
        distribution,
        lights: n,
        shading_points: points.len(),
        ploc_total_cluster_size: ploc_tree.total_cluster_size(),
        greedy_total_cluster_size: greedy_tree.total_cluster_size(),
        ploc_average_cut: ploc_cut,
        greedy_average_cut: greedy_cut,
        cut_excess: ploc_cut / greedy_cut - 1.0,
        greedy_build_seconds,
    })
}
