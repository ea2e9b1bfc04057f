//! The rough transmission's draws against Walter et al. 2007's BTDF,
//! written out here in f64 from its equations (pbrt-v4's
//! `DielectricBxDF::f` without the radiance's η² factor, docs/design.md
//! §5.8): over a grid of cells on the sphere, the mean weight the draws
//! leave in each cell equals the quadrature of f |cos| over the cell.
//! That checks the direction's density and the weight together.

use glam::{DVec3, Vec3};

use super::*;
use crate::util::sampling::Rng;

const Z_CELLS: usize = 16;
const PHI_CELLS: usize = 12;

/// A white, fully transmitting dielectric of roughness^2 `alpha`, IOR
/// `ior`: its tint is 1.
fn glass(alpha: f32, ior: f32) -> Pbr {
    Pbr { transmission: 1.0, alpha, ..Pbr::with_ior(Vec3::ONE, 0.0, alpha.sqrt(), 1.0, Vec3::ONE, ior) }
}

fn schlick(f0: f64, cos: f64) -> f64 {
    f0 + (1.0 - f0) * (1.0 - cos.clamp(0.0, 1.0)).powi(5)
}

fn lambda(cos: f64, alpha: f64) -> f64 {
    let tan2 = (1.0 - cos * cos).max(0.0) / (cos * cos);
    0.5 * ((1.0 + alpha * alpha * tan2).sqrt() - 1.0)
}

fn ggx_d(m: DVec3, alpha: f64) -> f64 {
    let a2 = alpha * alpha;
    let d = (m.x * m.x + m.y * m.y) + m.z * m.z * a2;
    a2 / (std::f64::consts::PI * d * d)
}

/// f |cos θi| of the transmission lobe from `wo` (z > 0) towards `wi`,
/// both in the shading frame, for `interface` with η `eta`.
fn reference(wo: DVec3, wi: DVec3, alpha: f64, eta: f64, f0: f64, interface: Interface) -> f64 {
    let g2 = |wi: DVec3| 1.0 / (1.0 + lambda(wo.z, alpha) + lambda(wi.z.abs(), alpha));
    // The microfacet reflection's f |cos| with a transmitted share `t`.
    let reflection = |wi: DVec3, t: &dyn Fn(f64, DVec3) -> f64| {
        let m = (wo + wi).normalize();
        if wi.z <= 0.0 || m.z <= 0.0 {
            return 0.0;
        }
        t(wo.dot(m), m) * ggx_d(m, alpha) * g2(wi) / (4.0 * wo.z)
    };
    match interface {
        Interface::ThinWall => {
            reflection(DVec3::new(wi.x, wi.y, -wi.z), &|cos, _| if wi.z < 0.0 { 1.0 - schlick(f0, cos) } else { 0.0 })
        }
        _ if wi.z > 0.0 => {
            // Total internal reflection at microfacets past the critical
            // angle: the share the Schlick term left.
            let past = |cos: f64, _| if 1.0 - cos * cos > eta * eta { 1.0 - schlick(f0, cos) } else { 0.0 };
            reflection(wi, &past)
        }
        _ => {
            // The generalised half-vector of a refraction, on the view's side.
            let mut m = (wi * eta + wo).normalize();
            if m.z < 0.0 {
                m = -m;
            }
            let (o_m, i_m) = (wo.dot(m), wi.dot(m));
            if o_m <= 0.0 || i_m >= 0.0 {
                return 0.0;
            }
            let air = if interface == Interface::Entering { o_m } else { -i_m };
            let denominator = (i_m + o_m / eta).powi(2);
            let f = (1.0 - schlick(f0, air)) * ggx_d(m, alpha) * g2(wi) * (i_m * o_m).abs()
                / (wi.z.abs() * wo.z * denominator);
            f * wi.z.abs()
        }
    }
}

/// The cell of a unit direction: z from -1 to 1, then φ.
fn cell(d: DVec3) -> usize {
    let zi = (((d.z + 1.0) / 2.0 * Z_CELLS as f64) as usize).min(Z_CELLS - 1);
    let phi = d.y.atan2(d.x).rem_euclid(std::f64::consts::TAU);
    let pi = ((phi / std::f64::consts::TAU * PHI_CELLS as f64) as usize).min(PHI_CELLS - 1);
    zi * PHI_CELLS + pi
}

/// The quadrature of the reference over every cell: the midpoint rule
/// on a grid uniform in θ (fine at the poles, where a smooth lobe's
/// refraction narrows by η) and φ, each point of solid angle sin θ dθ dφ.
fn quadrature(wo: DVec3, alpha: f64, eta: f64, f0: f64, interface: Interface) -> Vec<f64> {
    const THETA_STEPS: usize = 3000;
    const PHI_STEPS: usize = PHI_CELLS * 32;
    let (d_theta, d_phi) = (std::f64::consts::PI / THETA_STEPS as f64, std::f64::consts::TAU / PHI_STEPS as f64);
    let mut cells = vec![0.0; Z_CELLS * PHI_CELLS];
    for i in 0..THETA_STEPS {
        let theta = (i as f64 + 0.5) * d_theta;
        let (r, z) = (theta.sin(), theta.cos());
        for j in 0..PHI_STEPS {
            let phi = (j as f64 + 0.5) * d_phi;
            let wi = DVec3::new(r * phi.cos(), r * phi.sin(), z);
            cells[cell(wi)] += reference(wo, wi, alpha, eta, f0, interface) * r * d_theta * d_phi;
        }
    }
    cells
}

/// The mean weight the draws leave in each cell.
fn draws(pbr: &Pbr, wo: Vec3, interface: Interface, count: usize) -> Vec<f64> {
    let mut cells = vec![0.0; Z_CELLS * PHI_CELLS];
    let mut rng = Rng::seeded(7);
    for _ in 0..count {
        let u = [rng.next_f32(), rng.next_f32()];
        if let Some(s) = pbr.sample_rough_transmission(Vec3::Z, wo, interface, wo.z, u) {
            assert_eq!(s.crossed, s.direction.z < 0.0, "{s:?}");
            cells[cell(s.direction.as_dvec3())] += f64::from(s.weight.y);
        }
    }
    cells.iter().map(|c| c / count as f64).collect()
}

/// The largest difference between the draws and the quadrature over the
/// cells, and both totals.
fn compare(pbr: &Pbr, wo: Vec3, interface: Interface) -> (f64, f64, f64) {
    let eta = f64::from(interface.eta(pbr.ior));
    let f0 = f64::from(pbr.f0.x);
    let want = quadrature(wo.as_dvec3(), f64::from(pbr.alpha), eta, f0, interface);
    let got = draws(pbr, wo, interface, 400_000);
    let worst = want.iter().zip(&got).map(|(w, g)| (w - g).abs()).fold(0.0, f64::max);
    (worst, want.iter().sum(), got.iter().sum())
}

fn views() -> [Vec3; 3] {
    [Vec3::Z, Vec3::new(0.6, 0.0, 0.8), Vec3::new(-0.3, 0.9, 0.3).normalize()]
}

#[test]
fn the_draws_follow_walter_s_btdf_for_every_interface() {
    for (alpha, ior) in [(0.3, 1.5), (0.6, 1.5), (0.4, 2.4)] {
        let pbr = glass(alpha, ior);
        for interface in [Interface::Entering, Interface::Leaving, Interface::ThinWall] {
            for wo in views() {
                let (worst, want, got) = compare(&pbr, wo, interface);
                eprintln!(
                    "alpha {alpha} ior {ior} {interface:?} wo {wo}: total {got:.4} vs {want:.4}, worst cell {worst:.4}"
                );
                assert!((got - want).abs() < 0.01, "{interface:?} {wo}: total {got} vs {want}");
                assert!(worst < 0.006, "{interface:?} {wo}: a cell is {worst} off");
            }
        }
    }
}

#[test]
fn the_comparison_catches_a_wrong_weight() {
    // The same draws weighted by G2 alone (a G1 too many) are caught.
    let pbr = glass(0.6, 1.5);
    let wo = Vec3::new(-0.3, 0.9, 0.3).normalize();
    let want = quadrature(wo.as_dvec3(), 0.6, 1.5, 0.04, Interface::Entering);
    let g1 = 1.0 / (1.0 + lambda(f64::from(wo.z), 0.6));
    let got: Vec<f64> = draws(&pbr, wo, Interface::Entering, 400_000).iter().map(|c| c * g1).collect();
    let worst = want.iter().zip(&got).map(|(w, g)| (w - g).abs()).fold(0.0, f64::max);
    assert!(worst > 0.006, "a wrong weight passes: {worst}");
}
