use super::io::percent_decode;
use super::*;

#[test]
fn strips_and_fans_keep_one_winding() {
    // A strip 0 1 2 3: (0 1 2), then (2 1 3) with the second triangle's
    // first two reversed, so both wind the same way.
    assert_eq!(triangulate(Mode::TriangleStrip, &[0, 1, 2, 3]), vec![[0, 1, 2], [2, 1, 3]]);
    assert_eq!(triangulate(Mode::TriangleFan, &[0, 1, 2, 3]), vec![[0, 1, 2], [0, 2, 3]]);
    assert_eq!(triangulate(Mode::Triangles, &[0, 1, 2, 3]), vec![[0, 1, 2]], "a trailing partial triangle is dropped");
    assert!(triangulate(Mode::TriangleStrip, &[0, 1]).is_empty());
}

#[test]
fn uv_transform_flips_v_after_the_extension_s_transform() {
    // Without the extension: (u, v) -> (u, 1 - v).
    let flip = uv_transform(None);
    assert!((flip.transform_point2(Vec2::new(0.25, 0.1)) - Vec2::new(0.25, 0.9)).length() < 1e-6);
}

#[test]
fn percent_escapes_are_decoded_and_bad_ones_kept() {
    assert_eq!(percent_decode("my%20file.bin"), "my file.bin");
    assert_eq!(percent_decode("100%"), "100%");
    assert_eq!(percent_decode("a%zzb"), "a%zzb");
    assert_eq!(percent_decode("%"), "%");
}
