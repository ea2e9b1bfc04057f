//! What the builders merge: a cluster's bounds, cone, intensity and size.
//! The size metric is [LC05]'s (docs/design.md §7.2):
//! size(C) = I_C * (alpha_C^2 + c^2 (1 - cos beta_C)^2).

use glam::Vec3;

use super::NodeRef;
use crate::light::LightKind;

/// A cone of directions: unit `axis` and half-angle in radians (0..=pi).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cone {
    pub axis: Vec3,
    pub half_angle: f32,
}

impl Cone {
    #[must_use]
    pub fn of_direction(axis: Vec3) -> Self {
        Self { axis, half_angle: 0.0 }
    }

    /// The smallest cone (by this construction) containing both cones: the
    /// classic merge of bounding cones, widened by a small tolerance so that
    /// rounding never leaves a child direction outside.
    #[must_use]
    pub fn union(self, other: Self) -> Self {
        let (a, b) = if self.half_angle >= other.half_angle { (self, other) } else { (other, self) };
        let between = a.axis.dot(b.axis).clamp(-1.0, 1.0).acos();
        if between + b.half_angle <= a.half_angle {
            return a;
        }
        let half_angle = 0.5 * (a.half_angle + between + b.half_angle);
        if half_angle >= std::f32::consts::PI {
            return Self { axis: a.axis, half_angle: std::f32::consts::PI };
        }
        // Rotate a's axis towards b's by (half_angle - a.half_angle).
        let rotate = half_angle - a.half_angle;
        let ortho = (b.axis - a.axis * a.axis.dot(b.axis)).normalize_or_zero();
        let axis =
            if ortho == Vec3::ZERO { a.axis } else { (a.axis * rotate.cos() + ortho * rotate.sin()).normalize() };
        // 1e-5 rad covers the f32 rounding of acos, cos, sin and normalize above.
        Self { axis, half_angle: (half_angle + 1e-5).min(std::f32::consts::PI) }
    }

    /// The half-angle of `self.union(other)`, without computing its axis
    /// (what the size metric needs; one acos instead of acos, sin and cos).
    #[must_use]
    pub fn union_half_angle(self, other: Self) -> f32 {
        let (a, b) = if self.half_angle >= other.half_angle { (self, other) } else { (other, self) };
        let between = a.axis.dot(b.axis).clamp(-1.0, 1.0).acos();
        if between + b.half_angle <= a.half_angle {
            return a.half_angle;
        }
        (0.5 * (a.half_angle + between + b.half_angle) + 1e-5).min(std::f32::consts::PI)
    }

    /// Whether direction `d` (unit) lies inside the cone.
    #[must_use]
    pub fn contains(&self, d: Vec3) -> bool {
        self.axis.dot(d).clamp(-1.0, 1.0).acos() <= self.half_angle + 1e-5
    }
}

/// A cluster during the build: summary data plus the node it will become.
#[derive(Debug, Clone, Copy)]
pub struct Cluster {
    /// Box of positions (omni, oriented) or of directions (directional).
    pub min: Vec3,
    pub max: Vec3,
    /// Cone of normals (oriented only; unused otherwise).
    pub cone: Cone,
    /// Summed RGB intensity.
    pub intensity: Vec3,
    /// The scalar the metric and representative choice use (luminance).
    pub weight: f32,
    pub node: NodeRef,
}

/// The constants of the size metric for one tree.
#[derive(Debug, Clone, Copy)]
pub struct Metric {
    pub kind: LightKind,
    /// c^2: the squared diagonal of the lights' bounding box for oriented
    /// lights (so that angle and size weigh alike), 0 otherwise.
    pub c_squared: f64,
}

impl Metric {
    /// size(A u B), computed in f64: intensities up to 1e30 times squared
    /// diagonals up to 1e12 overflow f32.
    #[must_use]
    pub fn merged_size(&self, a: &Cluster, b: &Cluster) -> f64 {
        let diagonal = a.max.max(b.max) - a.min.min(b.min);
        let alpha2 = diagonal.as_dvec3().length_squared();
        let weight = f64::from(a.weight) + f64::from(b.weight);
        match self.kind {
            LightKind::Area | LightKind::Oriented | LightKind::Spot => {
                let cone = a.cone.union(b.cone);
                let angular = 1.0 - f64::from(cone.half_angle.cos());
                weight * (alpha2 + self.c_squared * angular * angular)
            }
            LightKind::Omni | LightKind::Directional | LightKind::Environment => weight * alpha2,
        }
    }

    /// size(C) of one cluster.
    #[must_use]
    pub fn size(&self, c: &Cluster) -> f64 {
        self.merged_size(c, c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::util::sampling::Rng;

    fn random_unit(rng: &mut Rng) -> Vec3 {
        loop {
            let v = Vec3::new(rng.range_f32(-1.0, 1.0), rng.range_f32(-1.0, 1.0), rng.range_f32(-1.0, 1.0));
            if v.length_squared() > 1e-4 && v.length_squared() <= 1.0 {
                return v.normalize();
            }
        }
    }

    #[test]
    fn merged_cones_contain_every_direction_of_their_parts() {
        let mut rng = Rng::seeded(3);
        for _ in 0..2000 {
            // Build cones from random direction sets and check each member.
            let dirs_a: Vec<Vec3> = (0..rng.below(4) + 1).map(|_| random_unit(&mut rng)).collect();
            let dirs_b: Vec<Vec3> = (0..rng.below(4) + 1).map(|_| random_unit(&mut rng)).collect();
            let cone_of =
                |d: &[Vec3]| d.iter().skip(1).fold(Cone::of_direction(d[0]), |c, &x| c.union(Cone::of_direction(x)));
            let (a, b) = (cone_of(&dirs_a), cone_of(&dirs_b));
            let u = a.union(b);
            for d in dirs_a.iter().chain(&dirs_b) {
                assert!(u.contains(*d), "{u:?} misses {d}");
            }
        }
    }
}
