//! KHR_materials_sheen's layer (docs/design.md §5.10): the "Charlie"
//! microfibre distribution and its visibility (Conty Estevez and Kulla
//! 2017, "Production Friendly Microfacet Sheen BRDF", as the extension's
//! implementation notes give them), and the sheen's directional albedo
//! E(cos), which scales the base below it ("albedo scaling").
//!
//! Each function is monotonic in the cosine it takes, as the cut's bound
//! needs (lightcut::bounds): D grows with sin(theta_h); Lambda falls as the
//! cosine grows, so f cos grows with n.l.

use std::f32::consts::PI;
use std::sync::OnceLock;

/// The smallest sheen roughness the lobe is evaluated with: below it D's
/// exponent 1 / r runs past 14 and the lobe is a sliver at grazing angles
/// no sampler finds (the Khronos sample viewer clamps at the same value).
pub const MIN_SHEEN_ROUGHNESS: f32 = 0.07;

/// The Charlie distribution D(h) = (2 + 1/r) sin(theta_h)^(1/r) / (2 pi)
/// of `sin2_h` = sin^2(theta_h), for roughness `r` (the extension's alphaG
/// = sheenRoughness, at least [`MIN_SHEEN_ROUGHNESS`]). Increasing in
/// sin^2, at most (2 + 1/r) / (2 pi) at a half-vector in the plane.
#[must_use]
pub fn distribution(sin2_h: f32, r: f32) -> f32 {
    let inverse = 1.0 / r;
    (2.0 + inverse) * sin2_h.clamp(0.0, 1.0).powf(0.5 * inverse) / (2.0 * PI)
}

/// The largest D over every half-vector: at sin(theta_h) = 1.
#[must_use]
pub fn peak_distribution(r: f32) -> f32 {
    (2.0 + 1.0 / r) / (2.0 * PI)
}

/// The fit l(x) of the Charlie masking's exponent (the paper's table,
/// interpolated in (1 - r)^2 between its two roughness rows).
fn l(x: f32, r: f32) -> f32 {
    let t = (1.0 - r) * (1.0 - r);
    let mix = |a: f32, b: f32| a + (b - a) * t;
    let (a, b, c) = (mix(21.5473, 25.3245), mix(3.82987, 3.32435), mix(0.19823, 0.16801));
    let (d, e) = (mix(-1.97760, -1.27393), mix(-4.32054, -4.85967));
    a / (1.0 + b * x.powf(c)) + d * x + e
}

/// The Charlie masking Lambda(cos theta): exp(l(cos)) below 0.5, and
/// exp(2 l(0.5) - l(1 - cos)) above (the paper's "terminator softening"
/// left out, as the extension does). Decreasing in the cosine (l falls
/// with x: each of its terms does).
#[must_use]
pub fn lambda(cos: f32, r: f32) -> f32 {
    let cos = cos.clamp(0.0, 1.0);
    if cos < 0.5 {
        l(cos, r).exp()
    } else {
        (2.0 * l(0.5, r) - l(1.0 - cos, r)).exp()
    }
}

/// The white sheen's f cos for n.l `cos_l` > 0, n.v `cos_v` and
/// sin^2(theta_h) `sin2_h`: D G / (4 n.l n.v) n.l with the height-
/// correlated G = 1 / (1 + Lambda(v) + Lambda(l)), i.e. D / (4 n.v (1 +
/// Lambda(v) + Lambda(l))). `lambda_v` is Lambda(n.v), computed once per
/// point.
#[must_use]
pub fn f_cos(sin2_h: f32, cos_l: f32, cos_v: f32, lambda_v: f32, r: f32) -> f32 {
    if cos_l <= 0.0 {
        return 0.0;
    }
    distribution(sin2_h, r) / (4.0 * cos_v * (1.0 + lambda_v + lambda(cos_l, r)))
}

/// Table size of E: cosines 0, 1/(N-1), ..., 1 and roughnesses from
/// [`MIN_SHEEN_ROUGHNESS`] to 1.
const COSINES: usize = 32;
const ROUGHNESSES: usize = 16;

/// The white sheen's directional albedo E(cos_v) = the integral of its f
/// cos over the hemisphere, for roughness `r`: what the base below keeps
/// 1 - max(sheen colour) E of (the extension's albedo scaling). Read from
/// a table integrated once (midpoint rule over n.l and the azimuth),
/// bilinearly; within a percent of a Monte Carlo estimate
/// (`the_albedo_table_matches_an_independent_estimate`).
#[must_use]
pub fn albedo(cos_v: f32, r: f32) -> f32 {
    let table = TABLE.get_or_init(integrate_table);
    let x = cos_v.clamp(0.0, 1.0) * (COSINES - 1) as f32;
    let y = ((r - MIN_SHEEN_ROUGHNESS) / (1.0 - MIN_SHEEN_ROUGHNESS)).clamp(0.0, 1.0) * (ROUGHNESSES - 1) as f32;
    let (i, j) = ((x as usize).min(COSINES - 2), (y as usize).min(ROUGHNESSES - 2));
    let (fx, fy) = (x - i as f32, y - j as f32);
    let at = |i: usize, j: usize| table[j * COSINES + i];
    let lower = at(i, j) + (at(i + 1, j) - at(i, j)) * fx;
    let upper = at(i, j + 1) + (at(i + 1, j + 1) - at(i, j + 1)) * fx;
    (lower + (upper - lower) * fy).clamp(0.0, 1.0)
}

static TABLE: OnceLock<Vec<f32>> = OnceLock::new();

/// E at the table's nodes, row by roughness. A view at cosine 0 is
/// integrated at a cosine of 1e-3 (the view term 1 / n.v is finite there
/// and the masking makes f cos vanish with it).
fn integrate_table() -> Vec<f32> {
    let mut table = Vec::with_capacity(COSINES * ROUGHNESSES);
    for j in 0..ROUGHNESSES {
        let r = MIN_SHEEN_ROUGHNESS + (1.0 - MIN_SHEEN_ROUGHNESS) * j as f32 / (ROUGHNESSES - 1) as f32;
        for i in 0..COSINES {
            let cos_v = (i as f32 / (COSINES - 1) as f32).max(1e-3);
            table.push(integrate(cos_v, r) as f32);
        }
    }
    table
}

/// The hemispherical integral of the white sheen's f cos seen at `cos_v`:
/// f cos dw = f cos d(n.l) d(phi), by the midpoint rule (phi over half
/// the circle: the lobe is symmetric about the plane of n and v).
fn integrate(cos_v: f32, r: f32) -> f64 {
    const STEPS_COS: usize = 96;
    const STEPS_PHI: usize = 48;
    let sin_v = (1.0 - cos_v * cos_v).max(0.0).sqrt();
    let v = glam::Vec3::new(sin_v, 0.0, cos_v);
    let lambda_v = lambda(cos_v, r);
    let mut sum = 0.0f64;
    for a in 0..STEPS_COS {
        let cos_l = (a as f32 + 0.5) / STEPS_COS as f32;
        let sin_l = (1.0 - cos_l * cos_l).max(0.0).sqrt();
        for b in 0..STEPS_PHI {
            let phi = (b as f32 + 0.5) / STEPS_PHI as f32 * PI;
            let l = glam::Vec3::new(sin_l * phi.cos(), sin_l * phi.sin(), cos_l);
            let h = (v + l).normalize();
            let sin2_h = h.x * h.x + h.y * h.y;
            sum += f64::from(f_cos(sin2_h, cos_l, cos_v, lambda_v, r));
        }
    }
    sum * 2.0 * std::f64::consts::PI / (STEPS_COS * STEPS_PHI) as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::util::sampling::Rng;

    #[test]
    fn lambda_falls_and_d_grows_with_their_arguments() {
        for r in [MIN_SHEEN_ROUGHNESS, 0.3, 0.6, 1.0] {
            let mut last = (f32::INFINITY, 0.0f32);
            for k in 0..=1000 {
                let x = k as f32 / 1000.0;
                let (lam, d) = (lambda(x, r), distribution(x, r));
                assert!(
                    lam <= last.0 && d >= last.1,
                    "r {r}, x {x}: lambda {lam} after {}, D {d} after {}",
                    last.0,
                    last.1
                );
                last = (lam, d);
            }
            assert!((distribution(1.0, r) - peak_distribution(r)).abs() <= 1e-6 * peak_distribution(r));
        }
    }

    /// The D integrates to 1 over the projected hemisphere of half-vectors
    /// (a distribution of normals: the integral of D cos theta_h is 1).
    #[test]
    fn the_distribution_is_normalised() {
        for r in [MIN_SHEEN_ROUGHNESS, 0.5, 1.0] {
            let steps = 20_000;
            let integral: f64 = (0..steps)
                .map(|k| {
                    let cos = (k as f64 + 0.5) / f64::from(steps);
                    f64::from(distribution((1.0 - cos * cos) as f32, r)) * cos
                })
                .sum::<f64>()
                * 2.0
                * std::f64::consts::PI
                / f64::from(steps);
            assert!((integral - 1.0).abs() < 1e-3, "r {r}: {integral}");
        }
    }

    /// E from the table against a Monte Carlo estimate with uniformly
    /// drawn directions (no shared quadrature), and between 0 and 1.
    #[test]
    fn the_albedo_table_matches_an_independent_estimate() {
        let mut rng = Rng::seeded(17);
        for (cos_v, r) in [(0.9f32, 0.3f32), (0.5, 0.5), (0.2, 1.0), (0.7, 0.1), (0.33, 0.8)] {
            let v = glam::Vec3::new((1.0 - cos_v * cos_v).sqrt(), 0.0, cos_v);
            let lambda_v = lambda(cos_v, r);
            let n = 400_000;
            let mut sum = 0.0f64;
            for _ in 0..n {
                let (u1, u2) = (rng.next_f32(), rng.next_f32());
                let z = u1;
                let s = (1.0 - z * z).max(0.0).sqrt();
                let l = glam::Vec3::new(s * (2.0 * PI * u2).cos(), s * (2.0 * PI * u2).sin(), z);
                let h = (v + l).normalize();
                sum += f64::from(f_cos(h.x * h.x + h.y * h.y, z, cos_v, lambda_v, r)) * 2.0 * std::f64::consts::PI;
            }
            let estimate = sum / f64::from(n);
            let table = f64::from(albedo(cos_v, r));
            assert!((0.0..=1.0).contains(&table), "E {table}");
            assert!(
                (table - estimate).abs() < 0.01 + 0.02 * estimate,
                "cos {cos_v}, r {r}: table {table}, estimate {estimate}"
            );
        }
    }
}
