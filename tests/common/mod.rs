//! Helpers for tests that run the real `lightcuts` binary.
#![allow(dead_code, unused_imports)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub use lightcuts::output::read::{read_exr, ExrImage};

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

pub fn s(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// The repository's scenes directory.
pub fn scenes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

/// A small scene: floor, two spheres, a grid of point lights.
pub fn small_scene(lights_per_side: u32) -> String {
    format!(
        r#"
[film]
width = 96
height = 72

[camera]
eye = [0, 3, 6]
look_at = [0, 0.5, 0]
fov_y = 45

[materials.floor]
albedo = [0.7, 0.7, 0.7]

[materials.shiny]
albedo = [0.6, 0.2, 0.1]
specular = [0.3, 0.3, 0.3]
exponent = 30

[materials.mirror]
albedo = [0.05, 0.05, 0.05]
mirror = [0.8, 0.8, 0.8]

[[shapes]]
type = "quad"
corner = [-5, 0, 5]
u = [10, 0, 0]
v = [0, 0, -10]
material = "floor"

[[shapes]]
type = "sphere"
center = [-0.8, 0.7, 0]
radius = 0.7
material = "shiny"

[[shapes]]
type = "sphere"
center = [0.9, 0.5, 0.4]
radius = 0.5
material = "mirror"

[[lights]]
type = "grid"
corner = [-2, 3, -2]
u = [4, 0, 0]
v = [0, 0, 4]
count = [{lights_per_side}, {lights_per_side}]
intensity = [1.0, 0.9, 0.8]
"#
    )
}

/// 300 coincident lights (20 x 15, intensities 0.01, 0.02, 0.03 W/sr each)
/// at the centre of a diffuse sphere of radius 2 (albedo 0.5), seen from
/// inside on a `width` x `height` film: every pixel has the known answer
/// L = k_d / pi * sum(I) / R^2 (see [`assert_inside_sphere_answer`]).
pub fn inside_sphere_scene(width: u32, height: u32) -> String {
    format!(
        r#"
[film]
width = {width}
height = {height}
[camera]
eye = [0.2, 0.1, 0]
look_at = [1, 0, 0.4]
fov_y = 60
[materials.inner]
albedo = [0.5, 0.5, 0.5]
[[shapes]]
type = "sphere"
center = [0, 0, 0]
radius = 2
segments = 512
material = "inner"
[[lights]]
type = "grid"
corner = [0, 0, 0]
u = [0, 0, 0]
v = [0, 0, 0]
count = [20, 15]
intensity = [0.01, 0.02, 0.03]
"#
    )
}

/// Asserts that every pixel of a render of [`inside_sphere_scene`] is the
/// known answer to 0.1%, channel by channel.
pub fn assert_inside_sphere_answer(path: &Path, image: &ExrImage) {
    for (c, name) in ["R", "G", "B"].iter().enumerate() {
        let expected = 0.5 / std::f32::consts::PI * 300.0 * 0.01 * (c as f32 + 1.0) / 4.0;
        for &v in image.channel(path, name).unwrap() {
            assert!((v - expected).abs() <= 1e-3 * expected, "{name}: {v} vs {expected}");
        }
    }
}
