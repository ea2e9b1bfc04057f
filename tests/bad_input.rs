//! Bad input: a clear error naming file and field, exit code 1, no output file.

mod common;
use common::*;

fn assert_rejected(dir: &TempDir, scene_name: &str, text: &str, expect: &[&str]) {
    let scene = dir.write(scene_name, text);
    let out = dir.path("out.exr");
    let stderr = lightcuts_fails(&["render", s(&scene), "-o", s(&out), "--exact", "--quiet"]);
    assert!(stderr.contains(scene_name), "message does not name {scene_name}: {stderr}");
    for e in expect {
        assert!(stderr.contains(e), "message lacks '{e}': {stderr}");
    }
    assert_eq!(stderr.lines().count(), 1, "one line: {stderr}");
    assert!(!out.exists(), "an output file was written");
    assert!(dir.files().iter().all(|f| !f.contains("out.exr")), "a temporary file was left: {:?}", dir.files());
}

#[test]
fn nan_intensity_is_named() {
    let dir = TempDir::new("nan");
    let text = small_scene(2).replace("intensity = [1.0, 0.9, 0.8]", "intensity = [1.0, nan, 0.8]");
    assert_rejected(&dir, "nan.toml", &text, &["lights[0].intensity", "NaN"]);
}

#[test]
fn missing_mesh_file_is_named() {
    let dir = TempDir::new("mesh");
    let text = format!(
        "{}\n[[shapes]]\ntype = \"mesh\"\nfile = \"nowhere/bunny.obj\"\nmaterial = \"floor\"\n",
        small_scene(2)
    );
    assert_rejected(&dir, "mesh.toml", &text, &["shapes[3].file", "bunny.obj"]);
}

#[test]
fn misspelt_field_is_named() {
    let dir = TempDir::new("typo");
    let text = small_scene(2).replace("radius = 0.7", "radious = 0.7");
    assert_rejected(&dir, "typo.toml", &text, &["shapes[1]", "radious"]);
}

#[test]
fn missing_scene_file_and_output_directory_are_clear_errors() {
    let dir = TempDir::new("paths");
    let stderr = lightcuts_fails(&["render", s(&dir.path("none.toml")), "-o", s(&dir.path("o.exr")), "--exact"]);
    assert!(stderr.contains("none.toml"), "{stderr}");
    let scene = dir.write("ok.toml", &small_scene(1));
    let out = dir.path("missing/dir/o.exr");
    let stderr = lightcuts_fails(&["render", s(&scene), "-o", s(&out), "--exact", "--quiet", "--resolution", "8x6"]);
    assert!(stderr.contains("missing/dir"), "{stderr}");
}

#[test]
fn bad_command_line_values_are_named() {
    let dir = TempDir::new("flags");
    let scene = dir.write("ok.toml", &small_scene(1));
    let out = dir.path("o.exr");
    let stderr = lightcuts_fails(&["render", s(&scene), "-o", s(&out), "--exact", "--pixel-bounds", "0,200,0,10"]);
    assert!(stderr.contains("--pixel-bounds"), "{stderr}");
    let stderr = lightcuts_fails(&["render", s(&scene), "-o", s(&out), "--exact", "--resolution", "100000x100000"]);
    assert!(stderr.contains("--resolution") && stderr.contains("memory"), "{stderr}");
    // Resampling is the stochastic cut's: at 4 spp the default mode is bounded.
    let stderr = lightcuts_fails(&["render", s(&scene), "-o", s(&out), "--spp", "4", "--resampled-rays", "2"]);
    assert!(stderr.contains("--resampled-rays") && stderr.contains("add --method stochastic"), "{stderr}");
    let stderr = lightcuts_fails(&["render", s(&scene), "-o", s(&out), "--bounded", "--resampled-rays", "2"]);
    assert!(stderr.contains("--resampled-rays"), "{stderr}");
    assert!(!out.exists());
}
