//! Four-lane maths the bounds and the light evaluation share: x^n by
//! `wide`'s vectorised pow (exp2 of n log2 x with extended-precision
//! logarithm, as Agner Fog's vector class library computes it), instead of
//! four calls into libm. Every mode evaluates a light with the same code,
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
use bytemuck::cast;
use wide::{f32x4, i32x4, u32x4, CmpEq, CmpGt, CmpLt};

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

/// x^n per lane, for x in [0, 1] and n >= 0 (0^0 = 1).
#[inline(always)]
#[must_use]
pub fn pow(x: f32x4, n: f32) -> f32x4 {
    wide_pow(x, f32x4::splat(n))
}

/// `wide` 0.7's `f32x4::pow_f32x4`, operation for operation, so the same
/// bits (`pow_is_wides_to_the_bit` compares them). `wide` marks it
/// `#[inline]` only, and it is too long for the compiler to inline: called
/// out of line, it ran in baseline code outside the AVX2 entry points, and
/// was a tenth of atrium's render. Written here `#[inline(always)]`, it is
/// compiled into each entry point (docs/design.md §4). Its helpers that
/// `wide` keeps private are written out below, as `wide` writes them.
#[inline(always)]
#[must_use]
#[allow(clippy::excessive_precision, clippy::unreadable_literal)]
fn wide_pow(base: f32x4, y: f32x4) -> f32x4 {
    let c = f32x4::splat;
    let (ln2f_hi, ln2f_lo) = (c(0.693359375), c(-2.12194440e-4));
    let (p0log, p1log, p2log) = (c(3.3333331174E-1), c(-2.4999993993E-1), c(2.0000714765E-1));
    let (p3log, p4log, p5log) = (c(-1.6668057665E-1), c(1.4249322787E-1), c(-1.2420140846E-1));
    let (p6log, p7log, p8log) = (c(1.1676998740E-1), c(-1.1514610310E-1), c(7.0376836292E-2));
    let (p2exp, p3exp, p4exp) = (c(1.0 / 2.0), c(1.0 / 6.0), c(1.0 / 24.0));
    let (p5exp, p6exp, p7exp) = (c(1.0 / 120.0), c(1.0 / 720.0), c(1.0 / 5040.0));

    let x1 = base.abs();
    let x = fraction_2(x1);
    let mask = x.cmp_gt(f32x4::SQRT_2 * f32x4::HALF);
    let x = (!mask).blend(x + x, x);
    let x = x - f32x4::ONE;
    let x2 = x * x;
    // wide's polynomial_8!.
    let lg1 = {
        let (x4, x8) = (x2 * x2, (x2 * x2) * (x2 * x2));
        x4.mul_add(
            x2.mul_add(p7log.mul_add(x, p6log), x.mul_add(p5log, p4log)),
            x8.mul_add(p8log, x2.mul_add(x.mul_add(p3log, p2log), x.mul_add(p1log, p0log))),
        )
    };
    let lg1 = lg1 * x2 * x;
    let ef = exponent(x1);
    let ef = mask.blend(ef + f32x4::ONE, ef);
    let e1 = (ef * y).round();
    let yr = ef.mul_sub(y, e1);
    let lg = f32x4::HALF.mul_neg_add(x2, x) + lg1;
    let x2_err = (f32x4::HALF * x).mul_sub(x, f32x4::HALF * x2);
    let lg_err = f32x4::HALF.mul_add(x2, lg - x) - lg1;
    let e2 = (lg * y * f32x4::LOG2_E).round();
    let v = lg.mul_sub(y, e2 * ln2f_hi);
    let v = e2.mul_neg_add(ln2f_lo, v);
    let v = v - (lg_err + x2_err).mul_sub(y, yr * f32x4::LN_2);
    let x = v;
    let e3 = (x * f32x4::LOG2_E).round();
    let x = e3.mul_neg_add(f32x4::LN_2, x);
    let x2 = x * x;
    // wide's polynomial_5!.
    let poly = {
        let (x2, x4) = (x * x, (x * x) * (x * x));
        p5exp.mul_add(x, p4exp).mul_add(x2, p7exp.mul_add(x, p6exp).mul_add(x4, p3exp.mul_add(x, p2exp)))
    };
    let z = x2.mul_add(poly, x + f32x4::ONE);
    let ee = e1 + e2 + e3;
    let ei: i32x4 = ee.round_int();
    let ej: i32x4 = ei + (cast::<_, i32x4>(z) >> 23_i32);
    let overflow = cast::<_, f32x4>(ej.cmp_gt(i32x4::splat(0x0FF))) | ee.cmp_gt(c(300.0));
    let underflow = cast::<_, f32x4>(ej.cmp_lt(i32x4::splat(0x000))) | ee.cmp_lt(c(-300.0));
    let z = cast::<_, f32x4>(cast::<_, i32x4>(z) + (ei << 23_i32));
    let z = if (overflow | underflow).any() {
        let z = underflow.blend(f32x4::ZERO, z);
        overflow.blend(infinity(), z)
    } else {
        z
    };
    let x_zero = is_zero_or_subnormal(base);
    let z = x_zero.blend(y.cmp_lt(f32x4::ZERO).blend(infinity(), y.cmp_eq(f32x4::ZERO).blend(f32x4::ONE, f32x4::ZERO)), z);
    let x_sign = base.sign_bit();
    let z = if x_sign.any() {
        let yi = y.cmp_eq(y.round());
        let y_odd = (y.round_int() << 31_i32).round_float();
        let z1 = yi.blend(z | y_odd, base.cmp_eq(f32x4::ZERO).blend(z, nan_pow()));
        x_sign.blend(z1, z)
    } else {
        z
    };
    if (base.is_finite() & y.is_finite() & (ee.is_finite() | x_zero)).all() {
        return z;
    }
    (base.is_nan() | y.is_nan()).blend(base + y, z)
}

/// wide's private `f32x4::exponent`: the unbiased exponent as a float.
#[inline(always)]
fn exponent(v: f32x4) -> f32x4 {
    let pow2_23 = f32x4::splat(8_388_608.0);
    let b = cast::<_, u32x4>(v) >> 23_i32;
    cast::<_, f32x4>(b | cast::<_, u32x4>(pow2_23)) - (pow2_23 + f32x4::splat(127.0))
}

/// wide's private `f32x4::fraction_2`: the mantissa scaled into [0.5, 1).
#[inline(always)]
fn fraction_2(v: f32x4) -> f32x4 {
    cast::<_, f32x4>((cast::<_, u32x4>(v) & u32x4::from(0x007F_FFFF)) | u32x4::from(0x3F00_0000))
}

/// wide's private `f32x4::is_zero_or_subnormal`.
#[inline(always)]
fn is_zero_or_subnormal(v: f32x4) -> f32x4 {
    let t = cast::<_, i32x4>(v) & i32x4::splat(0x7F80_0000);
    t.cmp_eq(i32x4::splat(0)).round_float()
}

#[inline(always)]
fn infinity() -> f32x4 {
    cast::<_, f32x4>(i32x4::splat(0x7F80_0000))
}

/// wide's private `f32x4::nan_pow`.
#[inline(always)]
fn nan_pow() -> f32x4 {
    cast::<_, f32x4>(i32x4::splat(0x7FC0_0000 | (0x101 & 0x003F_FFFF)))
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
    fn pow_is_wides_to_the_bit() {
        let mut rng = crate::util::sampling::Rng::seeded(11);
        let special = [0.0, -0.0, 1.0, -1.0, 0.5, 1e-40, -1e-40, f32::MIN_POSITIVE, f32::INFINITY, f32::NAN, -2.5, 3.0];
        let exponents = [0.0, 1.0, 2.0, 3.0, 0.5, 60.0, 1e6, -1.0, -3.0, f32::INFINITY, f32::NAN, 1e-7];
        let mut check = |x: [f32; 4], n: f32| {
            let (ours, theirs) = (pow(f32x4::new(x), n).to_array(), f32x4::new(x).powf(n).to_array());
            assert_eq!(ours.map(f32::to_bits), theirs.map(f32::to_bits), "pow({x:?}, {n})");
        };
        for &x in &special {
            for &n in &exponents {
                check([x, 0.25, x, 0.75], n);
            }
        }
        for _ in 0..1_000_000 {
            let x = std::array::from_fn(|_| match (rng.next_u64() as u32) % 4 {
                0 => rng.next_f32(),
                1 => rng.next_f32().powi(8),
                2 => rng.range_f32(-4.0, 4.0),
                _ => f32::from_bits((rng.next_u64() as u32)),
            });
            let n = match (rng.next_u64() as u32) % 3 {
                0 => rng.range_f32(0.0, 2000.0),
                1 => rng.range_f32(-50.0, 50.0).round(),
                _ => f32::from_bits((rng.next_u64() as u32)),
            };
            check(x, n);
        }
    }

    #[test]
    fn pow_is_within_its_error_and_pow_upper_above_the_truth() {
        let mut rng = Rng::seeded(9);
        let exponents = [0.0f32, 0.5, 1.0, 2.0, 7.5, 40.0, 500.0, 1e4, 1e6];
        for i in 0..400_000 {
            let n = if i % 3 == 0 { exponents[i % exponents.len()] } else { rng.range_f32(0.0, 2000.0) };
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
            }
        }
        assert_eq!(pow(f32x4::splat(0.0), 0.0).to_array()[0], 1.0);
        assert_eq!(pow_upper(f32x4::splat(0.0), 3.0).to_array()[0], 0.0);
        assert_eq!(pow(f32x4::splat(1.0), 1e6).to_array()[0], 1.0);
    }
}
