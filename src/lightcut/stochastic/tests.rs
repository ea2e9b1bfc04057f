//! The stochastic cut is unbiased: at fixed shading points, the mean over
//! 1,024 seeds of its estimate equals the exact sum within 4 standard errors
//! (estimated from the same samples), for each light kind; a deliberately
//! biased variant (one child of some nodes never taken) fails the same test.
use super::*;
use crate::embree::Device;
use crate::light::Lights;
use crate::scene::Scene;
use crate::shading::{Geometry, LightBatch};
use crate::util::color::luminance64;

// 256 seeds were too few for the spots: near a cone's edge the falloff
// makes the estimate heavy-tailed and its standard error underestimated
// (a point 7.6 standard errors off at 256 passed at 8,192).
const SEEDS: u64 = 1024;

/// A floor, an occluding sphere and a box, and `lights`.
fn scene(lights: &str) -> Scene {
    let text = format!(
        r#"
[film]
width = 32
height = 24
[camera]
eye = [0, 4, 7]
look_at = [0, 0.5, 0]
fov_y = 55
[materials.floor]
albedo = [0.7, 0.7, 0.7]
[materials.glossy]
albedo = [0.4, 0.3, 0.2]
specular = [0.3, 0.3, 0.3]
exponent = 30
[[shapes]]
type = "quad"
corner = [-6, 0, 6]
u = [12, 0, 0]
v = [0, 0, -12]
material = "floor"
[[shapes]]
type = "sphere"
center = [-0.8, 1, 0]
radius = 1
material = "glossy"
[[shapes]]
type = "box"
min = [1, 0, -1]
max = [2, 1.5, 0]
material = "floor"
{lights}
"#
    );
    Scene::from_spec(std::path::Path::new("stochastic.toml"), toml::from_str(&text).unwrap()).unwrap()
}

const OMNI: &str = r#"
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

const ORIENTED: &str = r#"
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

const DIRECTIONAL: &str = r#"
[[lights]]
type = "sun"
direction = [0.5, 1, 0.3]
irradiance = [3, 3, 2.5]
angular_radius = 8
samples = 300
[environment]
radiance = [0.3, 0.4, 0.6]
samples = 256
"#;

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

/// For each of 16 shading points seen through fixed pixels: the exact sum's
/// luminance, and the mean and standard error of the stochastic estimate's
/// luminance over `SEEDS` seeds. `biased`: child 1 of every third block
/// gets probability 0 (the lights below it are never drawn).
fn estimates(scene: &Scene, biased: bool) -> Vec<(f64, f64, f64)> {
    let lights = Lights::from_scene(scene);
    let device = Device::try_new().unwrap();
    let geometry = Geometry::try_new(&device, scene, std::slice::from_ref(&lights)).unwrap();
    let trees = LightTrees::build(&lights, 5);
    assert!(trees.trees.iter().all(|t| !t.blocks.is_empty()), "every tree must be big enough for a cut");
    let camera = scene.camera(32, 24);
    // A small cut, so that most of the estimate is sampled.
    let settings = CutSettings { error: 0.1, max_cut: 8, ..CutSettings::default() };
    let (mut scratch, mut batch) = (StochasticScratch::default(), BatchBuffers::default());
    let mut rows = Vec::new();
    let mut pixel = Rng::seeded(11);
    while rows.len() < 16 {
        let ray = camera.ray(pixel.range_f32(0.0, 32.0), pixel.range_f32(0.0, 24.0));
        let Some(hit) = geometry.embree.intersect(&ray) else { continue };
        let sp = geometry.surface(&ray, &hit);
        let mut exact = LightBatch::new(&geometry.embree, &sp, &mut batch);
        lights.for_each(|light| exact.add(&light));
        let exact = luminance64(exact.finish().radiance);
        let bounds = PointBounds::new(&sp, trees.scale);
        let production = |tree: &CutTree, blocks: [usize; 2]| {
            blocks.map(|b| bounds.importance(tree.kind, &tree.blocks[b], tree.cones_of(b)))
        };
        let wrong = |tree: &CutTree, blocks: [usize; 2]| {
            let weights = production(tree, blocks);
            [0, 1].map(|i| {
                let [w0, w1] = weights[i];
                [w0, if blocks[i] % 3 == 0 && w0 > 0.0 { 0.0 } else { w1 }]
            })
        };
        let importance: Importance<'_> = if biased { &wrong } else { &production };
        let values: Vec<f64> = (0..SEEDS)
            .map(|seed| {
                let mut rng = Rng::from_key(&[seed, rows.len() as u64]);
                let found = evaluate_with(
                    &trees,
                    &sp,
                    &geometry.embree,
                    &settings,
                    &mut rng,
                    &mut scratch,
                    &bounds,
                    importance,
                    &mut [],
                );
                luminance64(found.radiance)
            })
            .collect();
        let mean = values.iter().sum::<f64>() / SEEDS as f64;
        let variance = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (SEEDS - 1) as f64;
        rows.push((exact, mean, (variance / SEEDS as f64).sqrt()));
    }
    rows
}

/// Points whose mean is more than 4 standard errors from the exact sum.
fn biased_points(rows: &[(f64, f64, f64)]) -> usize {
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
    check_unbiased(DIRECTIONAL);
}

#[test]
fn a_variant_that_never_takes_some_children_is_caught() {
    for lights in [OMNI, ORIENTED, DIRECTIONAL, &spots()] {
        let rows = estimates(&scene(lights), true);
        assert!(biased_points(&rows) >= 8, "the bias must show at most points: {rows:?}");
    }
}
