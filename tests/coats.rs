//! Clear coats and sheens (docs/design.md §5.10), through the real
//! binary, against answers this file knows: a coated or sheened perfect
//! mirror under a uniform sky keeps all the light (the furnace), glTF's
//! KHR_materials_clearcoat and KHR_materials_sheen read as the extensions
//! say, and bit-identical images for any threads and window.

mod common;

use common::gltf::{pane_before_a_red_emitter, GltfBuilder};
use common::{assert_same_bits_for_any_threads_and_window, channel, lightcuts_fails, means, render, TempDir};
use serde_json::json;

/// A sphere of a white, smooth metal (a perfect mirror of reflectance 1)
/// with `layer`'s TOML fields over it, filling most of the view under a
/// uniform sky of radiance 1.
fn mirror_under_a_white_sky(layer: &str) -> String {
    format!(
        "[film]\nwidth = 24\nheight = 24\nspp = 32\n\
         [camera]\neye = [0, 0, 3]\nlook_at = [0, 0, 0]\nfov_y = 30\n\
         [materials.ball]\ntype = \"pbr\"\nalbedo = [1, 1, 1]\nmetallic = 1\nroughness = 0\n{layer}\n\
         [[shapes]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 0.6\nsegments = 256\nmaterial = \"ball\"\n\
         [environment]\nradiance = [1, 1, 1]\nsamples = 1024\n"
    )
}

#[test]
fn a_coated_mirror_under_a_white_sky_keeps_all_the_light() {
    // A smooth coat reflects its Fresnel weight w of the sky and leaves
    // the mirror below 1 - w of it: w + (1 - w) = 1 in every pixel, in
    // every mode. A sheen takes E(n.v) of the light and leaves the mirror
    // 1 - E(n.v): 1 again, to the accuracy of its albedo table.
    let dir = TempDir::new("coat-furnace");
    for (layer, what, tolerance) in [
        ("clearcoat = 1\nclearcoat_roughness = 0", "a smooth coat", 1e-4),
        ("clearcoat = 0.5\nclearcoat_roughness = 0", "half a smooth coat", 1e-4),
        ("sheen_colour = [1, 1, 1]\nsheen_roughness = 0.5", "a white sheen", 0.02),
        ("sheen_colour = [1, 1, 1]\nsheen_roughness = 0", "a sharp white sheen", 0.03),
    ] {
        for indirect in ["none", "path"] {
            for mode in ["--stochastic", "--exact"] {
                let scene = dir.write("furnace.toml", &mirror_under_a_white_sky(layer));
                let image = render(&scene, &dir.path("furnace.exr"), &[mode, "--indirect", indirect]);
                let green = channel(&image, "G");
                let worst = green.iter().map(|&v| (f64::from(v) - 1.0).abs()).fold(0.0, f64::max);
                let mean = means(&image)[1];
                eprintln!("{what}, indirect {indirect}, {mode}: mean {mean:.5}, worst pixel {worst:.5}");
                assert!((mean - 1.0).abs() < tolerance, "{what}, {indirect}, {mode}: mean {mean}");
                if tolerance < 1e-3 {
                    assert!(worst < 1e-3, "{what}, {indirect}, {mode}: a pixel is {worst} from 1");
                }
            }
        }
    }
    // A rough coat's GGX loses the light its single scattering misses, and
    // a coat over black shows its own reflectance: the test can tell.
    let rough = dir.write("rough.toml", &mirror_under_a_white_sky("clearcoat = 1\nclearcoat_roughness = 0.8"));
    let mean = means(&render(&rough, &dir.path("rough.exr"), &["--stochastic"]))[1];
    eprintln!("a rough coat: mean {mean:.5}");
    assert!((0.9..0.995).contains(&mean), "a rough coat: {mean}");
}

#[test]
fn coats_and_sheens_are_the_same_bits_for_any_threads_and_window() {
    let dir = TempDir::new("coat-bits");
    let scene = common::scenes().join("environment/coats.toml");
    for indirect in ["none", "path"] {
        let args = ["--stochastic", "--indirect", indirect, "--resolution", "80x60", "--spp", "2"];
        assert_same_bits_for_any_threads_and_window(&dir, &scene, 80, &args);
    }
}

/// A thin, fully transmitting glTF pane of `extensions` besides
/// KHR_materials_transmission, in front of a red emitter filling the view
/// (`pane_before_a_red_emitter`): what reaches the camera is the
/// transmitted weight.
fn pane(extensions: serde_json::Value) -> GltfBuilder {
    let mut all = json!({ "KHR_materials_transmission": { "transmissionFactor": 1.0 } });
    for (name, value) in extensions.as_object().expect("an object") {
        all[name] = value.clone();
    }
    let mut b = pane_before_a_red_emitter(all.clone());
    for name in all.as_object().expect("an object").keys() {
        b.use_extension(name);
    }
    b
}

#[test]
fn gltf_clearcoat_and_sheen_are_read_as_their_extensions_define_them() {
    let dir = TempDir::new("coat-gltf");
    let red_through = |extensions: serde_json::Value| {
        let path = pane(extensions).write_separate(&dir.path(""), "pane");
        means(&render(&path, &dir.path("pane.exr"), &["--spp", "64", "--resolution", "16x16"]))[0]
    };
    // Bare: 1 - F = 0.96 (views within 14 degrees of the normal).
    let bare = red_through(json!({}));
    // A coat of weight 1 reflects F_c = 0.04 more and leaves 0.96 of that:
    // 0.9216, rough or smooth (its weight is taken at n.v).
    let coated = red_through(json!({ "KHR_materials_clearcoat": { "clearcoatFactor": 1.0 } }));
    let rough = red_through(json!({
        "KHR_materials_clearcoat": { "clearcoatFactor": 1.0, "clearcoatRoughnessFactor": 0.5 }
    }));
    let half = red_through(json!({ "KHR_materials_clearcoat": { "clearcoatFactor": 0.5 } }));
    // A white sheen leaves 1 - E(n.v) of the base; a black one is none.
    let sheen = red_through(json!({
        "KHR_materials_sheen": { "sheenColorFactor": [1, 1, 1], "sheenRoughnessFactor": 0.5 }
    }));
    let black = red_through(json!({ "KHR_materials_sheen": { "sheenRoughnessFactor": 0.5 } }));
    eprintln!("bare {bare:.4}, coated {coated:.4}, rough coat {rough:.4}, half {half:.4}, sheen {sheen:.4}, black sheen {black:.4}");
    assert!((bare - 0.96).abs() < 0.005, "bare: {bare}");
    assert!((coated - 0.96 * 0.96).abs() < 0.005, "coated: {coated}");
    assert!((rough - coated).abs() < 0.005, "a rough coat: {rough}");
    assert!((half - 0.96 * 0.98).abs() < 0.005, "half a coat: {half}");
    assert!(sheen < 0.93 && sheen > 0.5, "a white sheen: {sheen}");
    assert_eq!(black, bare, "a black sheen is no sheen");
    // Out of range: the file and the field are named, nothing written.
    for (extension, field) in [
        (json!({ "KHR_materials_sheen": { "sheenColorFactor": [2, 0, 0] } }), "KHR_materials_sheen.sheenColorFactor"),
        (json!({ "KHR_materials_clearcoat": { "clearcoatFactor": -1 } }), "KHR_materials_clearcoat.clearcoatFactor"),
        (
            json!({ "KHR_materials_clearcoat": { "clearcoatFactor": 1, "clearcoatTexture": { "index": 7 } } }),
            "KHR_materials_clearcoat.clearcoatTexture.index",
        ),
    ] {
        let path = pane(extension).write_separate(&dir.path(""), "bad");
        let out = dir.path("bad.exr");
        let stderr = lightcuts_fails(&["render", common::s(&path), "-o", common::s(&out)]);
        assert!(stderr.contains("bad.gltf") && stderr.contains(field), "{field}: {stderr}");
        assert!(!out.exists());
    }
}
