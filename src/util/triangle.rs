//! A triangle's unit normal and area, computed in `f64`: a scene's
//! coordinates reach 1e16 m (`scene::MAX_COORDINATE`), and the cross product
//! of two edges longer than about 4e9 m has a squared length beyond `f32`'s
//! range, which made an emitter's area infinite and its whole image NaN.
//! Also the solid angle a triangle subtends and a point drawn uniformly in
//! it (Arvo 1995), how a triangle light is drawn (docs/design.md §6.1).

use glam::{DVec3, Vec3};

/// (p1 - p0) x (p2 - p0) in `f64`: the normal by the winding, twice the area long.
fn doubled_area_vector(p: [Vec3; 3]) -> DVec3 {
    let [p0, p1, p2] = p.map(|v| v.as_dvec3());
    (p1 - p0).cross(p2 - p0)
}

/// The unit normal of the triangle `p` by its winding ((p1 - p0) x (p2 - p0)),
/// or zero for a triangle of no area.
#[must_use]
pub fn normal(p: [Vec3; 3]) -> Vec3 {
    doubled_area_vector(p).normalize_or_zero().as_vec3()
}

/// The area of the triangle `p`, square metres (at most 2e32 for
/// coordinates within 1e16, inside `f32`).
#[must_use]
pub fn area(p: [Vec3; 3]) -> f64 {
    0.5 * doubled_area_vector(p).length()
}

/// The solid angles (sr) within which a triangle is drawn by solid angle
/// (pbrt-v4's `Triangle::Sample` keeps the same): below the first, Arvo's
/// angles lose the digits the draw needs and the triangle is as good as a
/// point, whose uniform draw by area is as good; above the second it
/// nearly covers the hemisphere, where the construction degenerates.
pub const SOLID_ANGLE_DRAWN: std::ops::RangeInclusive<f64> = 3e-4..=6.22;

/// A point drawn on a triangle uniformly in the solid angle it subtends
/// from a shading point, and that solid angle (sr): the density of the
/// direction is 1 / `solid_angle`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolidAngleDraw {
    pub point: DVec3,
    pub solid_angle: f64,
}

/// The solid angle (sr) the triangle `corners` subtends from `p`: the area
/// of its projection on the unit sphere, by Van Oosterom and Strackee's
/// formula 2 atan(a . (b x c) / (1 + a.b + b.c + c.a)) for the unit
/// directions a, b, c to the corners (as pbrt-v4's `SphericalTriangleArea`).
#[must_use]
pub fn solid_angle(p: DVec3, corners: [DVec3; 3]) -> f64 {
    let [a, b, c] = corners.map(|q| (q - p).normalize_or_zero());
    solid_angle_of_directions(a, b, c)
}

/// [`solid_angle`] from the unit directions to the corners.
fn solid_angle_of_directions(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    (2.0 * a.dot(b.cross(c)).atan2(1.0 + a.dot(b) + a.dot(c) + b.dot(c))).abs()
}

/// A point of the triangle `corners` whose direction from `p` is uniform
/// over the spherical triangle it subtends, from the numbers `u` in
/// [0, 1)^2: Arvo 1995, "Stratified sampling of spherical triangles", as
/// pbrt-v4's `SampleSphericalTriangle` writes it. `u[0]` picks the share
/// of the solid angle (a sub-triangle of area u[0] times the whole, cut
/// by a great arc through the first corner's opposite side), `u[1]` the
/// point along the arc from the second corner, so stratified numbers give
/// stratified directions. None where the solid angle is outside
/// [`SOLID_ANGLE_DRAWN`] or the triangle is seen edge-on.
#[must_use]
pub fn sample_spherical_triangle(p: DVec3, corners: [DVec3; 3], u: [f64; 2]) -> Option<SolidAngleDraw> {
    let [a, b, c] = corners.map(|q| (q - p).normalize_or_zero());
    let solid_angle = solid_angle_of_directions(a, b, c);
    if !SOLID_ANGLE_DRAWN.contains(&solid_angle) {
        return None;
    }
    let n_ab = a.cross(b).try_normalize()?;
    let n_ca = c.cross(a).try_normalize()?;
    // The spherical triangle's angle alpha at a, between the planes of its
    // arcs to b and to c, by its cosine and sine (in [0, pi]).
    let cos_alpha = -n_ab.dot(n_ca);
    let sin_alpha = n_ab.cross(n_ca).length();
    // The sub-triangle (a, b, c') of area u[0] times the whole: c' on the
    // arc from a to c, found by its cosine along a (Arvo's eq. 8 to 11, with
    // A' + pi's sine and cosine those of u[0] A negated).
    let (sin_area, cos_area) = (u[0] * solid_angle).sin_cos();
    let (sin_area, cos_area) = (-sin_area, -cos_area);
    let sin_phi = sin_area * cos_alpha - cos_area * sin_alpha;
    let cos_phi = cos_area * cos_alpha + sin_area * sin_alpha;
    let k1 = cos_phi + cos_alpha;
    let k2 = sin_phi - sin_alpha * a.dot(b);
    let cos_b = ((k2 + (k2 * cos_phi - k1 * sin_phi) * cos_alpha) / ((k2 * sin_phi + k1 * cos_phi) * sin_alpha))
        .clamp(-1.0, 1.0);
    if !cos_b.is_finite() {
        return None;
    }
    let sin_b = (1.0 - cos_b * cos_b).max(0.0).sqrt();
    let c_prime = cos_b * a + sin_b * (c - c.dot(a) * a).try_normalize()?;
    // The direction along the arc from b to c', uniform in the sub-triangle's
    // added area (Arvo's eq. 12).
    let cos_theta = 1.0 - u[1] * (1.0 - c_prime.dot(b));
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let w = cos_theta * b + sin_theta * (c_prime - c_prime.dot(b) * b).try_normalize()?;
    // Where the direction meets the triangle, by barycentric coordinates
    // clamped onto it (rounding may leave the direction just outside).
    let (e1, e2) = (corners[1] - corners[0], corners[2] - corners[0]);
    let s1 = w.cross(e2);
    let divisor = s1.dot(e1);
    if divisor == 0.0 {
        return None;
    }
    let s = p - corners[0];
    let mut b1 = (s.dot(s1) / divisor).clamp(0.0, 1.0);
    let mut b2 = (w.dot(s.cross(e1)) / divisor).clamp(0.0, 1.0);
    if b1 + b2 > 1.0 {
        let sum = b1 + b2;
        (b1, b2) = (b1 / sum, b2 / sum);
    }
    Some(SolidAngleDraw { point: corners[0] + b1 * e1 + b2 * e2, solid_angle })
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;
    use crate::util::sampling::{hammersley, Rng};

    /// The irradiance a Lambertian emitter of unit radiance over the
    /// triangle `corners` gives at `p` with normal `n`: Lambert's polygon
    /// formula, the sum over edges of the angle each subtends times the
    /// cosine between its plane's normal and n, over 2 (independent of
    /// the code under test).
    fn lambert_irradiance(p: DVec3, n: DVec3, corners: [DVec3; 3]) -> f64 {
        let r = corners.map(|q| (q - p).normalize());
        (0..3)
            .map(|i| {
                let (a, b) = (r[i], r[(i + 1) % 3]);
                a.dot(b).clamp(-1.0, 1.0).acos() * a.cross(b).normalize().dot(n)
            })
            .sum::<f64>()
            .abs()
            / 2.0
    }

    #[test]
    fn directions_drawn_by_solid_angle_give_lamberts_irradiance() {
        let corners = [DVec3::new(-0.3, 1.0, -0.2), DVec3::new(0.5, 1.0, -0.1), DVec3::new(0.1, 1.0, 0.6)];
        let mut rng = Rng::seeded(7);
        // Near (a solid angle near 2 pi), at a slant, and far (just above
        // the threshold): mean cos theta times the solid angle is the
        // irradiance, and every point lies on the triangle.
        for (p, n) in [
            (DVec3::new(0.1, 0.99, 0.1), DVec3::Y),
            (DVec3::new(0.4, 0.2, 0.3), DVec3::new(0.3, 1.0, 0.0).normalize()),
            (DVec3::new(0.0, -3.0, 0.0), DVec3::Y),
            (DVec3::new(1.5, 0.9, 0.0), DVec3::new(-1.0, 0.2, 0.1).normalize()),
        ] {
            let n_draws = 65_536;
            let shift = [rng.next_f32(), rng.next_f32()];
            let mut sum = 0.0;
            let mut omega = 0.0;
            for i in 0..n_draws {
                let [u0, u1] = hammersley(i, n_draws, shift);
                let draw = sample_spherical_triangle(p, corners, [f64::from(u0), f64::from(u1)]).unwrap();
                assert!((draw.point.y - 1.0).abs() < 1e-12, "{draw:?}");
                sum += (draw.point - p).normalize().dot(n).max(0.0);
                omega = draw.solid_angle;
            }
            let expected = lambert_irradiance(p, n, corners);
            let estimate = sum / f64::from(n_draws) * omega;
            assert!((estimate - expected).abs() < 2e-3 * expected, "{p}: {estimate} against {expected}");
        }
        // A triangle too small to draw by solid angle, or seen edge-on.
        assert_eq!(sample_spherical_triangle(DVec3::new(0.0, -100.0, 0.0), corners, [0.5, 0.5]), None);
        assert_eq!(sample_spherical_triangle(DVec3::new(3.0, 1.0, 0.0), corners, [0.5, 0.5]), None);
    }

    #[test]
    fn the_solid_angle_of_a_cube_face_is_a_sixth_of_the_sphere() {
        // Two triangles of a face of the cube [-1, 1]^3 seen from its centre.
        let q = |x: f64, z: f64| DVec3::new(x, 1.0, z);
        let face = solid_angle(DVec3::ZERO, [q(-1.0, -1.0), q(1.0, -1.0), q(1.0, 1.0)])
            + solid_angle(DVec3::ZERO, [q(-1.0, -1.0), q(1.0, 1.0), q(-1.0, 1.0)]);
        assert!((face - 4.0 * PI / 6.0).abs() < 1e-12, "{face}");
    }

    #[test]
    fn normals_and_areas_of_triangles_from_1e_minus_20_to_1e16_metres() {
        for scale in [1e-20f32, 1e-3, 1.0, 4.3e9, 1e16] {
            let p = [Vec3::ZERO, Vec3::new(scale, 0.0, 0.0), Vec3::new(0.0, scale, 0.0)];
            assert_eq!(normal(p), Vec3::Z, "{scale}");
            let expected = 0.5 * f64::from(scale) * f64::from(scale);
            assert!((area(p) - expected).abs() <= 1e-6 * expected, "{scale}: {}", area(p));
            // In f32 the same sums underflow to 0 at 1e-20 m and overflow
            // from about 4e9 m on.
            let f32_area = f64::from(0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length());
            let f32_right = (f32_area - expected).abs() <= 1e-6 * expected;
            assert_eq!(f32_right, (1e-3..=1.0).contains(&scale), "{scale}: {f32_area}");
        }
        assert_eq!(normal([Vec3::ZERO, Vec3::X, Vec3::X * 2.0]), Vec3::ZERO);
        assert_eq!(area([Vec3::ZERO, Vec3::X, Vec3::X * 2.0]), 0.0);
    }
}
