//! Colour helpers: the scalar an RGB value is compared on (Rec. 709
//! luminance) and the sRGB transfer functions (IEC 61966-2-1). The renderer's
//! RGB is linear Rec. 709 with a D65 white.

use glam::{DVec3, Vec3};

/// Rec. 709 luminance of linear RGB: the scalar lights and errors are compared
/// on (representative selection probabilities, cut error bounds, image error).
#[must_use]
pub fn luminance(rgb: Vec3) -> f32 {
    0.2126 * rgb.x + 0.7152 * rgb.y + 0.0722 * rgb.z
}

/// [`luminance`] in f64.
#[must_use]
pub fn luminance64(rgb: DVec3) -> f64 {
    0.2126 * rgb.x + 0.7152 * rgb.y + 0.0722 * rgb.z
}

/// The sRGB electro-optical transfer function: encoded value to linear.
#[must_use]
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The inverse: linear value to sRGB-encoded.
#[must_use]
pub fn linear_to_srgb(c: f32) -> f32 {
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_decoding_hits_known_points() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        assert!((srgb_to_linear(0.5) - 0.214).abs() < 1e-3);
    }

    #[test]
    fn srgb_encoding_round_trips_the_decoder() {
        for i in 0..=20 {
            let c = i as f32 / 20.0;
            let back = srgb_to_linear(linear_to_srgb(c));
            assert!((back - c).abs() < 1e-5, "{c} -> {back}");
        }
    }

    #[test]
    fn luminance_weights_sum_to_one() {
        assert!((luminance(Vec3::ONE) - 1.0).abs() < 1e-6);
        assert!((luminance64(DVec3::ONE) - 1.0).abs() < 1e-12);
    }
}
