//! The fibre BSDF against what it must satisfy whatever its parameters: a
//! fibre that absorbs nothing scatters all the light it meets (pbrt-v4's
//! `hair_test.cpp` white furnace), its sampling is exact for it, and the
//! cut's bound is above every value.

use std::f64::consts::PI;

use glam::Vec3;

use super::*;
use crate::util::sampling::Rng;

/// A fibre along +x hit at offset `h` across it, seen from `wo`.
fn fibre(wo: Vec3, h: f32, colour: Vec3, roughness: f32) -> Fibre {
    let x = Vec3::X;
    let across = (wo - x * x.dot(wo)).normalize();
    // The normal at azimuth gamma_o = asin h before the view's: n = wo
    // turned by -gamma_o about x.
    let normal = glam::Quat::from_axis_angle(x, -h.asin()) * across;
    Fibre::new(x, normal, wo, colour, roughness).unwrap()
}

fn unit(rng: &mut Rng) -> Vec3 {
    loop {
        let v = Vec3::new(rng.range_f32(-1.0, 1.0), rng.range_f32(-1.0, 1.0), rng.range_f32(-1.0, 1.0));
        if v.length_squared() > 1e-3 && v.length_squared() <= 1.0 {
            return v.normalize();
        }
    }
}

/// The integral of `g` over the sphere: the midpoint rule in (cos theta,
/// phi) about +x, `n` x 2n cells.
fn integrate(g: impl Fn(Vec3) -> f64, n: usize) -> f64 {
    let mut sum = 0.0;
    for i in 0..n {
        let z = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
        let r = (1.0 - z * z).max(0.0).sqrt();
        for j in 0..2 * n {
            let phi = PI * (j as f64 + 0.5) / n as f64;
            sum += g(Vec3::new(z as f32, (r * phi.cos()) as f32, (r * phi.sin()) as f32));
        }
    }
    sum * 4.0 * PI / (2 * n * n) as f64
}

#[test]
fn the_hit_offset_is_where_across_the_fibre_the_view_meets_it() {
    let wo = Vec3::new(0.3, 0.2, 0.9).normalize();
    for h in [-0.9, -0.3, 0.0, 0.5, 0.95] {
        let f = fibre(wo, h, Vec3::ONE, 0.3);
        assert!((f.gamma_o.sin() - h).abs() < 1e-5, "h = {h}: {}", f.gamma_o.sin());
    }
}

/// Chiang et al.'s model conserves energy to within the fits of its
/// variances: pbrt-v4 tests the same 5%. A fibre that absorbs nothing
/// returns all it meets, from every view, at every roughness.
#[test]
fn a_fibre_that_absorbs_nothing_scatters_all_the_light_it_meets() {
    let mut rng = Rng::seeded(3);
    for roughness in [0.2, 0.3, 0.5, 0.8, 1.0] {
        for _ in 0..4 {
            let wo = unit(&mut rng);
            let h = rng.range_f32(-1.0, 1.0);
            let f = fibre(wo, h, Vec3::ONE, roughness);
            let albedo = integrate(|wi| f64::from(f.f_cos(wi).y), 400);
            assert!((albedo - 1.0).abs() < 0.05, "beta {roughness}, wo {wo}, h {h}: {albedo}");
        }
    }
    // And one that absorbs does not.
    // And one that absorbs does not (a mat of such fibres looks 0.05: one
    // fibre still passes most of the light that enters it).
    let f = fibre(Vec3::new(0.1, 0.0, 1.0).normalize(), 0.2, Vec3::splat(0.05), 0.3);
    let albedo = integrate(|wi| f64::from(f.f_cos(wi).y), 200);
    assert!(albedo < 0.75, "{albedo}");
}

/// Without absorption the density is f cos itself (the A_p sum to 1), so
/// every sample weighs f cos / pdf = 1, as pbrt-v4's `SamplingWeights`.
#[test]
fn without_absorption_every_sample_weighs_one() {
    let mut rng = Rng::seeded(5);
    for roughness in [0.05, 0.2, 0.5, 1.0] {
        let wo = unit(&mut rng);
        let f = fibre(wo, rng.range_f32(-1.0, 1.0), Vec3::ONE, roughness);
        for _ in 0..2000 {
            let u = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
            let Some((wi, pdf)) = f.sample(u) else { continue };
            let weight = f.f_cos(wi).y / pdf;
            assert!((weight - 1.0).abs() < 1e-3, "beta {roughness}: {weight}");
            assert_eq!(pdf, f.pdf(wi));
        }
    }
}

/// The density integrates to one over the sphere, absorbing or not.
#[test]
fn the_density_integrates_to_one() {
    let mut rng = Rng::seeded(8);
    for (roughness, colour) in [(0.3, Vec3::new(0.6, 0.4, 0.2)), (0.7, Vec3::splat(0.05)), (0.2, Vec3::ONE)] {
        let wo = unit(&mut rng);
        let f = fibre(wo, rng.range_f32(-1.0, 1.0), colour, roughness);
        let total = integrate(|wi| f64::from(f.pdf(wi)), 600);
        assert!((total - 1.0).abs() < 5e-3, "beta {roughness}: {total}");
    }
}

/// The cut's bound is above f cos in every direction, the lobes' peaks
/// (where the sampler draws most) included, for narrow and wide lobes.
#[test]
fn the_bound_is_above_every_value() {
    let mut rng = Rng::seeded(11);
    for roughness in [0.05, 0.1, 0.3, 1.0] {
        for _ in 0..20 {
            let wo = unit(&mut rng);
            let colour = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            let f = fibre(wo, rng.range_f32(-1.0, 1.0), colour, roughness);
            let peak = f.peak();
            let mut highest = Vec3::ZERO;
            for k in 0..4000 {
                let wi = if k % 2 == 0 {
                    unit(&mut rng)
                } else {
                    match f.sample([rng.next_f32(), rng.next_f32(), rng.next_f32()]) {
                        Some((wi, _)) => wi,
                        None => continue,
                    }
                };
                let value = f.f_cos(wi);
                assert!(value.cmple(peak).all(), "beta {roughness}: {value} above {peak}");
                highest = highest.max(value);
            }
            // Not a bound that says nothing: within 3x of what is met.
            assert!(peak.y < 3.0 * highest.y + 1e-6, "beta {roughness}: {peak} against {highest}");
        }
    }
}

/// Light from behind a fibre reaches the viewer through it (TT), which a
/// surface's BSDF would give nothing for; a dark fibre passes less of it
/// (a single fibre of a mat that looks 0.05 still passes 60% a pass).
#[test]
fn light_from_behind_passes_through_a_light_fibre() {
    let wo = Vec3::new(0.0, 0.0, 1.0);
    let blond = fibre(wo, 0.0, Vec3::new(0.9, 0.8, 0.6), 0.3);
    let dark = fibre(wo, 0.0, Vec3::splat(0.05), 0.3);
    let behind = -wo;
    let side = Vec3::Y;
    assert!(blond.f_cos(behind).y > 2.0 * blond.f_cos(side).y, "{} {}", blond.f_cos(behind), blond.f_cos(side));
    assert!(dark.f_cos(behind).y < 0.8 * blond.f_cos(behind).y);
}

/// The search for M_p's peak finds what a fine grid of theta_i finds, for
/// narrow lobes seen from near the fibre's ends too (where M_p underflows
/// to 0 away from its lobe).
#[test]
fn the_longitudinal_peak_is_found() {
    let mut rng = Rng::seeded(11);
    for roughness in [0.05, 0.3] {
        for _ in 0..20 {
            let f = fibre(unit(&mut rng), rng.range_f32(-1.0, 1.0), Vec3::splat(0.5), roughness);
            for p in 0..=P_MAX {
                let (sin_o, cos_o) = f.tilted[p];
                let grid = (0..=20_000)
                    .map(|k| {
                        let theta = std::f32::consts::PI * (k as f32 / 20_000.0 - 0.5);
                        f.mp(p, theta.cos(), theta.sin(), cos_o, sin_o)
                    })
                    .fold(0.0f32, f32::max);
                let found = f.mp_peak(p);
                assert!(found >= 0.999 * grid && found <= 1.01 * grid, "beta {roughness}, p {p}: {found} {grid}");
            }
        }
    }
}
