//! Reuse between pixels is unbiased: at 16 fixed camera hits, taken as four
//! blocks of four, the mean over 1,024 seeds of each hit's estimate from
//! its block's draws equals its exact sum within 4 standard errors; MIS
//! weights that give every hit of the block the same share (1/4, which sums
//! to 1 only for lights every hit can draw) fail the same test, and so do
//! weights summed over all four hits where only the hits on a hit's
//! surface light it (tried by hand).
use super::*;
use crate::embree::Device;
use crate::light::Lights;
use crate::lightcut::stochastic::tests as stochastic_tests;
use crate::lightcut::stochastic::tests::biased_points;
use crate::lightcut::stochastic::{draw_lights, StochasticScratch, STOCHASTIC_DEFAULTS};
use crate::lightcut::CutSettings;
use crate::shading::{BatchBuffers, Geometry, SurfacePoint};
use crate::util::sampling::{mix64, Rng};

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
/// its block's draws, MIS-weighted by `weight`; the block's hits drawing
/// with the renderer's stratified [`block_sample`]s when `stratified`,
/// else each with numbers of its own. The hits are those of random pixels
/// of a 32 x 24 film (blocks spread over surfaces of every orientation), or
/// with `neighbours` of 2 x 2 pixel blocks at random corners of a 160 x 120
/// film (blocks as rendered). Each hit is lit by the hits on its surface
/// ([`same_surfaces`], as rendered), or with `every_hit` by all four.
fn estimates(
    weight: impl Fn(usize, &[f64]) -> f64 + Copy,
    stratified: bool,
    neighbours: bool,
    every_hit: bool,
) -> Vec<(f64, f64, f64)> {
    let scene = scene();
    let lights = Lights::from_scene(&scene);
    let device = Device::try_new().unwrap();
    let geometry = Geometry::try_new(&device, &scene, std::slice::from_ref(&lights)).unwrap();
    let trees = crate::lightcut::build_trees(std::slice::from_ref(&lights), 5);
    // A small cut, so that most of the estimate is sampled.
    let settings = CutSettings { error: 0.1, max_cut: 8, pixel_cut: false, ..STOCHASTIC_DEFAULTS };
    let (width, height) = if neighbours { (160, 120) } else { (32, 24) };
    let camera = scene.camera(width, height);
    let mut pixel = Rng::seeded(11);
    let mut points: Vec<SurfacePoint<'_>> = Vec::new();
    while points.len() < 4 * BLOCK {
        let (x, y) = (pixel.range_f32(0.0, width as f32 - 1.0), pixel.range_f32(0.0, height as f32 - 1.0));
        let pixels = if neighbours {
            let (x, y) = (x.floor() + 0.5, y.floor() + 0.5);
            vec![(x, y), (x + 1.0, y), (x, y + 1.0), (x + 1.0, y + 1.0)]
        } else {
            vec![(x, y)]
        };
        let rays: Vec<_> = pixels.iter().map(|&(x, y)| camera.ray(x, y)).collect();
        let hits: Vec<_> = rays.iter().filter_map(|ray| geometry.embree.intersect(ray).map(|hit| (ray, hit))).collect();
        if hits.len() == pixels.len() {
            points.extend(hits.iter().map(|(ray, hit)| geometry.surface(ray, hit)));
        }
    }
    let (mut cut, mut reuse, mut batch) =
        (StochasticScratch::default(), ReuseScratch::default(), BatchBuffers::default());
    let mut drawn: Vec<Choices> = (0..BLOCK).map(|_| Choices::default()).collect();
    let mut rows = Vec::new();
    for block in points.chunks(BLOCK) {
        let evaluators: Vec<_> = block.iter().map(|sp| Some(LightEvaluator::new(sp))).collect();
        let same = if every_hit {
            vec![true; BLOCK * BLOCK]
        } else {
            same_surfaces(&block.iter().map(Some).collect::<Vec<_>>())
        };
        let mut sums = vec![Vec::new(); BLOCK];
        for seed in 0..SEEDS {
            let mut results = vec![CutResult::default(); BLOCK];
            let block_key = mix64(seed ^ mix64(rows.len() as u64));
            for (k, sp) in block.iter().enumerate() {
                let mut rng = Rng::from_key(&[seed, rows.len() as u64, k as u64]);
                let mut sp = sp.clone();
                sp.sample = stratified.then(|| block_sample(block_key, BLOCK, k, 0, 1));
                results[k] =
                    draw_lights(&trees, &sp, &geometry.embree, &settings, &mut rng, &mut cut, 0, &mut drawn[k]);
            }
            estimate_with(&evaluators, &same, &drawn, &geometry.embree, &mut results, &mut reuse, weight);
            for (sum, result) in sums.iter_mut().zip(&results) {
                sum.push(luminance64(result.radiance));
            }
        }
        for (sp, values) in block.iter().zip(sums) {
            let exact = stochastic_tests::exact_luminance(&lights, &geometry.embree, sp, &mut batch);
            rows.push(stochastic_tests::row(exact, &values));
        }
    }
    rows
}

/// Reuse is unbiased with the block's stratified numbers (as rendered)
/// and with every hit's own, for blocks spread over the scene and for
/// blocks of neighbouring pixels; and the stratified numbers have the
/// smaller variance (summed over the hits, relative to each hit's exact
/// sum; every hit put in one stratum, tried by hand, has the larger).
#[test]
fn reuse_between_hits_is_unbiased_and_stratified_draws_lower_its_variance() {
    let relative_variance =
        |rows: &[(f64, f64, f64)]| rows.iter().filter(|r| r.0 > 0.0).map(|(e, _, se)| (se / e).powi(2)).sum::<f64>();
    let mut variances = Vec::new();
    for neighbours in [false, true] {
        for stratified in [true, false] {
            let rows = estimates(balance, stratified, neighbours, false);
            assert!(rows.iter().filter(|r| r.2 > 0.0).count() >= 8, "most points must be sampled: {rows:?}");
            let said =
                format!("neighbours {neighbours}, stratified {stratified}: (exact, mean, standard error) {rows:?}");
            assert_eq!(biased_points(&rows), 0, "{said}");
            variances.push(relative_variance(&rows));
        }
    }
    eprintln!("summed relative variance, stratified against own numbers: {variances:?}");
    for (layout, pair) in ["spread", "neighbours"].iter().zip(variances.chunks(2)) {
        assert!(pair[0] < pair[1], "{layout}: stratified {}, own numbers {}", pair[0], pair[1]);
    }
}

#[test]
fn equal_shares_for_every_hit_are_caught() {
    let rows = estimates(|_, luminances| 1.0 / luminances.len() as f64, true, false, false);
    assert!(biased_points(&rows) > 0, "(exact, mean, standard error) per point: {rows:?}");
}

/// Every hit lit by all four hits' draws (the weights over all four) is
/// unbiased too; hits on other surfaces left out (as rendered) has the
/// smaller variance on blocks spread over surfaces of every orientation.
#[test]
fn hits_on_other_surfaces_left_out() {
    let relative_variance =
        |rows: &[(f64, f64, f64)]| rows.iter().filter(|r| r.0 > 0.0).map(|(e, _, se)| (se / e).powi(2)).sum::<f64>();
    let every = estimates(balance, true, false, true);
    assert_eq!(biased_points(&every), 0, "(exact, mean, standard error) per point: {every:?}");
    let own = estimates(balance, true, false, false);
    assert_eq!(biased_points(&own), 0, "(exact, mean, standard error) per point: {own:?}");
    let (every, own) = (relative_variance(&every), relative_variance(&own));
    assert!(own < every, "summed relative variance: every hit {every}, same surface {own}");
}

/// `estimate` evaluates the block's draws packed into full quads, lanes
/// moved from one hit's quads to another's: every light keeps the value
/// and slot it has in its own hit's quads, bit for bit, under point and
/// oriented lights mixed (a new quad wherever the kind changes).
#[test]
fn packed_draws_keep_every_value() {
    let scene = stochastic_tests::scene(&format!("{}{}", stochastic_tests::OMNI, stochastic_tests::ORIENTED));
    let settings = CutSettings { error: 0.3, max_cut: 6, pixel_cut: false, ..STOCHASTIC_DEFAULTS };
    let (mut moved, mut kinds_mixed) = (0, 0);
    let mut seed = 0;
    stochastic_tests::with_points(&scene, 16, |_, geometry, trees, sp| {
        let mut cut = StochasticScratch::default();
        let mut drawn: Vec<Choices> = (0..BLOCK).map(|_| Choices::default()).collect();
        for lights in &mut drawn {
            seed += 1;
            draw_lights(trees, sp, &geometry.embree, &settings, &mut Rng::seeded(seed), &mut cut, 0, lights);
        }
        let evaluator = LightEvaluator::new(sp);
        let (mut own, mut packed, mut block) = (Evaluations::default(), Evaluations::default(), Choices::default());
        for lights in &drawn {
            evaluate_into(&evaluator, lights, &mut own);
            block.append_packed(lights);
        }
        evaluate_into(&evaluator, &block, &mut packed);
        let own_slots: Vec<u32> = drawn.iter().flat_map(Choices::slots).collect();
        assert_eq!(block.slots().collect::<Vec<_>>(), own_slots);
        let bits = |e: &Evaluations| e.values().iter().map(|v| v.to_array().map(f64::to_bits)).collect::<Vec<_>>();
        assert_eq!(bits(&packed), bits(&own));
        assert_eq!(packed.traced().count(), own.traced().count(), "the same shadow rays");
        moved += usize::from(drawn.iter().any(|lights| lights.len() % 4 != 0) && block.len() > 4);
        let kinds: Vec<_> = drawn.iter().flat_map(Choices::kinds).collect();
        assert_eq!(block.kinds().collect::<Vec<_>>(), kinds);
        kinds_mixed += usize::from(kinds.iter().any(|&kind| kind != kinds[0]));
    });
    assert!(moved >= 8, "most points must move lanes between quads: {moved} of 16");
    assert!(kinds_mixed >= 4, "some points must draw lights of both kinds: {kinds_mixed} of 16");
}
