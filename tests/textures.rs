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

/// scenes/checker.toml at 1 spp: towards the horizon its checks shrink
/// below a pixel. Read at each hit they alias into noise; through the MIP
/// map chosen by the pixel's footprint (docs/design.md §5.3, "MIP maps")
/// the far floor comes near each pixel's own average of the checks, which
/// a 64-spp render reading the image at each hit estimates. Filtering
/// keeps the image the same bits for any thread count and window.
#[test]
fn far_checks_through_the_mip_map_come_near_each_pixel_average() {
    let dir = TempDir::new("texture-mip");
    let scene = scenes().join("checker.toml");
    let film = ["--resolution", "160x90", "--bounded"];
    let render_with = |name: &str, more: &[&str]| {
        let image = render(&scene, &dir.path(name), &[&film[..], more].concat());
        common::luminance(&image)
    };
    let reference = render_with("reference.exr", &["--spp", "64", "--texture-filter", "off"]);
    let unfiltered = render_with("off.exr", &["--spp", "1", "--texture-filter", "off"]);
    let mip = render_with("mip.exr", &["--spp", "1"]);
    // The horizon is near row 42 of 90: the floor's far rows.
    let far = 42 * 160..56 * 160;
    let error = |test: &[f64]| {
        let squares: f64 = far.clone().map(|i| (test[i] - reference[i]).powi(2)).sum();
        let mean = far.clone().map(|i| reference[i]).sum::<f64>() / far.len() as f64;
        (squares / far.len() as f64).sqrt() / mean
    };
    let (unfiltered, mip) = (error(&unfiltered), error(&mip));
    assert!(unfiltered > 0.4, "the unfiltered far floor should alias: relative RMSE {unfiltered}");
    assert!(mip < 0.5 * unfiltered, "through the MIP map: relative RMSE {mip}, unfiltered {unfiltered}");
    common::assert_same_bits_for_any_threads_and_window(&dir, &scene, 96, &["--resolution", "96x54", "--bounded"]);
}
