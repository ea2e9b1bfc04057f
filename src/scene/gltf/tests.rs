use glam::Vec2;
use gltf::mesh::Mode;

use super::geometry::triangulate;
use super::io::percent_decode;
use super::materials::{uv_transform, KhrTextureTransform};

#[test]
fn strips_and_fans_keep_one_winding() {
    // A strip 0 1 2 3: (0 1 2), then (2 1 3) with the second triangle's
    // first two reversed, so both wind the same way.
    assert_eq!(triangulate(Mode::TriangleStrip, &[0, 1, 2, 3]), vec![[0, 1, 2], [2, 1, 3]]);
    assert_eq!(triangulate(Mode::TriangleFan, &[0, 1, 2, 3]), vec![[0, 1, 2], [0, 2, 3]]);
    assert_eq!(triangulate(Mode::Triangles, &[0, 1, 2, 3]), vec![[0, 1, 2]], "a trailing partial triangle is dropped");
    assert!(triangulate(Mode::TriangleStrip, &[0, 1]).is_empty());
}

/// The map from a mesh's uv to the texture lookup's: KHR_texture_transform
/// (translation x rotation x scale), then v flipped (glTF's v = 0 is the
/// image's top row, the lookup's its bottom).
#[test]
fn uv_transform_flips_v_after_the_extension_s_transform() {
    let close = |t: glam::Affine2, uv: [f32; 2], expected: [f32; 2]| {
        let got = t.transform_point2(Vec2::from_array(uv));
        assert!((got - Vec2::from_array(expected)).length() < 1e-6, "{uv:?} -> {got}, expected {expected:?}");
    };
    // Without the extension: (u, v) -> (u, 1 - v).
    close(uv_transform(None), [0.25, 0.1], [0.25, 0.9]);
    let khr = |offset: [f32; 2], rotation: f32, scale: [f32; 2]| {
        uv_transform(Some(KhrTextureTransform::new(offset, rotation, scale)))
    };
    // An offset moves the uv, then v flips: (0.25 + 0.5, 1 - (0.1 + 0.25)).
    close(khr([0.5, 0.25], 0.0, [1.0, 1.0]), [0.25, 0.1], [0.75, 0.65]);
    // A scale multiplies each component: (0.25 x 2, 1 - 0.1 x 3).
    close(khr([0.0, 0.0], 0.0, [2.0, 3.0]), [0.25, 0.1], [0.5, 0.7]);
    // A quarter turn of the uv counter-clockwise (v pointing down): u's
    // axis turns to -v, v's to +u: (1, 0) -> (0, -1), (0, 1) -> (1, 0),
    // before the flip.
    let quarter = std::f32::consts::FRAC_PI_2;
    close(khr([0.0, 0.0], quarter, [1.0, 1.0]), [1.0, 0.0], [0.0, 2.0]);
    close(khr([0.0, 0.0], quarter, [1.0, 1.0]), [0.0, 1.0], [1.0, 1.0]);
    // The extension's example, the lower left quadrant turned clockwise:
    // (u, v) -> (v / 2, 1 - u / 2), then flipped to (v / 2, u / 2).
    for (u, v) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (0.3, 0.8)] {
        close(khr([0.0, 1.0], quarter, [0.5, 0.5]), [u, v], [v / 2.0, u / 2.0]);
    }
}

#[test]
fn percent_escapes_are_decoded_and_bad_ones_kept() {
    assert_eq!(percent_decode("my%20file.bin"), "my file.bin");
    assert_eq!(percent_decode("100%"), "100%");
    assert_eq!(percent_decode("a%zzb"), "a%zzb");
    assert_eq!(percent_decode("%"), "%");
}
