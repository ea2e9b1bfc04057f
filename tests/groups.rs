//! Light groups and Cryptomatte, through the real binary: the group layers
//! sum to the beauty in every mode, the bounded cut holds each group to its
//! own error, and the mattes decode (with the specification's algorithm) to
//! the objects' silhouettes.

mod common;

use common::{channel, lightcuts, lightcuts_fails, lightcuts_ok, matte, read_exr, s, ExrImage, TempDir};
use lightcuts::render::cryptomatte::{id_of, CryptoType};

/// A floor and a wall under a bright warm key (a point light), a dim cool
/// fill (a 20 x 20 grid, more lights than are evaluated one by one, ten
/// times weaker in all) and a sky in a third
/// group; one-bounce VPLs.
const SCENE: &str = r#"
[film]
width = 48
height = 32
spp = 1
[camera]
eye = [0, 1.5, 5]
look_at = [0, 0.6, 0]
fov_y = 40
[materials.grey]
albedo = [0.6, 0.6, 0.6]
[materials.red]
albedo = [0.7, 0.2, 0.1]
[[shapes]]
type = "quad"
name = "floor"
corner = [-5, 0, 5]
u = [10, 0, 0]
v = [0, 0, -10]
material = "grey"
[[shapes]]
type = "quad"
name = "wall"
corner = [-5, 0, -2]
u = [10, 0, 0]
v = [0, 3, 0]
material = "grey"
[[shapes]]
type = "sphere"
name = "ball"
center = [0, 0.6, 0]
radius = 0.6
material = "red"
[[lights]]
type = "point"
group = "key"
position = [-2, 3, 2]
intensity = [8, 7, 6]
[[lights]]
type = "grid"
group = "fill"
corner = [2.5, 0.3, 2]
u = [0, 0, -3]
v = [0, 2, 0]
count = [20, 20]
intensity = [0.0007, 0.001, 0.0014]
[environment]
radiance = [0.05, 0.07, 0.1]
samples = 512
group = "sky"
[indirect]
paths = 3000
[render]
distance_clamp = 0.2
"#;

const GROUPS: [&str; 3] = ["key", "fill", "sky"];

fn render(dir: &TempDir, name: &str, extra: &[&str]) -> ExrImage {
    let scene = dir.path("groups.toml");
    if !scene.exists() {
        dir.write("groups.toml", SCENE);
    }
    common::render(&scene, &dir.path(name), extra)
}

/// Largest |sum of the group layers - beauty| relative to the beauty's
/// brightest value, over pixels and channels.
fn sum_mismatch(image: &ExrImage) -> f64 {
    let mut worst = 0.0f64;
    for c in ["R", "G", "B"] {
        let beauty = channel(image, c);
        let scale = beauty.iter().fold(0.0f32, |m, &v| m.max(v.abs())).max(1e-30);
        for (i, &b) in beauty.iter().enumerate() {
            let sum: f32 = GROUPS.iter().map(|g| channel(image, &format!("Combined_{g}.{c}"))[i]).sum();
            worst = worst.max(f64::from((sum - b).abs() / scale));
        }
    }
    worst
}

/// Mean |test - reference| / reference of a group's luminance over the
/// pixels where the reference group is at least 1% of its mean.
fn group_error(test: &ExrImage, reference: &ExrImage, group: &str) -> f64 {
    let lum = |i: &ExrImage| -> Vec<f64> {
        let [r, g, b] = ["R", "G", "B"].map(|c| channel(i, &format!("Combined_{group}.{c}")));
        (0..r.len()).map(|k| 0.2126 * f64::from(r[k]) + 0.7152 * f64::from(g[k]) + 0.0722 * f64::from(b[k])).collect()
    };
    let (t, r) = (lum(test), lum(reference));
    let mean = r.iter().sum::<f64>() / r.len() as f64;
    let pixels: Vec<f64> =
        t.iter().zip(&r).filter(|(_, &r)| r > 0.01 * mean).map(|(&t, &r)| (t - r).abs() / r).collect();
    pixels.iter().sum::<f64>() / pixels.len() as f64
}

#[test]
fn group_layers_sum_to_the_beauty_in_every_mode_and_hold_their_own_light() {
    let dir = TempDir::new("groups");
    let exact = render(&dir, "exact.exr", &["--exact"]);
    let bounded = render(&dir, "bounded.exr", &["--bounded"]);
    let stochastic = render(&dir, "stochastic.exr", &["--stochastic", "--spp", "4"]);
    for (mode, image) in [("exact", &exact), ("bounded", &bounded), ("stochastic", &stochastic)] {
        let names: Vec<&String> = image.channels.keys().filter(|n| n.starts_with("Combined_")).collect();
        assert_eq!(names.len(), 9, "{mode}: three RGB group layers: {names:?}");
        let mismatch = sum_mismatch(image);
        assert!(mismatch < 1e-5, "{mode}: groups sum to the beauty to float rounding, off by {mismatch:e}");
    }
    // Each group has light of its own where the others have little: the key
    // is warm and bright, the fill cool and dim, the sky lights the floor.
    let mean = |i: &ExrImage, c: &str| channel(i, c).iter().map(|&v| f64::from(v)).sum::<f64>();
    let (key, fill) = (mean(&exact, "Combined_key.G"), mean(&exact, "Combined_fill.G"));
    assert!(key > 3.0 * fill && fill > 0.0, "key {key}, fill {fill}");
    assert!(mean(&exact, "Combined_fill.B") > mean(&exact, "Combined_fill.R"), "the fill is cool");
    assert!(mean(&exact, "Combined_sky.B") > 0.0);
    // The bounded cut holds every group, the dim fill too, near its own light.
    for group in GROUPS {
        let e = group_error(&bounded, &exact, group);
        assert!(e < 0.03, "bounded {group}: mean relative error {e}");
    }
}

#[test]
fn per_group_error_control_holds_the_dim_group_closer_than_the_pixel_threshold() {
    let dir = TempDir::new("group-error");
    let exact = render(&dir, "exact.exr", &["--exact"]);
    let per_group = render(&dir, "group.exr", &["--bounded", "--group-error", "group"]);
    let per_pixel = render(&dir, "pixel.exr", &["--bounded", "--group-error", "pixel"]);
    let (g, p) = (group_error(&per_group, &exact, "fill"), group_error(&per_pixel, &exact, "fill"));
    assert!(g < p, "the fill's own threshold is tighter: {g} vs {p}");
    let nodes = |i: &ExrImage| channel(i, "lightcuts.cut_size").iter().map(|&v| f64::from(v)).sum::<f64>();
    assert!(nodes(&per_group) > nodes(&per_pixel), "and costs more nodes");
    assert_eq!(per_pixel.attributes["lightcuts:renderMode"], "lightcuts error=0.02 max_cut=1000 group_error=pixel");
    // The stochastic cut too: a cut per group is larger than one through all,
    // and both split into layers that sum to the beauty.
    let stochastic = |name: &str, error: &str| {
        let image = render(&dir, name, &["--stochastic", "--spp", "2", "--group-error", error]);
        assert!(sum_mismatch(&image) < 1e-5, "stochastic, --group-error {error}");
        nodes(&image)
    };
    let (g, p) = (stochastic("sg.exr", "group"), stochastic("sp.exr", "pixel"));
    assert!(g > p, "stochastic cut nodes: per group {g}, per pixel {p}");
}

#[test]
fn a_scene_without_groups_writes_no_group_layer_and_aovs_can_leave_them_out() {
    let dir = TempDir::new("no-groups");
    let plain = dir.write("plain.toml", &SCENE.replace("group = ", "# group = "));
    let out = dir.path("plain.exr");
    lightcuts_ok(&["render", s(&plain), "-o", s(&out), "-q"]);
    let image = read_exr(&out).unwrap();
    assert!(!image.channels.keys().any(|n| n.starts_with("Combined_")), "{:?}", image.channels.keys());
    let without = render(&dir, "without.exr", &["--aovs", "albedo"]);
    assert!(!without.channels.keys().any(|n| n.starts_with("Combined_")));
}

#[test]
fn a_bad_group_is_an_error_naming_the_file_and_field() {
    let dir = TempDir::new("bad-group");
    let bad = dir.write("bad.toml", &SCENE.replace(r#"group = "fill""#, r#"group = "fill.light""#));
    let out = dir.path("bad.exr");
    let e = lightcuts_fails(&["render", s(&bad), "-o", s(&out)]);
    assert!(e.contains("bad.toml") && e.contains("lights[1].group") && e.contains("fill.light"), "{e}");
    assert!(!out.exists());
    let typed = dir.write("typed.toml", &SCENE.replace(r#"group = "key""#, "group = 3"));
    let e = lightcuts_fails(&["render", s(&typed), "-o", s(&out)]);
    assert!(e.contains("lights[0].group") && e.contains("string"), "{e}");
}

#[test]
fn cryptomatte_decodes_to_each_objects_silhouette() {
    let dir = TempDir::new("cryptomatte");
    let image = render(&dir, "crypto.exr", &["--exact", "--cryptomatte", "--spp", "16", "--aovs", "Z"]);
    // Header: each type's name, hash, conversion and a manifest with its names.
    for kind in CryptoType::ALL {
        let key = kind.key();
        let attribute = |f: &str| image.attributes[&format!("cryptomatte/{key}/{f}")].clone();
        assert_eq!(attribute("name"), kind.name());
        assert_eq!(attribute("hash"), "MurmurHash3_32");
        assert_eq!(attribute("conversion"), "uint32_to_float32");
        let manifest: std::collections::BTreeMap<String, String> =
            serde_json::from_str(&attribute("manifest")).unwrap();
        let names: Vec<&str> = match kind {
            CryptoType::Object => vec!["ball", "floor", "wall"],
            CryptoType::Material => vec!["grey", "red"],
        };
        assert_eq!(manifest.keys().map(String::as_str).collect::<Vec<_>>(), names);
        for (name, hex) in &manifest {
            assert_eq!(*hex, format!("{:08x}", id_of(name).to_bits()));
        }
    }
    let (width, height) = (48usize, 32usize);
    let objects = ["ball", "floor", "wall"].map(|n| matte(&image, CryptoType::Object, n));
    let alpha = channel(&image, "A");
    for i in 0..width * height {
        // Every sample hits one of the three: coverages sum to the alpha, 1.
        let sum: f32 = objects.iter().map(|m| m[i]).sum();
        assert!((sum - alpha[i]).abs() < 1e-5 && (alpha[i] - 1.0).abs() < 1e-6, "pixel {i}: {sum} vs {}", alpha[i]);
    }
    // The ball's matte is its silhouette: 1 well inside the projected disc,
    // 0 well outside, between only near its edge. The silhouette is found by
    // intersecting the camera's rays through the pixel's corners with the
    // sphere (the scene's camera, from the library).
    let scene = lightcuts::scene::Scene::load(&dir.path("groups.toml")).unwrap();
    let camera = scene.camera(width as u32, height as u32);
    let hits_ball = |x: f32, y: f32| {
        let ray = camera.ray(x, y);
        let (o, d) = (ray.origin - glam::Vec3::new(0.0, 0.6, 0.0), ray.direction.normalize());
        let b = o.dot(d);
        b * b - (o.length_squared() - 0.36) > 0.0 && b < 0.0
    };
    let (mut inside, mut outside, mut edge) = (0, 0, 0);
    for y in 0..height {
        for x in 0..width {
            let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                .map(|(dx, dy)| hits_ball(x as f32 + dx, y as f32 + dy))
                .iter()
                .filter(|&&h| h)
                .count();
            let value = objects[0][y * width + x];
            match corners {
                4 => {
                    inside += 1;
                    assert_eq!(value, 1.0, "pixel ({x}, {y}) inside the ball");
                }
                0 => {
                    outside += 1;
                    assert_eq!(value, 0.0, "pixel ({x}, {y}) outside the ball");
                }
                _ => {
                    edge += 1;
                    assert!((0.0..=1.0).contains(&value), "pixel ({x}, {y}): {value}");
                }
            }
        }
    }
    assert!(inside > 20 && outside > 500 && edge > 10, "{inside} inside, {outside} outside, {edge} on the edge");
    // Materials: the ball is the only red object.
    let red = matte(&image, CryptoType::Material, "red");
    assert_eq!(red, objects[0], "the red matte is the ball's");
}

#[test]
fn tiles_and_threads_leave_the_group_layers_and_the_mattes_bit_identical() {
    let dir = TempDir::new("groups-tiles");
    // One thread for the whole frame, every CPU for the tiles: the same bits.
    let whole = render(&dir, "whole.exr", &["--cryptomatte", "--threads", "1"]);
    let scene = dir.path("groups.toml");
    let mut tiles = Vec::new();
    for i in 0..2 {
        let tile = dir.path(&format!("tile{i}.exr"));
        lightcuts_ok(&["render", s(&scene), "-o", s(&tile), "-q", "--cryptomatte", "--tile", &format!("{i}/2")]);
        tiles.push(tile);
    }
    let out = dir.path("assembled.exr");
    let output = lightcuts(&["assemble", s(&out), s(&tiles[0]), s(&tiles[1])]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let assembled = read_exr(&out).unwrap();
    assert_eq!(assembled.channels.keys().collect::<Vec<_>>(), whole.channels.keys().collect::<Vec<_>>());
    for (name, values) in &whole.channels {
        assert_eq!(&assembled.channels[name], values, "{name}: bit for bit");
    }
    let crypto = |i: &ExrImage| {
        i.attributes
            .iter()
            .filter(|(k, _)| k.starts_with("cryptomatte/"))
            .map(|(k, v)| (k.clone(), v.clone()))
            .collect::<Vec<_>>()
    };
    assert_eq!(crypto(&assembled), crypto(&whole));
    assert_eq!(crypto(&whole).len(), 8);
}

#[test]
fn with_paths_the_group_layers_sum_to_the_beauty_and_tiles_keep_their_bits() {
    // A path's light is credited to the group of the light each vertex's
    // next-event estimate found (docs/design.md §6.7): the layers still sum
    // to the beauty, each group keeps its bounced light (the key's, off the
    // red ball onto the wall), and tiles assemble to the one-process bits.
    let dir = TempDir::new("groups-paths");
    let paths = ["--indirect", "path", "--max-depth", "4"];
    for mode in ["--stochastic", "--exact", "--bounded"] {
        let image = render(&dir, "paths.exr", &[&paths[..], &[mode, "--spp", "2"]].concat());
        let mismatch = sum_mismatch(&image);
        assert!(mismatch < 1e-5, "{mode}: groups sum to the beauty to float rounding, off by {mismatch:e}");
    }
    let mean = |i: &ExrImage, c: &str| channel(i, c).iter().map(|&v| f64::from(v)).sum::<f64>();
    let with = render(&dir, "with.exr", &[&paths[..], &["--stochastic", "--spp", "8"]].concat());
    let without = render(&dir, "without.exr", &["--stochastic", "--spp", "8", "--indirect", "none"]);
    for group in GROUPS {
        let (a, b) = (mean(&with, &format!("Combined_{group}.G")), mean(&without, &format!("Combined_{group}.G")));
        assert!(a > 1.05 * b, "{group}: paths add bounced light to its layer: {a} vs {b}");
    }
    let whole = render(&dir, "whole.exr", &[&paths[..], &["--stochastic", "--cryptomatte", "--threads", "1"]].concat());
    let scene = dir.path("groups.toml");
    let mut tiles = Vec::new();
    for i in 0..2 {
        let tile = dir.path(&format!("tile{i}.exr"));
        let args = [&["render", s(&scene), "-o", s(&tile), "-q", "--stochastic", "--cryptomatte"][..], &paths[..]];
        lightcuts_ok(&[&args.concat()[..], &["--tile", &format!("{i}/2")]].concat());
        tiles.push(tile);
    }
    let out = dir.path("assembled.exr");
    let output = lightcuts(&["assemble", s(&out), s(&tiles[0]), s(&tiles[1])]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let assembled = read_exr(&out).unwrap();
    for (name, values) in &whole.channels {
        assert_eq!(&assembled.channels[name], values, "{name}: bit for bit");
    }
}
