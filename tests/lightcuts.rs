//! Lightcuts mode, run as the real binary, against the exact renderer.

mod common;
use common::*;

fn bits(image: &ExrImage, name: &str) -> Vec<f32> {
    image.channels[name].clone()
}

/// The small scene's floor and spheres with glTF's metallic-roughness
/// material: a rough dielectric, a gold metal, a near-mirror chrome.
fn small_pbr_scene(lights_per_side: u32) -> String {
    use lightcuts::scene::builder::SceneText;
    let pbr =
        |metallic: f32, roughness: f32| format!("type = \"pbr\"\nmetallic = {metallic}\nroughness = {roughness}\n");
    SceneText::new(96, 72)
        .camera([0.0, 3.0, 6.0], [0.0, 0.5, 0.0], 45.0)
        .material("floor", [0.7, 0.7, 0.7], &pbr(0.0, 0.6))
        .material("gold", [1.0, 0.78, 0.34], &pbr(1.0, 0.3))
        .material("chrome", [0.55, 0.56, 0.55], &pbr(1.0, 0.05))
        .floor(0.0, 5.0, "floor")
        .sphere([-0.8, 0.7, 0.0], 0.7, "gold")
        .sphere([0.9, 0.5, 0.4], 0.5, "chrome")
        .grid([-2.0, 3.0, -2.0], [4.0, 0.0, 0.0], [0.0, 0.0, 4.0], [lights_per_side; 2], [1.0, 0.9, 0.8])
        .toml()
}

/// The same grid over layered and transmitting materials (docs/design.md
/// §5.8, §5.10): a rough clear coat over red, a white sheen over blue, and
/// rough glass, whose transmission the camera paths draw.
fn small_layered_scene(lights_per_side: u32) -> String {
    use lightcuts::scene::builder::SceneText;
    let pbr = |extra: &str| format!("type = \"pbr\"\nmetallic = 0\nroughness = 0.5\n{extra}\n");
    SceneText::new(96, 72)
        .camera([0.0, 3.0, 6.0], [0.0, 0.5, 0.0], 45.0)
        .material("floor", [0.7, 0.7, 0.7], &pbr(""))
        .material("coated", [0.8, 0.1, 0.1], &pbr("clearcoat = 1\nclearcoat_roughness = 0.2"))
        .material("velvet", [0.1, 0.2, 0.6], &pbr("sheen_colour = [1, 1, 1]\nsheen_roughness = 0.4"))
        .material("frosted", [1.0, 1.0, 1.0], &pbr("transmission = 1").replace("roughness = 0.5", "roughness = 0.3"))
        .floor(0.0, 5.0, "floor")
        .sphere([-1.2, 0.6, 0.0], 0.6, "coated")
        .sphere([0.1, 0.5, 0.5], 0.5, "frosted")
        .sphere([1.3, 0.5, -0.2], 0.5, "velvet")
        .grid([-2.0, 3.0, -2.0], [4.0, 0.0, 0.0], [0.0, 0.0, 4.0], [lights_per_side; 2], [1.0, 0.9, 0.8])
        .toml()
}

#[test]
fn error_zero_reproduces_the_exact_image() {
    // 16 x 16 = 256 lights: above the exhaustive limit, so the cut runs.
    error_zero_reproduces_the_exact_image_of(&small_scene(16), "error-zero");
    error_zero_reproduces_the_exact_image_of(&small_pbr_scene(16), "error-zero-pbr");
    // The chrome sphere's lobe (roughness 0.05) is sharp for the
    // environment's lights: its part is sampled, the same in both.
    let environment = "\n[environment]\nradiance = [0.4, 0.5, 0.6]\nsamples = 256\n";
    error_zero_reproduces_the_exact_image_of(&(small_pbr_scene(16) + environment), "error-zero-environment");
    // Coats, sheens and rough glass: their bounds let no cluster go
    // unrefined at --error 0 either.
    error_zero_reproduces_the_exact_image_of(&small_layered_scene(16), "error-zero-layered");
    // Reconstruction cuts assume no visibility at --error 0.
    error_zero_reproduces_the_exact_image_with(&small_scene(16), "error-zero-reconstruct", &["--reconstruct", "2"]);
}

fn error_zero_reproduces_the_exact_image_of(text: &str, name: &str) {
    error_zero_reproduces_the_exact_image_with(text, name, &[]);
}

fn error_zero_reproduces_the_exact_image_with(text: &str, name: &str, flags: &[&str]) {
    let dir = TempDir::new(name);
    let scene = dir.write("s.toml", text);
    let (lc, exact) = (dir.path("lc.exr"), dir.path("exact.exr"));
    let args = ["render", s(&scene), "-o", s(&lc), "--error", "0", "--max-cut", "100000", "--quiet"];
    let stdout = lightcuts_ok(&[&args[..], flags].concat());
    assert!(stdout.contains("cut size"), "{stdout}");
    lightcuts_ok(&["render", s(&scene), "-o", s(&exact), "--exact", "--quiet"]);
    let (a, b) = (read_exr(&lc).unwrap(), read_exr(&exact).unwrap());
    for name in ["R", "G", "B", "A", "Z", "N.X", "albedo.G"] {
        for (x, y) in bits(&a, name).iter().zip(bits(&b, name)) {
            // The two sum the same terms in different orders (in f64).
            assert!((x - y).abs() <= 1e-6 * y.abs().max(1e-30), "{name}: {x} vs {y}");
            assert!(x.is_finite());
        }
    }
    assert!(a.channels.contains_key("lightcuts.cut_size") && a.channels.contains_key("lightcuts.shadow_rays"));
    assert!(!b.channels.contains_key("lightcuts.cut_size"), "the exact render writes no cut AOVs");
}

#[test]
fn lightcuts_at_two_percent_stays_close_to_exact_and_casts_fewer_rays() {
    let dir = TempDir::new("accuracy");
    let scene = dir.write("s.toml", &small_scene(24));
    let (lc, exact) = (dir.path("lc.exr"), dir.path("exact.exr"));
    lightcuts_ok(&["render", s(&scene), "-o", s(&lc), "--quiet"]);
    lightcuts_ok(&["render", s(&scene), "-o", s(&exact), "--exact", "--quiet"]);
    let out = lightcuts_ok(&["compare", s(&lc), s(&exact), "--json"]);
    let c: serde_json::Value = serde_json::from_str(&out).unwrap();
    let mean = c["mean_relative_error"].as_f64().unwrap();
    let p99 = c["p99_relative_error"].as_f64().unwrap();
    // Each cluster's error is at most 2% of its point's total; errors of
    // different clusters partly cancel, so the image stays within a few percent.
    assert!(mean > 0.0 && mean < 0.01, "mean relative error {mean}");
    assert!(p99 < 0.05, "99th percentile {p99}");
    let rays = |p: &std::path::Path| read_exr(p).unwrap().channels["lightcuts.shadow_rays"].iter().sum::<f32>();
    let lc_rays = rays(&lc);
    let exact_out = lightcuts_ok(&["render", s(&scene), "-o", s(&exact), "--exact", "--quiet"]);
    let exact_rays: f64 = exact_out
        .lines()
        .find(|l| l.contains("shadow rays  "))
        .unwrap()
        .split_whitespace()
        .nth(2)
        .unwrap()
        .parse()
        .unwrap();
    assert!(f64::from(lc_rays) < 0.5 * exact_rays, "lightcuts {lc_rays} vs exact {exact_rays} shadow rays");
}

/// A shell of lights inside a sphere seen from inside (Newton's shell
/// theorem gives every pixel the known answer L = k_d / pi * sum(I) / R^2):
/// the lights are apart, so the cut must refine, and its error, bounded per
/// cluster by 2% of the total, stays within a few percent of the answer.
#[test]
fn known_answer_holds_in_lightcuts_mode() {
    let dir = TempDir::new("lc-known");
    let scene = dir.write("inside.toml", &inside_sphere_scene(24, 16));
    let out = dir.path("o.exr");
    lightcuts_ok(&["render", s(&scene), "-o", s(&out), "--quiet", "--bounded"]);
    let image = read_exr(&out).unwrap();
    // Measured: at most 0.46% at an average cut of 85 nodes.
    assert_inside_sphere_answer(&out, &image, 0.02);
    let cuts = &image.channels["lightcuts.cut_size"];
    let average = cuts.iter().sum::<f32>() / cuts.len() as f32;
    assert!(average > 8.0, "the cut refines: {average} nodes on average");
    // --error 0 refines to every light: the exact answer.
    lightcuts_ok(&["render", s(&scene), "-o", s(&out), "--quiet", "--bounded", "--error", "0"]);
    let image = read_exr(&out).unwrap();
    assert_inside_sphere_answer(&out, &image, 1e-3);
    assert!(image.channels["lightcuts.cut_size"].iter().all(|&c| c as usize == SHELL_LIGHTS));
}

/// Reconstruction cuts ([LC05] §6, `--reconstruct B`): full cuts at the
/// corners of 2 x 2 pixel blocks, the camera hits between them reconstructed:
/// as close to the exact image as the bounded cut, with far fewer shadow
/// rays; the anchors depend on the image alone, so threads, windows and
/// tiles change no bit.
#[test]
fn reconstruction_cuts_stay_close_to_exact_with_fewer_rays_for_any_threads_window_and_tiles() {
    let dir = TempDir::new("reconstruct");
    let scene = dir.write("s.toml", &small_scene(24));
    let render = |name: &str, flags: &[&str]| {
        let out = dir.path(name);
        let quiet = if flags.contains(&"--stats") { "--threads=2" } else { "--quiet" };
        let args = ["render", s(&scene), "-o", s(&out), "--spp", "4", quiet];
        let stdout = lightcuts_ok(&[&args[..], flags].concat());
        (out, stdout)
    };
    let (reconstructed, stdout) = render("rc.exr", &["--reconstruct", "2"]);
    assert!(stdout.contains("reconstruction_block=2"), "{stdout}");
    let (bounded, _) = render("lc.exr", &["--bounded"]);
    let (exact, _) = render("exact.exr", &["--exact"]);
    let (rc_error, lc_error) = (mean_error(&reconstructed, &exact), mean_error(&bounded, &exact));
    assert!(rc_error > 0.0 && rc_error < 0.01, "mean relative error {rc_error} (bounded {lc_error})");
    assert!(rc_error < 1.5 * lc_error, "{rc_error} against the bounded cut's {lc_error}");
    // The pass's totals count the anchors' rays too (the AOV counts each
    // pixel's samples' own).
    let rays = |flags: &[&str]| {
        let (_, stdout) = render("stats.exr", &[flags, &["--stats"][..]].concat());
        let line = stdout.lines().find(|l| l.contains("shadow rays  ")).unwrap().to_string();
        line.split_whitespace().nth(2).unwrap().parse::<f64>().unwrap()
    };
    let (rc_rays, lc_rays) = (rays(&["--reconstruct", "2"]), rays(&["--bounded"]));
    assert!(2.0 * rc_rays < lc_rays, "{rc_rays} rays against the bounded cut's {lc_rays}");

    assert_same_bits_for_any_threads_and_window(&dir, &scene, 96, &["--reconstruct", "2", "--spp", "2"]);
    // Bands of 7 tiles (block rows cut across) assemble to the one-process render.
    assert_tiles_assemble_to(&dir, &scene, &["--spp", "4", "--reconstruct", "2"], 7, &reconstructed);

    let stderr = lightcuts_fails(&["render", s(&scene), "-o", s(&dir.path("x.exr")), "--reconstruct", "0"]);
    assert!(stderr.contains("--reconstruct") && stderr.contains("at least 1"), "{stderr}");
    // A flag of another method names the method in use.
    let out = lightcuts(&["render", s(&scene), "-o", s(&dir.path("x.exr")), "--reconstruct", "2", "--stochastic"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("--reconstruct") && stderr.contains("method is stochastic"),
        "{stderr}"
    );
    assert!(!dir.path("x.exr").exists());
}

#[test]
fn lightcuts_images_are_identical_for_any_thread_count_and_window() {
    let dir = TempDir::new("lc-threads");
    let scene = dir.write("s.toml", &small_scene(16));
    assert_same_bits_for_any_threads_and_window(&dir, &scene, 96, &["--bounded"]);
}

#[test]
fn compare_rejects_mismatched_images_and_writes_a_heat_map() {
    let dir = TempDir::new("compare");
    let scene = dir.write("s.toml", &small_scene(2));
    let (a, b) = (dir.path("a.exr"), dir.path("b.exr"));
    lightcuts_ok(&["render", s(&scene), "-o", s(&a), "--quiet", "--exact"]);
    lightcuts_ok(&["render", s(&scene), "-o", s(&b), "--quiet", "--exact", "--resolution", "48x36"]);
    let stderr = lightcuts_fails(&["compare", s(&a), s(&b)]);
    assert!(stderr.contains("data window"), "{stderr}");
    let (diff, diff_exr) = (dir.path("d.png"), dir.path("d.exr"));
    let out = lightcuts_ok(&["compare", s(&a), s(&a), "--diff", s(&diff), "--diff-exr", s(&diff_exr)]);
    assert!(out.contains("mean"), "{out}");
    assert!(diff.exists());
    let d = read_exr(&diff_exr).unwrap();
    assert!(d.channels["relative_error"].iter().all(|&e| e == 0.0));
    let stderr = lightcuts_fails(&["compare", s(&a), s(&dir.path("missing.exr"))]);
    assert!(stderr.contains("missing.exr"), "{stderr}");
}
