//! A triangle's unit normal and area, computed in `f64`: a scene's
//! coordinates reach 1e16 m (`scene::MAX_COORDINATE`), and the cross product
//! of two edges longer than about 4e9 m has a squared length beyond `f32`'s
//! range, which made an emitter's area infinite and its whole image NaN.

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

#[cfg(test)]
mod tests {
    use super::*;

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
