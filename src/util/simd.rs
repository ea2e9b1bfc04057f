//! Four-lane maths the bounds and the light evaluation share: x^n by
//! repeated squaring for whole exponents and otherwise by `wide`'s
//! vectorised pow (exp2 of n log2 x with extended-precision logarithm, as
//! Agner Fog's vector class library computes it), instead of four calls
//! into libm. Every mode evaluates a light with the same code,
//! so they agree bit for bit on it.
//!
//! And which instruction set the hot paths run with: the per-point entry
//! points of the cut modes and of the exact renderer are compiled twice
//! (the `multiversion` crate), for baseline x86-64 (SSE2, which Debian's
//! packages must run on) and for AVX2 + FMA, and the best the CPU has is
//! chosen at run time. Both run the same operations in the same order (no
//! operation is fused: Rust never contracts a * b + c, and `wide` picks its
//! instructions by the crate's compile-time features, the same for both),
//! so the images are bit-identical either way (`tests/render_exact.rs`
//! renders with `LIGHTCUTS_BASELINE_SIMD=1` to check).
//!
//! No `unsafe` is written here: calling a function compiled for AVX2 is
//! unsafe in Rust, and the `multiversion` macro's generated dispatcher does
//! it only after `is_x86_feature_detected!` has found AVX2 and FMA (the
//! crate's own check, once per process).

use std::sync::OnceLock;

use multiversion::multiversion;
use wide::{f32x4, f64x4, CmpGt};

/// Whether the hot paths must run their baseline (SSE2) version even where
/// the CPU has AVX2 and FMA: set by the environment variable
/// `LIGHTCUTS_BASELINE_SIMD` (any value), for tests and A/B measurements.
#[must_use]
pub fn baseline_only() -> bool {
    static BASELINE: OnceLock<bool> = OnceLock::new();
    *BASELINE.get_or_init(|| std::env::var_os("LIGHTCUTS_BASELINE_SIMD").is_some())
}

/// Runs `f` compiled for the best instruction set the CPU has (AVX2 + FMA,
/// or baseline x86-64), unless [`baseline_only`]. What `f` calls runs in
/// that instruction set only where it is inlined into `f`: the hot paths'
/// functions are `#[inline(always)]` down to the evaluation and the bounds.
#[inline(always)]
pub fn best<R>(f: impl FnOnce() -> R) -> R {
    if baseline_only() {
        f()
    } else {
        avx2_fma(f)
    }
}

#[multiversion(targets("x86_64+avx2+fma"))]
fn avx2_fma<R, F: FnOnce() -> R>(f: F) -> R {
    f()
}

/// A 3-vector per lane.
pub type V3 = [f32x4; 3];

/// `v` in every lane.
#[inline(always)]
#[must_use]
pub fn splat3(v: glam::Vec3) -> V3 {
    [f32x4::splat(v.x), f32x4::splat(v.y), f32x4::splat(v.z)]
}

/// (a.x b.x + a.y b.y) + a.z b.z per lane: glam's Vec3::dot, lane by lane.
#[inline(always)]
#[must_use]
pub fn dot3(a: &V3, b: &V3) -> f32x4 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Largest relative error of [`pow`] against f64's powf, for x in [0, 1],
/// n from 0 to 1e6 and results above 1e-30 (4.4e-6 measured by the test
/// below over 4 million pairs), with a margin.
pub const POW_RELATIVE_ERROR: f32 = 1e-5;

/// What [`pow_upper`] adds to a non-zero result: covers results below
/// 1e-30, where the relative error is not measured.
const POW_ABSOLUTE_SLACK: f32 = 1e-30;

/// Largest exponent [`pow`] raises by repeated squaring (2^20).
const POW_SQUARING_LIMIT: f32 = 1_048_576.0;

/// x^n per lane, for x in [0, 1] and n >= 0 (0^0 = 1).
///
/// A whole exponent up to 2^20 (Phong exponents are, in every scene here)
/// is raised by repeated squaring in f64: at most 40 products, whose
/// relative error (at most one f64 rounding each, 40 x 1.1e-16) is far
/// below f32's, so the result is x^n correctly rounded to f32 or one ulp
/// off. It costs a tenth of `wide`'s exp2(n log2 x), which the walks of
/// the stochastic cut evaluated at every step on a glossy surface (14% of
/// a 256-spp render of `scenes/dof.toml`, docs/notebook/measurements.md). Other
/// exponents take `wide`'s pow.
#[inline(always)]
#[must_use]
pub fn pow(x: f32x4, n: f32) -> f32x4 {
    if (0.0..=POW_SQUARING_LIMIT).contains(&n) && n.fract() == 0.0 {
        // `n` is a whole number below 2^20: exact as a u32.
        let mut e = n as u32;
        let mut base = f64x4::from(x.to_array().map(f64::from));
        let mut power = f64x4::ONE;
        while e > 0 {
            if e & 1 == 1 {
                power *= base;
            }
            e >>= 1;
            if e > 0 {
                base *= base;
            }
        }
        // Round each lane to f32 (below f32's range this is 0 or subnormal,
        // as the true x^n rounds).
        return f32x4::from(power.to_array().map(|p| p as f32));
    }
    x.powf(n)
}

/// An upper bound of x^n per lane, for x in [0, 1] and n >= 0: [`pow`]
/// raised by its largest error. 0 stays 0 where x is 0 and n is not
/// (the bound of a lobe nothing can reach stays 0).
#[inline(always)]
#[must_use]
pub fn pow_upper(x: f32x4, n: f32) -> f32x4 {
    let p = pow(x, n);
    let raised = p * f32x4::splat(1.0 + POW_RELATIVE_ERROR) + f32x4::splat(POW_ABSOLUTE_SLACK);
    p.cmp_gt(f32x4::ZERO).blend(raised, p)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::util::sampling::Rng;

    #[test]
    fn pow_is_within_its_error_and_pow_upper_above_the_truth() {
        let mut rng = Rng::seeded(9);
        let exponents = [0.0f32, 0.5, 1.0, 2.0, 7.5, 40.0, 500.0, 1e4, 1e6, 1_048_576.0, 1_048_577.0];
        for i in 0..400_000 {
            let n = match i % 3 {
                0 => exponents[i % exponents.len()],
                1 => rng.range_f32(0.0, 2000.0).floor(),
                _ => rng.range_f32(0.0, 2000.0),
            };
            let x = if i % 2 == 0 { rng.next_f32() } else { 1.0 - 1e-3 * rng.next_f32() };
            let exact = f64::from(x).powf(f64::from(n));
            let (p, upper) = (pow(f32x4::splat(x), n).to_array()[0], pow_upper(f32x4::splat(x), n).to_array()[0]);
            // Below f32's normal range the evaluation (the same pow) is 0
            // too: the bound holds over what the renderer evaluates.
            if exact >= 1e-37 {
                assert!(f64::from(upper) >= exact, "pow_upper({x}, {n}) = {upper} below {exact}");
            }
            assert!(upper >= p, "pow_upper({x}, {n}) = {upper} below pow {p}");
            if exact > 1e-30 {
                let error = (f64::from(p) - exact).abs() / exact;
                assert!(error <= f64::from(POW_RELATIVE_ERROR) / 2.0, "pow({x}, {n}): relative error {error}");
                // Whole exponents by squaring in f64: within an f32 ulp.
                if n.fract() == 0.0 && n <= POW_SQUARING_LIMIT && exact >= 1e-37 {
                    assert!(error <= f64::from(f32::EPSILON), "pow({x}, {n}) by squaring: relative error {error}");
                }
            }
        }
        assert_eq!(pow(f32x4::splat(0.0), 0.0).to_array()[0], 1.0);
        assert_eq!(pow_upper(f32x4::splat(0.0), 3.0).to_array()[0], 0.0);
        assert_eq!(pow(f32x4::splat(1.0), 1e6).to_array()[0], 1.0);
    }
}
