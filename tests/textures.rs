//! Every texture format the renderer reads, through the binary: the same
//! picture in each lossless 8-bit format renders the same image, bit for
//! bit, as its PNG; a stage's UsdUVTexture reads OpenEXR, Radiance HDR and
//! float TIFF files without a warning. The files, and the script that wrote
//! them with tools that are not this renderer's, are in `scenes/textures/`.

mod common;

use common::{lightcuts, render, s, scenes, small_scene, TempDir};

/// The small scene with its floor textured by `texture`.
fn textured(texture: &std::path::Path) -> String {
    let toml =
        format!("{}\n[materials.wood]\ntexture = \"{}\"\ntexture_scale = [0.5, 0.5]\n", small_scene(2), s(texture));
    toml.replacen("material = \"floor\"", "material = \"wood\"", 1)
}

#[test]
fn every_lossless_eight_bit_format_renders_as_its_png() {
    let dir = TempDir::new("texture-formats");
    let textures = scenes().join("textures");
    let scene = dir.write("png.toml", &textured(&textures.join("rgba8.png")));
    let png = render(&scene, &dir.path("png.exr"), &["--resolution", "48x32"]);
    for name in ["rgba8.tga", "rgb8.bmp", "rgb8.tif", "palette.png"] {
        let scene = dir.write("other.toml", &textured(&textures.join(name)));
        let other = render(&scene, &dir.path("other.exr"), &["--resolution", "48x32"]);
        assert!(png.channels == other.channels, "{name} renders differently from rgba8.png");
    }
    // The picture shows: a floor of one flat colour would hide a reader
    // that returned the wrong quadrant everywhere.
    let flat = dir.write("flat.toml", &small_scene(2));
    let plain = render(&flat, &dir.path("flat.exr"), &["--resolution", "48x32"]);
    assert!(plain.channels != png.channels);
}

#[test]
fn a_stage_reads_float_textures_without_a_warning() {
    let dir = TempDir::new("texture-float");
    let stage = std::fs::read_to_string(scenes().join("usd/fuzz/stage.usda")).unwrap();
    assert!(stage.contains("@texture.png@"));
    for name in ["half.exr", "float.exr", "radiance.hdr", "float32.tif", "rgba8.tga", "cmyk.jpg", "grey16.tif"] {
        let texture = scenes().join("textures").join(name);
        let scene = dir.write("stage.usda", &stage.replace("@texture.png@", &format!("@{}@", s(&texture))));
        let out = dir.path("out.exr");
        let run = lightcuts(&["render", s(&scene), "-o", s(&out), "--resolution", "16x12", "--strict", "--quiet"]);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(run.status.success(), "{name}: {stderr}");
        assert!(!stderr.contains(name), "{name}: {stderr}");
    }
}
