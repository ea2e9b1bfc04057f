//! Drawing GGX's microfacet normals, which the BSDF's reflection lobes
//! (`super::bsdf`) and the rough transmission (`super::refraction`) share.

use std::f32::consts::PI;

use glam::Vec3;

/// A normal visible from `v` (shading frame, z > 0) of the GGX distribution
/// of roughness^2 `alpha`, drawn with density D_v(h) = G1(v) max(0, v.h)
/// D(h) / v.z from the uniform numbers (u1, u2): Heitz 2018, listing 1
/// (stretch the view to the unit hemisphere's, sample the projected disc
/// with the half towards the view warped, unstretch).
pub fn sample_visible_normal(v: Vec3, alpha: f32, u1: f32, u2: f32) -> Vec3 {
    let vh = Vec3::new(alpha * v.x, alpha * v.y, v.z).normalize();
    let length2 = vh.x * vh.x + vh.y * vh.y;
    let t1 = if length2 > 0.0 { Vec3::new(-vh.y, vh.x, 0.0) / length2.sqrt() } else { Vec3::X };
    let t2 = vh.cross(t1);
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
    let nh = t1 * p1 + t2 * p2 + vh * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
    Vec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(0.0)).normalize_or(Vec3::Z)
}
