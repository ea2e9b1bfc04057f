//! Glass (docs/design.md §5.8), through the real binary, against answers
//! this file knows: a glass sphere under a uniform sky is invisible (the
//! furnace), a rough one loses no more than GGX's masking takes, a slab's
//! Fresnel and Beer-Lambert terms against their closed form (smooth and
//! rough), glTF's transmission extensions read as the specification says
//! (a rough pane passes what Walter et al.'s BTDF passes), and
//! bit-identical images for any threads and window.

mod common;

use common::gltf::{pane_before_a_red_emitter, rough_pane_before_a_red_emitter, GltfBuilder};
use common::{assert_same_bits_for_any_threads_and_window, channel, lightcuts_fails, means, read_exr, render, TempDir};
use serde_json::json;

/// A sphere of `material`'s fields (a TOML `pbr` material) filling most
/// of the view under a uniform sky of radiance 1, paths of up to 64
/// vertices (mirror paths and, if asked for, sampled ones): near its
/// silhouette, where Fresnel's reflectance nears 1, a ray may reflect
/// inside many times before it leaves.
fn sphere_under_a_white_sky(material: &str) -> String {
    format!(
        "[film]\nwidth = 24\nheight = 24\nspp = 32\n\
         [camera]\neye = [0, 0, 3]\nlook_at = [0, 0, 0]\nfov_y = 30\n\
         [materials.glass]\ntype = \"pbr\"\nalbedo = [1, 1, 1]\nmetallic = 0\nroughness = 0\n{material}\n\
         [[shapes]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 0.6\nsegments = 256\nmaterial = \"glass\"\n\
         [environment]\nradiance = [1, 1, 1]\nsamples = 1024\n\
         [indirect]\nmax_depth = 64\n[render]\nmax_mirror_depth = 64\n"
    )
}

#[test]
fn a_glass_sphere_under_a_white_sky_is_invisible() {
    // Whatever a smooth, white, lossless dielectric reflects it does not
    // transmit: at every interface the mirror and the transmission sum to
    // 1, and every path ends in the sky of radiance 1, so every pixel is 1.
    let dir = TempDir::new("glass-furnace");
    for (material, what) in [
        ("transmission = 1", "a solid"),
        ("transmission = 1\nior = 2.4", "a diamond"),
        ("transmission = 1\nthin_walled = true", "a thin wall"),
    ] {
        for indirect in ["none", "path"] {
            for mode in ["--stochastic", "--exact", "--multidimensional"] {
                let scene = dir.write("furnace.toml", &sphere_under_a_white_sky(material));
                let image = render(&scene, &dir.path("furnace.exr"), &[mode, "--indirect", indirect]);
                let green = channel(&image, "G");
                let worst = green.iter().map(|&v| (f64::from(v) - 1.0).abs()).fold(0.0, f64::max);
                let mean = means(&image)[1];
                eprintln!("{what}, indirect {indirect}, {mode}: mean {mean:.6}, worst pixel {worst:.5}");
                assert!((mean - 1.0).abs() < 1e-3, "{what}, {indirect}, {mode}: mean {mean}");
                assert!(worst < 1e-3, "{what}, {indirect}, {mode}: a pixel is {worst} from 1");
            }
        }
    }
    // Absorbing 10% over a metre inside, the same sphere is seen: the
    // test can tell.
    let grey = "transmission = 1\nattenuation_colour = [0.9, 0.9, 0.9]\nattenuation_distance = 1";
    let scene = dir.write("grey.toml", &sphere_under_a_white_sky(grey));
    let mean = means(&render(&scene, &dir.path("grey.exr"), &["--stochastic", "--indirect", "none"]))[1];
    eprintln!("grey glass: mean {mean:.5}");
    assert!(mean < 0.98, "absorbing glass: {mean}");
}

#[test]
fn a_rough_glass_sphere_under_a_white_sky_loses_only_what_masking_takes() {
    // Rough, the same sphere's microfacets shadow and mask each other: GGX
    // loses light at grazing angles (single scattering), and nothing
    // else. The mean stays below 1 (no light made) and above what the
    // silhouette's losses take.
    let dir = TempDir::new("rough-furnace");
    for (material, what, least) in [
        ("roughness = 0.3\ntransmission = 1", "a rough solid", 0.93),
        ("roughness = 0.3\ntransmission = 1\nthin_walled = true", "a rough thin wall", 0.94),
        ("roughness = 0.1\ntransmission = 1", "a frosted solid", 0.96),
    ] {
        for indirect in ["none", "path"] {
            for mode in ["--stochastic", "--exact"] {
                let scene =
                    dir.write("furnace.toml", &sphere_under_a_white_sky(material).replace("roughness = 0\n", ""));
                let image = render(&scene, &dir.path("furnace.exr"), &[mode, "--indirect", indirect]);
                let mean = means(&image)[1];
                eprintln!("{what}, indirect {indirect}, {mode}: mean {mean:.5}");
                assert!(mean < 1.0 + 3e-3 && mean > least, "{what}, {indirect}, {mode}: mean {mean}");
            }
        }
    }
}

/// A glass slab 1 m thick (z from -0.5 to 0.5) of `roughness` filling a
/// narrow view straight on, under a uniform sky of radiance 1, absorbing
/// to `colour` over 1 m.
fn slab(colour: [f64; 3], spp: u32, roughness: f32) -> String {
    format!(
        "[film]\nwidth = 4\nheight = 4\nspp = {spp}\n\
         [camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\nfov_y = 2\n\
         [materials.glass]\ntype = \"pbr\"\nalbedo = [1, 1, 1]\nmetallic = 0\nroughness = {roughness}\n\
         transmission = 1\nattenuation_colour = {colour:?}\nattenuation_distance = 1\n\
         [[shapes]]\ntype = \"box\"\nmin = [-1, -1, -0.5]\nmax = [1, 1, 0.5]\nmaterial = \"glass\"\n\
         [environment]\nradiance = [1, 1, 1]\nsamples = 1024\n[indirect]\nmax_depth = 64\n"
    )
}

#[test]
fn a_slab_reflects_and_transmits_as_fresnel_and_beer_lambert_say() {
    // Straight on, each face reflects R = 0.04 (IOR 1.5) and a pass
    // through the slab keeps a = colour (its thickness is the attenuation
    // distance). The light back from the sky is R from the front face,
    // plus what enters, crosses, and leaves by either face after any
    // number of inner reflections: (1 - R)^2 a (1 + R a + (R a)^2 + ...)
    // = (1 - R)^2 a / (1 - R a).
    // Rough (roughness 0.1: GGX alpha 0.01), the microfacets spread the
    // light by a few degrees and lose too little to see straight on; a
    // path inside the slab follows its inner reflections by drawing them,
    // with or without the path method.
    let dir = TempDir::new("glass-slab");
    let colour = [0.2, 0.8, 0.5];
    let r = 0.04;
    for (roughness, indirect) in [(0.0, "none"), (0.1, "none"), (0.1, "path")] {
        let scene = dir.write("slab.toml", &slab(colour, 8192, roughness));
        let image = render(&scene, &dir.path("slab.exr"), &["--stochastic", "--indirect", indirect]);
        for (c, (got, a)) in means(&image).into_iter().zip(colour).enumerate() {
            let want = r + (1.0 - r) * (1.0 - r) * a / (1.0 - r * a);
            eprintln!("roughness {roughness}, indirect {indirect}, channel {c}: {got:.5} vs {want:.5}");
            // 131,072 samples whose values differ by up to 1 - a: a
            // standard error below 1e-3.
            assert!((got - want).abs() < 4e-3, "roughness {roughness}, {indirect}, channel {c}: {got} vs {want}");
        }
    }
}

#[test]
fn glass_is_the_same_bits_for_any_threads_and_window() {
    // Clear and absorbing solids and a thin wall, under a sky.
    let dir = TempDir::new("glass-bits");
    // Rough solids too, whose transmission is drawn.
    for scene in ["glass.toml", "rough_glass_peer.toml"] {
        let scene = common::scenes().join("environment").join(scene);
        for indirect in ["none", "path"] {
            let args = ["--stochastic", "--indirect", indirect, "--resolution", "80x60", "--spp", "2"];
            assert_same_bits_for_any_threads_and_window(&dir, &scene, 80, &args);
        }
    }
}

#[test]
fn gltf_transmission_is_read_as_its_extensions_define_it() {
    let dir = TempDir::new("glass-gltf");
    // The pane of `roughness` and `extensions` at `spp`: its image and
    // what the render said on stderr.
    let render_rough_pane = |extensions: serde_json::Value, used: &[&str], roughness: f32, spp: &str| {
        let mut b = rough_pane_before_a_red_emitter(extensions, roughness);
        for name in used {
            b.use_extension(name);
        }
        let path = b.write_separate(&dir.path(""), "pane");
        let out = dir.path("pane.exr");
        let args = ["render", common::s(&path), "-o", common::s(&out), "--spp", spp, "--resolution", "16x16"];
        let run = common::lightcuts(&args);
        let stderr = String::from_utf8_lossy(&run.stderr).into_owned();
        assert!(run.status.success(), "lightcuts {args:?} failed:\n{stderr}");
        (read_exr(&out).unwrap(), stderr)
    };
    let render_pane = |extensions: serde_json::Value, used: &[&str]| render_rough_pane(extensions, used, 0.0, "64");
    // A thin pane (no KHR_materials_volume) passes 1 - F = 0.96 of the
    // emitter straight through (views within 14 degrees of the normal:
    // Schlick's weight is below 3e-8); the rest is a reflection of the
    // dark.
    let (image, _) = render_pane(
        json!({ "KHR_materials_transmission": { "transmissionFactor": 1.0 } }),
        &["KHR_materials_transmission"],
    );
    let red = means(&image)[0];
    assert!((red - 0.96).abs() < 0.01, "a clear pane: {red}");
    // Half transmitting: half of that.
    let (image, _) = render_pane(
        json!({ "KHR_materials_transmission": { "transmissionFactor": 0.5 } }),
        &["KHR_materials_transmission"],
    );
    let red = means(&image)[0];
    assert!((red - 0.48).abs() < 0.01, "a half-clear pane: {red}");
    // Without the extension the pane hides the emitter.
    let (image, _) = render_pane(json!({}), &[]);
    assert_eq!(means(&image)[0], 0.0, "an opaque pane");
    // IOR 1 reflects nothing: every path passes.
    let (image, _) = render_pane(
        json!({ "KHR_materials_transmission": { "transmissionFactor": 1.0 }, "KHR_materials_ior": { "ior": 1.0 } }),
        &["KHR_materials_transmission", "KHR_materials_ior"],
    );
    assert_eq!(means(&image)[0], 1.0, "IOR 1");
    // Rough (0.2: GGX alpha 0.04), the thin pane passes each view's
    // reflection about a microfacet mirrored through it, weighted (1 - F)
    // G2 / G1: 0.958 of the emitter on average (views within 14 degrees of
    // the normal; the mean of that weight, by Monte Carlo, over the
    // visible normals), all but 0.3% of it within 60 degrees of the view,
    // where the emitter is. Its roughness is no longer warned.
    let (image, stderr) = render_rough_pane(
        json!({ "KHR_materials_transmission": { "transmissionFactor": 1.0 } }),
        &["KHR_materials_transmission"],
        0.2,
        "256",
    );
    assert!(!stderr.contains("warning"), "{stderr}");
    let red = means(&image)[0];
    eprintln!("a rough pane: {red:.4}");
    assert!((red - 0.957).abs() < 0.004, "a rough pane: {red}");
    // Out of range: the file and the field are named.
    let mut b = pane_before_a_red_emitter(json!({ "KHR_materials_transmission": { "transmissionFactor": 2.0 } }));
    b.use_extension("KHR_materials_transmission");
    let path = b.write_separate(&dir.path(""), "bad");
    let out = dir.path("bad.exr");
    let stderr = lightcuts_fails(&["render", common::s(&path), "-o", common::s(&out)]);
    assert!(
        stderr.contains("bad.gltf") && stderr.contains("KHR_materials_transmission.transmissionFactor"),
        "{stderr}"
    );
    assert!(!out.exists());
}

#[test]
fn alpha_blending_is_a_partial_coverage_for_camera_and_shadow_rays() {
    // A pane of alpha 0.3 (BLEND) in front of the red emitter: camera rays
    // pass with probability 0.7, and the pane, lit by nothing, is black.
    let dir = TempDir::new("glass-blend");
    let mut b = GltfBuilder::new();
    let pane = b.material(json!({
        "pbrMetallicRoughness": { "baseColorFactor": [1, 1, 1, 0.3], "metallicFactor": 0 },
        "alphaMode": "BLEND",
    }));
    let mesh = b.quad([-1.0, -1.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0], Some(pane));
    b.node(json!({ "mesh": mesh }), true);
    let red =
        b.material(json!({ "pbrMetallicRoughness": { "baseColorFactor": [0, 0, 0, 1] }, "emissiveFactor": [1, 0, 0] }));
    let mesh = b.quad([-3.0, -3.0, -1.0], [6.0, 0.0, 0.0], [0.0, 6.0, 0.0], Some(red));
    b.node(json!({ "mesh": mesh }), true);
    let camera = b.camera(json!({ "type": "perspective", "perspective": { "yfov": 0.5, "znear": 0.01 } }));
    b.node(json!({ "camera": camera, "translation": [0.0, 0.0, 3.0] }), true);
    let path = b.write_separate(&dir.path(""), "blend");
    let image = render(&path, &dir.path("blend.exr"), &["--spp", "64", "--resolution", "16x16"]);
    let red = means(&image)[0];
    eprintln!("through alpha 0.3: {red:.4}");
    // 16,384 samples of 0 or 1: a standard error of 0.0036.
    assert!((red - 0.7).abs() < 0.015, "{red}");
    // Each ray's draw is its own: the same bits for any threads and window.
    assert_same_bits_for_any_threads_and_window(&dir, &path, 64, &["--resolution", "64x56", "--spp", "4"]);
    // The same pane between a point light and a white floor, seen from
    // above past the pane's edge: the floor in its shadow keeps 0.7 of its
    // light on average, the floor beside it all.
    let mut b = GltfBuilder::new();
    let white = b.material(json!({ "pbrMetallicRoughness": { "baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0, "roughnessFactor": 1 } }));
    let floor = b.quad([-4.0, 0.0, 4.0], [8.0, 0.0, 0.0], [0.0, 0.0, -8.0], Some(white));
    b.node(json!({ "mesh": floor }), true);
    let pane = b.material(json!({
        "pbrMetallicRoughness": { "baseColorFactor": [1, 1, 1, 0.3], "metallicFactor": 0 },
        "alphaMode": "BLEND",
        "doubleSided": true,
    }));
    // Above the floor's left half (x < 0) and above the camera, which
    // looks down: out of its view.
    let occluder = b.quad([-20.0, 5.0, 20.0], [20.0, 0.0, 0.0], [0.0, 0.0, -40.0], Some(pane));
    b.node(json!({ "mesh": occluder }), true);
    let down = [-std::f32::consts::FRAC_1_SQRT_2, 0.0, 0.0, std::f32::consts::FRAC_1_SQRT_2];
    let light = b.light(json!({ "type": "directional", "intensity": 683.0 }));
    b.node(json!({ "extensions": { "KHR_lights_punctual": { "light": light } }, "rotation": down }), true);
    let camera = b.camera(json!({ "type": "perspective", "perspective": { "yfov": 0.5, "znear": 0.01 } }));
    b.node(json!({ "camera": camera, "translation": [0.0, 3.0, 0.0], "rotation": down }), true);
    let path = b.write_separate(&dir.path(""), "shadow");
    let image = render(&path, &dir.path("shadow.exr"), &["--spp", "64", "--resolution", "16x16", "--exact"]);
    let r = channel(&image, "R");
    let half = |left: bool| {
        let values: Vec<f64> = (0..256).filter(|i| (i % 16 < 8) == left).map(|i| f64::from(r[i])).collect();
        values.iter().sum::<f64>() / values.len() as f64
    };
    let (shadowed, lit) = (half(true), half(false));
    eprintln!("floor under alpha 0.3: {shadowed:.4} of {lit:.4}");
    assert!(lit > 0.0);
    assert!((shadowed / lit - 0.7).abs() < 0.02, "{shadowed} / {lit}");
}
