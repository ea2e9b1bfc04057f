//! Reuse between pixels is unbiased: at 16 fixed camera hits, taken as four
//! blocks of four, the mean over 1,024 seeds of each hit's estimate from
//! its block's draws equals its exact sum within 4 standard errors; MIS
//! weights that give every hit of the block the same share (1/4, which sums
//! to 1 only for lights every hit can draw) fail the same test.
use super::*;
use crate::embree::Device;
use crate::light::Lights;
use crate::lightcut::stochastic::tests as stochastic_tests;
use crate::lightcut::stochastic::{draw_lights, StochasticScratch, STOCHASTIC_DEFAULTS};
use crate::lightcut::CutSettings;
use crate::shading::{BatchBuffers, Geometry, LightBatch, SurfacePoint};
use crate::util::sampling::Rng;

const SEEDS: u64 = 1024;

/// Hits a block has: a 2 x 2 block's.
const BLOCK: usize = 4;

/// The stochastic cut's test scene and point lights, the brighter row
/// lower (faces of every orientation: a light behind one hit's surface is
/// one that hit never draws).
fn scene() -> crate::scene::Scene {
    let (row, lower) = ("corner = [-4, 1.2, 2]", "corner = [-4, 0.6, 1.5]");
    assert!(stochastic_tests::OMNI.contains(row));
    stochastic_tests::scene(&stochastic_tests::OMNI.replace(row, lower))
}

/// For each of 16 hits: the exact sum's luminance, and the mean and
/// standard error over `SEEDS` seeds of the luminance of its estimate from
/// its block's draws, MIS-weighted by `weight`.
fn estimates(weight: impl Fn(usize, &[f64]) -> f64 + Copy) -> Vec<(f64, f64, f64)> {
    let scene = scene();
    let lights = Lights::from_scene(&scene);
    let device = Device::try_new().unwrap();
    let geometry = Geometry::try_new(&device, &scene, std::slice::from_ref(&lights)).unwrap();
    let trees = crate::lightcut::build_trees(std::slice::from_ref(&lights), 5);
    // A small cut, so that most of the estimate is sampled.
    let settings = CutSettings { error: 0.1, max_cut: 8, pixel_cut: false, ..STOCHASTIC_DEFAULTS };
    let camera = scene.camera(32, 24);
    let mut pixel = Rng::seeded(11);
    let mut points: Vec<SurfacePoint<'_>> = Vec::new();
    while points.len() < 4 * BLOCK {
        let ray = camera.ray(pixel.range_f32(0.0, 32.0), pixel.range_f32(0.0, 24.0));
        if let Some(hit) = geometry.embree.intersect(&ray) {
            points.push(geometry.surface(&ray, &hit));
        }
    }
    let (mut cut, mut reuse, mut batch) =
        (StochasticScratch::default(), ReuseScratch::default(), BatchBuffers::default());
    let mut drawn: Vec<Choices> = (0..BLOCK).map(|_| Choices::default()).collect();
    let mut rows = Vec::new();
    for block in points.chunks(BLOCK) {
        let evaluators: Vec<_> = block.iter().map(|sp| Some(LightEvaluator::new(sp))).collect();
        let mut sums = vec![Vec::new(); BLOCK];
        for seed in 0..SEEDS {
            let mut results = vec![CutResult::default(); BLOCK];
            for (k, sp) in block.iter().enumerate() {
                let mut rng = Rng::from_key(&[seed, rows.len() as u64, k as u64]);
                results[k] = draw_lights(&trees, sp, &geometry.embree, &settings, &mut rng, &mut cut, 0, &mut drawn[k]);
            }
            estimate_with(&evaluators, &drawn, &geometry.embree, &mut results, &mut reuse, weight);
            for (sum, result) in sums.iter_mut().zip(&results) {
                sum.push(luminance64(result.radiance));
            }
        }
        for (sp, values) in block.iter().zip(sums) {
            let mut exact = LightBatch::new(&geometry.embree, sp, &mut batch);
            lights.for_each(|light| exact.add(&light));
            let exact = luminance64(exact.finish().radiance);
            let mean = values.iter().sum::<f64>() / SEEDS as f64;
            let variance = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (SEEDS - 1) as f64;
            rows.push((exact, mean, (variance / SEEDS as f64).sqrt()));
        }
    }
    rows
}

/// Points whose mean is more than 4 standard errors from the exact sum.
fn biased_points(rows: &[(f64, f64, f64)]) -> usize {
    rows.iter().filter(|(exact, mean, se)| (mean - exact).abs() > 4.0 * se + 1e-9 * exact.abs()).count()
}

#[test]
fn reuse_between_hits_is_unbiased() {
    let rows = estimates(balance);
    assert!(rows.iter().filter(|r| r.2 > 0.0).count() >= 8, "most points must be sampled: {rows:?}");
    assert_eq!(biased_points(&rows), 0, "(exact, mean, standard error) per point: {rows:?}");
}

#[test]
fn equal_shares_for_every_hit_are_caught() {
    let rows = estimates(|_, luminances| 1.0 / luminances.len() as f64);
    assert!(biased_points(&rows) > 0, "(exact, mean, standard error) per point: {rows:?}");
}
