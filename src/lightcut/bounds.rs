//! Upper bounds of the material and geometric terms over a cluster
//! ([LC05] sec. 4.2; ../shared/LIGHTCUTS.md sections 2 to 4). Each is tested
//! to be >= the true maximum over the cluster's lights at random points.

use std::f32::consts::PI;

use glam::{DVec3, Vec3};

use crate::light::LightKind;
use crate::light_tree::Cone;
use crate::scene::material::phong_normalisation;
use crate::shading::SurfacePoint;
use crate::util::color::luminance64;

/// Relative slack added to every cosine bound: the bound is evaluated in f32
/// with a few roundings (rotation, sqrt), each within 1 ulp; 1e-5 covers
/// them with a wide margin and changes cut sizes by nothing measurable.
const COS_SLACK: f32 = 1e-5;

/// An orthonormal frame whose third axis is a given unit axis, for
/// [`cos_bound_in`]; build it once per shading point and axis.
#[derive(Debug, Clone, Copy)]
pub struct Frame {
    tangent: Vec3,
    bitangent: Vec3,
    axis: Vec3,
}

impl Frame {
    #[must_use]
    pub fn new(axis: Vec3) -> Self {
        let (tangent, bitangent) = axis.any_orthonormal_pair();
        Self { tangent, bitangent, axis }
    }
}

/// Upper bound of cos(angle between unit `axis` and v) over all v in the box
/// [lo, hi] (LIGHTCUTS.md section 3).
#[must_use]
pub fn cos_bound(axis: Vec3, lo: Vec3, hi: Vec3) -> f32 {
    cos_bound_in(&Frame::new(axis), 0.5 * (lo + hi), 0.5 * (hi - lo))
}

/// [`cos_bound`] in a prepared frame, for the box with centre `c` and
/// half-extent `h` (>= 0): along a unit axis e the box spans
/// e.c -/+ |e|.h, which gives the box of the rotated box; then
/// w / sqrt(u^2 + v^2 + w^2) at the largest w and the smallest |u|, |v|.
#[must_use]
pub fn cos_bound_in(frame: &Frame, c: Vec3, h: Vec3) -> f32 {
    let z1 = frame.axis.dot(c) + frame.axis.abs().dot(h);
    if z1 <= 0.0 {
        return 0.0;
    }
    // Distance from 0 to the interval m -/+ r, 0 when it contains 0.
    let nearest = |e: Vec3| (e.dot(c).abs() - e.abs().dot(h)).max(0.0);
    let (mx, my) = (nearest(frame.tangent), nearest(frame.bitangent));
    if mx == 0.0 && my == 0.0 {
        // The box reaches the axis itself: the bound is 1 (saves a divide).
        return 1.0;
    }
    let bound = z1 / (mx * mx + my * my + z1 * z1).sqrt();
    (bound * (1.0 + COS_SLACK) + COS_SLACK).min(1.0)
}

/// Squared distance from `p` to the box [lo, hi] (0 inside).
#[must_use]
pub fn distance_squared_to_box(p: Vec3, lo: Vec3, hi: Vec3) -> f64 {
    let d = (lo - p).max(p - hi).max(Vec3::ZERO);
    d.as_dvec3().length_squared()
}

/// What the bounds need of one shading point, prepared once per point.
pub struct PointBounds<'a, 'p> {
    pub sp: &'a SurfacePoint<'p>,
    normal_frame: Frame,
    /// The Phong lobe: (frame around the mirror direction, k_s (n+2)/(2 pi), n).
    phong: Option<(Frame, Vec3, f32)>,
    diffuse: Vec3,
    min_distance_squared: f64,
}

impl<'a, 'p> PointBounds<'a, 'p> {
    #[must_use]
    pub fn new(sp: &'a SurfacePoint<'p>) -> Self {
        let m = sp.material;
        let phong =
            m.has_specular().then(|| (Frame::new(sp.r), m.specular * phong_normalisation(m.exponent), m.exponent));
        Self {
            sp,
            normal_frame: Frame::new(sp.n),
            phong,
            diffuse: sp.kd * (1.0 / PI),
            min_distance_squared: sp.min_distance_squared(),
        }
    }

    /// Upper bound of the material term M = f_r cos(theta) over directions in
    /// the box [lo, hi] (vectors from the shading point; any length), per
    /// channel (LIGHTCUTS.md section 4).
    #[must_use]
    pub fn material(&self, lo: Vec3, hi: Vec3) -> DVec3 {
        let (c, h) = (0.5 * (lo + hi), 0.5 * (hi - lo));
        let cos_theta = cos_bound_in(&self.normal_frame, c, h);
        if cos_theta == 0.0 {
            return DVec3::ZERO;
        }
        let mut f = self.diffuse;
        if let Some((frame, lobe, exponent)) = &self.phong {
            f += *lobe * cos_bound_in(frame, c, h).powf(*exponent);
        }
        (f * cos_theta).as_dvec3()
    }

    /// Upper bound of M * G over a cluster, per channel (V's bound is 1).
    /// `lo, hi`: the cluster's box of positions (omni, oriented) or
    /// directions (directional); `cone`: its cone of normals (oriented only).
    #[must_use]
    pub fn cluster(&self, kind: LightKind, lo: Vec3, hi: Vec3, cone: Cone) -> DVec3 {
        let p = self.sp.p;
        match kind {
            LightKind::Directional => self.material(lo, hi),
            LightKind::Omni | LightKind::Oriented => {
                let m = self.material(lo - p, hi - p);
                if m == DVec3::ZERO {
                    return m;
                }
                // The same clamp as the exact evaluation: G_i <= 1 / max(d_i^2, eps^2),
                // so 1 / max(d_min^2, eps^2) bounds it and stays finite inside the box.
                let g = 1.0 / distance_squared_to_box(p, lo, hi).max(self.min_distance_squared);
                if kind == LightKind::Omni {
                    return m * g;
                }
                // cos(phi) <= cos(max(theta_min - beta, 0)), theta_min the smallest
                // angle between the cone axis and x - y over the box.
                let cos_theta_min = cos_bound(cone.axis, p - hi, p - lo);
                let theta_min = cos_theta_min.clamp(-1.0, 1.0).acos();
                let cos_phi = (theta_min - cone.half_angle).max(0.0).cos();
                m * g * f64::from((cos_phi * (1.0 + COS_SLACK) + COS_SLACK).min(1.0))
            }
        }
    }
}

/// Upper bound of M * G over a cluster (one-off form of [`PointBounds::cluster`]).
#[must_use]
pub fn cluster_bound(kind: LightKind, sp: &SurfacePoint<'_>, lo: Vec3, hi: Vec3, cone: Cone) -> DVec3 {
    PointBounds::new(sp).cluster(kind, lo, hi, cone)
}

/// The scalar error bound of a cluster of total intensity `intensity`:
/// luminance of M_ub * G_ub * I_C (all terms are non-negative, so the
/// luminance of the bound bounds the luminance of the error).
#[must_use]
pub fn error_bound(mg_bound: DVec3, intensity: Vec3) -> f64 {
    luminance64(mg_bound * intensity.as_dvec3())
}

#[cfg(test)]
mod tests;
