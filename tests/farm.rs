//! Tiles for a farm: `render --tile I/N` and `--no-overwrite`, and
//! `assemble`, run as the real binary. (ci/slurm-test.sh runs the same on a
//! real Slurm cluster.)

mod common;
use common::*;

/// Renders tile `tile` (I/N) of `scene` quietly into `dir`/`out`, with `extra` flags.
fn render_tile(dir: &TempDir, scene: &std::path::Path, out: &str, tile: &str, extra: &[&str]) -> std::path::PathBuf {
    let out = dir.path(out);
    lightcuts_ok(&[&["render", s(scene), "-o", s(&out), "--tile", tile, "--quiet"][..], extra].concat());
    out
}

fn same_pixels(a: &ExrImage, b: &ExrImage) {
    assert_eq!(a.channels.keys().collect::<Vec<_>>(), b.channels.keys().collect::<Vec<_>>());
    for (name, values) in &a.channels {
        let other = &b.channels[name];
        assert!(values.iter().zip(other).all(|(x, y)| x.to_bits() == y.to_bits()), "{name} differs");
    }
    assert_eq!((a.width, a.height, a.x0, a.y0), (b.width, b.height, b.x0, b.y0));
}

#[test]
fn tiles_assemble_to_the_one_process_render_bit_for_bit() {
    let dir = TempDir::new("farm-tiles");
    let scene = dir.write("s.toml", &small_scene(16));
    let one = dir.path("one.exr");
    let common = ["--resolution", "40x30", "--spp", "2", "--quiet"];
    lightcuts_ok(&[&["render", s(&scene), "-o", s(&one)][..], &common].concat());
    let one = read_exr(&one).unwrap();
    for n in [1u32, 3, 7] {
        let mut tiles = Vec::new();
        for i in 0..n {
            let tile = dir.path(&format!("t{n}-{i}.exr"));
            let spec = format!("{i}/{n}");
            lightcuts_ok(&[&["render", s(&scene), "-o", s(&tile), "--tile", &spec][..], &common].concat());
            let image = read_exr(&tile).unwrap();
            // Bands: rows floor(i H / n) .. floor((i + 1) H / n), full width.
            assert_eq!((image.x0, image.y0 as u32, image.width), (0, i * 30 / n, 40));
            assert_eq!(image.height as u32, (i + 1) * 30 / n - i * 30 / n);
            tiles.push(tile);
        }
        let frame = dir.path(&format!("frame{n}.exr"));
        let args: Vec<&str> = ["assemble", s(&frame)].into_iter().chain(tiles.iter().map(|t| s(t))).collect();
        lightcuts_ok(&args);
        same_pixels(&read_exr(&frame).unwrap(), &one);
    }
}

#[test]
fn assemble_refuses_gaps_overlaps_and_tiles_of_other_renders() {
    let dir = TempDir::new("farm-refuse");
    let scene = dir.write("s.toml", &small_scene(16));
    let render = |out: &str, tile: &str, seed: &str| {
        render_tile(&dir, &scene, out, tile, &["--seed", seed, "--resolution", "16x12"])
    };
    let (a, b, c) = (render("a.exr", "0/3", "0"), render("b.exr", "1/3", "0"), render("c.exr", "2/3", "0"));
    let other_seed = render("d.exr", "2/3", "7");
    let frame = dir.path("frame.exr");
    let missing = dir.path("never-rendered.exr");
    let stderr = lightcuts_fails(&["assemble", s(&frame), s(&a), s(&missing), s(&c)]);
    assert!(stderr.contains("64 pixels of the frame are in no tile: x 0..16, y 4..8"), "{stderr}");
    assert!(stderr.contains("never-rendered.exr"), "{stderr}");
    let stderr = lightcuts_fails(&["assemble", s(&frame), s(&missing)]);
    assert!(stderr.contains("none of the tiles exists") && stderr.contains("never-rendered.exr"), "{stderr}");
    let stderr = lightcuts_fails(&["assemble", s(&frame), s(&a), s(&b), s(&b), s(&c)]);
    assert!(stderr.contains("overlaps") && stderr.contains("y 4..8"), "{stderr}");
    let stderr = lightcuts_fails(&["assemble", s(&frame), s(&a), s(&b), s(&other_seed)]);
    assert!(stderr.contains("lightcuts:seed is '7'") && stderr.contains("d.exr"), "{stderr}");
    assert!(!frame.exists(), "no frame written on refusal");
    lightcuts_ok(&["assemble", s(&frame), s(&a), s(&b), s(&c)]);
    // A changed scene file changes the scene hash.
    let text = small_scene(16);
    assert!(text.contains("fov_y = 45"));
    std::fs::write(&scene, text.replace("fov_y = 45", "fov_y = 46")).unwrap();
    let changed = render("e.exr", "2/3", "0");
    let stderr = lightcuts_fails(&["assemble", s(&frame), s(&a), s(&b), s(&changed)]);
    assert!(stderr.contains("lightcuts:sceneHash"), "{stderr}");
    // Usage errors.
    for bad in ["3/3", "1/0", "x/2"] {
        // clap's usage errors exit 2.
        let output = lightcuts(&["render", s(&scene), "-o", s(&dir.path("u.exr")), "--tile", bad]);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(output.status.code() == Some(2) && stderr.contains("--tile"), "{stderr}");
    }
    let stderr =
        lightcuts_fails(&["render", s(&scene), "-o", s(&dir.path("u.exr")), "--tile", "12/13", "--resolution", "4x12"]);
    assert!(stderr.contains("--tile: 13 tiles of a frame 12 rows high"), "{stderr}");
}

/// Rewrites `from` into `to` with its data window moved to `origin` and
/// its display window's corner to `display` (as another tool might write
/// a tile), every attribute kept.
fn moved(from: &std::path::Path, to: &std::path::Path, origin: (i32, i32), display: (i32, i32)) {
    use exr::prelude::*;
    let mut image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(from)
        .unwrap();
    image.attributes.display_window.position = Vec2(display.0, display.1);
    image.layer_data[0].attributes.layer_position = Vec2(origin.0, origin.1);
    image.write().to_file(to).unwrap();
}

/// A tile from another tool whose data window reaches left of or above the
/// frame, or whose display window does not start at (0, 0): an error naming
/// the file, no frame, no panic.
#[test]
fn assemble_refuses_tiles_outside_the_frame() {
    let dir = TempDir::new("farm-outside");
    let scene = dir.write("s.toml", &small_scene(4));
    let render = |out: &str, tile: &str| render_tile(&dir, &scene, out, tile, &["--resolution", "16x12"]);
    let (a, b, c) = (render("a.exr", "0/3"), render("b.exr", "1/3"), render("c.exr", "2/3"));
    let frame = dir.path("frame.exr");
    for (name, origin, display, expect) in [
        (
            "left.exr",
            (-4, 0),
            (0, 0),
            "its data window x -4..12, y 0..4 is not inside its display window x 0..16, y 0..12",
        ),
        ("above.exr", (0, -1), (0, 0), "its data window x 0..16, y -1..3 is not inside"),
        ("right.exr", (2, 0), (0, 0), "its data window x 2..18, y 0..4 is not inside"),
        ("display.exr", (0, 0), (3, 2), "its display window starts at (3, 2)"),
    ] {
        let tile = dir.path(name);
        moved(&a, &tile, origin, display);
        let stderr = lightcuts_fails(&["assemble", s(&frame), s(&tile), s(&b), s(&c)]);
        assert!(stderr.contains(name) && stderr.contains(expect), "{stderr}");
        assert!(!frame.exists(), "no frame written on refusal");
    }
    // The same tile moved back to where it was assembles.
    let back = dir.path("back.exr");
    moved(&a, &back, (0, 0), (0, 0));
    lightcuts_ok(&["assemble", s(&frame), s(&back), s(&b), s(&c)]);
}

#[test]
fn no_overwrite_skips_existing_and_claimed_outputs_and_releases_its_claim() {
    let dir = TempDir::new("farm-claim");
    let scene = dir.write("s.toml", &small_scene(16));
    let out = dir.path("o.exr");
    let render =
        || lightcuts_ok(&["render", s(&scene), "-o", s(&out), "--no-overwrite", "--resolution", "8x6", "--quiet"]);
    render();
    assert!(out.exists() && !dir.path("o.exr.claim").exists(), "rendered, claim released: {:?}", dir.files());
    let before = std::fs::read(&out).unwrap();
    assert!(render().contains("exists, skipped"));
    assert_eq!(std::fs::read(&out).unwrap(), before, "an existing output is left alone");
    // Another process's claim: skipped, the claim left alone.
    std::fs::remove_file(&out).unwrap();
    std::fs::write(dir.path("o.exr.claim"), "pid 1 on elsewhere\n").unwrap();
    assert!(render().contains("claimed by another process, skipped"));
    assert!(!out.exists() && dir.path("o.exr.claim").exists());
    // A failed render releases its claim, so that a re-run tries again.
    std::fs::remove_file(dir.path("o.exr.claim")).unwrap();
    let bad = dir.write("bad.toml", "[film]\nwidth = 0\n");
    lightcuts_fails(&["render", s(&bad), "-o", s(&out), "--no-overwrite"]);
    assert!(!dir.path("o.exr.claim").exists() && !out.exists(), "{:?}", dir.files());
}

#[test]
fn assemble_refuses_tiles_through_different_cameras() {
    use serde_json::json;
    let dir = TempDir::new("farm-camera");
    let mut g = common::gltf::floor_and_point_light();
    let side = g.camera(json!({ "type": "perspective", "name": "side", "perspective": { "yfov": 0.6, "aspectRatio": 1.5, "znear": 0.1 } }));
    g.node(json!({ "camera": side, "translation": [0.0, 1.0, 8.0] }), true);
    let scene = dir.write("s.gltf", &g.embedded());
    let render = |out: &str, tile: &str, camera: &str| {
        render_tile(&dir, &scene, out, tile, &["--camera", camera, "--resolution", "12x8"])
    };
    let (a, b) = (render("a.exr", "0/2", "top"), render("b.exr", "1/2", "side"));
    let stderr = lightcuts_fails(&["assemble", s(&dir.path("f.exr")), s(&a), s(&b)]);
    assert!(stderr.contains("worldToCamera"), "{stderr}");
    let c = render("c.exr", "1/2", "top");
    lightcuts_ok(&["assemble", s(&dir.path("f.exr")), s(&a), s(&c)]);
}
