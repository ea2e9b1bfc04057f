//! Helpers for tests that run the real `lightcuts` binary.
#![allow(dead_code, unused_imports)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub use lightcuts::output::read::{read_exr, ExrImage};
pub use lightcuts::scene::builder::{floor_spheres_grid, SceneText};

pub mod glossy;
pub mod gltf;

/// A fresh temporary directory (tempfile's), removed on drop, with helpers
/// for the files a test writes into it.
pub struct TempDir(tempfile::TempDir);

impl TempDir {
    pub fn new(name: &str) -> Self {
        Self(tempfile::Builder::new().prefix(&format!("lightcuts-it-{name}-")).tempdir().unwrap())
    }

    pub fn path(&self, name: &str) -> PathBuf {
        self.0.path().join(name)
    }

    pub fn write(&self, name: &str, text: &str) -> PathBuf {
        let path = self.path(name);
        std::fs::write(&path, text).unwrap();
        path
    }

    /// Every file in the directory.
    pub fn files(&self) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(self.0.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }
}

pub fn lightcuts(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lightcuts")).args(args).output().expect("run lightcuts")
}

/// How a run under limits ended.
#[derive(Debug)]
pub struct Limited {
    /// The exit code; None when a signal ended it (an abort, or the kill at the deadline).
    pub code: Option<i32>,
    pub stdout: String,
    pub stderr: String,
    /// Whether it was still running at the deadline (then killed).
    pub timed_out: bool,
}

/// Runs lightcuts with at most `memory_mib` MiB of address space
/// (`prlimit --as`, util-linux's, on every Debian: an allocation past it
/// fails, which aborts a Rust process) and `seconds` of wall-clock time
/// (then it is killed): what a hostile input must not exceed.
pub fn lightcuts_limited(args: &[&str], memory_mib: u64, seconds: u64) -> Limited {
    use std::io::Read;
    let mut child = Command::new("prlimit")
        .arg(format!("--as={}", memory_mib << 20))
        .arg(env!("CARGO_BIN_EXE_lightcuts"))
        .args(args)
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("run prlimit (util-linux)");
    // Both pipes drained while waiting, so that a chatty child cannot block.
    let mut out = child.stdout.take().unwrap();
    let mut err = child.stderr.take().unwrap();
    let out_thread = std::thread::spawn(move || {
        let mut text = String::new();
        let _ = out.read_to_string(&mut text);
        text
    });
    let err_thread = std::thread::spawn(move || {
        let mut text = String::new();
        let _ = err.read_to_string(&mut text);
        text
    });
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(seconds);
    let mut timed_out = false;
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if std::time::Instant::now() >= deadline {
            timed_out = true;
            let _ = child.kill();
            break child.wait().unwrap();
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    };
    Limited { code: status.code(), stdout: out_thread.join().unwrap(), stderr: err_thread.join().unwrap(), timed_out }
}

/// [`lightcuts_limited`] within 1 GiB and 30 s, asserted to end by itself
/// with exit 1 and one error line naming each of `expect`.
pub fn refused_within_limits(args: &[&str], expect: &[&str]) -> String {
    let run = lightcuts_limited(args, 1024, 30);
    assert!(!run.timed_out, "lightcuts {args:?} still ran after 30 s");
    assert_eq!(run.code, Some(1), "lightcuts {args:?} (exit {:?}): {}", run.code, run.stderr);
    let errors: Vec<&str> = run.stderr.lines().filter(|l| l.starts_with("error")).collect();
    assert_eq!(errors.len(), 1, "one error line: {}", run.stderr);
    for e in expect {
        assert!(errors[0].contains(e), "'{e}' missing from: {}", errors[0]);
    }
    run.stderr
}

/// Runs lightcuts and asserts success, returning stdout.
pub fn lightcuts_ok(args: &[&str]) -> String {
    let out = lightcuts(args);
    assert!(out.status.success(), "lightcuts {args:?} failed:\n{}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Runs lightcuts, asserts a clean failure (non-zero, no panic), returns stderr.
pub fn lightcuts_fails(args: &[&str]) -> String {
    let out = lightcuts(args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success(), "lightcuts {args:?} should fail");
    assert_eq!(out.status.code(), Some(1), "exit code for {args:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "panic for {args:?}: {stderr}");
    assert!(stderr.starts_with("error: "), "one clear message expected: {stderr}");
    stderr
}

/// Asserts that a render's summary (its stdout) counts no value that was
/// NaN or infinite when the film stored it: the film turns such a value
/// into a finite one, so the EXR alone cannot show it.
pub fn assert_no_value_was_non_finite(stdout: &str) {
    let line = stdout.lines().find(|l| l.trim_start().starts_with("non-finite")).expect("the summary counts them");
    assert!(line.split_whitespace().nth(1) == Some("0"), "NaN or Inf reached the film: {line}");
}

/// Renders `scene` to `out` with `flags` (on top of `--quiet`), asserts
/// that it succeeded, that its summary counts no value that was NaN or
/// infinite and that every value of the EXR is finite, and reads it.
pub fn render(scene: &Path, out: &Path, flags: &[&str]) -> ExrImage {
    let stdout = lightcuts_ok(&[&["render", s(scene), "-o", s(out), "--quiet"][..], flags].concat());
    assert_no_value_was_non_finite(&stdout);
    let image = read_exr(out).unwrap();
    for (channel, values) in &image.channels {
        assert!(values.iter().all(|v| v.is_finite()), "{} {flags:?}: channel {channel} has NaN or Inf", out.display());
    }
    image
}

/// The named channel of `image`; a panic naming it when there is none.
/// The Cryptomatte matte of `name` (an object's or a material's, as
/// `kind` says) by the specification's decoding: per pixel, the sum of the
/// coverages of the ranks whose ID is `name`'s.
pub fn matte(image: &ExrImage, kind: lightcuts::render::cryptomatte::CryptoType, name: &str) -> Vec<f32> {
    let id = lightcuts::render::cryptomatte::id_of(name).to_bits();
    let ranks: Vec<(&[f32], &[f32])> =
        kind.channels().chunks(2).map(|pair| (channel(image, &pair[0]), channel(image, &pair[1]))).collect();
    (0..image.width * image.height)
        .map(|i| ranks.iter().filter(|(ids, _)| ids[i].to_bits() == id).map(|(_, coverage)| coverage[i]).sum())
        .collect()
}

pub fn channel<'a>(image: &'a ExrImage, name: &str) -> &'a [f32] {
    image.channels.get(name).unwrap_or_else(|| panic!("no channel {name}: {:?}", image.channels.keys()))
}

/// The mean of each of R, G, B over the image.
pub fn means(image: &ExrImage) -> [f64; 3] {
    ["R", "G", "B"].map(|c| {
        let values = channel(image, c);
        values.iter().map(|&v| f64::from(v)).sum::<f64>() / values.len() as f64
    })
}

/// The mean relative error of `test` against `reference`, by `lightcuts
/// compare` (the figure the README's tables give).
pub fn mean_error(test: &Path, reference: &Path) -> f64 {
    let out = lightcuts_ok(&["compare", s(test), s(reference), "--json"]);
    let c: serde_json::Value = serde_json::from_str(&out).unwrap();
    c["mean_relative_error"].as_f64().unwrap()
}

pub fn s(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// The repository's scenes directory.
pub fn scenes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

/// A small scene: floor, two spheres, a grid of point lights (the
/// library's [`floor_spheres_grid`], as text).
pub fn small_scene(lights_per_side: u32) -> String {
    floor_spheres_grid(lights_per_side).toml()
}

/// Lights of the known-answer scene: on a sphere of this radius (metres)
/// around the centre of the receiving sphere of radius 2.
pub const SHELL_RADIUS: f32 = 0.5;
/// How many: more than a tree evaluated light by light, so a cut refines.
pub const SHELL_LIGHTS: usize = 1000;

/// [`SHELL_LIGHTS`] point lights spread evenly over a sphere of radius
/// [`SHELL_RADIUS`] (a Fibonacci lattice), (3, 6, 9) W/sr in all, at the
/// centre of a diffuse sphere of radius R = 2 (albedo 0.5) seen from inside
/// on a `width` x `height` film. By Newton's shell theorem, a uniform shell
/// of isotropic sources inside a sphere gives every point of the sphere the
/// irradiance of the same sources at the centre, I / R^2: every pixel has
/// the known answer L = k_d / pi * sum(I) / R^2 (see
/// [`assert_inside_sphere_answer`]); the lattice's sum is within 1e-5 of
/// the shell's integral at these sizes. The lights are apart, so every cut
/// mode must refine to reach it.
pub fn inside_sphere_scene(width: u32, height: u32) -> String {
    inside_sphere_with(width, height, &shell_lights(SHELL_LIGHTS, f64::from(SHELL_RADIUS), [3.0, 6.0, 9.0]))
}

/// The diffuse sphere of radius 2 (albedo 0.5) seen from inside, with
/// `lights` (TOML) inside it.
pub fn inside_sphere_with(width: u32, height: u32, lights: &str) -> String {
    SceneText::new(width, height)
        .camera([0.2, 0.1, 0.0], [1.0, 0.0, 0.4], 60.0)
        .material("inner", [0.5, 0.5, 0.5], "")
        .raw("[[shapes]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 2\nsegments = 512\nmaterial = \"inner\"\n")
        .raw(lights)
        .toml()
}

/// `count` point lights on a Fibonacci lattice over the sphere of `radius`
/// around the origin, `total` W/sr in all (TOML).
pub fn shell_lights(count: usize, radius: f64, total: [f64; 3]) -> String {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let n = count as f64;
    let mut text = String::new();
    for i in 0..count {
        let z = 1.0 - 2.0 * (i as f64 + 0.5) / n;
        let (r, phi) = ((1.0 - z * z).sqrt(), golden * i as f64);
        let [x, y, z] = [radius * r * phi.cos(), radius * r * phi.sin(), radius * z];
        let [a, b, c] = total.map(|t| t / n);
        text +=
            &format!("[[lights]]\ntype = \"point\"\nposition = [{x}, {y}, {z}]\nintensity = [{a:e}, {b:e}, {c:e}]\n");
    }
    text
}

/// The radiance every pixel of [`inside_sphere_with`] has when its lights
/// are uniform shells (or points at the centre) of `total` W/sr in all:
/// k_d / pi * sum(I) / R^2, per channel.
#[must_use]
pub fn inside_sphere_answer(total: [f64; 3]) -> [f64; 3] {
    total.map(|t| 0.5 / std::f64::consts::PI * t / 4.0)
}

/// Asserts that every pixel of a render of [`inside_sphere_scene`] is the
/// known answer to `tolerance` (relative), channel by channel; returns the
/// largest relative error found.
pub fn assert_inside_sphere_answer(path: &Path, image: &ExrImage, tolerance: f32) -> f32 {
    assert_inside_sphere_is(path, image, inside_sphere_answer([3.0, 6.0, 9.0]), f64::from(tolerance)) as f32
}

/// Asserts that every pixel of `image` is `expected` to `tolerance`
/// (relative), channel by channel; returns the largest relative error.
pub fn assert_inside_sphere_is(path: &Path, image: &ExrImage, expected: [f64; 3], tolerance: f64) -> f64 {
    let mut worst = 0.0f64;
    for (c, name) in ["R", "G", "B"].iter().enumerate() {
        for &v in image.channel(path, name).unwrap() {
            let error = (f64::from(v) - expected[c]).abs() / expected[c];
            assert!(error <= tolerance, "{}: {name}: {v} vs {} ({error} > {tolerance})", path.display(), expected[c]);
            worst = worst.max(error);
        }
    }
    worst
}

/// Rec. 709 luminance of every pixel of `image`.
pub fn luminance(image: &ExrImage) -> Vec<f64> {
    let (r, g, b) = (&image.channels["R"], &image.channels["G"], &image.channels["B"]);
    (0..r.len()).map(|i| 0.2126 * f64::from(r[i]) + 0.7152 * f64::from(g[i]) + 0.0722 * f64::from(b[i])).collect()
}

/// Mean relative error of `test`'s luminance against `reference`'s, over
/// the pixels brighter than a thousandth of the reference's mean.
pub fn mean_relative_error(test: &ExrImage, reference: &ExrImage) -> f64 {
    let (t, r) = (luminance(test), luminance(reference));
    let mean = r.iter().sum::<f64>() / r.len() as f64;
    let errors: Vec<f64> =
        t.iter().zip(&r).filter(|(_, &r)| r > 1e-3 * mean).map(|(&t, &r)| (t - r).abs() / r).collect();
    errors.iter().sum::<f64>() / errors.len() as f64
}

/// Renders `scene` (a `width`-pixel-wide film) with `args` on one thread,
/// on two and on three, and on the window x 13..61, y 7..50 (which does not
/// align with the 16-pixel tiles), and asserts that every channel of every
/// render has the same bits as the one-thread render's pixels.
pub fn assert_same_bits_for_any_threads_and_window(dir: &TempDir, scene: &Path, width: usize, args: &[&str]) {
    let render = |name: &str, more: &[&str]| {
        let out = dir.path(name);
        lightcuts_ok(&[&["render", s(scene), "-o", s(&out), "--quiet"][..], args, more].concat());
        read_exr(&out).unwrap()
    };
    let one = render("threads1.exr", &["--threads", "1"]);
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    for threads in ["2", "3"] {
        let other = render(&format!("threads{threads}.exr"), &["--threads", threads]);
        assert_eq!(one.channels.keys().collect::<Vec<_>>(), other.channels.keys().collect::<Vec<_>>());
        for (name, values) in &one.channels {
            assert_eq!(bits(values), bits(&other.channels[name]), "{name}: 1 vs {threads} threads");
        }
    }
    let window = render("window.exr", &["--pixel-bounds", "13,61,7,50"]);
    assert_eq!((window.x0, window.y0, window.width, window.height), (13, 7, 48, 43));
    for (name, values) in &one.channels {
        for y in 0..43 {
            for x in 0..48 {
                let (a, b) = (values[(y + 7) * width + x + 13], window.channels[name][y * 48 + x]);
                assert_eq!(a.to_bits(), b.to_bits(), "{name} at ({}, {})", x + 13, y + 7);
            }
        }
    }
}

/// Renders `scene` with `args` as `bands` horizontal tiles (`--tile
/// i/bands`), assembles them, and asserts that every channel has the bits
/// of `one`, the one-process render with the same `args`.
pub fn assert_tiles_assemble_to(dir: &TempDir, scene: &Path, args: &[&str], bands: u32, one: &Path) {
    let tiles: Vec<PathBuf> = (0..bands)
        .map(|i| {
            let tile = dir.path(&format!("band{i}of{bands}.exr"));
            let spec = format!("{i}/{bands}");
            let more = ["-o", s(&tile), "--tile", &spec, "--quiet"];
            lightcuts_ok(&[&["render", s(scene)][..], args, &more].concat());
            tile
        })
        .collect();
    let frame = dir.path(&format!("assembled{bands}.exr"));
    lightcuts_ok(&[&["assemble", s(&frame)][..], &tiles.iter().map(|t| s(t)).collect::<Vec<_>>()].concat());
    let (one, frame) = (read_exr(one).unwrap(), read_exr(&frame).unwrap());
    assert_eq!(one.channels.keys().collect::<Vec<_>>(), frame.channels.keys().collect::<Vec<_>>());
    for (name, values) in &one.channels {
        let same = values.iter().zip(&frame.channels[name]).all(|(a, b)| a.to_bits() == b.to_bits());
        assert!(same, "{args:?}: {name} differs between {bands} tiles and the one-process render");
    }
}

/// Which pixels a comparison with a peer covers: its mean over them and
/// its 8x8 blocks that they fill.
#[derive(Clone, Copy, Debug)]
pub enum Part {
    /// Every pixel.
    Image,
    /// The pixels an object covers (by the render's depth): the background
    /// alone is easy to match.
    Objects,
    /// The pixels a metal covers (an object whose diffuse albedo is 0):
    /// where two renderers whose dielectrics differ by definition define
    /// the same BRDF.
    Metals,
}

/// Renders `scene` with each of `flags` and compares its luminance with
/// a peer's converged render `reference` (both under scenes/`dir`/):
/// the mean within 1% and the 8x8 blocks within 2% on average, over the
/// whole image and again over the objects alone.
pub fn matches_peer(name: &str, dir: &str, scene: &str, reference: &str, flags: &[&[&str]]) {
    matches_peers(name, dir, scene, &[(reference, &[Part::Image, Part::Objects])], flags);
}

/// [`matches_peer`] against several peers' references, each over its
/// parts of the image: each render compared with every one of them.
pub fn matches_peers(name: &str, dir: &str, scene: &str, references: &[(&str, &[Part])], flags: &[&[&str]]) {
    let scenes = scenes().join(dir);
    let dir = TempDir::new(name);
    let scene = scenes.join(scene);
    let luminance = |image: &ExrImage| -> Vec<f64> {
        let [r, g, b] = ["R", "G", "B"].map(|c| channel(image, c));
        (0..r.len()).map(|p| 0.2126 * f64::from(r[p]) + 0.7152 * f64::from(g[p]) + 0.0722 * f64::from(b[p])).collect()
    };
    let references: Vec<(&str, &[Part], ExrImage)> =
        references.iter().map(|&(path, parts)| (path, parts, read_exr(&scenes.join(path)).unwrap())).collect();
    let (width, height) = (references[0].2.width, references[0].2.height);
    let blocks = |values: &[f64]| -> Vec<f64> {
        let mut sums = vec![0.0; (width / 8) * (height / 8)];
        for y in 0..height / 8 * 8 {
            for x in 0..width / 8 * 8 {
                sums[(y / 8) * (width / 8) + x / 8] += values[y * width + x];
            }
        }
        sums
    };
    let mut failures = Vec::new();
    for &flags in flags {
        let image = render(&scene, &dir.path("render.exr"), flags);
        let got = luminance(&image);
        let depth = channel(&image, "Z");
        let albedo = ["albedo.R", "albedo.G", "albedo.B"].map(|c| channel(&image, c));
        let mask = |part: Part| -> Vec<f64> {
            (0..got.len())
                .map(|p| match part {
                    Part::Image => 1.0,
                    Part::Objects => f64::from(u8::from(depth[p] < 1e9)),
                    Part::Metals => f64::from(u8::from(depth[p] < 1e9 && albedo.iter().all(|a| a[p] == 0.0))),
                })
                .collect()
        };
        for (path, parts, reference) in &references {
            assert_eq!((image.width, image.height), (reference.width, reference.height), "{path}");
            let want = luminance(reference);
            let (g, w) = (blocks(&got), blocks(&want));
            for &part in *parts {
                let mask = mask(part);
                let covered: Vec<bool> = blocks(&mask).iter().map(|&n| n == 64.0).collect();
                let on_part = |values: &[f64]| -> f64 { values.iter().zip(&mask).map(|(v, m)| v * m).sum() };
                let errors: Vec<f64> =
                    (0..w.len()).filter(|&k| covered[k]).map(|k| (g[k] - w[k]).abs() / w[k]).collect();
                assert!(errors.len() >= 20, "{part:?}: only {} blocks to compare", errors.len());
                let blocks = errors.iter().sum::<f64>() / errors.len() as f64;
                let ratio = on_part(&got) / on_part(&want);
                eprintln!(
                    "{name} {flags:?} vs {path}, {part:?}: mean ratio {ratio:.4}, mean 8x8 block error {:.2}% ({} blocks)",
                    100.0 * blocks,
                    errors.len()
                );
                if (ratio - 1.0).abs() > 0.01 || blocks > 0.02 {
                    failures.push(format!(
                        "{flags:?} vs {path}, {part:?}: ratio {ratio:.4}, blocks {:.2}%",
                        100.0 * blocks
                    ));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{name} is off from its peer: {failures:?}");
}
