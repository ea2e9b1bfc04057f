//! Numerical extremes: every render finishes, every channel of every pixel is
//! finite, and where the answer is known it is asserted (a diffuse sphere
//! seen from inside, lit from its centre or by uniform shells of lights:
//! L = k_d / pi * sum(I) / R^2 everywhere), else each cut mode is held to
//! the exact render. Every render mode: exact, bounded, stochastic and
//! multidimensional.

mod common;
use common::*;

const MODES: [&[&str]; 4] = [&["--exact"], &["--bounded"], &["--stochastic"], &["--multidimensional"]];

/// How far each mode may be from a known answer, relative, per pixel: the
/// exact render up to the sphere's tessellation; the bounded and
/// stochastic cuts up to their error (measured: within 0.5% on these
/// scenes); the multidimensional cut, whose threshold is relative to a
/// pixel's total over all its gather points, up to its own (measured: 2.4%
/// at worst, on the shell of 1e27 W/sr lights; the same at 1 W/sr).
fn tolerance(mode: &[&str]) -> f64 {
    match mode {
        ["--exact"] => 1e-3,
        ["--multidimensional"] => 0.04,
        _ => 0.02,
    }
}

/// A floor and a sphere at `scale`, lights given as TOML.
fn scene(scale: f64, lights: &str) -> String {
    scene_seen_from([0.0, 3.0, 6.0], scale, lights)
}

/// [`scene`] with the eye at `eye` (before scaling).
fn scene_seen_from(eye: [f64; 3], scale: f64, lights: &str) -> String {
    let s = |v: [f64; 3]| v.map(|x| x * scale);
    SceneText::new(40, 30)
        .camera(s(eye), s([0.0, 0.5, 0.0]), 50.0)
        .material("floor", [0.7, 0.7, 0.7], "specular = [0.2, 0.2, 0.2]\nexponent = 20\n")
        .floor(0.0, 5.0 * scale, "floor")
        .sphere(s([0.0, 0.8, 0.0]), 0.8 * scale, "floor")
        .raw(lights)
        .toml()
}

fn grid(scale: f64, n: u32, intensity: f64) -> String {
    format!(
        "[[lights]]\ntype = \"grid\"\ncorner = [{}, {}, {}]\nu = [{}, 0, 0]\nv = [0, 0, {}]\ncount = [{n}, {n}]\nintensity = [{intensity:e}, {intensity:e}, {intensity:e}]\n",
        -2.0 * scale,
        3.0 * scale,
        -2.0 * scale,
        4.0 * scale,
        4.0 * scale
    )
}

fn render_text(dir: &TempDir, name: &str, text: &str, extra: &[&str]) -> ExrImage {
    render_at(dir, name, text, extra).1
}

/// Renders `text` with `extra` flags; the output's path and image, every
/// value of which is checked finite (and counted so by the summary).
fn render_at(dir: &TempDir, name: &str, text: &str, extra: &[&str]) -> (std::path::PathBuf, ExrImage) {
    let scene = dir.write(&format!("{name}.toml"), text);
    let out = dir.path(&format!("{name}.exr"));
    let image = common::render(&scene, &out, extra);
    (out, image)
}

#[test]
fn intensities_from_1e_minus_30_to_1e30_in_one_scene() {
    let dir = TempDir::new("extreme-intensities");
    // Two uniform shells inside the sphere, of 1e-30 and 1e27 W/sr a light
    // (1e-27 and 1e30 in all), alone and together: each has the known answer.
    let tiny = shell_lights(1000, 0.4, [1e-27; 3]);
    let huge = shell_lights(1000, 0.9, [1e30, 2e30, 3e30]);
    for (name, lights, total) in [
        ("tiny", tiny.clone(), [1e-27; 3]),
        ("huge", huge.clone(), [1e30, 2e30, 3e30]),
        ("mixed", format!("{tiny}{huge}"), [1e30 + 1e-27, 2e30 + 1e-27, 3e30 + 1e-27]),
    ] {
        for mode in MODES {
            let (path, image) = render_at(&dir, name, &inside_sphere_with(16, 12, &lights), mode);
            assert_inside_sphere_is(&path, &image, inside_sphere_answer(total), tolerance(mode));
        }
    }
}

#[test]
fn a_hundred_thousand_lights_at_one_point() {
    let dir = TempDir::new("one-point");
    let lights = "[[lights]]\ntype = \"grid\"\ncorner = [0.5, 2, 0.5]\nu = [0, 0, 0]\nv = [0, 0, 0]\ncount = [400, 250]\nintensity = [1e-5, 1e-5, 1e-5]\n[[lights]]\ntype = \"point\"\nposition = [0.5, 2, 0.5]\nintensity = [0, 0, 0]\n";
    // Exact on a small window (100,000 shadow rays per pixel).
    let ex = render_text(&dir, "ex", &scene(1.0, lights), &["--exact", "--pixel-bounds", "18,22,20,24"]);
    // Both cut modes: the coincident cluster is exact (its representative
    // stands for all, drawn with probability 1), so the cut stays tiny and
    // the pixels are the exact ones.
    for mode in ["--bounded", "--stochastic", "--multidimensional"] {
        let lc = render_text(&dir, "lc", &scene(1.0, lights), &[mode]);
        assert!(lc.channels["lightcuts.cut_size"].iter().all(|&c| c <= 2.0), "{mode}");
        let lcl = luminance(&lc);
        for (i, l) in luminance(&ex).iter().enumerate() {
            let (x, y) = (18 + i % 4, 20 + i / 4);
            let a = lcl[y * 40 + x];
            assert!((a - l).abs() <= 1e-4 * l.max(1e-12), "{mode} ({x}, {y}): {a} vs {l}");
        }
    }
}

#[test]
fn a_light_on_a_surface_and_shading_points_at_a_light() {
    let dir = TempDir::new("on-surface");
    // One light exactly on the floor, one exactly on the sphere's top
    // vertex, and a grid for the cut: each cut mode is held to the exact
    // render (no closed form: the singular lights' clamp decides).
    let lights = format!(
        "{}[[lights]]\ntype = \"point\"\nposition = [0, 0, 2]\nintensity = [5, 5, 5]\n[[lights]]\ntype = \"point\"\nposition = [0, 1.6, 0]\nintensity = [5, 5, 5]\n",
        grid(1.0, 16, 0.01)
    );
    let exact = render_text(&dir, "exact", &scene(1.0, &lights), &["--exact"]);
    assert!(luminance(&exact).iter().any(|&l| l > 0.0));
    for (mode, within) in [("--bounded", 0.02), ("--stochastic", 0.1), ("--multidimensional", 0.02)] {
        let image = render_text(&dir, "on", &scene(1.0, &lights), &[mode]);
        let error = mean_relative_error(&image, &exact);
        assert!(error < within, "{mode}: mean error {error} against the exact render");
    }
}

#[test]
fn no_lights_is_a_black_image_and_one_light_at_the_centre_gives_the_answer() {
    let dir = TempDir::new("few");
    for mode in MODES {
        let black = render_text(&dir, "none", &scene(1.0, ""), mode);
        assert!(luminance(&black).iter().all(|&l| l == 0.0));
        assert!(black.channels["A"].contains(&1.0), "geometry is still there");
        let one = "[[lights]]\ntype = \"point\"\nposition = [0, 0, 0]\nintensity = [1, 2, 3]\n";
        let (path, image) = render_at(&dir, "one", &inside_sphere_with(16, 12, one), mode);
        assert_inside_sphere_is(&path, &image, inside_sphere_answer([1.0, 2.0, 3.0]), tolerance(mode));
    }
}

#[test]
fn scaling_intensities_by_k_scales_the_image_by_k() {
    let dir = TempDir::new("scale-k");
    for mode in MODES {
        let a = luminance(&render_text(&dir, "a", &scene(1.0, &grid(1.0, 16, 0.01)), mode));
        // A power of two: every product scales exactly, and the cut (which
        // compares ratios) is the same.
        let b = luminance(&render_text(&dir, "b", &scene(1.0, &grid(1.0, 16, 0.01 * 1024.0)), mode));
        for (x, y) in a.iter().zip(&b) {
            assert!((x * 1024.0 - y).abs() <= 1e-5 * y.abs(), "{mode:?}: {x} * 1024 vs {y}");
        }
    }
}

#[test]
fn scaling_the_scene_and_intensities_together_leaves_the_image_unchanged() {
    let dir = TempDir::new("scale-scene");
    for mode in MODES {
        let reference = luminance(&render_text(&dir, "one", &scene(1.0, &grid(1.0, 16, 0.01)), mode));
        // Radiance from a point light goes as I / d^2: scale lengths by s and
        // intensities by s^2. Scales of about 1e-4 and 1e6 metres, as powers
        // of two (2^-13, 2^20) so that every coordinate scales exactly and
        // both modes see the same numbers up to exponent.
        for s in [2f64.powi(-13), 2f64.powi(20)] {
            let image = luminance(&render_text(&dir, "scaled", &scene(s, &grid(s, 16, 0.01 * s * s)), mode));
            let mean: f64 = reference.iter().sum::<f64>() / reference.len() as f64;
            let mut worst = 0.0f64;
            for (a, b) in reference.iter().zip(&image) {
                worst = worst.max((a - b).abs() / mean);
            }
            assert!(worst <= 1e-4, "{mode:?} scale {s}: worst difference {worst} of the mean");
        }
    }
}

#[test]
fn degenerate_and_zero_area_triangles_render() {
    let dir = TempDir::new("degenerate");
    std::fs::write(
        dir.path("bad.obj"),
        "v 0 0 0\nv 0 0 0\nv 0 0 0\nv 1 0.5 0\nv 2 0.5 0\nv 3 0.5 0\nv 0 1 0\nv 1 1 0\nv 0 2 0\nf 1 2 3\nf 4 5 6\nf 7 8 9\n",
    )
    .unwrap();
    let text = format!(
        "{}\n[[shapes]]\ntype = \"mesh\"\nfile = \"bad.obj\"\nmaterial = \"floor\"\n",
        scene(1.0, &grid(1.0, 16, 0.01))
    );
    for mode in MODES {
        render_text(&dir, "deg", &text, mode);
    }
}

#[test]
fn error_and_cut_extremes_terminate_with_finite_images() {
    let dir = TempDir::new("cut-extremes");
    let text = scene(1.0, &grid(1.0, 16, 0.01));
    let exact = render_text(&dir, "exact", &text, &["--exact"]);
    for mode in ["--bounded", "--stochastic", "--multidimensional"] {
        for args in [&["--error", "0"][..], &["--error", "1"], &["--max-cut", "1"], &["--error", "1e9"]] {
            let image = render_text(&dir, "cut", &text, &[&[mode][..], args].concat());
            assert!(luminance(&image).iter().any(|&l| l > 0.0), "{mode} {args:?}");
            if args == ["--error", "0"] && mode != "--stochastic" {
                // Every cluster split: the exact render.
                assert!(mean_relative_error(&image, &exact) < 1e-6, "{mode} --error 0");
            }
        }
    }
}

#[test]
fn a_camera_inside_geometry() {
    let dir = TempDir::new("inside");
    let text = scene_seen_from([0.1, 0.6, 0.2], 1.0, &grid(1.0, 16, 0.01));
    for mode in MODES {
        let image = render_text(&dir, "inside", &text, mode);
        assert!(image.channels["A"].iter().all(|&a| a == 1.0), "every ray hits the inside of the sphere");
    }
}

/// An emitter is held to the same extremes as the point lights: a
/// rectangle from a millimetre to 8e15 m across (its corners near the
/// coordinate limit), rendered in every mode and along paths, gives a
/// finite, lit image. An emitter 4.3e9 m across once made every pixel NaN
/// (its triangles' areas overflowed `f32`).
#[test]
fn emitters_from_a_millimetre_to_the_coordinate_limit() {
    let dir = TempDir::new("extreme-emitters");
    for size in [1e-3f64, 1.0, 4.3e9, 8e15] {
        // Facing down (u x v along -y), centred 3 m above the floor.
        let light = format!(
            "[[lights]]\ntype = \"area\"\ncorner = [{:e}, 3, {:e}]\nu = [{size:e}, 0, 0]\nv = [0, 0, {:e}]\nradiance = [{:e}, {:e}, {:e}]\n",
            -size / 2.0,
            -size / 2.0,
            size,
            1.0 / size.min(1.0).powi(2),
            1.0 / size.min(1.0).powi(2),
            1.0 / size.min(1.0).powi(2),
        );
        let text = scene(1.0, &light);
        for mode in MODES.iter().map(|m| m.to_vec()).chain([vec!["--exact", "--indirect", "path", "--max-depth", "3"]])
        {
            let image = render_text(&dir, "emitter", &text, &mode);
            assert!(luminance(&image).iter().any(|&l| l > 0.0), "{size} {mode:?}: black");
        }
    }
}
