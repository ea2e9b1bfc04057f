//! The cut against the exact sum at real shading points of a real scene.
use super::*;
use crate::embree::Device;
use crate::light::Lights;
use crate::lightcut::EXHAUSTIVE_LIGHTS;
use crate::scene::builder::SceneText;
use crate::scene::Scene;
use crate::shading::Geometry;
use crate::shading::LightBatch;
use crate::util::sampling::Rng;

/// A floor, two occluding spheres (one glossy) and `n x n` lights of mixed
/// brightness over them; returns the scene loaded from text.
pub(crate) fn scene(n: u32) -> Scene {
    scene_with(n, "")
}

/// [`scene`] with more `lights` (TOML `[[lights]]` entries).
fn scene_with(n: u32, lights: &str) -> Scene {
    SceneText::new(64, 48)
        .camera([0.0, 4.0, 7.0], [0.0, 0.5, 0.0], 50.0)
        .material("floor", [0.7, 0.7, 0.7], "")
        .material("glossy", [0.5, 0.3, 0.2], "specular = [0.4, 0.4, 0.4]\nexponent = 60\n")
        .floor(0.0, 6.0, "floor")
        .sphere([-1.0, 1.0, 0.0], 1.0, "glossy")
        .sphere([1.5, 0.6, 1.0], 0.6, "floor")
        .grid([-3.0, 3.0, -3.0], [6.0, 0.0, 0.0], [0.0, 0.0, 6.0], [n, n], [0.05, 0.05, 0.05])
        .grid([-4.0, 1.5, -4.0], [8.0, 0.0, 0.0], [0.0, 0.0, 8.0], [n, 2], [0.2, 0.1, 0.05])
        .raw(lights)
        .load(std::path::Path::new("test.toml"))
        .unwrap()
}

/// Runs `check(cut, exact, error_bound)` at shading points seen through
/// random pixels.
fn at_shading_points(scene: &Scene, settings: CutSettings, mut check: impl FnMut(DVec3, DVec3, f64)) {
    at_shading_points_with(scene, settings, |cut, exact, _, _| check(cut.radiance, exact, cut.error_bound));
}

/// [`at_shading_points`], `check` also given the cut's scratch (its
/// entries) and the trees' scale.
fn at_shading_points_with(
    scene: &Scene,
    settings: CutSettings,
    mut check: impl FnMut(&CutResult, DVec3, &CutScratch, f32),
) {
    let device = Device::try_new().unwrap();
    let lights = Lights::from_scene(scene);
    let geometry = Geometry::try_new(&device, scene, std::slice::from_ref(&lights)).unwrap();
    let trees = crate::lightcut::build_trees(std::slice::from_ref(&lights), 3);
    assert!(trees.trees.iter().any(|t| t.light_count() > EXHAUSTIVE_LIGHTS), "the test must exercise the cut");
    let camera = scene.camera(64, 48);
    let mut rng = Rng::seeded(5);
    let (mut scratch, mut batch) = (CutScratch::default(), BatchBuffers::default());
    let mut points = 0;
    while points < 400 {
        let ray = camera.ray(rng.range_f32(0.0, 64.0), rng.range_f32(0.0, 48.0));
        let Some(hit) = geometry.embree.intersect(&ray) else { continue };
        let sp = geometry.surface(&ray, &hit);
        let cut = evaluate(&trees, &sp, &geometry.embree, &settings, &mut scratch, 0);
        let mut exact = LightBatch::new(&geometry.embree, &sp, &mut batch);
        lights.for_each(|light| exact.add(&light));
        check(&cut, exact.finish().radiance, &scratch, trees.scale);
        points += 1;
    }
}

/// At 2%, the error of the cut at every test point of `scene` is within
/// the sum of its bounds, and somewhere the cut does approximate.
fn check_error_within_bounds(scene: &Scene) {
    let settings = CutSettings { error: 0.02, max_cut: 1000, ..CutSettings::default() };
    let mut worst = 0.0f64;
    at_shading_points(scene, settings, |cut, exact, bound| {
        let error = (luminance64(cut) - luminance64(exact)).abs();
        // 1e-9 relative: f64 summation order differs between the two.
        assert!(error <= bound + 1e-9 * luminance64(exact), "error {error} > bound sum {bound}");
        worst = worst.max(error / luminance64(exact).max(1e-12));
    });
    assert!(worst > 0.0, "at 2% the cut must actually approximate somewhere");
}

#[test]
fn the_error_of_every_cut_is_within_the_sum_of_its_bounds() {
    check_error_within_bounds(&scene(24));
}

#[test]
fn error_zero_refines_to_the_exact_sum_at_every_point() {
    let scene = scene(24);
    let settings = CutSettings { error: 0.0, max_cut: usize::MAX, ..CutSettings::default() };
    at_shading_points(&scene, settings, |cut, exact, bound| {
        assert_eq!(bound, 0.0, "error 0 refines every cluster with a non-zero bound");
        let diff = (cut - exact).abs().max_element();
        assert!(diff <= 1e-9 * exact.max_element().max(1e-300), "error 0: {cut} vs {exact}");
    });
}

/// 20 x 20 spots over the scene, tilted and of widths from 10 to 88 degrees.
fn spots() -> String {
    let mut rng = Rng::seeded(17);
    let mut text = String::new();
    for j in 0..20 {
        for i in 0..20 {
            let (x, z) = (-4.0 + 0.4 * i as f32, -4.0 + 0.4 * j as f32);
            let outer = rng.range_f32(10.0, 88.0);
            let inner = outer * rng.range_f32(0.0, 0.9);
            let (dx, dz) = (rng.range_f32(-0.8, 0.8), rng.range_f32(-0.8, 0.8));
            text += &format!(
                "[[lights]]\ntype = \"spot\"\nposition = [{x}, {}, {z}]\ndirection = [{dx}, -1, {dz}]\n\
                 intensity = [0.3, 0.25, 0.2]\ninner_angle = {inner}\nouter_angle = {outer}\n",
                rng.range_f32(1.5, 3.5)
            );
        }
    }
    text
}

/// The same check through trees of spots: the widest outer angle of a node
/// (`SpotBlock::min_cos_outer`) must cover every light below it.
#[test]
fn spot_cuts_are_within_the_sum_of_their_bounds() {
    check_error_within_bounds(&scene_with(4, &spots()));
}

/// Lightcuts' stopping rule holds at the end of every cut that stayed under
/// `max_cut`: no node of the cut has a bound above error x the cut's total.
/// Nodes whose bounds were under the threshold when they joined wait
/// outside the heap (`Cut::admit`); when the total falls they must join it
/// again, which this checks.
#[test]
fn no_node_of_a_finished_cut_has_a_bound_above_the_threshold() {
    let scene = scene(24);
    let settings = CutSettings { error: 0.02, max_cut: 100_000, ..CutSettings::default() };
    let mut refined = 0;
    at_shading_points_with(&scene, settings, |cut, _, scratch, scale| {
        let threshold = settings.error * luminance64(cut.radiance).max(0.0) * f64::from(scale);
        for entry in scratch.entries.iter().filter(|e| e.in_cut) {
            let bound = f64::from(entry.bound);
            assert!(
                bound <= threshold * (1.0 + 1e-6),
                "a node of bound {bound} left in a cut whose threshold is {threshold}"
            );
        }
        refined += usize::from(scratch.entries.iter().any(|e| !e.in_cut));
    });
    assert!(refined > 100, "the cuts must refine");
}
