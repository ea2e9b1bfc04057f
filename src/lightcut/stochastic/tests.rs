//! The stochastic cut is unbiased: at fixed shading points, the mean over
//! 1,024 seeds of its estimate equals the exact sum within 4 standard errors
//! (estimated from the same samples), for each light kind; a deliberately
//! biased variant (one child of some nodes never taken) fails the same test.
use super::*;
use crate::embree::Device;
use crate::light::Lights;
use crate::scene::builder::SceneText;
use crate::scene::Scene;
use crate::shading::{Geometry, LightBatch, SurfacePoint};
use crate::util::color::luminance64;
use crate::util::sampling::mix64;

// 256 seeds were too few for the spots: near a cone's edge the falloff
// makes the estimate heavy-tailed and its standard error underestimated
// (a point 7.6 standard errors off at 256 passed at 8,192).
const SEEDS: u64 = 1024;

/// A floor, an occluding sphere and a box (faces of every orientation),
/// and `lights` (also the scene of `lightcut::reuse`'s tests).
pub(in crate::lightcut) fn scene(lights: &str) -> Scene {
    SceneText::new(32, 24)
        .camera([0.0, 4.0, 7.0], [0.0, 0.5, 0.0], 55.0)
        .material("floor", [0.7, 0.7, 0.7], "")
        .material("glossy", [0.4, 0.3, 0.2], "specular = [0.3, 0.3, 0.3]\nexponent = 30\n")
        .floor(0.0, 6.0, "floor")
        .sphere([-0.8, 1.0, 0.0], 1.0, "glossy")
        .cuboid([1.0, 0.0, -1.0], [2.0, 1.5, 0.0], "floor")
        .raw(lights)
        .load(std::path::Path::new("stochastic.toml"))
        .unwrap()
}

/// Point lights: a grid overhead and a brighter row low beside the box.
pub(in crate::lightcut) const OMNI: &str = r#"
[[lights]]
type = "grid"
corner = [-3, 3, -3]
u = [6, 0, 0]
v = [0, 0, 6]
count = [20, 15]
intensity = [0.05, 0.04, 0.03]
[[lights]]
type = "grid"
corner = [-4, 1.2, 2]
u = [8, 0, 0]
v = [0, 0, 1]
count = [10, 3]
intensity = [0.2, 0.1, 0.05]
"#;

pub(in crate::lightcut) const ORIENTED: &str = r#"
[[lights]]
type = "area"
corner = [-1.5, 3, -1.5]
u = [3, 0, 0]
v = [0, 0, 3]
radiance = [3, 3, 3]
samples = 300
[[lights]]
type = "area"
corner = [3, 0.5, -2]
u = [0, 0, 2]
v = [0, 1.5, 0]
radiance = [1, 2, 4]
samples = 120
"#;

/// 300 suns (a sun's disc is in no tree: point-like ones make a
/// directional tree) about (0.5, 1, 0.3), and the environment's directions.
fn directional() -> String {
    let mut text = String::new();
    for j in 0..15 {
        for i in 0..20 {
            let (x, z) = (0.2 + 0.03 * i as f32, 0.1 + 0.03 * j as f32);
            text +=
                &format!("[[lights]]\ntype = \"sun\"\ndirection = [{x}, 1, {z}]\nirradiance = [0.01, 0.01, 0.008]\n");
        }
    }
    text + "[environment]\nradiance = [0.3, 0.4, 0.6]\nsamples = 256\n"
}

/// 16 x 16 spots over the scene, pointing down and outwards, of different widths.
fn spots() -> String {
    let mut text = String::new();
    for j in 0..16 {
        for i in 0..16 {
            let (x, z) = (-3.0 + 0.4 * i as f32, -3.0 + 0.4 * j as f32);
            let outer = 15.0 + 2.0 * ((i + j) % 20) as f32;
            text += &format!(
                "[[lights]]\ntype = \"spot\"\nposition = [{x}, 3, {z}]\ndirection = [{}, -1, {}]\nintensity = [0.3, 0.25, 0.2]\ninner_angle = {}\nouter_angle = {outer}\n",
                0.2 * x,
                0.2 * z,
                0.6 * outer
            );
        }
    }
    text
}

/// The shading points of the tests: `count` points seen through seeded
/// pixels, with the scene's lights, Embree geometry and light trees.
pub(in crate::lightcut) fn with_points(
    scene: &Scene,
    count: usize,
    mut check: impl FnMut(&Lights, &Geometry<'_>, &LightTrees, &SurfacePoint<'_>),
) {
    let lights = Lights::from_scene(scene);
    let device = Device::try_new().unwrap();
    let geometry = Geometry::try_new(&device, scene, std::slice::from_ref(&lights)).unwrap();
    let trees = crate::lightcut::build_trees(std::slice::from_ref(&lights), 5);
    assert!(trees.trees.iter().all(|t| !t.blocks.is_empty()), "every tree must be big enough for a cut");
    let camera = scene.camera(32, 24);
    let mut pixel = Rng::seeded(11);
    let mut found = 0;
    while found < count {
        let ray = camera.ray(pixel.range_f32(0.0, 32.0), pixel.range_f32(0.0, 24.0));
        let Some(hit) = geometry.embree.intersect(&ray) else { continue };
        check(&lights, &geometry, &trees, &geometry.surface(&ray, &hit));
        found += 1;
    }
}

/// For each of 16 shading points seen through fixed pixels: the exact sum's
/// luminance, and the mean and standard error of the stochastic estimate's
/// luminance over `SEEDS` seeds: the renderer's own [`evaluate`], or with
/// `biased` its walk made wrong (child 1 of every third block gets
/// probability 0: the lights below it are never drawn).
fn estimates(scene: &Scene, biased: bool) -> Vec<(f64, f64, f64)> {
    estimates_with(scene, biased, 0, 0)
}

/// [`estimates`] with `resampled_rays` shadow rays resampled per cut (0:
/// every cut node's), or `cut_draws` lights drawn over the cut (0: one
/// per node).
fn estimates_with(scene: &Scene, biased: bool, resampled_rays: usize, cut_draws: usize) -> Vec<(f64, f64, f64)> {
    // A small cut, so that most of the estimate is sampled.
    let settings = CutSettings { error: 0.1, max_cut: 8, resampled_rays, cut_draws, ..CutSettings::default() };
    let (mut scratch, mut batch) = (StochasticScratch::default(), BatchBuffers::default());
    let mut rows = Vec::new();
    with_points(scene, 16, |lights, geometry, trees, sp| {
        let exact = exact_luminance(lights, &geometry.embree, sp, &mut batch);
        let bounds = PointBounds::new(sp, trees.scale);
        let shipped = walk_importance(&bounds);
        let wrong = |tree: &CutTree, blocks: [usize; 2]| {
            let weights = shipped(tree, blocks);
            [0, 1].map(|i| {
                let [w0, w1] = weights[i];
                [w0, if blocks[i] % 3 == 0 && w0 > 0.0 { 0.0 } else { w1 }]
            })
        };
        let values: Vec<f64> = (0..SEEDS)
            .map(|seed| {
                let mut rng = Rng::from_key(&[seed, rows.len() as u64]);
                let embree = &geometry.embree;
                let found = if biased {
                    let at = AtPoint { trees, sp, embree, settings: &settings, bounds: &bounds, importance: &wrong };
                    evaluate_with(&at, &mut rng, &mut scratch, 0)
                } else {
                    evaluate(trees, sp, embree, &settings, &mut rng, &mut scratch, 0)
                };
                luminance64(found.radiance)
            })
            .collect();
        rows.push(row(exact, &values));
    });
    rows
}

/// The luminance of the exact sum at `sp`: every light, one shadow ray each.
pub(in crate::lightcut) fn exact_luminance(
    lights: &Lights,
    embree: &EmbreeScene,
    sp: &SurfacePoint<'_>,
    batch: &mut BatchBuffers,
) -> f64 {
    let mut exact = LightBatch::new(embree, sp, batch);
    lights.for_each(|light| exact.add(&light));
    luminance64(exact.finish().radiance)
}

/// (exact, mean, standard error of the mean) of one point's estimates,
/// one per seed.
pub(in crate::lightcut) fn row(exact: f64, values: &[f64]) -> (f64, f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let variance = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (exact, mean, (variance / n).sqrt())
}

/// Points whose mean is more than 4 standard errors from the exact sum.
pub(in crate::lightcut) fn biased_points(rows: &[(f64, f64, f64)]) -> usize {
    rows.iter().filter(|(exact, mean, se)| (mean - exact).abs() > 4.0 * se + 1e-9 * exact.abs()).count()
}

fn check_unbiased(lights: &str) {
    let rows = estimates(&scene(lights), false);
    assert!(rows.iter().filter(|r| r.2 > 0.0).count() >= 8, "most points must be sampled: {rows:?}");
    assert_eq!(biased_points(&rows), 0, "(exact, mean, standard error) per point: {rows:?}");
}

#[test]
fn omni_estimates_are_unbiased() {
    check_unbiased(OMNI);
}

#[test]
fn oriented_estimates_are_unbiased() {
    check_unbiased(ORIENTED);
}

#[test]
fn spot_estimates_are_unbiased() {
    check_unbiased(&spots());
}

#[test]
fn directional_estimates_are_unbiased() {
    check_unbiased(&directional());
}

#[test]
fn a_variant_that_never_takes_some_children_is_caught() {
    for lights in [OMNI, ORIENTED, &directional(), &spots()] {
        let rows = estimates(&scene(lights), true);
        assert!(biased_points(&rows) >= 8, "the bias must show at most points: {rows:?}");
    }
}

/// The stochastic cut with 2 of its (up to 8) nodes' shadow rays resampled
/// (`--resampled-rays 2`) is unbiased too, for points and triangle lights.
#[test]
fn resampled_cuts_are_unbiased() {
    for lights in [OMNI, ORIENTED] {
        let rows = estimates_with(&scene(lights), false, 2, 0);
        assert!(rows.iter().filter(|r| r.2 > 0.0).count() >= 8, "most points must be sampled: {rows:?}");
        assert_eq!(biased_points(&rows), 0, "(exact, mean, standard error) per point: {rows:?}");
    }
}

/// Lights drawn over the cut (`--cut-draws`: 1 and 3 per point, each cut
/// node by its importance, design §10.10) are unbiased for every light
/// kind; with the walks made wrong (as [`estimates`]' biased variant) the
/// bias shows.
#[test]
fn draws_over_the_cut_are_unbiased_and_a_wrong_walk_is_caught() {
    for lights in [OMNI, ORIENTED, &directional(), &spots()] {
        for draws in [1, 3] {
            let rows = estimates_with(&scene(lights), false, 0, draws);
            assert!(rows.iter().filter(|r| r.2 > 0.0).count() >= 8, "most points must be sampled: {rows:?}");
            assert_eq!(biased_points(&rows), 0, "{draws} draws: (exact, mean, standard error) per point: {rows:?}");
        }
        let rows = estimates_with(&scene(lights), true, 0, 1);
        assert!(biased_points(&rows) >= 4, "the bias must show: {rows:?}");
    }
}

/// Resampling is unbiased term by term, on its own: with every light of
/// the scene chosen at a shading point, the mean of
/// [`crate::shading::resample_and_trace`]'s sum over its one random number
/// (a step function of it, averaged on a grid of 16,384 midpoints) equals
/// the sum of every light traced, within 0.5%, keeping 4 rays of hundreds;
/// a variant whose weights never pick every third term is caught at most
/// points. Returns the (exact, mean) luminances per point.
fn resampled_means(lights: &str, weight: impl Fn(usize, DVec3) -> f64 + Copy) -> Vec<(f64, f64)> {
    use crate::light::TreeLight;
    use crate::shading::{evaluate_and_trace, resample_and_trace_by, Choices, Evaluations};
    const GRID: usize = 16_384;
    let mut rows = Vec::new();
    let mut evaluations = Evaluations::default();
    with_points(&scene(lights), 16, |lights, geometry, _, sp| {
        let mut chosen = Choices::default();
        lights.for_each(|light| {
            let tree_light = TreeLight::of(&light);
            chosen.push(light.kind(), &tree_light, tree_light.intensity.as_dvec3(), 0);
        });
        let evaluator = LightEvaluator::new(sp);
        let (embree, width) = (&geometry.embree, PacketWidth::Sixteen);
        let (values, _) = evaluate_and_trace(&evaluator, embree, width, &chosen, &mut evaluations);
        let exact: f64 = values.iter().map(|&v| luminance64(v)).sum();
        let mean = (0..GRID)
            .map(|j| {
                let xi = (j as f64 + 0.5) / GRID as f64;
                let (values, rays) =
                    resample_and_trace_by(&evaluator, embree, width, &chosen, &mut evaluations, 4, xi, weight);
                assert!(rays <= 4);
                values.iter().map(|&v| luminance64(v)).sum::<f64>()
            })
            .sum::<f64>()
            / GRID as f64;
        rows.push((exact, mean));
    });
    rows
}

#[test]
fn resampling_keeps_the_sum_and_a_wrong_weight_is_caught() {
    for lights in [OMNI, ORIENTED] {
        let rows = resampled_means(lights, |_, v| luminance64(v));
        assert!(rows.iter().filter(|r| r.0 > 0.0).count() >= 8, "most points must be lit: {rows:?}");
        let off = |rows: &[(f64, f64)]| rows.iter().filter(|(e, m)| (m - e).abs() > 5e-3 * e.abs()).count();
        assert_eq!(off(&rows), 0, "(exact, mean) per point: {rows:?}");
        let wrong = resampled_means(lights, |k, v| if k % 3 == 0 { 0.0 } else { luminance64(v) });
        assert!(off(&wrong) >= 8, "the bias must show at most points: {wrong:?}");
    }
}

/// Walks draws from the root of each tree at 4 shading points, and checks
/// the walk against its [`pmf`] as pbrt-v4's light-sampler tests do: each
/// draw's weight is the light's intensity over exactly pmf(its slot); the
/// pmf sums to 1 over the slots a walk can end at; and over the draws, each
/// slot's count over (pmf x draws) is within a few percent of 1.
fn check_pmf(lights: &str) {
    const DRAWS: u64 = 1 << 20;
    with_points(&scene(lights), 4, |_, _, trees, sp| {
        let bounds = PointBounds::new(sp, trees.scale);
        let importance = walk_importance(&bounds);
        for (t, tree) in trees.trees.iter().enumerate() {
            let below = tree.blocks[0].child[0].index();
            // Every slot a walk can end at, and its pmf.
            let mut ends = Vec::new();
            let mut pending = vec![below];
            while let Some(b) = pending.pop() {
                for k in 0..2 {
                    let child = tree.blocks[b].child[k];
                    if child.is_exact() {
                        ends.push(((b, k), pmf(tree, &importance, below, (b, k))));
                    } else if child != Child::EMPTY {
                        pending.push(child.index());
                    }
                }
            }
            let total: f64 = ends.iter().map(|e| e.1).sum();
            if total == 0.0 {
                continue; // no light of the tree reaches this point
            }
            // A walk ends without a light where both children of a block it
            // reaches have weight 0 (no light below can reach the point,
            // although the block's own bound is not 0): the rest of the mass.
            assert!(total <= 1.0 + 1e-9, "tree {t}: the pmf sums to {total}");
            ends.push(((usize::MAX, 0), (1.0 - total).max(0.0)));
            let pmf_of: std::collections::HashMap<(usize, usize), f64> = ends.iter().copied().collect();
            let mut counts: std::collections::HashMap<(usize, usize), u64> = std::collections::HashMap::new();
            let mut scratch = StochasticScratch::default();
            let mut rng = Rng::seeded(3);
            for _ in 0..DRAWS {
                scratch.nodes.clear();
                scratch.nodes.push(Node {
                    importance: 1.0,
                    block: 0,
                    slot: 0,
                    tree: t as crate::light_tree::TreeIndex,
                    in_cut: true,
                });
                draw(trees, &mut rng, PixelSample::ALONE, &mut scratch, &importance);
                let Some(d) = scratch.drawn.first() else {
                    *counts.entry((usize::MAX, 0)).or_default() += 1;
                    continue;
                };
                let end = (d.block as usize, usize::from(d.slot));
                let intensity = luminance64(slot_intensity(tree, end.0, end.1).as_dvec3());
                let probability = intensity / luminance64(d.weight);
                let expected = pmf_of[&end];
                assert!(
                    (probability - expected).abs() <= 1e-12 * expected,
                    "tree {t}, slot {end:?}: drawn with {probability}, pmf {expected}"
                );
                *counts.entry(end).or_default() += 1;
            }
            // Per slot: the sum of 1 / (pmf x draws) over its draws is 1 up
            // to its standard error, 1 / sqrt(expected count). Each slot
            // likely enough is checked to 5 standard errors, and the mean
            // square of the deviations in standard errors (a chi-square per
            // slot, 1 on average) catches a distortion spread over many.
            let (mut checked, mut chi_square) = (0, 0.0);
            for (end, p) in &ends {
                let expected = p * DRAWS as f64;
                let count = counts.get(end).copied().unwrap_or(0) as f64;
                if *p == 0.0 {
                    assert_eq!(count, 0.0, "tree {t}, slot {end:?}: drawn with pmf 0");
                } else if expected >= 1_000.0 {
                    let deviation = (count / expected - 1.0) * expected.sqrt();
                    assert!(deviation.abs() < 5.0, "tree {t}, slot {end:?}: {count} draws, {expected} expected");
                    chi_square += deviation * deviation;
                    checked += 1;
                }
            }
            let mass: f64 = ends.iter().filter(|e| e.1 * DRAWS as f64 >= 1_000.0).map(|e| e.1).sum();
            assert!(mass >= 0.75, "tree {t}: the slots checked hold only {mass} of the pmf");
            assert!(chi_square / f64::from(checked) < 1.5, "tree {t}: chi-square {chi_square} over {checked} slots");
        }
    });
}

#[test]
fn the_walk_draws_with_its_pmf_for_every_kind() {
    for lights in [OMNI, ORIENTED, &directional(), &spots()] {
        check_pmf(lights);
    }
}

/// [`PixelSample::number`]: at every pixel, the numbers a node gets at the
/// pixel's `count` samples fall one in each stratum of the grid rotated by
/// the node's shift, whatever the samples' own numbers; over pixels, each
/// sample's number is uniform (a histogram of 64 bins within 5 standard
/// errors), so every sample's estimate stays unbiased. Without the shift
/// (every pixel's strata the same) sample 0 would only see [0, 1/count).
#[test]
fn stratified_numbers_are_uniform_and_one_per_stratum() {
    const PIXELS: u64 = 65_536;
    const BINS: usize = 64;
    let count = 16u32;
    let mut xi = Rng::seeded(5);
    let mut histograms = vec![[0u64; BINS]; count as usize];
    for pixel in 0..PIXELS {
        let key = mix64(pixel);
        for node in [node_key(0, 0, 0), node_key(3, 12_345, 1)] {
            let shift = PixelSample { pixel: key, index: 0, count: 1 }.number(node, 0.0);
            let mut strata = vec![false; count as usize];
            for index in 0..count {
                let u = PixelSample { pixel: key, index, count }.number(node, xi.next_f64());
                assert!((0.0..1.0).contains(&u), "{u}");
                let stratum = ((u - shift).rem_euclid(1.0) * f64::from(count)) as usize;
                assert!(!strata[stratum.min(count as usize - 1)], "pixel {pixel}: stratum {stratum} twice");
                strata[stratum.min(count as usize - 1)] = true;
                histograms[index as usize][(u * BINS as f64) as usize] += 1;
            }
        }
    }
    let expected = (2 * PIXELS) as f64 / BINS as f64;
    for (index, histogram) in histograms.iter().enumerate() {
        for (bin, &n) in histogram.iter().enumerate() {
            let deviation = (n as f64 - expected) / expected.sqrt();
            assert!(deviation.abs() < 5.0, "sample {index}, bin {bin}: {n} against {expected}");
        }
    }
}

/// The pixel's mean over 16 stratified samples at one shading point is
/// the exact sum on average over pixels (unbiased), and its variance is
/// below the independent samples' (a sixteenth of one sample's): the
/// stratification is what makes the pixel's error fall faster than
/// 1 / sqrt(spp) where its samples see the same lights. Independent
/// numbers (a new pixel key per sample) give the sixteenth, and are caught.
#[test]
fn stratified_samples_of_a_pixel_are_unbiased_and_less_noisy() {
    const SPP: u32 = 16;
    let settings = CutSettings { error: 0.1, max_cut: 8, ..CutSettings::default() };
    let ratios = variance_ratios(&settings, SPP, |pixel, index| PixelSample { pixel, index, count: SPP });
    assert!(ratios.len() >= 4, "most points must be sampled: {ratios:?}");
    // Pooled over the points: the stratified pixels' variance is well below
    // the independent ones'.
    let pooled = ratios.iter().sum::<f64>() / ratios.len() as f64;
    eprintln!("variance of stratified over independent pixels: mean {pooled:.3}, per point {ratios:.3?}");
    assert!(pooled < 0.5, "variance of stratified over independent pixels, per point: {ratios:?}");
}

/// At 8 shading points, a pixel's mean over `spp` samples, each numbered by
/// `sample(pixel, index)`, and over `spp` independent samples (a new pixel
/// key per sample), each over 512 pixels: both means must be the exact sum
/// within 4 standard errors. Returns the variance of the first over the
/// second's, per point with any sampled light.
fn variance_ratios(settings: &CutSettings, spp: u32, sample: impl Fn(u64, u32) -> PixelSample) -> Vec<f64> {
    const PIXELS: u64 = 512;
    let mut scratch = StochasticScratch::default();
    let mut batch = BatchBuffers::default();
    let mut ratios = Vec::new();
    with_points(&scene(OMNI), 8, |lights, geometry, trees, sp| {
        let exact = exact_luminance(lights, &geometry.embree, sp, &mut batch);
        let variance_of = |independent: bool, scratch: &mut StochasticScratch| {
            let means: Vec<f64> = (0..PIXELS)
                .map(|pixel| {
                    (0..spp)
                        .map(|index| {
                            let mut rng = Rng::from_key(&[pixel, u64::from(index)]);
                            let numbered = if independent {
                                PixelSample { pixel: mix64(pixel * 64 + u64::from(index)), index, count: 1 }
                            } else {
                                sample(pixel, index)
                            };
                            let sp = SurfacePoint { sample: Some(numbered), ..sp.clone() };
                            let found = evaluate(trees, &sp, &geometry.embree, settings, &mut rng, scratch, 0);
                            luminance64(found.radiance)
                        })
                        .sum::<f64>()
                        / f64::from(spp)
                })
                .collect();
            let mean = means.iter().sum::<f64>() / PIXELS as f64;
            let variance = means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (PIXELS - 1) as f64;
            (mean, variance)
        };
        let (mean, variance) = variance_of(false, &mut scratch);
        let (independent_mean, independent) = variance_of(true, &mut scratch);
        if independent == 0.0 {
            return; // every light of this point is in exact nodes
        }
        for (m, v) in [(mean, variance), (independent_mean, independent)] {
            let se = (v / PIXELS as f64).sqrt();
            assert!((m - exact).abs() <= 4.0 * se + 1e-9 * exact, "mean {m} against {exact} (standard error {se})");
        }
        ratios.push(variance / independent);
    });
    ratios
}

/// A kept cut's draws (design §10.10) take its sequence in turn
/// ([`PixelSample::in_turn`]), not the strata of the samples' indices:
/// 16 samples of a 256-sample pixel at one point, indices 0 to 15 (the
/// samples a moving object leaves on one surface need not spread over the
/// pixel's indices; these take a sixteenth of the strata), one light drawn
/// over the kept cut each. Their mean is the exact sum on average over
/// pixels, and its variance is below half that of 16 independent draws;
/// drawn by the indices' strata, the 16 numbers fall within a sixteenth
/// of [0, 1) and the variance is above the independent draws', so the test
/// fails without the sequence.
#[test]
fn a_kept_cuts_draws_take_its_sequence_in_turn() {
    const USES: u32 = 16;
    let settings = CutSettings { error: 0.1, max_cut: 8, pixel_cut: true, cut_draws: 1, ..CutSettings::default() };
    let ratios = variance_ratios(&settings, USES, |pixel, index| PixelSample { pixel, index, count: 256 });
    assert!(ratios.len() >= 4, "most points must be sampled: {ratios:?}");
    let pooled = ratios.iter().sum::<f64>() / ratios.len() as f64;
    eprintln!("variance of a kept cut's sequence over independent draws: mean {pooled:.3}, per point {ratios:.3?}");
    assert!(pooled < 0.5, "variance of a kept cut's sequence over independent draws, per point: {ratios:?}");
}

/// A pixel's cut (design §10.9) chosen at one shading point A (the
/// pixel's first sample) and walked at another, B (its second), 1.4
/// pixels away on the same surface: at 16 such pairs B's mean over
/// `SEEDS` pixels is its exact sum, walking A's cut (different from B's
/// own at most points); a kept cut missing its largest node (no longer
/// covering every light) is caught; and a B on another surface than its A
/// chooses its own cut, kept beside A's: a later sample on either surface
/// walks that surface's cut.
#[test]
fn a_pixel_cut_serves_its_later_samples_unbiasedly_and_a_partial_one_is_caught() {
    check_pixel_cut(0);
}

/// The same with one light drawn over the kept cut (`--cut-draws 1`, by
/// the probabilities A's importance gave its nodes, design §10.10); the
/// partial variant gives the largest node probability 0.
#[test]
fn a_pixel_cut_drawn_over_serves_its_later_samples_unbiasedly_and_a_partial_one_is_caught() {
    check_pixel_cut(1);
}

/// The distribution of draws over the cut (design §10.10) is the walks'
/// weights W_k, each node weighed alone, mixed with the uniform share; not
/// the bounds that chose the cut (which at many of these points give it
/// other probabilities: the test fails if the bounds are used, or if a
/// paired evaluation hands a node its neighbour's weight).
#[test]
fn draws_over_the_cut_follow_the_walks_weights() {
    let settings = CutSettings { error: 0.02, max_cut: 64, ..CutSettings::default() };
    let (mut differ, mut checked) = (0, 0);
    for lights in [OMNI, ORIENTED] {
        with_points(&scene(lights), 16, |_, _, trees, sp| {
            let bounds = PointBounds::new(sp, trees.scale);
            let importance = walk_importance(&bounds);
            let mut scratch = StochasticScratch::default();
            choose_cut(trees, 0..trees.trees.len(), &settings, &bounds, &mut scratch);
            let cut: Vec<Node> = scratch.nodes.iter().filter(|n| n.in_cut).copied().collect();
            if cut.len() < 3 {
                return; // a point no light reaches keeps the roots
            }
            checked += 1;
            let mut cdf = Vec::new();
            cut_distribution(trees, &importance, &cut, &mut cdf);
            let alone: Vec<f64> = cut
                .iter()
                .map(|n| {
                    let [w, _] = importance(&trees.trees[n.tree as usize], [n.block as usize; 2]);
                    f64::from(w[n.slot as usize])
                })
                .collect();
            let (total, n) = (alone.iter().sum::<f64>(), cut.len() as f64);
            let bound_total: f64 = cut.iter().map(|n| f64::from(n.importance)).sum();
            let mut low = 0.0;
            for (k, node) in cut.iter().enumerate() {
                let q = cdf[k] - low;
                low = cdf[k];
                let expected = (1.0 - UNIFORM_SHARE) * alone[k] / total + UNIFORM_SHARE / n;
                assert!((q - expected).abs() <= 1e-9, "node {k}: q {q}, the walks' weight gives {expected}");
                let by_bound = (1.0 - UNIFORM_SHARE) * f64::from(node.importance) / bound_total + UNIFORM_SHARE / n;
                differ += usize::from((by_bound - expected).abs() > 1e-3);
            }
        });
    }
    assert!(checked >= 24, "most points must have cuts to draw over: {checked} of 32");
    assert!(differ > 0, "the bounds must give some node another probability, or the test shows nothing");
}

fn check_pixel_cut(cut_draws: usize) {
    let settings = CutSettings { error: 0.1, max_cut: 8, pixel_cut: true, cut_draws, ..CutSettings::default() };
    let scene = scene(OMNI);
    let lights = Lights::from_scene(&scene);
    let device = Device::try_new().unwrap();
    let geometry = Geometry::try_new(&device, &scene, std::slice::from_ref(&lights)).unwrap();
    let trees = crate::lightcut::build_trees(std::slice::from_ref(&lights), 5);
    let mut pixel = Rng::seeded(11);
    let camera = scene.camera(32, 24);
    let mut pairs = Vec::new();
    while pairs.len() < 400 {
        let (x, y) = (pixel.range_f32(0.0, 31.0), pixel.range_f32(0.0, 23.0));
        let [a, b] = [camera.ray(x, y), camera.ray(x + 1.0, y + 1.0)];
        if let (Some(hit_a), Some(hit_b)) = (geometry.embree.intersect(&a), geometry.embree.intersect(&b)) {
            pairs.push(((a, hit_a), (b, hit_b)));
        }
    }
    let points: Vec<[SurfacePoint<'_>; 2]> =
        pairs.iter().map(|((a, ha), (b, hb))| [geometry.surface(a, ha), geometry.surface(b, hb)]).collect();
    let fits = |[a, b]: &[SurfacePoint<'_>; 2]| {
        SurfaceKey::of(a.material_address(), a).holds_within(b.material_address(), b, PIXEL_CUT_NORMAL_COS)
    };
    let (same, other): (Vec<_>, Vec<_>) = points.iter().partition(|pair| fits(pair));
    assert!(same.len() >= 16 && other.len() >= 4, "pairs on one surface {}, on two {}", same.len(), other.len());
    fn at<'a>(sp: &SurfacePoint<'a>, pixel: u64, index: u32) -> SurfacePoint<'a> {
        SurfacePoint { sample: Some(PixelSample { pixel, index, count: 2 }), ..sp.clone() }
    }
    let cut_of = |scratch: &StochasticScratch| -> Vec<(u32, u8)> {
        scratch.nodes.iter().filter(|n| n.in_cut).map(|n| (n.block, n.slot)).collect()
    };
    let (mut scratch, mut batch) = (StochasticScratch::default(), BatchBuffers::default());
    let embree = &geometry.embree;
    let own_settings = CutSettings { pixel_cut: false, ..settings };
    // On two surfaces: B chooses its own cut.
    for (i, [a, b]) in other.iter().take(8).enumerate() {
        evaluate(&trees, b, embree, &own_settings, &mut Rng::seeded(1), &mut scratch, 0);
        let own = cut_of(&scratch);
        evaluate(&trees, &at(a, mix64(i as u64), 0), embree, &settings, &mut Rng::seeded(1), &mut scratch, 0);
        let first = cut_of(&scratch);
        evaluate(&trees, &at(b, mix64(i as u64), 1), embree, &settings, &mut Rng::seeded(1), &mut scratch, 0);
        assert_eq!(cut_of(&scratch), own, "a point on another surface must choose its own cut");
        // Both cuts kept, each for its surface: a third and a fourth sample,
        // on A's surface and on B's, walk them without choosing a cut.
        let kept = |scratch: &StochasticScratch| (scratch.pixel_cuts.surfaces.len(), scratch.pixel_cuts.nodes.len());
        let after_b = kept(&scratch);
        assert_eq!(after_b.0, 2, "the pixel must keep a cut for each of its two surfaces");
        for (index, point, cut) in [(2, a, first), (3, b, own)] {
            let later = at(point, mix64(i as u64), index);
            evaluate(&trees, &later, embree, &settings, &mut Rng::seeded(1), &mut scratch, 0);
            assert_eq!(kept(&scratch), after_b, "a later sample on a kept surface must not keep another cut");
            if cut_draws == 0 {
                assert_eq!(cut_of(&scratch), cut, "a later sample must walk its surface's kept cut");
            }
        }
    }
    let (mut shared_rows, mut partial_rows, mut other_cuts) = (Vec::new(), Vec::new(), 0);
    for (i, [a, b]) in same.iter().take(16).enumerate() {
        let exact = exact_luminance(&lights, embree, b, &mut batch);
        evaluate(&trees, b, embree, &own_settings, &mut Rng::seeded(1), &mut scratch, 0);
        let own = cut_of(&scratch);
        for partial in [false, true] {
            let values: Vec<f64> = (0..SEEDS)
                .map(|seed| {
                    let mut rng = Rng::from_key(&[seed, i as u64]);
                    let first = evaluate(&trees, &at(a, mix64(seed), 0), embree, &settings, &mut rng, &mut scratch, 0);
                    let kept = cut_of(&scratch);
                    let kept_cut = &mut scratch.pixel_cuts;
                    let largest = (0..kept_cut.nodes.len())
                        .max_by(|&x, &y| kept_cut.nodes[x].importance.total_cmp(&kept_cut.nodes[y].importance))
                        .unwrap();
                    let dropped = u64::from(partial && cut_draws == 0);
                    if partial && cut_draws == 0 {
                        // Drop the kept cut's largest node.
                        kept_cut.nodes.remove(largest);
                        kept_cut.cuts[0].nodes.end -= 1;
                    } else if partial {
                        // Never draw it: its interval of the cdf emptied.
                        kept_cut.cdf[largest] = if largest == 0 { 0.0 } else { kept_cut.cdf[largest - 1] };
                    }
                    let later = evaluate(&trees, &at(b, mix64(seed), 1), embree, &settings, &mut rng, &mut scratch, 0);
                    assert_eq!(later.nodes, first.nodes - dropped, "the later sample must walk the kept cut");
                    if !partial {
                        assert_eq!(cut_of(&scratch), kept, "the later sample must walk the kept cut");
                        other_cuts += usize::from(seed == 0 && kept != own);
                    }
                    luminance64(later.radiance)
                })
                .collect();
            if partial {
                partial_rows.push(row(exact, &values))
            } else {
                shared_rows.push(row(exact, &values))
            }
        }
    }
    eprintln!(
        "kept cut differs from own at {other_cuts} of 16 points; partial caught at {}",
        biased_points(&partial_rows)
    );
    assert!(other_cuts >= 4, "the test needs points whose own cut differs from the kept one: {other_cuts}");
    assert!(shared_rows.iter().filter(|r| r.2 > 0.0).count() >= 8, "most points must be sampled: {shared_rows:?}");
    assert_eq!(biased_points(&shared_rows), 0, "(exact, mean, standard error) per point: {shared_rows:?}");
    assert!(biased_points(&partial_rows) >= 4, "a partial cut must be caught: {partial_rows:?}");
}

/// A sharp glossy lobe turns between a pixel's samples (design §10.9,
/// "The lobe's turn"): with lights drawn over the kept cut, a later sample
/// whose mirror direction turned past `lobe_turn_cos` draws by the kept
/// nodes weighed at its own point (the test fails if it draws by the kept
/// distribution); one within the turn, or on the diffuse floor, by the
/// kept distribution; and the reweighed draws are unbiased.
#[test]
fn a_turned_sharp_lobe_draws_by_its_own_weights_of_the_kept_nodes() {
    let settings = CutSettings { error: 0.05, max_cut: 64, pixel_cut: true, cut_draws: 2, ..CutSettings::default() };
    let scene = SceneText::new(32, 24)
        .camera([0.0, 4.0, 7.0], [0.0, 0.5, 0.0], 55.0)
        .material("floor", [0.7, 0.7, 0.7], "")
        .material("metal", [0.9, 0.9, 0.9], "type = \"pbr\"\nmetallic = 1.0\nroughness = 0.2\n")
        .floor(0.0, 6.0, "floor")
        .sphere([-0.8, 1.0, 0.0], 1.0, "metal")
        .raw(OMNI)
        .load(std::path::Path::new("stochastic.toml"))
        .unwrap();
    let lights = Lights::from_scene(&scene);
    let device = Device::try_new().unwrap();
    let geometry = Geometry::try_new(&device, &scene, std::slice::from_ref(&lights)).unwrap();
    let trees = crate::lightcut::build_trees(std::slice::from_ref(&lights), 5);
    let camera = scene.camera(32, 24);
    let embree = &geometry.embree;
    let (mut scratch, mut batch) = (StochasticScratch::default(), BatchBuffers::default());
    fn at<'a>(sp: &SurfacePoint<'a>, pixel: u64, index: u32) -> SurfacePoint<'a> {
        SurfacePoint { sample: Some(PixelSample { pixel, index, count: 2 }), ..sp.clone() }
    }
    let ids =
        |nodes: &[Node]| -> Vec<(TreeIndex, u32, u8)> { nodes.iter().map(|n| (n.tree, n.block, n.slot)).collect() };
    let (mut turned, mut within, mut diffuse) = (0, 0, 0);
    let mut rows = Vec::new();
    let mut pixel = Rng::seeded(5);
    for i in 0..4000u64 {
        if turned >= 12 && within >= 4 && diffuse >= 8 {
            break;
        }
        let (x, y, shift) = (pixel.range_f32(0.0, 31.0), pixel.range_f32(0.0, 23.0), pixel.range_f32(0.0, 0.4));
        let [ray_a, ray_b] = [camera.ray(x, y), camera.ray(x + shift, y + shift)];
        let (Some(hit_a), Some(hit_b)) = (embree.intersect(&ray_a), embree.intersect(&ray_b)) else { continue };
        let (a, b) = (geometry.surface(&ray_a, &hit_a), geometry.surface(&ray_b, &hit_b));
        if !SurfaceKey::of(a.material_address(), &a).holds_within(b.material_address(), &b, PIXEL_CUT_NORMAL_COS) {
            continue;
        }
        let lobe = b.pbr.is_some();
        let turns = b.r.dot(a.r) < b.lobe_turn_cos(LOBE_TURN_RATIO);
        evaluate(&trees, &at(&a, mix64(i), 0), embree, &settings, &mut Rng::seeded(1), &mut scratch, 0);
        let kept = ids(&scratch.pixel_cuts.nodes[scratch.pixel_cuts.cuts[0].nodes.clone()]);
        if kept.len() < 3 {
            continue; // a point no light reaches keeps the roots
        }
        scratch.cut.clear();
        scratch.cdf.clear();
        evaluate(&trees, &at(&b, mix64(i), 1), embree, &settings, &mut Rng::seeded(1), &mut scratch, 0);
        if turns {
            assert!(lobe, "only a glossy lobe turns");
            turned += 1;
            assert_eq!(ids(&scratch.cut), kept, "the turned sample must draw over the kept nodes");
            let bounds = PointBounds::new(&b, trees.scale);
            let mut own = Vec::new();
            cut_distribution(&trees, &walk_importance(&bounds), &scratch.cut, &mut own);
            assert_eq!(scratch.cdf, own, "the turned sample must weigh the kept nodes at its own point");
            if rows.len() < 8 {
                let exact = exact_luminance(&lights, embree, &b, &mut batch);
                let values: Vec<f64> = (0..SEEDS)
                    .map(|seed| {
                        let mut rng = Rng::from_key(&[seed, i]);
                        evaluate(&trees, &at(&a, mix64(seed), 0), embree, &settings, &mut rng, &mut scratch, 0);
                        let later =
                            evaluate(&trees, &at(&b, mix64(seed), 1), embree, &settings, &mut rng, &mut scratch, 0);
                        luminance64(later.radiance)
                    })
                    .collect();
                rows.push(row(exact, &values));
            }
        } else {
            assert!(scratch.cdf.is_empty(), "a sample within the turn must draw by the kept distribution");
            if lobe {
                within += 1;
            } else {
                diffuse += 1;
            }
        }
    }
    eprintln!("turned {turned}, within the turn {within}, diffuse {diffuse}; (exact, mean, se): {rows:?}");
    assert!(turned >= 12 && within >= 4 && diffuse >= 8, "turned {turned}, within {within}, diffuse {diffuse}");
    assert!(rows.iter().filter(|r| r.0 > 0.0 && r.2 > 0.0).count() >= 4, "most points must be lit: {rows:?}");
    assert_eq!(biased_points(&rows), 0, "(exact, mean, standard error) per point: {rows:?}");
}
