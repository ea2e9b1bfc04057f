//! The exact renderer, run as the real binary.

mod common;
use common::*;

/// A diffuse sphere of radius R seen from inside with a point light of
/// intensity I at its centre: every visible point has wi = n, cos = 1 and
/// distance R, so L = (k_d / pi) * I / R^2 everywhere.
#[test]
fn known_answer_sphere_seen_from_inside() {
    let dir = TempDir::new("known-answer");
    let (kd, intensity, radius) = ([0.5f32, 0.25, 0.8], [3.0f32, 2.0, 1.0], 2.0f32);
    let scene = dir.write(
        "inside.toml",
        &format!(
            r#"
[film]
width = 32
height = 24
spp = 2
[camera]
eye = [0.3, -0.2, 0.1]
look_at = [1, 0, 0.5]
fov_y = 60
[materials.inner]
albedo = {kd:?}
[[shapes]]
type = "sphere"
center = [0, 0, 0]
radius = {radius}
segments = 512
material = "inner"
[[lights]]
type = "point"
position = [0, 0, 0]
intensity = {intensity:?}
"#
        ),
    );
    let out = dir.path("inside.exr");
    lightcuts_ok(&["render", s(&scene), "-o", s(&out), "--exact", "--quiet"]);
    let image = read_exr(&out).unwrap();
    for (c, name) in ["R", "G", "B"].iter().enumerate() {
        let expected = kd[c] / std::f32::consts::PI * intensity[c] / (radius * radius);
        for &v in image.channel(&out, name).unwrap() {
            // The tessellation (512 segments) moves points by at most 2e-5 R.
            assert!((v - expected).abs() <= 1e-3 * expected, "{name}: {v} vs {expected}");
        }
    }
    assert!(image.channel(&out, "A").unwrap().iter().all(|&a| a == 1.0));
}

#[test]
fn exr_has_every_channel_and_attribute_and_a_png_preview() {
    let dir = TempDir::new("channels");
    let scene = dir.write("small.toml", &small_scene(3));
    let (out, png) = (dir.path("small.exr"), dir.path("small.png"));
    let stdout =
        lightcuts_ok(&["render", s(&scene), "-o", s(&out), "--exact", "--png", s(&png), "--seed", "7", "--spp", "2"]);
    assert!(stdout.contains("shadow rays/s"), "statistics block: {stdout}");
    let image = read_exr(&out).unwrap();
    let names: Vec<&str> = image.channels.keys().map(String::as_str).collect();
    assert_eq!(names, ["A", "B", "G", "N.X", "N.Y", "N.Z", "R", "Z", "albedo.B", "albedo.G", "albedo.R"]);
    assert_eq!((image.width, image.height), (96, 72));
    assert_eq!(image.attributes["lightcuts:renderMode"], "exact");
    assert_eq!(image.attributes["lightcuts:lights"], "9");
    assert_eq!(image.attributes["lightcuts:seed"], "7");
    assert_eq!(image.attributes["lightcuts:samplesPerPixel"], "2");
    assert!(image.attributes["software"].starts_with("lightcuts "));
    assert!(image.attributes["lightcuts:sceneFile"].ends_with("small.toml"));
    assert!(image.attributes["lightcuts:renderTimeSeconds"].parse::<f64>().unwrap() > 0.0);
    for (name, values) in &image.channels {
        assert!(values.iter().all(|v| v.is_finite()), "{name} has a non-finite value");
    }
    // The image is not black, and the floor's normal points up.
    assert!(image.channel(&out, "R").unwrap().iter().any(|&v| v > 0.01));
    let ny = image.channel(&out, "N.Y").unwrap();
    assert!((ny[ny.len() - 1] - 1.0).abs() < 1e-5, "bottom-right pixel sees the floor");
    let decoder = png::Decoder::new(std::fs::File::open(&png).unwrap());
    let info = decoder.read_info().unwrap();
    assert_eq!((info.info().width, info.info().height), (96, 72));
    // Only the two outputs are left in the directory: no temporary files.
    assert_eq!(dir.files(), ["small.exr", "small.png", "small.toml"]);
}

#[test]
fn half_floats_for_the_beauty_only() {
    let dir = TempDir::new("half");
    let scene = dir.write("small.toml", &small_scene(2));
    let out = dir.path("half.exr");
    lightcuts_ok(&["render", s(&scene), "-o", s(&out), "--exact", "--half", "--quiet", "--resolution", "16x12"]);
    let header = exr::meta::MetaData::read_from_file(&out, false).unwrap();
    for channel in &header.headers[0].channels.list {
        let expected = if ["R", "G", "B", "A"].contains(&channel.name.to_string().as_str()) {
            exr::meta::attribute::SampleType::F16
        } else {
            exr::meta::attribute::SampleType::F32
        };
        assert_eq!(channel.sample_type, expected, "{}", channel.name);
    }
}

fn pixels(image: &ExrImage, name: &str) -> Vec<u32> {
    image.channels[name].iter().map(|v| v.to_bits()).collect()
}

#[test]
fn any_thread_count_and_window_give_the_same_bits() {
    let dir = TempDir::new("threads");
    let scene = dir.write("small.toml", &small_scene(4));
    assert_same_bits_for_any_threads_and_window(&dir, &scene, 96, &["--exact", "--spp", "2"]);
}

#[test]
fn command_line_overrides_apply() {
    let dir = TempDir::new("overrides");
    let scene = dir.write("small.toml", &small_scene(2));
    let (a, b) = (dir.path("a.exr"), dir.path("b.exr"));
    lightcuts_ok(&["render", s(&scene), "-o", s(&a), "--exact", "--quiet", "--resolution", "40x30", "--seed", "1"]);
    lightcuts_ok(&["render", s(&scene), "-o", s(&b), "--exact", "--quiet", "--resolution", "40x30", "--seed", "2"]);
    let (a, b) = (read_exr(&a).unwrap(), read_exr(&b).unwrap());
    assert_eq!((a.width, a.height), (40, 30));
    assert_ne!(pixels(&a, "R"), pixels(&b, "R"), "the seed moves the samples");
}

/// The hot paths run compiled for AVX2 + FMA where the CPU has them and
/// for baseline x86-64 otherwise (`util::simd::best`): both must give the
/// same image to the bit, in every mode, on a scene with every light kind
/// (point, oriented, spot, directional), a glossy lobe and light groups.
/// `LIGHTCUTS_BASELINE_SIMD` forces the baseline path.
#[test]
fn the_avx2_and_the_baseline_paths_give_the_same_bits() {
    let dir = TempDir::new("simd-paths");
    let scene = dir.write(
        "kinds.toml",
        r#"
[film]
width = 64
height = 48
spp = 2
[camera]
eye = [0, 1.5, 5]
look_at = [0, 0.6, 0]
fov_y = 40
[materials.glossy]
albedo = [0.5, 0.5, 0.5]
specular = [0.3, 0.3, 0.3]
exponent = 40
[materials.red]
albedo = [0.7, 0.2, 0.1]
[[shapes]]
type = "quad"
corner = [-5, 0, 5]
u = [10, 0, 0]
v = [0, 0, -10]
material = "glossy"
[[shapes]]
type = "sphere"
center = [0, 0.6, 0]
radius = 0.6
material = "red"
[[lights]]
type = "grid"
group = "fill"
corner = [2.5, 0.3, 2]
u = [0, 0, -3]
v = [0, 2, 0]
count = [20, 20]
intensity = [0.001, 0.0012, 0.0014]
[[lights]]
type = "area"
group = "key"
corner = [-2.5, 2.5, 1.5]
u = [1, 0, 0]
v = [0, 0, -1]
radiance = [4, 4, 4]
samples = 256
[[lights]]
type = "spot"
group = "key"
position = [1, 3, 1]
direction = [-0.3, -1, -0.2]
intensity = [6, 5, 4]
outer_angle = 30
[environment]
radiance = [0.05, 0.07, 0.1]
samples = 256
group = "sky"
"#,
    );
    for mode in ["--exact", "--bounded", "--stochastic"] {
        let render = |name: &str, baseline: bool| {
            let out = dir.path(name);
            let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_lightcuts"));
            command.args(["render", s(&scene), "-o", s(&out), "--quiet", mode]);
            command.env_remove("LIGHTCUTS_BASELINE_SIMD");
            if baseline {
                command.env("LIGHTCUTS_BASELINE_SIMD", "1");
            }
            let output = command.output().expect("run lightcuts");
            assert!(output.status.success(), "{mode}: {}", String::from_utf8_lossy(&output.stderr));
            read_exr(&out).unwrap()
        };
        let (best, baseline) = (render("best.exr", false), render("baseline.exr", true));
        assert_eq!(best.channels.keys().collect::<Vec<_>>(), baseline.channels.keys().collect::<Vec<_>>());
        for (name, values) in &best.channels {
            let other = &baseline.channels[name];
            let differ = values.iter().zip(other).position(|(a, b)| a.to_bits() != b.to_bits());
            if let Some(i) = differ {
                panic!("{mode}, channel {name}, sample {i}: {} (best) vs {} (baseline)", values[i], other[i]);
            }
        }
    }
}
