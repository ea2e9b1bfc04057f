//! Upper bounds of the material and geometric terms over a cluster
//! ([LC05] sec. 4.2; ../shared/LIGHTCUTS.md sections 2 to 4). Each is tested
//! to be >= the true maximum over the cluster's lights at random points.

use std::f32::consts::PI;

use glam::{DVec3, Vec3};

use crate::light::luminance64;
use crate::light_tree::{Cone, LightKind};
use crate::render::geometry::SurfacePoint;
use crate::scene::material::phong_normalisation;

/// Relative slack added to every cosine bound: the bound is evaluated in f32
/// with a few roundings (rotation, sqrt), each within 1 ulp; 1e-5 covers
/// them with a wide margin and changes cut sizes by nothing measurable.
const COS_SLACK: f32 = 1e-5;

/// Upper bound of cos(angle between unit `axis` and v) over all v in the box
/// [lo, hi] (LIGHTCUTS.md section 3): the box of the rotated box, by interval
/// arithmetic, then w / sqrt(u^2 + v^2 + w^2) at the largest w and smallest |u|, |v|.
#[must_use]
pub fn cos_bound(axis: Vec3, lo: Vec3, hi: Vec3) -> f32 {
    let (tangent, bitangent) = axis.any_orthonormal_pair();
    let range = |e: Vec3| {
        let (a, b) = (e * lo, e * hi);
        (a.min(b).element_sum(), a.max(b).element_sum())
    };
    let (x0, x1) = range(tangent);
    let (y0, y1) = range(bitangent);
    let (_, z1) = range(axis);
    if z1 <= 0.0 {
        return 0.0;
    }
    let nearest = |a: f32, b: f32| if a <= 0.0 && 0.0 <= b { 0.0 } else { a.abs().min(b.abs()) };
    let (mx, my) = (nearest(x0, x1), nearest(y0, y1));
    let bound = z1 / (mx * mx + my * my + z1 * z1).sqrt();
    (bound * (1.0 + COS_SLACK) + COS_SLACK).min(1.0)
}

/// Squared distance from `p` to the box [lo, hi] (0 inside).
#[must_use]
pub fn distance_squared_to_box(p: Vec3, lo: Vec3, hi: Vec3) -> f64 {
    let d = (lo - p).max(p - hi).max(Vec3::ZERO);
    d.as_dvec3().length_squared()
}

/// Upper bound of the material term M = f_r cos(theta) over directions in
/// the box `dirs` (vectors from the shading point; any length), per channel.
#[must_use]
pub fn material_bound(sp: &SurfacePoint<'_>, lo: Vec3, hi: Vec3) -> DVec3 {
    let cos_theta = cos_bound(sp.n, lo, hi);
    if cos_theta == 0.0 {
        return DVec3::ZERO;
    }
    let mut f = sp.kd * (1.0 / PI);
    if sp.material.has_specular() {
        let cos_alpha = cos_bound(sp.r, lo, hi);
        f += sp.material.specular * (phong_normalisation(sp.material.exponent) * cos_alpha.powf(sp.material.exponent));
    }
    (f * cos_theta).as_dvec3()
}

/// Upper bound of M * G over a cluster, per channel (V's bound is 1).
/// `lo, hi`: the cluster's box of positions (omni, oriented) or directions
/// (directional); `cone`: its cone of normals (oriented only).
#[must_use]
pub fn cluster_bound(kind: LightKind, sp: &SurfacePoint<'_>, lo: Vec3, hi: Vec3, cone: Cone) -> DVec3 {
    match kind {
        LightKind::Directional => material_bound(sp, lo, hi),
        LightKind::Omni | LightKind::Oriented => {
            // The same clamp as the exact evaluation: G_i <= 1 / max(d_i^2, eps^2),
            // so 1 / max(d_min^2, eps^2) bounds it and stays finite inside the box.
            let g = 1.0 / distance_squared_to_box(sp.p, lo, hi).max(sp.min_distance_squared());
            let m = material_bound(sp, lo - sp.p, hi - sp.p);
            if kind == LightKind::Omni {
                return m * g;
            }
            // cos(phi) <= cos(max(theta_min - beta, 0)), theta_min the smallest
            // angle between the cone axis and x - y over the box.
            let cos_theta_min = cos_bound(cone.axis, sp.p - hi, sp.p - lo);
            let theta_min = cos_theta_min.clamp(-1.0, 1.0).acos();
            let cos_phi = (theta_min - cone.half_angle).max(0.0).cos();
            m * g * f64::from((cos_phi * (1.0 + COS_SLACK) + COS_SLACK).min(1.0))
        }
    }
}

/// The scalar error bound of a cluster of total intensity `intensity`:
/// luminance of M_ub * G_ub * I_C (all terms are non-negative, so the
/// luminance of the bound bounds the luminance of the error).
#[must_use]
pub fn error_bound(mg_bound: DVec3, intensity: Vec3) -> f64 {
    luminance64(mg_bound * intensity.as_dvec3())
}

/// M * G of one light for the shading point, per unit intensity (V not
/// included), in f64. `position` is the direction towards the light for a
/// directional light; `normal` is used by oriented lights only.
#[must_use]
pub fn light_term(kind: LightKind, sp: &SurfacePoint<'_>, position: Vec3, normal: Vec3) -> DVec3 {
    match kind {
        LightKind::Directional => sp.material_term(position).as_dvec3(),
        LightKind::Omni | LightKind::Oriented => {
            let d = position - sp.p;
            let d2 = d.length_squared();
            if d2 == 0.0 {
                // The shading point is at the light: the direction is undefined
                // and the light contributes nothing here (docs/scene-format.md).
                return DVec3::ZERO;
            }
            let wi = d / d2.sqrt();
            let m = sp.material_term(wi);
            if m == Vec3::ZERO {
                return DVec3::ZERO;
            }
            let mut g = 1.0 / f64::from(d2).max(sp.min_distance_squared());
            if kind == LightKind::Oriented {
                g *= f64::from(normal.dot(-wi).max(0.0));
            }
            m.as_dvec3() * g
        }
    }
}

#[cfg(test)]
mod tests;
