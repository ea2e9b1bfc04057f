//! Rough transmission (docs/design.md §5.8): a transmitting dielectric
//! rougher than a mirror passes light through GGX microfacets, each a
//! small smooth interface. The transmitted direction is drawn as pbrt-v4's
//! `DielectricBxDF` draws it (Walter et al. 2007, "Microfacet Models for
//! Refraction through Rough Surfaces", with Heitz 2018's visible normals):
//! a microfacet normal m visible from the view, then the view refracted
//! through m by Snell's law. Weighted by what the BTDF over the density
//! leaves, (1 − F) G2 / G1 of what the surface transmits
//! (`Pbr::transmitted`), the draw is the whole lobe: the renderer
//! follows it as a sampled event of the path (`SurfacePoint::transmit`),
//! and the lights never evaluate it, as shadow rays stop at glass.

use glam::Vec3;

use super::microfacet::sample_visible_normal;
use super::pbr::{Interface, Pbr, MIN_COS_VIEW};

/// A direction a rough transmission drew: unit, world space; what the
/// path's throughput is multiplied by (before the choice of the event);
/// and whether it crossed the surface (false: a microfacet past the
/// critical angle reflected it back, total internal reflection).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transmitted {
    pub direction: Vec3,
    pub weight: Vec3,
    pub crossed: bool,
}

/// GGX's Smith Λ of a direction at cosine `cos` to the normal, for
/// roughness^2 `alpha`: (sqrt(1 + alpha^2 tan^2) − 1) / 2.
fn smith_lambda(cos: f32, alpha: f32) -> f32 {
    let cos2 = (cos * cos).max(1e-12);
    let tan2 = (1.0 - cos2).max(0.0) / cos2;
    0.5 * ((1.0 + alpha * alpha * tan2).sqrt() - 1.0)
}

/// G2 / G1 of the height-correlated masking-shadowing: (1 + Λ(o)) / (1 +
/// Λ(o) + Λ(i)), what a visible normal's draw leaves of G2.
fn shadowing_over_masking(cos_o: f32, cos_i: f32, alpha: f32) -> f32 {
    let lambda_o = smith_lambda(cos_o, alpha);
    (1.0 + lambda_o) / (1.0 + lambda_o + smith_lambda(cos_i, alpha))
}

impl Pbr {
    /// A rough transmission's direction drawn from the uniform numbers
    /// `u`, seen from unit `wo` through the unit shading normal `n` on the
    /// viewer's side (docs/design.md §5.8):
    ///
    /// - m is a visible normal of GGX of the specular lobe's alpha;
    /// - a solid's interface refracts ωo through m with its η, weighted by
    ///   (1 − max F) G2 / G1, F Schlick's form at the cosine on the air's
    ///   side (ωo·m entering, the refracted ray's leaving);
    /// - where m is past the critical angle, ωo reflects about m instead,
    ///   with (1 − max F(ωo·m)) G2 / G1: the share the reflection lobe's
    ///   Schlick term left to the transmission is reflected too;
    /// - a thin wall passes ωo's reflection about m mirrored through the
    ///   surface (its roughness blurs what is seen through it, and the
    ///   view goes on straight where the wall is smooth), weighted as a
    ///   reflection, by (1 − max F(ωo·m)) G2 / G1.
    ///
    /// None where the drawn direction is on the wrong side of the surface
    /// (the view's microfacet sends it back under the macro-surface).
    #[must_use]
    pub fn sample_rough_transmission(
        &self,
        n: Vec3,
        wo: Vec3,
        interface: Interface,
        coat_cos_view: f32,
        u: [f32; 2],
    ) -> Option<Transmitted> {
        let (t, b) = n.any_orthonormal_pair();
        let local = Vec3::new(wo.dot(t), wo.dot(b), wo.dot(n).max(MIN_COS_VIEW)).normalize_or(Vec3::Z);
        let m = sample_visible_normal(local, self.alpha, u[0], u[1]);
        let cos_m = local.dot(m).max(0.0);
        let fresnel = |cos: f32| self.fresnel(cos).0.max_element();
        let reflected = 2.0 * cos_m * m - local;
        let (direction, air_cos, crossed) = match interface {
            Interface::ThinWall => (Vec3::new(reflected.x, reflected.y, -reflected.z), cos_m, true),
            Interface::Entering | Interface::Leaving => {
                let eta = interface.eta(self.ior);
                let sin2_t = (1.0 - cos_m * cos_m).max(0.0) / (eta * eta);
                if sin2_t >= 1.0 {
                    (reflected, cos_m, false)
                } else {
                    let cos_t = (1.0 - sin2_t).sqrt();
                    let refracted = -local / eta + (cos_m / eta - cos_t) * m;
                    (refracted, if interface == Interface::Entering { cos_m } else { cos_t }, true)
                }
            }
        };
        let direction = direction.normalize_or_zero();
        // A crossing goes under the surface, a reflection stays over it.
        let cos_i = if crossed { -direction.z } else { direction.z };
        if cos_i.is_nan() || cos_i <= 0.0 {
            return None;
        }
        let share = (1.0 - fresnel(air_cos)) * shadowing_over_masking(local.z, cos_i, self.alpha);
        let weight = self.transmitted(share, local.z, coat_cos_view);
        let direction = (t * direction.x + b * direction.y + n * direction.z).normalize_or_zero();
        Some(Transmitted { direction, weight, crossed })
    }
}

#[cfg(test)]
mod tests;
