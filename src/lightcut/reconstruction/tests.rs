//! Reconstructed cuts against the exact sum at real shading points of a
//! real scene, their anchors cut at neighbouring camera hits.
use super::*;
use crate::embree::Device;
use crate::light::Lights;
use crate::lightcut::cut::{evaluate_anchor, CutScratch};
use crate::lightcut::EXHAUSTIVE_LIGHTS;
use crate::shading::{Geometry, LightBatch};
use crate::util::color::luminance64;
use crate::util::sampling::Rng;

/// What the checks see at one camera hit.
struct Found {
    reconstructed: CutResult,
    bounded: CutResult,
    exact: DVec3,
}

/// At camera hits through random film points, `check` gets the cut
/// reconstructed from anchors cut at the four film points `spread` pixels
/// around it (those that hit something), the bounded cut and the exact sum.
fn at_camera_hits(settings: CutSettings, spread: f32, mut check: impl FnMut(&Found)) {
    // A floor, two occluding spheres (one glossy) and two grids of lights
    // of mixed brightness over them, whose shadows cross the floor.
    let scene = crate::lightcut::cut::tests::scene(20);
    let device = Device::try_new().unwrap();
    let lights = Lights::from_scene(&scene);
    let geometry = Geometry::try_new(&device, &scene, std::slice::from_ref(&lights)).unwrap();
    let trees = crate::lightcut::build_trees(std::slice::from_ref(&lights), 3);
    assert!(trees.trees.iter().any(|t| t.light_count() > EXHAUSTIVE_LIGHTS), "the test must exercise the cut");
    let camera = scene.camera(64, 48);
    let embree = &geometry.embree;
    let mut rng = Rng::seeded(11);
    let (mut cut, mut scratch, mut batch) =
        (CutScratch::default(), ReconstructionScratch::default(), BatchBuffers::default());
    let mut points = 0;
    while points < 300 {
        let (x, y) = (rng.range_f32(2.0, 62.0), rng.range_f32(2.0, 46.0));
        let Some(hit) = embree.intersect(&camera.ray(x, y)) else { continue };
        let sp = geometry.surface(&camera.ray(x, y), &hit);
        let corners = [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)];
        let anchors: Option<Vec<AnchorCut>> = corners
            .iter()
            .map(|(dx, dy)| {
                let ray = camera.ray(x + dx * spread, y + dy * spread);
                let hit = embree.intersect(&ray)?;
                let at = geometry.surface(&ray, &hit);
                let mut anchor = AnchorCut::default();
                evaluate_anchor(&trees, &at, embree, &settings, &mut cut, 0, &mut anchor);
                Some(anchor)
            })
            .collect();
        let Some(anchors) = anchors else { continue };
        let block = AnchorBlock::merge(std::array::from_fn(|a| &anchors[a]));
        let reconstructed = evaluate(&trees, &sp, embree, &settings, &block, &mut scratch, 0);
        let bounded = crate::lightcut::evaluate(&trees, &sp, embree, &settings, &mut cut, 0);
        let mut exact = LightBatch::new(embree, &sp, &mut batch);
        lights.for_each(|light| exact.add(&light));
        check(&Found { reconstructed, bounded, exact: exact.finish().radiance });
        points += 1;
    }
}

/// Whatever visibility the anchors lend a node, its estimate and its exact
/// sum lie between 0 and its bound: the point's error stays within the sum
/// of its cut's bounds. Where the anchors agree no ray is traced, so the
/// cut traces far fewer rays than the bounded cut at the same point.
#[test]
fn a_reconstructed_cut_stays_within_its_bounds_and_traces_fewer_rays() {
    let settings = CutSettings { error: 0.02, max_cut: 1000, ..CutSettings::default() };
    let (mut rays, mut bounded_rays, mut nodes, mut worst) = (0, 0, 0, 0.0f64);
    let (mut traced_somewhere, mut skipped_somewhere) = (false, false);
    at_camera_hits(settings, 1.0, |found| {
        let (cut, exact) = (&found.reconstructed, luminance64(found.exact));
        let error = (luminance64(cut.radiance) - exact).abs();
        assert!(error <= cut.error_bound + 1e-9 * exact, "error {error} > bound sum {}", cut.error_bound);
        assert!(cut.radiance.is_finite());
        worst = worst.max(error / exact.max(1e-12));
        rays += cut.shadow_rays;
        bounded_rays += found.bounded.shadow_rays;
        nodes += cut.nodes;
        traced_somewhere |= cut.shadow_rays > 0;
        skipped_somewhere |= cut.shadow_rays < cut.nodes;
    });
    assert!(traced_somewhere && skipped_somewhere, "both rules must be exercised");
    assert!(worst > 0.0, "at 2% the cut must approximate somewhere");
    assert!(3 * rays < bounded_rays, "{rays} rays against the bounded cut's {bounded_rays} ({nodes} nodes)");
}

/// Anchors far from the point (a quarter of the image away) agree on
/// things the point does not see alike: the bound still holds.
#[test]
fn anchors_that_see_another_scene_still_leave_the_error_within_the_bounds() {
    let settings = CutSettings { error: 0.02, max_cut: 1000, ..CutSettings::default() };
    at_camera_hits(settings, 12.0, |found| {
        let (cut, exact) = (&found.reconstructed, luminance64(found.exact));
        let error = (luminance64(cut.radiance) - exact).abs();
        assert!(error <= cut.error_bound + 1e-9 * exact, "error {error} > bound sum {}", cut.error_bound);
    });
}

/// At `error` 0 nothing is assumed seen: the reconstructed cut is the exact
/// sum, every light traced.
#[test]
fn at_error_zero_a_reconstructed_cut_is_the_exact_sum() {
    let settings = CutSettings { error: 0.0, max_cut: 100_000, ..CutSettings::default() };
    at_camera_hits(settings, 1.0, |found| {
        let (cut, exact) = (found.reconstructed.radiance, found.exact);
        for (a, b) in cut.to_array().into_iter().zip(exact.to_array()) {
            assert!((a - b).abs() <= 1e-9 * b.abs().max(1e-30), "{cut} vs {exact}");
        }
        assert_eq!(found.reconstructed.error_bound, 0.0);
    });
}

/// The anchors' views merge a nibble per anchor: agreement needs all four,
/// and a node an anchor did not make takes its parent's visibility.
#[test]
fn views_agree_only_when_all_four_anchors_do() {
    let node = |visibility, refined| AnchorNode { visibility, refined };
    let mut cuts: [AnchorCut; ANCHORS] = Default::default();
    let (parent, child) = (Child::internal(3, false), Child::leaf(7));
    for (a, cut) in cuts.iter_mut().enumerate() {
        let refined = a < 2;
        cut.insert(0, parent, node(Visibility::Occluded, refined));
        if refined {
            cut.insert(0, child, node(Visibility::Occluded, false));
        }
    }
    let block = AnchorBlock::merge(std::array::from_fn(|a| &cuts[a]));
    let views = block.views(0, parent, 0x8888);
    assert_eq!(agreement(views), (Visibility::Occluded, true));
    // Anchors 2 and 3 did not make the child: they lend the parent's view.
    assert_eq!(agreement(block.views(0, child, views)), (Visibility::Occluded, false));
    cuts[3].insert(0, child, node(Visibility::Visible, false));
    let block = AnchorBlock::merge(std::array::from_fn(|a| &cuts[a]));
    assert_eq!(agreement(block.views(0, child, views)), (Visibility::Mixed, false));
    // An unknown parent (a root no anchor made) is a disagreement.
    assert_eq!(agreement(block.views(1, child, 0x8888)).0, Visibility::Mixed);
}
