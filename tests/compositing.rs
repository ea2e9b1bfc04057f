//! What a compositor reads besides the beauty, through the real binary:
//! OpenEXR's `worldToNDC` as the standard defines it (checked against where
//! the objects' Cryptomatte mattes are), the background's depth, and the
//! background's alpha with an opaque and a transparent film.

mod common;
use common::*;

use lightcuts::render::cryptomatte::CryptoType;

const WIDTH: usize = 96;
const HEIGHT: usize = 64;

/// Four small spheres spread over the frame (no floor: the sky is seen
/// around them), one of them a mirror, under a constant sky and a point light.
const SPHERES: [(&str, [f32; 3]); 4] = [
    ("upper_left", [-2.4, 1.2, 0.0]),
    ("lower_right", [2.3, -1.0, 0.5]),
    ("centre", [0.3, 0.2, -1.0]),
    ("mirror", [-1.4, -1.1, 1.0]),
];
const SKY: [f32; 3] = [0.2, 0.3, 0.4];

fn spheres_scene() -> String {
    let mut text = format!(
        r#"
[film]
width = {WIDTH}
height = {HEIGHT}
[camera]
eye = [0, 0, 8]
look_at = [0, 0, 0]
fov_y = 40
[materials.grey]
albedo = [0.6, 0.6, 0.6]
[materials.chrome]
albedo = [0, 0, 0]
mirror = [0.9, 0.9, 0.9]
[[lights]]
type = "point"
position = [0, 3, 8]
intensity = [5, 5, 5]
[environment]
radiance = {SKY:?}
samples = 64
"#
    );
    for (name, [x, y, z]) in SPHERES {
        let material = if name == "mirror" { "chrome" } else { "grey" };
        text += &format!(
            "[[shapes]]\ntype = \"sphere\"\nname = \"{name}\"\ncenter = [{x}, {y}, {z}]\nradius = 0.35\nmaterial = \"{material}\"\n"
        );
    }
    text
}

fn render(dir: &TempDir, name: &str, extra: &[&str]) -> ExrImage {
    let scene = dir.path("spheres.toml");
    if !scene.exists() {
        dir.write("spheres.toml", &spheres_scene());
    }
    common::render(&scene, &dir.path(name), &[&["--exact", "--spp", "16", "--cryptomatte"][..], extra].concat())
}

fn project(m: &[f32; 16], p: [f32; 3]) -> [f32; 3] {
    let column = |c: usize| p[0] * m[c] + p[1] * m[4 + c] + p[2] * m[8 + c] + m[12 + c];
    let w = column(3);
    [column(0) / w, column(1) / w, column(2) / w]
}

#[test]
fn world_to_ndc_puts_each_object_where_its_matte_is() {
    let dir = TempDir::new("ndc");
    let image = render(&dir, "ndc.exr", &[]);
    let ndc = image.world_to_ndc.expect("worldToNDC is written");
    for (name, centre) in SPHERES {
        let m = matte(&image, CryptoType::Object, name);
        let total: f32 = m.iter().sum();
        assert!(total > 20.0, "{name} covers {total} pixels");
        let (mut cx, mut cy) = (0.0, 0.0);
        for (i, &c) in m.iter().enumerate() {
            cx += c * ((i % WIDTH) as f32 + 0.5);
            cy += c * ((i / WIDTH) as f32 + 0.5);
        }
        let (cx, cy) = (cx / total, cy / total);
        // OpenEXR's NDC: (0, 0) the display window's upper-left corner,
        // (1, 1) its lower-right (y down).
        let [x, y, _] = project(&ndc, centre);
        assert!((0.0..=1.0).contains(&x) && (0.0..=1.0).contains(&y), "{name}: NDC ({x}, {y}) is outside the frame");
        let (px, py) = (x * WIDTH as f32, y * HEIGHT as f32);
        // A sphere's silhouette is an ellipse whose centre lies slightly
        // outward of the projected centre: well under a pixel here.
        assert!((px - cx).hypot(py - cy) < 0.75, "{name}: projected to ({px}, {py}), matte centroid ({cx}, {cy})");
    }
}

#[test]
fn the_background_is_far_and_opaque_by_default_and_empty_when_transparent() {
    let dir = TempDir::new("background");
    let opaque = render(&dir, "opaque.exr", &[]);
    let transparent = render(&dir, "transparent.exr", &["--transparent"]);
    let mattes: Vec<Vec<f32>> = SPHERES.iter().map(|(name, _)| matte(&opaque, CryptoType::Object, name)).collect();
    let coverage: Vec<f32> = (0..WIDTH * HEIGHT).map(|i| mattes.iter().map(|m| m[i]).sum()).collect();

    let (mut background, mut mirrored) = (0, 0);
    let mirror = matte(&opaque, CryptoType::Object, "mirror");
    for i in 0..WIDTH * HEIGHT {
        for image in [&opaque, &transparent] {
            let z = channel(image, "Z")[i];
            if coverage[i] == 0.0 {
                assert_eq!(z, 1e10, "pixel {i}: no surface, depth far away");
            } else {
                assert!(z > 5.0 && z < 10.0, "pixel {i}: a sphere at depth {z}");
            }
        }
        // Opaque film: every sample sees a sphere or the sky.
        assert_eq!(channel(&opaque, "A")[i], 1.0, "pixel {i}: alpha with the sky seen");
        // Transparent film: alpha is the spheres' coverage.
        assert!((channel(&transparent, "A")[i] - coverage[i]).abs() < 1e-6, "pixel {i}: alpha vs coverage");
        if coverage[i] == 0.0 {
            background += 1;
            for (c, name) in ["R", "G", "B"].iter().enumerate() {
                assert!((channel(&opaque, name)[i] - SKY[c]).abs() < 1e-6, "pixel {i}: the sky's {name}");
                assert_eq!(channel(&transparent, name)[i], 0.0, "pixel {i}: transparent background {name}");
            }
        }
        if mirror[i] == 1.0 {
            // The mirror still shows the sky (and the other spheres) on a transparent film.
            mirrored += 1;
            assert_eq!(channel(&transparent, "B")[i], channel(&opaque, "B")[i], "pixel {i}: the mirror's reflection");
            assert!(channel(&transparent, "B")[i] > 0.0, "pixel {i}: the mirror shows the sky");
        }
    }
    assert!(background > 3000 && mirrored > 10, "{background} background pixels, {mirrored} inside the mirror");
}
