//! The shading point: where a camera (or light) path meets a surface, with
//! what the material term and the shadow rays need ([LC05] eq. 1).

use glam::Vec3;

use super::fibre::Fibre;
use super::lobes::Lobes;
use super::pbr::{Interface, Pbr};
use crate::embree::{Ray, ShadowRay};
use crate::scene::material::Material;
use crate::util::sampling::PixelSample;

/// A shading point: position, normals (facing the viewer), outgoing direction.
#[derive(Debug, Clone)]
pub struct SurfacePoint<'s> {
    pub p: Vec3,
    /// Shading normal, unit, on the viewer's side.
    pub n: Vec3,
    /// Geometric normal, unit, on the viewer's side.
    pub ng: Vec3,
    /// A clear coat's shading normal, unit, on the viewer's side: the
    /// interpolated normal, or its own normal map's (docs/design.md
    /// §5.10); `n` for a point without a coat.
    pub coat_n: Vec3,
    /// Unit direction towards the viewer.
    pub wo: Vec3,
    /// Mirror direction of wo about n.
    pub r: Vec3,
    /// Diffuse albedo here (texture evaluated; a metallic-roughness
    /// material's diffuse reflectance, `Pbr::diffuse_albedo`).
    pub kd: Vec3,
    pub material: &'s Material,
    /// The metallic-roughness BRDF's parameters here (textures looked up),
    /// for a material that has one.
    pub pbr: Option<Pbr>,
    /// A round curve's hit is a fibre's (docs/design.md §5.7): its BSDF,
    /// which takes the place of the material's lobes and lights the point
    /// from every side, not from above a surface alone.
    pub fibre: Option<Fibre>,
    /// The fibre's radius, metres (0 for a surface): the rays that leave
    /// through the fibre start past its far side.
    pub fibre_radius: f32,
    /// Distance from the ray origin, metres.
    pub distance: f32,
    /// The time of the ray that found the point, in the shutter (0 at its
    /// open, 1 at its close): its shadow and mirror rays are traced then.
    pub time: f32,
    /// Radiance the surface emits towards the viewer (area-light emitters).
    pub emitted: Vec3,
    /// The reflectance of its perfect mirror towards `r` (traced as a
    /// mirror bounce): a material's mirror layer, or a smooth metallic-
    /// roughness surface's Fresnel term at n . wo (`Pbr::is_smooth`); 0
    /// for none.
    pub mirror: Vec3,
    /// The weight of its transmitted delta lobe towards `transmitted`
    /// (traced as a delta bounce, as the mirror is): a transmitting
    /// dielectric's (`Pbr::delta_lobes`); 0 for none. A rough one's is
    /// drawn (`SurfacePoint::transmit`), and this weighs the choice of it.
    pub transmission: Vec3,
    /// The transmitted ray's unit direction, on the far side of the surface.
    pub transmitted: Vec3,
    /// How its transmission crosses the surface (None: it transmits
    /// nothing).
    pub interface: Option<Interface>,
    /// What the ray that found the point kept of its light through the
    /// solid it crossed to get here (Beer-Lambert inside a transmitting
    /// material's volume, docs/design.md §5.8): 1 outside any.
    pub interior_transmittance: Vec3,
    /// The ray offset, metres (see `Geometry::ray_epsilon`).
    pub(crate) epsilon: f32,
    /// The distance below which 1/d^2 is clamped: the ray offset, or the
    /// scene's `render.distance_clamp` when larger.
    pub(crate) min_distance: f32,
    /// The lobes the environment's lights light this point with: every
    /// lobe, unless its glossy lobe is too sharp for them, which the
    /// environment's sampling then lights (set by the integrator;
    /// docs/design.md §6.2).
    pub emitter_lobes: Lobes,
    /// The pixel sample of a camera path's point (set by the integrator):
    /// the stochastic cut's walks and the points drawn on triangle lights
    /// are stratified over the pixel's samples (docs/design.md §10.8).
    /// None: each point draws on its own.
    pub sample: Option<PixelSample>,
}

impl<'m> SurfacePoint<'m> {
    /// A point at `p` of `material` with shading and geometric normal `n`,
    /// seen from `wo`, diffuse albedo `kd` and no glTF lobes: nothing
    /// emitted or mirrored, at 1 m from the eye, offsets of 0.1 mm, every
    /// lobe lighting every light. What benchmarks and tests shade without
    /// a scene (each sets what it needs otherwise).
    #[must_use]
    pub fn bare(material: &'m Material, p: Vec3, n: Vec3, wo: Vec3, kd: Vec3) -> Self {
        SurfacePoint {
            p,
            n,
            ng: n,
            coat_n: n,
            wo,
            r: crate::scene::material::reflect(wo, n),
            kd,
            material,
            pbr: None,
            fibre: None,
            fibre_radius: 0.0,
            distance: 1.0,
            time: 0.0,
            emitted: Vec3::ZERO,
            mirror: Vec3::ZERO,
            transmission: Vec3::ZERO,
            transmitted: -wo,
            interface: None,
            interior_transmittance: Vec3::ONE,
            epsilon: 1e-4,
            min_distance: 1e-4,
            emitter_lobes: Lobes::ALL,
            sample: None,
        }
    }
}

impl SurfacePoint<'_> {
    /// Its material's identity for [`SurfaceKey`]: the material's address
    /// (points of one material share it).
    #[must_use]
    pub fn material_address(&self) -> usize {
        std::ptr::from_ref(self.material) as usize
    }

    /// The least cosine between this point's mirror direction `r` and
    /// another point's for which the glossy lobe towards a light at the
    /// other's peak keeps at least 1 / `ratio` of its peak value here
    /// (docs/design.md §10.9, "The lobe's turn"). Phong's cos(r, l)^n falls
    /// to cos(delta)^n at delta from its peak: cos delta >= ratio^(-1/n).
    /// GGX's D falls from its peak by at most (1 + tan^2 theta_h / alpha^2)^2
    /// at theta_h from the normal, and mirror directions delta apart put a
    /// light theta_h = delta / 2 off the half-vector's peak: tan^2(delta / 2)
    /// = (1 - cos delta) / (1 + cos delta) <= a = alpha^2 (sqrt(ratio) - 1),
    /// so cos delta >= (1 - a) / (1 + a). -1 (any turn) where no glossy lobe
    /// takes lights (none, or a perfect mirror's).
    /// A fibre's lobes turn with its tangent, which `r` does not follow:
    /// 2, no turn at all.
    #[must_use]
    pub fn lobe_turn_cos(&self, ratio: f32) -> f32 {
        if self.fibre.is_some() {
            return 2.0;
        }
        if let Some(pbr) = &self.pbr {
            // The sharpest of its glossy lobes (the base's, a rough coat's).
            let base = (!pbr.is_smooth()).then_some(pbr.alpha);
            let coat = (pbr.clearcoat > 0.0 && !pbr.coat_is_smooth()).then_some(pbr.clearcoat_alpha);
            let Some(alpha) = base.into_iter().chain(coat).reduce(f32::min) else { return -1.0 };
            let a = alpha * alpha * (ratio.sqrt() - 1.0);
            return (1.0 - a) / (1.0 + a);
        }
        let material = self.material;
        if material.exponent > 0.0 && material.specular.max_element() > 0.0 {
            return ratio.powf(-1.0 / material.exponent);
        }
        -1.0
    }

    /// Origin for rays leaving the surface on the viewer's side.
    #[must_use]
    pub fn offset_origin(&self) -> Vec3 {
        self.p + self.ng * self.epsilon
    }

    /// The shadow ray from here to a point light at `y`, stopping `epsilon`
    /// short of it so a light lying on a surface is not hidden by that surface.
    /// `None` when the light is within `epsilon`: nothing can lie between.
    #[must_use]
    pub fn shadow_ray_to(&self, y: Vec3) -> Option<ShadowRay> {
        let origin = self.offset_origin();
        let direction = y - origin;
        let length = direction.length();
        let (t_near, t_far) = (self.fibre_exit(direction), 1.0 - self.epsilon / length);
        if length <= 2.0 * self.epsilon || t_near >= t_far {
            return None;
        }
        Some(ShadowRay::new(Ray { origin, direction, t_near, t_far, time: self.time }))
    }

    /// Where a ray from `offset_origin` along `d` (any length) leaves a
    /// fibre's tube, in units of `d`, and a ray offset past it: 0 for a
    /// surface, and for a direction on the viewer's side of the fibre.
    /// The fibre's BSDF already holds the light that crosses the fibre
    /// (TT, TRT), so its own far side must not shadow it (docs/design.md
    /// §5.7). The tube is taken as straight, of axis p - r n_perp: the
    /// far root of |(r + e) n_perp + s d_perp| = r, n_perp (unit) and
    /// d_perp square to the axis.
    #[must_use]
    #[inline]
    pub fn fibre_exit(&self, d: Vec3) -> f32 {
        let Some(fibre) = &self.fibre else { return 0.0 };
        let x = fibre.axis();
        let across = d - x * x.dot(d);
        // A tapering tube's normal leans along it: the axis is square to
        // the axis's direction.
        let outwards = (self.ng - x * x.dot(self.ng)).normalize_or(self.ng);
        let a = across.length_squared();
        let lifted = self.fibre_radius + self.epsilon;
        let b = 2.0 * lifted * outwards.dot(across);
        let c = lifted * lifted - self.fibre_radius * self.fibre_radius;
        let discriminant = b * b - 4.0 * a * c;
        if b >= 0.0 || a <= 0.0 || discriminant <= 0.0 {
            return 0.0;
        }
        let far = (-b + discriminant.sqrt()) / (2.0 * a);
        let exit = far * 1.001 + self.epsilon / d.length();
        if exit.is_finite() {
            exit
        } else {
            0.0
        }
    }

    /// The shadow ray towards a light at infinity in unit direction `d`.
    #[must_use]
    pub fn shadow_ray_towards(&self, d: Vec3) -> ShadowRay {
        ShadowRay::new(Ray {
            origin: self.offset_origin(),
            direction: d,
            t_near: self.fibre_exit(d),
            t_far: f32::INFINITY,
            time: self.time,
        })
    }

    /// The mirror-reflected ray. A shading normal tilted far from the
    /// geometric one (a normal map's steep slope) can reflect the view
    /// below the surface, where the ray would see the surface's own back
    /// and the mirror would show a black ring; the direction is then lifted
    /// just above the surface, as Cycles' `ensure_valid_specular_reflection`
    /// does (docs/design.md §5.6).
    #[must_use]
    pub fn mirror_ray(&self) -> Ray {
        let ng = self.ng_facing_viewer();
        let lowest = (0.9 * ng.dot(self.wo)).min(0.01);
        self.ray_towards(at_least_above(self.mirror_direction(), ng, lowest))
    }

    /// The direction its perfect mirror reflects towards: `r`, or a
    /// smooth clear coat's about its own normal (a smooth base under a
    /// smooth coat of another normal reflects along the coat's too: one
    /// mirror ray carries both).
    #[must_use]
    pub fn mirror_direction(&self) -> Vec3 {
        match &self.pbr {
            Some(p) if p.coat_is_smooth() && self.coat_n != self.n => {
                crate::scene::material::reflect(self.wo, self.coat_n)
            }
            _ => self.r,
        }
    }

    /// n . wo of the clear coat's normal.
    #[must_use]
    pub fn coat_cos_view(&self) -> f32 {
        self.coat_n.dot(self.wo)
    }

    /// The transmitted ray, leaving from the far side of the surface. A
    /// shading normal tilted far from the geometric one can bend it back
    /// to the viewer's side, where it would meet the surface again from
    /// the wrong side: it is then lowered just below the surface, as the
    /// mirror ray is lifted (`mirror_ray`).
    #[must_use]
    pub fn transmitted_ray(&self) -> Ray {
        self.ray_through(self.transmitted)
    }

    /// A ray leaving from the far side of the surface towards unit
    /// `direction`, lowered below the surface as `transmitted_ray` says.
    fn ray_through(&self, direction: Vec3) -> Ray {
        let ng = self.ng_facing_viewer();
        let direction = at_least_above(direction, -ng, 0.01);
        Ray { origin: self.p - ng * self.epsilon, direction, t_near: 0.0, t_far: f32::INFINITY, time: self.time }
    }

    /// Where its transmission sends a path (docs/design.md §5.8) and what
    /// the path's throughput is multiplied by, before the choice of the
    /// event: a smooth surface's transmitted ray with its weight; a rough
    /// one's drawn from the uniform numbers `u`
    /// (`Pbr::sample_rough_transmission`), a microfacet's total internal
    /// reflection leaving on the viewer's side. None: the draw went
    /// nowhere.
    #[must_use]
    pub fn transmit(&self, u: [f32; 2]) -> Option<(Ray, Vec3)> {
        let rough = self.pbr.filter(|p| !p.is_smooth()).zip(self.interface);
        let Some((pbr, interface)) = rough else { return Some((self.transmitted_ray(), self.transmission)) };
        let drawn = pbr.sample_rough_transmission(self.n, self.wo, interface, self.coat_cos_view(), u)?;
        let ng = self.ng_facing_viewer();
        let ray = if drawn.crossed {
            self.ray_through(drawn.direction)
        } else {
            self.ray_towards(at_least_above(drawn.direction, ng, 0.01))
        };
        Some((ray, drawn.weight))
    }

    /// Whether it is a rough solid's boundary seen from inside: its
    /// reflection lobe is lit by no light (shadow rays stop at glass), so
    /// a camera path follows it by drawing it, even without the path
    /// method (docs/design.md §5.8).
    #[must_use]
    pub fn inside_rough_solid(&self) -> bool {
        self.interface == Some(Interface::Leaving) && self.pbr.is_some_and(|p| !p.is_smooth())
    }

    /// The geometric normal turned to the viewer's side.
    fn ng_facing_viewer(&self) -> Vec3 {
        if self.ng.dot(self.wo) < 0.0 {
            -self.ng
        } else {
            self.ng
        }
    }

    /// An unbounded ray leaving the surface on the viewer's side towards
    /// unit `direction`, at the point's time: a bounce's ray (a mirror's,
    /// a BSDF draw's, a light path's).
    #[must_use]
    pub fn ray_towards(&self, direction: Vec3) -> Ray {
        let t_near = self.fibre_exit(direction);
        Ray { origin: self.offset_origin(), direction, t_near, t_far: f32::INFINITY, time: self.time }
    }

    /// The distance clamp for point-light singularities: squared distances
    /// below min_distance^2 count as min_distance^2 (the ray offset, or the
    /// scene's larger `render.distance_clamp`), so a light on a surface gives
    /// a large but finite value. Applied identically by every render mode and
    /// by the bounds.
    #[must_use]
    pub fn min_distance_squared(&self) -> f64 {
        // f64: the offset may be as small as 1e-30, whose square underflows f32.
        f64::from(self.min_distance) * f64::from(self.min_distance)
    }
}

/// Unit `d`, or, where it rises less than `least` above the plane of unit
/// `normal` (d . normal), `d` moved along the normal to rise `least` and
/// made unit again: what keeps a mirror or a transmitted ray on its side
/// of the surface.
fn at_least_above(d: Vec3, normal: Vec3, least: f32) -> Vec3 {
    let height = d.dot(normal);
    if height < least {
        (d + (least - height) * normal).normalize_or(d)
    } else {
        d
    }
}

/// Where a camera hit was, to tell whether another hit is on the same
/// surface: the same material (an identity: the scene's index, or the
/// material's address), normals within `NORMAL_COS`, distances from the
/// viewer within `DISTANCE_RATIO`. Reconstruction cuts take an anchor's
/// cut only there (docs/design.md §9.6), and the stochastic cut's later
/// samples walk their pixel's cut only there, with normals closer
/// (docs/design.md §10.9).
#[derive(Debug, Clone, Copy)]
pub struct SurfaceKey {
    material: usize,
    normal: Vec3,
    distance: f32,
}

impl SurfaceKey {
    /// The least cosine between the two hits' normals.
    pub const NORMAL_COS: f32 = 0.9;
    /// The largest ratio between the two hits' distances from the viewer.
    pub const DISTANCE_RATIO: f32 = 1.1;

    /// The key of `sp`, of material `material`.
    #[must_use]
    pub fn of(material: usize, sp: &SurfacePoint<'_>) -> Self {
        Self { material, normal: sp.n, distance: sp.distance }
    }

    /// Whether `sp` (of material `material`) is on this key's surface.
    #[must_use]
    pub fn holds(&self, material: usize, sp: &SurfacePoint<'_>) -> bool {
        self.holds_within(material, sp, Self::NORMAL_COS)
    }

    /// Whether `sp` (of material `material`) is on this key's surface with
    /// normals within `normal_cos` (a stricter test than [`Self::holds`]
    /// where the normal weighs more).
    #[must_use]
    pub fn holds_within(&self, material: usize, sp: &SurfacePoint<'_>, normal_cos: f32) -> bool {
        let ratio = self.distance.max(sp.distance) / self.distance.min(sp.distance);
        self.material == material && self.normal.dot(sp.n) >= normal_cos && ratio <= Self::DISTANCE_RATIO
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::scene::material::{Albedo, Material};

    /// On the plane z = 0 (geometric normal +z), seen from `wo`, with the
    /// shading normal `n`.
    fn point(material: &Material, n: Vec3, wo: Vec3) -> SurfacePoint<'_> {
        SurfacePoint { ng: Vec3::Z, mirror: Vec3::ONE, ..SurfacePoint::bare(material, Vec3::ZERO, n, wo, Vec3::ZERO) }
    }

    #[test]
    fn a_mirror_ray_below_the_surface_is_lifted_above_it() {
        let material = Material::diffuse("mirror", Albedo::Constant(Vec3::ZERO));
        // Seen 70 degrees from the normal, the shading normal tilted 15
        // degrees away from the viewer: r = reflect(wo, n) points below the
        // plane.
        let (view, tilt) = (70f32.to_radians(), 15f32.to_radians());
        let wo = Vec3::new(view.sin(), 0.0, view.cos());
        let n = Vec3::new(-tilt.sin(), 0.0, tilt.cos());
        let sp = point(&material, n, wo);
        assert!(sp.r.z < 0.0, "the case needs a mirror direction below the surface: {}", sp.r);
        let d = sp.mirror_ray().direction;
        assert!((d.length() - 1.0).abs() < 1e-5);
        assert!((d.z - 0.01).abs() < 1e-3, "lifted to just above the surface: {d}");
        assert!(d.x < 0.0, "still away from the viewer's side: {d}");
        // A direction above the surface is left as it is.
        let sp = point(&material, Vec3::Z, wo);
        assert_eq!(sp.mirror_ray().direction, sp.r);
    }

    /// At the cosine `lobe_turn_cos` returns, a light at one point's peak
    /// keeps exactly 1 / ratio of the other's peak value for Phong (by
    /// the material term the lights are evaluated with), and
    /// between cos^4(theta_h) / ratio and 1 / ratio of it for GGX (the
    /// renderer's own D); a surface with no lobe that takes lights (a
    /// diffuse one, a perfect mirror) allows any turn.
    #[test]
    fn the_lobe_turn_keeps_a_light_at_the_other_peak_within_the_ratio() {
        use crate::shading::pbr::{distribution_of_sine, Pbr, MIN_ALPHA};
        use wide::f32x4;
        let mut phong = Material::diffuse("phong", Albedo::Constant(Vec3::splat(0.5)));
        phong.specular = Vec3::splat(0.3);
        // The glossy lobe's f (its f cos over cos theta) as the lights are
        // evaluated with it (`MaterialLanes::term`).
        let glossy_f = |sp: &SurfacePoint<'_>, wi: Vec3| {
            let lanes = crate::shading::direct::MaterialLanes::new(sp);
            let wi4 = [f32x4::splat(wi.x), f32x4::splat(wi.y), f32x4::splat(wi.z)];
            f64::from(lanes.term(&wi4, crate::shading::Lobes::GLOSSY)[0].to_array()[0] / wi.dot(sp.n))
        };
        for (exponent, ratio) in [(40.0f32, 4.0f32), (500.0, 2.0), (3.0, 16.0)] {
            phong.exponent = exponent;
            let sp = point(&phong, Vec3::Z, Vec3::Z);
            let c = sp.lobe_turn_cos(ratio);
            let turned = Vec3::new((1.0 - c * c).max(0.0).sqrt(), 0.0, c);
            let kept = glossy_f(&sp, turned) / glossy_f(&sp, sp.r);
            assert!((kept * f64::from(ratio) - 1.0).abs() < 1e-4, "Phong {exponent}: keeps {kept} at {c}");
        }
        let diffuse = Material::diffuse("diffuse", Albedo::Constant(Vec3::splat(0.5)));
        assert_eq!(point(&diffuse, Vec3::Z, Vec3::Z).lobe_turn_cos(4.0), -1.0);
        for roughness in [0.08f32, 0.25, 0.5, 0.9] {
            let mut sp = point(&diffuse, Vec3::Z, Vec3::Z);
            sp.pbr = Some(Pbr::new(Vec3::ONE, 1.0, roughness, 1.0, Vec3::ONE));
            let c = sp.lobe_turn_cos(4.0);
            let alpha2 = roughness.powi(4);
            let d = |theta_h: f32| {
                distribution_of_sine(f32x4::splat(theta_h.sin().powi(2)), f32x4::splat(alpha2)).to_array()[0]
            };
            let theta_h = 0.5 * c.acos();
            let falls = d(0.0) / d(theta_h);
            let least = 4.0 * theta_h.cos().powi(4);
            assert!(
                falls <= 4.0 * 1.001 && falls >= least * 0.999,
                "roughness {roughness}: D falls {falls}x at {theta_h} rad, not within [{least}, 4]"
            );
        }
        let mut mirror = point(&diffuse, Vec3::Z, Vec3::Z);
        mirror.pbr = Some(Pbr::new(Vec3::ONE, 1.0, 0.5 * MIN_ALPHA.sqrt(), 1.0, Vec3::ONE));
        assert!(mirror.pbr.as_ref().unwrap().is_smooth());
        assert_eq!(mirror.lobe_turn_cos(4.0), -1.0);
    }

    /// A ray leaving through a fibre's tube starts past its far side: the
    /// chord through a tube of radius r from its top (+z) straight down is
    /// 2 r, and half that at 60 degrees from the axis of the chord's plane,
    /// for a straight tube and for a tapering one (its normal leaning along
    /// it); a ray leaving on the viewer's side starts at once, and a
    /// surface has no tube.
    #[test]
    fn a_ray_through_a_fibre_starts_past_its_far_side() {
        let material = Material::diffuse("hair", crate::scene::material::Albedo::Constant(Vec3::ONE));
        let r = 0.01;
        for lean in [0.0f32, 0.4] {
            let ng = Vec3::new(lean, 0.0, 1.0).normalize();
            let mut sp =
                SurfacePoint { ng, ..SurfacePoint::bare(&material, Vec3::new(0.0, 0.0, r), ng, Vec3::Z, Vec3::ONE) };
            sp.epsilon = 1e-5;
            assert_eq!(sp.fibre_exit(-Vec3::Z), 0.0, "a surface");
            sp.fibre = super::super::fibre::Fibre::new(Vec3::X, ng, Vec3::Z, Vec3::ONE, 0.3);
            sp.fibre_radius = r;
            let down = sp.fibre_exit(-Vec3::Z);
            assert!(down > 2.0 * r && down < 2.0 * r * 1.01, "lean {lean}: {down}");
            // Twice as long a direction: half the parameter.
            assert!((sp.fibre_exit(-2.0 * Vec3::Z) - 0.5 * down).abs() < 1e-6);
            let slanted = Vec3::new(0.0, 0.75f32.sqrt(), -0.5);
            let exit = sp.fibre_exit(slanted);
            assert!(exit > r && exit < r * 1.01, "lean {lean}: {exit}");
            assert_eq!(sp.fibre_exit(Vec3::new(0.0, 0.6, 0.8)), 0.0);
        }
    }
}
