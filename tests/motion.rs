//! Motion blur, run as the real binary: a moving quad covers each pixel for
//! the part of the shutter it spends there; a moving light lights a still
//! floor as the lights along its path do on average; a moving scene is the
//! exact render at `--error 0` in the multidimensional mode, and the same
//! bits for any thread count and window; a glTF file's animation blurs over
//! `--shutter`; bad motion is named.

mod common;
use common::gltf::{diffuse, GltfBuilder};
use common::*;
use serde_json::json;

/// A 1 m wide quad at z = 0 sliding 3 m along +x over the shutter, seen
/// head-on from 10 m on a 48 x 4 film, `spp` samples per pixel.
fn sliding_quad(shutter: &str, spp: u32) -> String {
    format!(
        "[film]\nwidth = 48\nheight = 4\nspp = {spp}\n\
         [camera]\neye = [0, 0, 10]\nlook_at = [0, 0, 0]\nfov_y = 5.0\nshutter = {shutter}\n\
         [materials.grey]\nalbedo = [0.5, 0.5, 0.5]\n\
         [[shapes]]\ntype = \"quad\"\ncorner = [-3, -1, 0]\nu = [1, 0, 0]\nv = [0, 2, 0]\nmaterial = \"grey\"\n\
         motion = {{ translate = [3, 0, 0] }}\n\
         [[lights]]\ntype = \"point\"\nposition = [0, 0, 5]\nintensity = [1, 1, 1]\n"
    )
}

/// The fraction of a shutter over which a 1 m quad spanning [-3 + o, -2 + o]
/// in x covers the point x, its offset o moving from `a` to `b`.
fn coverage(x: f64, a: f64, b: f64) -> f64 {
    let (t0, t1) = ((x + 2.0 - a) / (b - a), (x + 3.0 - a) / (b - a));
    (t1.min(1.0) - t0.max(0.0)).max(0.0)
}

/// The world x at z = 0 of the centre of pixel column `column` of a film
/// `width` pixels wide and 1/12 as high, seen as [`sliding_quad`] sees it.
fn column_x(column: usize, width: usize) -> f64 {
    let half_width = (2.5f64).to_radians().tan() * 12.0 * 10.0;
    ((column as f64 + 0.5) / width as f64 * 2.0 - 1.0) * half_width
}

/// The mean of each column of a `width`-pixel-wide image's channel.
fn column_means(values: &[f32], width: usize) -> Vec<f64> {
    let rows = values.len() / width;
    (0..width).map(|c| (0..rows).map(|r| f64::from(values[r * width + c])).sum::<f64>() / rows as f64).collect()
}

#[test]
fn a_moving_quad_covers_each_pixel_for_the_part_of_the_shutter_it_spends_there() {
    let dir = TempDir::new("quad-coverage");
    // 243 = 3^5 samples: the shutter times fill every 1/243 of it once.
    let scene = dir.write("q.toml", &sliding_quad("[0.0, 0.02]", 243));
    let out = dir.path("q.exr");
    lightcuts_ok(&["render", s(&scene), "-o", s(&out), "--exact", "--quiet"]);
    let image = read_exr(&out).unwrap();
    // Each sample's point of the pixel is random, so the samples near
    // either end of a point's covered stretch of the shutter count at
    // random: the 4 rows' mean keeps that noise near 0.006.
    let alpha = column_means(&image.channels["A"], 48);
    for (column, &a) in alpha.iter().enumerate() {
        // The quad spans [-3 + 3t, -2 + 3t] at time t: a point x is covered
        // for t in [(x + 2) / 3, (x + 3) / 3], clipped to [0, 1].
        let x = column_x(column, 48);
        let expected = coverage(x, 0.0, 3.0);
        assert!((a - expected).abs() < 0.02, "column {column} (x = {x:.3}): coverage {a}, expected {expected}");
    }
    // In all, the quad covers 1 m of the row for the whole shutter: the
    // coverages sum to 1 m over a column's width.
    let covered: f64 = alpha.iter().sum();
    let expected_total = 1.0 / (column_x(1, 48) - column_x(0, 48));
    assert!((covered - expected_total).abs() < 0.01 * expected_total, "{covered} vs {expected_total}");
    // With the shutter closed the quad stands at its open position, sharp.
    let still = dir.write("still.toml", &sliding_quad("[0.0, 0.0]", 9));
    lightcuts_ok(&["render", s(&still), "-o", s(&out), "--exact", "--quiet"]);
    let image = read_exr(&out).unwrap();
    for column in 0..48 {
        let x = column_x(column, 48);
        let a = image.channels["A"][column];
        if (x + 3.0).abs() > 0.2 && (x + 2.0).abs() > 0.2 {
            assert_eq!(a, if (-3.0..-2.0).contains(&x) { 1.0 } else { 0.0 }, "column {column} (x = {x:.3})");
        }
    }
}

#[test]
fn a_turning_quad_is_shaded_where_it_is_at_each_sample_time() {
    // A 2 m quad facing the camera turns 60 degrees about +y through its
    // centre: the centre pixels see it all along, with the normal
    // (sin t, 0, cos t) at angle t, whose mean over the turn is
    // ((1 - cos 60) / (pi / 3), 0, sin 60 / (pi / 3)). Shading that placed
    // the hit as at the shutter's open would see (0, 0, 1).
    let dir = TempDir::new("turning-quad");
    let text = sliding_quad("[0.0, 0.02]", 243)
        .replace("corner = [-3, -1, 0]\nu = [1, 0, 0]", "corner = [-1, -1, 0]\nu = [2, 0, 0]")
        .replace("translate = [3, 0, 0]", "rotate_axis = [0, 1, 0], rotate_degrees = 60");
    assert!(text.contains("rotate_degrees") && text.contains("corner = [-1, -1, 0]"));
    let scene = dir.write("turn.toml", &text);
    let out = dir.path("turn.exr");
    lightcuts_ok(&["render", s(&scene), "-o", s(&out), "--exact", "--quiet"]);
    let image = read_exr(&out).unwrap();
    let third = std::f64::consts::PI / 3.0;
    let expected = [(1.0 - third.cos()) / third, 0.0, third.sin() / third];
    for column in [23, 24] {
        for row in 0..4 {
            let at = row * 48 + column;
            assert_eq!(image.channels["A"][at], 1.0, "the centre is covered all along");
            for (axis, want) in ["N.X", "N.Y", "N.Z"].iter().zip(expected) {
                let found = f64::from(image.channels[*axis][at]);
                assert!((found - want).abs() < 0.01, "{axis} at column {column}, row {row}: {found} vs {want}");
            }
        }
    }
}

/// A floor lit by one point light 1 m above it: moving from x = -1 to 1
/// over an open shutter, or the `lights` given instead.
fn floor_lit_by(lights: &str, shutter: &str) -> String {
    format!(
        "[film]\nwidth = 32\nheight = 24\nspp = 243\n\
         [camera]\neye = [0, 4, 3]\nlook_at = [0, 0, 0]\nfov_y = 50.0\nshutter = {shutter}\n\
         [materials.grey]\nalbedo = [0.5, 0.5, 0.5]\n\
         [[shapes]]\ntype = \"quad\"\ncorner = [-4, 0, 4]\nu = [8, 0, 0]\nv = [0, 0, -8]\nmaterial = \"grey\"\n\
         {lights}"
    )
}

#[test]
fn a_moving_light_lights_a_still_floor_as_the_lights_along_its_path_do_on_average() {
    let dir = TempDir::new("moving-light");
    let moving = dir.write(
        "moving.toml",
        &floor_lit_by(
            "[[lights]]\ntype = \"point\"\nposition = [-1, 1, 0]\nposition_end = [1, 1, 0]\nintensity = [2, 2, 2]\n",
            "[0, 1]",
        ),
    );
    // The time average over the straight path, by the midpoint rule: 81
    // lights at the centres of 81 equal stretches, each 1/81 of the light.
    let path = dir.write(
        "path.toml",
        &floor_lit_by(
            "[[lights]]\ntype = \"grid\"\ncorner = [-1, 1, -0.0005]\nu = [2, 0, 0]\nv = [0, 0, 0.001]\n\
             count = [81, 1]\nintensity = [0.024691358, 0.024691358, 0.024691358]\n",
            "[0, 0]",
        ),
    );
    let render = |scene: &std::path::Path, name: &str, mode: &str| {
        let out = dir.path(name);
        lightcuts_ok(&["render", s(scene), "-o", s(&out), mode, "--quiet"]);
        read_exr(&out).unwrap()
    };
    let reference = render(&path, "path.exr", "--exact");
    for mode in ["--exact", "--bounded", "--stochastic", "--multidimensional"] {
        let image = render(&moving, "moving.exr", mode);
        let error = mean_relative_error(&image, &reference);
        assert!(error < 0.01, "{mode}: mean relative error {error}");
    }
    // Standing at its start instead, the light is another picture.
    let still = dir.write(
        "still.toml",
        &floor_lit_by(
            "[[lights]]\ntype = \"point\"\nposition = [-1, 1, 0]\nposition_end = [1, 1, 0]\nintensity = [2, 2, 2]\n",
            "[0, 0]",
        ),
    );
    assert!(mean_relative_error(&render(&still, "still.exr", "--exact"), &reference) > 0.2);
}

/// The small scene with its shiny sphere sliding, its camera moving and a
/// point light crossing it over an open shutter.
fn moving_scene(lights_per_side: u32) -> String {
    let scene = small_scene(lights_per_side)
        .replacen("[camera]\n", "[camera]\nshutter = [0.0, 0.5]\neye_end = [0.4, 3.0, 6.0]\n", 1)
        .replacen(
            "radius = 0.7\nmaterial = \"shiny\"\n",
            "radius = 0.7\nmaterial = \"shiny\"\nmotion = { translate = [0.8, 0, 0], rotate_axis = [0, 1, 0], rotate_degrees = 30 }\n",
            1,
        );
    assert!(scene.contains("eye_end") && scene.contains("motion"));
    format!(
        "{scene}\n[[lights]]\ntype = \"point\"\nposition = [-1.5, 1.2, 1.5]\nposition_end = [1.5, 1.2, 1.5]\nintensity = [2, 2, 2]\n"
    )
}

#[test]
fn a_moving_scene_at_error_0_is_its_exact_render_and_the_same_for_any_threads_and_window() {
    let dir = TempDir::new("motion-md");
    let scene = dir.write("m.toml", &moving_scene(10));
    let common = ["--spp", "9", "--resolution", "24x18", "--quiet"];
    let render = |name: &str, mode: &[&str]| {
        let out = dir.path(name);
        lightcuts_ok(&[&["render", s(&scene), "-o", s(&out)][..], mode, &common].concat());
        read_exr(&out).unwrap()
    };
    let exact = render("exact.exr", &["--exact"]);
    let md = render("md.exr", &["--multidimensional", "--error", "0", "--max-cut", "100000000"]);
    for channel in ["R", "G", "B"] {
        for (i, (a, b)) in md.channels[channel].iter().zip(&exact.channels[channel]).enumerate() {
            assert!((a - b).abs() <= 1e-5 * b.abs() + 1e-9, "{channel} pixel {i}: {a} vs exact {b}");
        }
    }
    // The motion shows: the same scene with its shutter closed differs.
    let still_text = moving_scene(10).replace("shutter = [0.0, 0.5]", "shutter = [0.0, 0.0]");
    let still = dir.write("still.toml", &still_text);
    let out = dir.path("still.exr");
    lightcuts_ok(&[&["render", s(&still), "-o", s(&out), "--exact"][..], &common].concat());
    let sharp = read_exr(&out).unwrap();
    let differ = sharp.channels["G"].iter().zip(&exact.channels["G"]).filter(|(a, b)| a != b).count();
    assert!(differ > 100, "{differ} pixels differ from the still scene's");
    let threads = TempDir::new("motion-threads");
    let scene = threads.write("m.toml", &moving_scene(16));
    assert_same_bits_for_any_threads_and_window(&threads, &scene, 96, &["--multidimensional", "--spp", "4"]);
    assert_same_bits_for_any_threads_and_window(&threads, &scene, 96, &["--bounded", "--spp", "2", "--cryptomatte"]);
}

/// The sliding quad as a glTF file: a node whose animation ("slide")
/// moves it 3 m along +x from 0 s to 2 s, seen by a camera 10 m away.
fn animated_quad() -> GltfBuilder {
    let mut g = GltfBuilder::new();
    g.use_extension("KHR_materials_specular");
    let grey = g.material(diffuse([0.5, 0.5, 0.5]));
    let quad = g.quad([-3.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 2.0, 0.0], Some(grey));
    let node = g.node(json!({ "mesh": quad, "name": "slider" }), true);
    let light = g.light(json!({ "type": "point", "intensity": 683.0 }));
    g.node(
        json!({ "translation": [0.0, 0.0, 5.0], "extensions": { "KHR_lights_punctual": { "light": light } } }),
        true,
    );
    let camera = g.camera(json!({ "type": "perspective", "perspective": { "yfov": 5f32.to_radians(), "znear": 0.1 } }));
    g.node(json!({ "camera": camera, "translation": [0.0, 0.0, 10.0] }), true);
    let times = g.floats(&[0.0, 2.0], "SCALAR", 1);
    let offsets = g.floats(&[0.0, 0.0, 0.0, 3.0, 0.0, 0.0], "VEC3", 3);
    g.json["animations"] = json!([{
        "name": "slide",
        "samplers": [{ "input": times, "output": offsets, "interpolation": "LINEAR" }],
        "channels": [{ "sampler": 0, "target": { "node": node, "path": "translation" } }],
    }]);
    g
}

#[test]
fn a_gltf_animation_blurs_over_the_shutter_the_command_line_opens() {
    let dir = TempDir::new("gltf-animation");
    let file = dir.write("anim.gltf", &animated_quad().embedded());
    let out = dir.path("a.exr");
    let render = |more: &[&str]| {
        let args = [&["render", s(&file), "-o", s(&out), "--exact", "--resolution", "96x8", "--quiet"][..], more];
        lightcuts_ok(&args.concat());
        column_means(&read_exr(&out).unwrap().channels["A"], 96)
    };
    // Over the whole animation, then its second second only: the quad's
    // offset moves 0 -> 3 m, then 1.5 -> 3 m.
    for (shutter, a, b) in [("0,2", 0.0, 3.0), ("1,2", 1.5, 3.0)] {
        let alpha = render(&["--shutter", shutter, "--spp", "243", "--animation", "slide"]);
        // The 8 rows' mean: the noise of a pixel's random points is near 0.004.
        for (column, &found) in alpha.iter().enumerate() {
            let (x, expected) = (column_x(column, 96), coverage(column_x(column, 96), a, b));
            assert!(
                (found - expected).abs() < 0.02,
                "--shutter {shutter}, column {column} (x = {x:.3}): {found} vs {expected}"
            );
        }
    }
    // Without a shutter the file renders in its nodes' own pose, sharp.
    let alpha = render(&["--spp", "9"]);
    for (column, &a) in alpha.iter().enumerate() {
        let x = column_x(column, 96);
        if (x + 3.0).abs() > 0.2 && (x + 2.0).abs() > 0.2 {
            assert_eq!(a, if (-3.0..-2.0).contains(&x) { 1.0 } else { 0.0 }, "column {column}");
        }
    }
    let bad = dir.path("bad.exr");
    let stderr = lightcuts_fails(&["render", s(&file), "-o", s(&bad), "--shutter", "0,1", "--animation", "run"]);
    assert!(stderr.contains("anim.gltf") && stderr.contains("animations") && stderr.contains("slide"), "{stderr}");
    let stderr = lightcuts_fails(&["render", s(&file), "-o", s(&bad), "--shutter", "2,1"]);
    assert!(stderr.contains("--shutter"), "{stderr}");
    assert!(!bad.exists());
}

/// An instant (`--shutter T,T`) renders the animation's pose at T, sharp:
/// the quad 3 T / 2 m along; the summary names the animation and the
/// instant (or the interval it blurs over). A shutter beyond the
/// animation's keys (frames typed as seconds) is warned about with their
/// range; an animation the file lacks is an error with or without a
/// shutter, and one named without a shutter is not played, with a warning.
#[test]
fn a_gltf_animation_at_an_instant_is_its_pose_then() {
    let dir = TempDir::new("gltf-instant");
    let file = dir.write("anim.gltf", &animated_quad().embedded());
    let out = dir.path("a.exr");
    let render = |more: &[&str]| {
        let args = [&["render", s(&file), "-o", s(&out), "--exact", "--resolution", "96x8", "--spp", "9"][..], more];
        let output = lightcuts(&args.concat());
        assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
        let text = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
        (column_means(&read_exr(&out).unwrap().channels["A"], 96), text(&output.stdout), text(&output.stderr))
    };
    for (time, offset) in [("0.5", 0.75), ("1", 1.5), ("2", 3.0)] {
        let (alpha, stdout, stderr) = render(&["--shutter", &format!("{time},{time}")]);
        // Sharp at the pose: 1 where the quad is, 0 elsewhere (columns
        // near an edge left out: a pixel there is partly covered).
        for (column, &a) in alpha.iter().enumerate() {
            let x = column_x(column, 96) - offset;
            if (x + 3.0).abs() > 0.2 && (x + 2.0).abs() > 0.2 {
                assert_eq!(a, if (-3.0..-2.0).contains(&x) { 1.0 } else { 0.0 }, "at {time} s, column {column}");
            }
        }
        assert!(stdout.contains(&format!("animation        'slide' posed at {time} s")), "{stdout}");
        assert!(!stderr.contains("not within"), "{stderr}");
    }
    let (_, stdout, _) = render(&["--shutter", "0.5,1"]);
    assert!(stdout.contains("animation        'slide' over 0.5 to 1 s"), "{stdout}");
    // Frames typed as seconds: the animation's keys end at 2 s.
    let (_, _, stderr) = render(&["--shutter", "6,8"]);
    assert!(stderr.contains("the shutter 6,8 s is not within animation 'slide''s keys, 0 to 2 s"), "{stderr}");
    let (_, stdout, stderr) = render(&["--animation", "slide"]);
    assert!(stderr.contains("'slide' is not played: give a shutter"), "{stderr}");
    assert!(!stdout.contains("animation "), "{stdout}");
    let bad = dir.path("bad.exr");
    let stderr = lightcuts_fails(&["render", s(&file), "-o", s(&bad), "--animation", "NoSuchName"]);
    assert!(stderr.contains("no animation named 'NoSuchName'") && stderr.contains("slide"), "{stderr}");
    assert!(!bad.exists());
}

#[test]
fn hostile_animations_are_errors_naming_the_field_never_panics() {
    let dir = TempDir::new("gltf-hostile-animation");
    let base = animated_quad();
    let times = base.json["animations"][0]["samplers"][0]["input"].as_u64().unwrap();
    type Breaks = Box<dyn Fn(&mut serde_json::Value)>;
    let cases: Vec<(Breaks, &str)> = vec![
        (Box::new(|j| j["animations"][0]["channels"][0]["target"]["node"] = json!(99)), "channels[0].target.node"),
        (Box::new(|j| j["animations"][0]["channels"][0]["target"]["path"] = json!("wobble")), "target.path"),
        (Box::new(|j| j["animations"][0]["channels"][0]["sampler"] = json!(5)), "channels[0].sampler"),
        (Box::new(|j| j["animations"][0]["samplers"][0]["input"] = json!(99)), "samplers[0].input"),
        // The key times' accessor as the output: 2 values for 2 keys, but SCALAR.
        (Box::new(move |j| j["animations"][0]["samplers"][0]["output"] = json!(times)), "samplers[0].output"),
        (Box::new(|j| j["animations"][0]["samplers"][0]["interpolation"] = json!("CUBICSPLINE")), "samplers[0].output"),
        (Box::new(|j| j["animations"][0]["samplers"][0]["interpolation"] = json!("BOUNCY")), "interpolation"),
    ];
    for (k, (break_it, field)) in cases.iter().enumerate() {
        let mut g = animated_quad();
        break_it(&mut g.json);
        let file = dir.write(&format!("bad{k}.gltf"), &g.embedded());
        let out = dir.path("out.exr");
        let stderr = lightcuts_fails(&["render", s(&file), "-o", s(&out), "--shutter", "0,1", "--quiet"]);
        assert!(stderr.contains(&format!("bad{k}.gltf")) && stderr.contains(field), "case {k}: {stderr}");
        assert!(!stderr.contains("panicked"), "case {k}: {stderr}");
        assert!(!out.exists());
    }
    // Key times that go back are named too.
    let mut g = GltfBuilder::new();
    g.json = base.json.clone();
    g.bin = base.bin.clone();
    let backwards = g.floats(&[2.0, 0.0], "SCALAR", 1);
    g.json["animations"][0]["samplers"][0]["input"] = json!(backwards);
    let file = dir.write("backwards.gltf", &g.embedded());
    let stderr = lightcuts_fails(&["render", s(&file), "-o", s(&dir.path("b.exr")), "--shutter", "0,1"]);
    assert!(stderr.contains("samplers[0].input") && stderr.contains("strictly increasing"), "{stderr}");
}

#[test]
fn bad_motion_is_named() {
    let dir = TempDir::new("bad-motion");
    let cases = [
        (moving_scene(2).replace("shutter = [0.0, 0.5]", "shutter = [0.5, 0.0]"), "camera.shutter"),
        (moving_scene(2).replace("rotate_axis = [0, 1, 0], ", ""), "shapes[1].motion.rotate_axis"),
        (moving_scene(2).replace("rotate_degrees = 30", "rotate_degrees = 720"), "shapes[1].motion.rotate_degrees"),
        (moving_scene(2).replace("translate = [0.8, 0, 0]", "translate = [0.8, nan, 0]"), "shapes[1].motion.translate"),
        (moving_scene(2).replace("rotate_degrees = 30", "rotate_degree = 30"), "shapes[1].motion.rotate_degree"),
        (moving_scene(2).replace("position_end = [1.5, 1.2, 1.5]", "position_end = [1.5, 1e30, 1.5]"), "position_end"),
        (moving_scene(2).replace("eye_end = [0.4, 3.0, 6.0]", "eye_end = [0.0, 0.5, 0.0]"), "camera.eye_end"),
    ];
    for (k, (text, field)) in cases.iter().enumerate() {
        let name = format!("bad{k}.toml");
        let scene = dir.write(&name, text);
        let out = dir.path("out.exr");
        let stderr = lightcuts_fails(&["render", s(&scene), "-o", s(&out), "--quiet"]);
        assert!(stderr.contains(&name) && stderr.contains(field), "case {k}: {stderr}");
        assert!(!out.exists());
    }
}
