//! glTF 2.0's metallic-roughness BRDF, as the specification's Appendix B
//! defines it (docs/design.md §5.3): a Trowbridge-Reitz (GGX) distribution
//! with alpha = roughness^2, the height-correlated Smith visibility term,
//! Schlick's Fresnel, and the mix of a dielectric (diffuse under a
//! specular layer, `fresnel_mix`) and a metal (`conductor_fresnel`) by
//! `metallic`; KHR_materials_specular's factor and colour scale the
//! dielectric's reflectance.
//!
//! The terms are written as functions of the cosines they depend on, each
//! monotonic in its argument, so that the cut's bound (lightcut::bounds)
//! evaluates the same functions at bounding cosines.

use std::f32::consts::PI;

use glam::Vec3;
use wide::{f32x4, CmpGt};

use super::lobes::Lobes;
use super::sheen::{self, MIN_SHEEN_ROUGHNESS};
use crate::scene::material::{PbrMaterial, TexCoords, DEFAULT_IOR};
use crate::scene::texture::Texture;
use crate::util::simd::{dot3, splat3, V3};

/// The smallest alpha (roughness^2) the lobe is a lobe at: a smoother
/// surface (roughness below 0.032) is a perfect mirror whose reflectance is
/// the Fresnel term at n . wo, traced as a mirror bounce and never lit by a
/// point light (no glint of a delta light), as Cycles treats a roughness
/// too small to sample (docs/design.md §5.3). At 1e-3 the lobe's peak D = 1
/// / (pi alpha^2) = 3.2e5 is finite and still wider than the directions f32
/// resolves (1 - n.h is resolved to about 6e-8, against alpha^2 = 1e-6), and
/// its visible normals sample stably.
pub const MIN_ALPHA: f32 = 1e-3;

/// The smallest n . wo the visibility term is evaluated with (grazing
/// views, and shading normals that tilt away from the viewer).
pub const MIN_COS_VIEW: f32 = 1e-4;

/// The BRDF's parameters at one shading point (textures looked up).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pbr {
    /// Base colour, linear (factor x texture x vertex colour).
    pub base: Vec3,
    /// 0 (dielectric) to 1 (metal).
    pub metallic: f32,
    /// Roughness^2; below [`MIN_ALPHA`] the specular lobe is a perfect
    /// mirror ([`Pbr::is_smooth`]).
    pub alpha: f32,
    /// The dielectric's reflectance at normal incidence: min(0.04 x
    /// specular colour, 1) x specular factor (KHR_materials_specular; 0.04
    /// is IOR 1.5).
    pub f0: Vec3,
    /// The dielectric's reflectance at grazing incidence: the specular factor.
    pub f90: f32,
    /// The dielectric's index of refraction (KHR_materials_ior).
    pub ior: f32,
    /// The fraction of the dielectric's base transmitted instead of
    /// diffused (KHR_materials_transmission, texture looked up): traced as
    /// a delta bounce (`Pbr::delta_lobes`), and taken out of the diffuse
    /// lobe the lights see.
    pub transmission: f32,
    /// The clear coat's weight (KHR_materials_clearcoat, texture looked
    /// up; 0 without a coat) and its alpha = roughness^2: below
    /// [`MIN_ALPHA`] the coat is a perfect mirror (docs/design.md §5.10).
    pub clearcoat: f32,
    pub clearcoat_alpha: f32,
    /// The sheen's colour (KHR_materials_sheen; black without one) and
    /// roughness, at least `sheen::MIN_SHEEN_ROUGHNESS`.
    pub sheen: Vec3,
    pub sheen_roughness: f32,
}

/// IOR 1.5's reflectance at normal incidence: the clear coat's
/// (KHR_materials_clearcoat fixes its IOR).
const COAT_F0: f32 = 0.04;

/// How a ray crosses a transmitting dielectric's surface: straight on
/// through a thin wall, or bent by Snell's law into or out of a solid
/// (docs/design.md §5.8).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Interface {
    ThinWall,
    Entering,
    Leaving,
}

impl Interface {
    /// The interface of a surface `thin_walled` or not, seen from the
    /// `inside` of its solid or not.
    #[must_use]
    pub fn of(thin_walled: bool, inside: bool) -> Self {
        match (thin_walled, inside) {
            (true, _) => Self::ThinWall,
            (false, false) => Self::Entering,
            (false, true) => Self::Leaving,
        }
    }

    /// The relative index of refraction η = n_t / n_i across it, for a
    /// dielectric of index `ior` in air: 1 for a thin wall.
    #[must_use]
    pub fn eta(self, ior: f32) -> f32 {
        match self {
            Self::ThinWall => 1.0,
            Self::Entering => ior,
            Self::Leaving => 1.0 / ior,
        }
    }
}

/// A transmitting dielectric's delta lobes towards one view
/// (`Pbr::delta_lobes`): the mirror's reflectance, the transmitted
/// weight and the transmitted ray's unit direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeltaLobes {
    pub mirror: Vec3,
    pub transmission: Vec3,
    pub transmitted: Vec3,
}

/// A dielectric's reflectance at normal incidence from air for an index
/// of refraction `ior`: ((ior - 1) / (ior + 1))^2, and glTF's constant 0.04
/// exactly at its default 1.5 (f32's (0.5 / 2.5)^2 is 0.040000003).
#[must_use]
pub fn f0_of_ior(ior: f32) -> f32 {
    if ior == DEFAULT_IOR {
        return 0.04;
    }
    let r = (ior - 1.0) / (ior + 1.0);
    r * r
}

impl Pbr {
    /// The parameters of a base colour, metallic, roughness and
    /// KHR_materials_specular's factor and colour (1 and white without it).
    /// The base colour and the specular factor are reflectances: each is
    /// taken within [0, 1], where the Fresnel terms grow with Schlick's
    /// weight and the diffuse weight stays >= 0, as the cut's bound needs
    /// (the importers clamp them there already, with a warning).
    #[must_use]
    pub fn new(base: Vec3, metallic: f32, roughness: f32, specular: f32, specular_colour: Vec3) -> Self {
        Self::with_ior(base, metallic, roughness, specular, specular_colour, DEFAULT_IOR)
    }

    /// The same parameters for a dielectric of index of refraction `ior`
    /// (KHR_materials_ior: its reflectance at normal incidence is
    /// `f0_of_ior`, times KHR_materials_specular's colour and factor),
    /// opaque.
    #[must_use]
    pub fn with_ior(base: Vec3, metallic: f32, roughness: f32, specular: f32, specular_colour: Vec3, ior: f32) -> Self {
        let (base, specular) = (base.clamp(Vec3::ZERO, Vec3::ONE), specular.clamp(0.0, 1.0));
        Self {
            base,
            metallic,
            alpha: roughness * roughness,
            f0: (f0_of_ior(ior) * specular_colour).min(Vec3::ONE) * specular,
            f90: specular,
            ior,
            transmission: 0.0,
            clearcoat: 0.0,
            clearcoat_alpha: 0.0,
            sheen: Vec3::ZERO,
            sheen_roughness: 1.0,
        }
    }

    /// The parameters of `material` at a point of base colour `base` and
    /// texture coordinates `uvs` (its metallic-roughness texture looked up).
    #[must_use]
    pub fn of(material: &PbrMaterial, base: Vec3, uvs: &TexCoords, textures: &[Texture]) -> Self {
        let (mut metallic, mut roughness) = (material.metallic, material.roughness);
        if let Some(t) = &material.metallic_roughness {
            let texel = t.lookup(uvs, textures);
            roughness *= texel.y;
            metallic *= texel.z;
        }
        let (metallic, roughness) = (metallic.clamp(0.0, 1.0), roughness.clamp(0.0, 1.0));
        let mut specular = material.specular;
        if let Some(t) = &material.specular_texture {
            specular *= t.lookup(uvs, textures).x;
        }
        let mut specular_colour = material.specular_colour;
        if let Some(t) = &material.specular_colour_texture {
            specular_colour *= t.lookup(uvs, textures);
        }
        let mut pbr = Self::with_ior(base, metallic, roughness, specular, specular_colour, material.ior);
        if let Some(transmission) = &material.transmission {
            let texel = transmission.texture.map_or(1.0, |t| t.lookup(uvs, textures).x);
            pbr.transmission = (transmission.factor * texel).clamp(0.0, 1.0);
        }
        if let Some(coat) = &material.clearcoat {
            let weight = coat.texture.map_or(1.0, |t| t.lookup(uvs, textures).x);
            let roughness = coat.roughness_texture.map_or(1.0, |t| t.lookup(uvs, textures).x);
            pbr.clearcoat = (coat.factor * weight).clamp(0.0, 1.0);
            pbr.clearcoat_alpha = (coat.roughness * roughness).clamp(0.0, 1.0).powi(2);
        }
        if let Some(sheen) = &material.sheen {
            let colour = sheen.colour_texture.map_or(Vec3::ONE, |t| t.lookup(uvs, textures));
            let roughness = sheen.roughness_texture.map_or(1.0, |t| t.lookup(uvs, textures).x);
            pbr.sheen = (sheen.colour * colour).clamp(Vec3::ZERO, Vec3::ONE);
            pbr.sheen_roughness = (sheen.roughness * roughness).clamp(MIN_SHEEN_ROUGHNESS, 1.0);
        }
        pbr
    }

    /// The clear coat's Fresnel weight at the view, clearcoat x (0.04 +
    /// 0.96 (1 - n_c.v)^5), n_c the coat's normal: the share of the light
    /// the coat reflects, which the layers below lose
    /// (KHR_materials_clearcoat's fresnel_coat, its Fresnel at n_c.v).
    #[must_use]
    pub fn coat_blend(&self, coat_cos_view: f32) -> f32 {
        if self.clearcoat == 0.0 {
            return 0.0;
        }
        let x = 1.0 - coat_cos_view.clamp(0.0, 1.0);
        self.clearcoat * (COAT_F0 + (1.0 - COAT_F0) * (x * x * x * x * x))
    }

    /// What the sheen leaves the base towards a direction at `cos` to the
    /// normal: 1 - max(sheen colour) E(cos) (the extension's albedo
    /// scaling takes the smaller of the view's and the light's).
    #[must_use]
    pub fn sheen_scaling(&self, cos: f32) -> f32 {
        let strongest = self.sheen.max_element();
        if strongest == 0.0 {
            return 1.0;
        }
        1.0 - strongest * sheen::albedo(cos, self.sheen_roughness)
    }

    /// What the layers over the base (coat, then sheen) leave of a base
    /// lobe seen at `n_dot_v` (the coat's normal at `coat_cos_view`) and
    /// leaving in a direction at the same cosine (the mirror's; a delta
    /// lobe's weight).
    #[must_use]
    pub fn base_weight(&self, n_dot_v: f32, coat_cos_view: f32) -> f32 {
        (1.0 - self.coat_blend(coat_cos_view)) * self.sheen_scaling(n_dot_v)
    }

    /// Whether the clear coat is a perfect mirror (a coat whose alpha is
    /// below [`MIN_ALPHA`]): traced as a mirror bounce, lit by no light.
    #[must_use]
    pub fn coat_is_smooth(&self) -> bool {
        self.clearcoat > 0.0 && self.clearcoat_alpha < MIN_ALPHA
    }

    /// The reflectance of its perfect mirror seen at `n_dot_v` (the
    /// coat's normal at `coat_cos_view`): a smooth base's Fresnel term
    /// under the layers over it, plus a smooth coat's weight; 0 where
    /// neither is smooth.
    #[must_use]
    pub fn mirror(&self, n_dot_v: f32, coat_cos_view: f32) -> Vec3 {
        let base = if self.is_smooth() { self.mirror_reflectance(n_dot_v) } else { Vec3::ZERO };
        self.layered(base, n_dot_v, coat_cos_view)
    }

    /// Whether the specular lobe is a perfect mirror (alpha below
    /// [`MIN_ALPHA`]): traced as a mirror bounce, lit by no light.
    #[must_use]
    pub fn is_smooth(&self) -> bool {
        self.alpha < MIN_ALPHA
    }

    /// The specular layer's reflectance towards the mirror direction of a
    /// view at `n_dot_v`: the Fresnel term with Schlick's weight (1 -
    /// n.v)^5, the dielectric's and the metal's mixed by `metallic` (glTF's
    /// BRDF as the half-vector meets the normal). A smooth surface's mirror.
    #[must_use]
    pub fn mirror_reflectance(&self, n_dot_v: f32) -> Vec3 {
        let (dielectric, metal) = self.fresnel(n_dot_v);
        self.mirror_of(dielectric, metal)
    }

    /// The dielectric's and the metal's Fresnel terms at `n_dot_v`, with
    /// Schlick's weight (1 - n.v)^5: F_d = f0 + (f90 - f0) w, F_m = base +
    /// (1 - base) w.
    pub(super) fn fresnel(&self, n_dot_v: f32) -> (Vec3, Vec3) {
        let x = (1.0 - n_dot_v.clamp(0.0, 1.0)).max(0.0);
        let w = x * x * x * x * x;
        (self.f0 + (Vec3::splat(self.f90) - self.f0) * w, self.base + (Vec3::ONE - self.base) * w)
    }

    /// The mirror's reflectance of Fresnel terms `dielectric` and `metal`,
    /// mixed by `metallic`.
    fn mirror_of(&self, dielectric: Vec3, metal: Vec3) -> Vec3 {
        dielectric * (1.0 - self.metallic) + metal * self.metallic
    }

    /// The diffuse reflectance: what a bounce of indirect light and the
    /// albedo AOV take.
    #[must_use]
    pub fn diffuse_albedo(&self) -> Vec3 {
        self.base * (1.0 - self.metallic) * (1.0 - self.transmission) * (1.0 - self.f0.max_element())
    }

    /// The delta lobes of a transmitting dielectric seen from unit `wo`
    /// through the unit shading normal `n` on the viewer's side, across
    /// its `interface` (docs/design.md §5.8):
    ///
    /// - a thin wall passes the ray straight on; a solid's boundary bends
    ///   it by Snell's law, eta = ior entering and 1 / ior leaving, and
    ///   reflects all of it past the critical angle (total internal
    ///   reflection: no transmission, the dielectric's mirror 1; a rough
    ///   surface's microfacets may still pass some, so its transmission
    ///   is then what it passes before Fresnel, the weight that chooses
    ///   its draw);
    /// - the Fresnel term is the specification's Schlick form at the
    ///   cosine on the air's side (the view's entering, the transmitted
    ///   ray's leaving), as Fresnel's reflectance is the same both ways;
    /// - the transmitted weight is base x transmission x (1 - metallic) x
    ///   (1 - max F_d), what the diffuse lobe would have had under the
    ///   specular layer, and the mirror is the smooth surface's
    ///   reflectance (0 for a rough one, whose reflection is its lobe). A
    ///   rough surface's transmission is drawn instead
    ///   (`Pbr::sample_rough_transmission`): these are then the weight
    ///   that chooses the draw and the direction of its smooth mean.
    ///
    /// A white, smooth, fully transmitting dielectric's mirror and
    /// transmission sum to 1: it keeps all the light (the glass furnace,
    /// tests/transmission.rs).
    #[must_use]
    pub fn delta_lobes(&self, n: Vec3, wo: Vec3, interface: Interface, coat_cos_view: f32) -> DeltaLobes {
        let cos_i = n.dot(wo).clamp(0.0, 1.0);
        let (transmitted, cos_air) = if interface == Interface::ThinWall {
            (-wo, cos_i)
        } else {
            let eta = interface.eta(self.ior);
            let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
            if sin2_t >= 1.0 {
                // The metal's share as it was; the dielectric's is all.
                let mirror = self.mirror_of(Vec3::ONE, self.fresnel(cos_i).1);
                let mirror = if self.is_smooth() { mirror.min(Vec3::ONE) } else { Vec3::ZERO };
                let mirror = self.layered(mirror, cos_i, coat_cos_view);
                // A rough surface's microfacets may still pass some: its
                // draw's weight, not this, is what the path keeps.
                let rough = if self.is_smooth() { Vec3::ZERO } else { self.transmitted(1.0, cos_i, coat_cos_view) };
                return DeltaLobes { mirror, transmission: rough, transmitted: -wo };
            }
            let cos_t = (1.0 - sin2_t).sqrt();
            let d = (-wo / eta + (cos_i / eta - cos_t) * n).normalize_or(-n);
            (d, if interface == Interface::Leaving { cos_t } else { cos_i })
        };
        let (f_d, f_m) = self.fresnel(cos_air);
        let transmission = self.transmitted(1.0 - f_d.max_element(), cos_i, coat_cos_view);
        let mirror = if self.is_smooth() { self.mirror_of(f_d, f_m) } else { Vec3::ZERO };
        DeltaLobes { mirror: self.layered(mirror, cos_i, coat_cos_view), transmission, transmitted }
    }

    /// What a transmitting dielectric seen at `n_dot_v` (its coat's normal
    /// at `coat_cos_view`) passes of the `share` its interface lets through
    /// (1 − F for a smooth one, docs/design.md §5.8): base · t · (1 −
    /// metallic) · share under the layers over it.
    #[must_use]
    pub fn transmitted(&self, share: f32, n_dot_v: f32, coat_cos_view: f32) -> Vec3 {
        self.base * (self.transmission * (1.0 - self.metallic) * share) * self.base_weight(n_dot_v, coat_cos_view)
    }

    /// A base mirror's reflectance `mirror` seen at `n_dot_v` under the
    /// layers over it, plus a smooth coat's.
    fn layered(&self, mirror: Vec3, n_dot_v: f32, coat_cos_view: f32) -> Vec3 {
        let coat = if self.coat_is_smooth() { self.coat_blend(coat_cos_view) } else { 0.0 };
        mirror * self.base_weight(n_dot_v, coat_cos_view) + Vec3::splat(coat)
    }
}

/// Trowbridge-Reitz D(h) = alpha^2 / (pi ((n.h)^2 (alpha^2 - 1) + 1)^2),
/// increasing in n.h for alpha <= 1. The bracket is computed as (1 -
/// (n.h)^2) + (n.h)^2 alpha^2, which keeps alpha^2's digits where (alpha^2
/// - 1) + 1 would lose them: at n.h = 1 it is alpha^2 exactly.
#[inline(always)]
#[must_use]
pub fn distribution(n_dot_h: f32x4, alpha2: f32x4) -> f32x4 {
    let c2 = n_dot_h * n_dot_h;
    let d = (f32x4::ONE - c2) + c2 * alpha2;
    alpha2 / (f32x4::splat(PI) * d * d)
}

/// The same D from sin^2(theta_h) = |n x h|^2, the form the evaluation
/// uses: near the lobe's peak 1 - (n.h)^2 in f32 resolves nothing below
/// 6e-8 (n.h's last digit), where a lobe of roughness 0.05 has alpha^2 =
/// 6e-6 and D would be percents off (a furnace at that roughness read
/// 1.3% bright); the cross product keeps the sine's digits. The bound
/// keeps [`distribution`] of an upper bound on n.h, whose slack covers
/// the difference (docs/design.md §5.3).
#[inline(always)]
#[must_use]
pub fn distribution_of_sine(sin2_h: f32x4, alpha2: f32x4) -> f32x4 {
    let d = sin2_h + (f32x4::ONE - sin2_h) * alpha2;
    alpha2 / (f32x4::splat(PI) * d * d)
}

/// The height-correlated Smith visibility V = G / (4 |n.l| |n.v|) times
/// n.l: 0.5 n.l / (n.l sqrt((n.v)^2 (1 - alpha^2) + alpha^2) + n.v
/// sqrt((n.l)^2 (1 - alpha^2) + alpha^2)). Increasing in n.l (divide
/// through by n.l: the denominator falls as n.l grows). `n_dot_l` >= 0.
#[inline(always)]
#[must_use]
pub fn visibility_cos(n_dot_l: f32x4, n_dot_v: f32, alpha2: f32x4) -> f32x4 {
    let v = f32x4::splat(n_dot_v);
    let one_minus = f32x4::ONE - alpha2;
    let view = (v * v * one_minus + alpha2).sqrt();
    let light = (n_dot_l * n_dot_l * one_minus + alpha2).sqrt();
    let denominator = n_dot_l * view + v * light;
    let value = f32x4::splat(0.5) * n_dot_l / denominator;
    denominator.cmp_gt(f32x4::ZERO).blend(value, f32x4::ZERO)
}

/// Schlick's weight (1 - v.h)^5, decreasing in v.h.
#[inline(always)]
#[must_use]
pub fn schlick_weight(v_dot_h: f32x4) -> f32x4 {
    let x = (f32x4::ONE - v_dot_h).fast_max(f32x4::ZERO);
    let x2 = x * x;
    x2 * x2 * x
}

/// The BRDF's parameters in four lanes, for one shading point.
#[derive(Clone, Copy)]
pub struct PbrLanes {
    pub base: V3,
    pub metallic: f32x4,
    pub alpha2: f32x4,
    pub f0: V3,
    pub f90: f32x4,
    /// The diffuse part's weight against 1 - max(F) (KHR_materials_specular).
    pub diffuse: V3,
    /// n . wo, at least [`MIN_COS_VIEW`].
    pub n_dot_v: f32,
    /// Whether the specular lobe is a lobe (false: a perfect mirror, which
    /// no light lights: its part of f is 0).
    pub glossy: bool,
    /// What the clear coat leaves the layers below at this view: 1 - its
    /// Fresnel weight (1 without a coat).
    pub under_coat: f32x4,
    /// A rough clear coat's lobe (None without a coat, or for a smooth
    /// one: a mirror).
    pub coat: Option<CoatLanes>,
    /// A sheen's lobe (None without one).
    pub sheen: Option<SheenLanes>,
}

/// What a rough clear coat's lobe needs at one shading point
/// (docs/design.md §5.10): its Fresnel weight at the view, its alpha^2,
/// its normal and n_c . wo (at least [`MIN_COS_VIEW`]).
#[derive(Clone, Copy)]
pub struct CoatLanes {
    pub weight: f32x4,
    pub alpha2: f32x4,
    pub n: V3,
    pub n_dot_v: f32,
}

/// What a sheen's lobe needs at one shading point (docs/design.md §5.10).
#[derive(Clone, Copy)]
pub struct SheenLanes {
    pub colour: Vec3,
    /// max(colour): the albedo scaling's weight.
    pub strongest: f32,
    pub roughness: f32,
    /// Lambda(n.v) and E(n.v).
    pub lambda_v: f32,
    pub albedo_v: f32,
}

impl PbrLanes {
    #[inline(always)]
    #[must_use]
    pub fn new(pbr: &Pbr, n_dot_v: f32, coat_n: Vec3, coat_cos_view: f32) -> Self {
        Self {
            base: splat3(pbr.base),
            metallic: f32x4::splat(pbr.metallic),
            // A smooth surface's lobe is never evaluated (`glossy`); its
            // alpha is kept where D and V stay finite.
            alpha2: f32x4::splat(pbr.alpha.max(MIN_ALPHA) * pbr.alpha.max(MIN_ALPHA)),
            f0: splat3(pbr.f0),
            f90: f32x4::splat(pbr.f90),
            diffuse: splat3(pbr.base * ((1.0 - pbr.metallic) * (1.0 - pbr.transmission) / PI)),
            n_dot_v: n_dot_v.max(MIN_COS_VIEW),
            glossy: !pbr.is_smooth(),
            under_coat: f32x4::splat(1.0 - pbr.coat_blend(coat_cos_view)),
            coat: (pbr.clearcoat > 0.0 && !pbr.coat_is_smooth()).then(|| {
                let alpha = pbr.clearcoat_alpha.max(MIN_ALPHA);
                CoatLanes {
                    weight: f32x4::splat(pbr.coat_blend(coat_cos_view)),
                    alpha2: f32x4::splat(alpha * alpha),
                    n: splat3(coat_n),
                    n_dot_v: coat_cos_view.max(MIN_COS_VIEW),
                }
            }),
            sheen: (pbr.sheen.max_element() > 0.0).then(|| {
                let cos_v = n_dot_v.max(MIN_COS_VIEW);
                SheenLanes {
                    colour: pbr.sheen,
                    strongest: pbr.sheen.max_element(),
                    roughness: pbr.sheen_roughness,
                    lambda_v: sheen::lambda(cos_v, pbr.sheen_roughness),
                    albedo_v: sheen::albedo(cos_v, pbr.sheen_roughness),
                }
            }),
        }
    }

    /// f_r cos(theta_i) per channel, from the cosines it depends on:
    /// n.l (`cos_theta`, >= 0), n.h, v.h (glTF Appendix B):
    ///
    ///   F_d = f0 + (f90 - f0) w,   F_m = base + (1 - base) w,   w = (1 - v.h)^5
    ///   f = (1 - metallic) (base / pi (1 - max F_d) + F_d D V)
    ///       + metallic F_m D V
    ///
    /// `spread` = D V n.l, and `weight` = w, may be bounds instead of the
    /// values (the cut's bound: every factor grows with them).
    #[inline(always)]
    #[must_use]
    pub fn combine(&self, cos_theta: f32x4, specular: f32x4, weight: f32x4, diffuse_fresnel: f32x4) -> V3 {
        let one = f32x4::ONE;
        let dielectric = |k: usize| self.f0[k] + (self.f90 - self.f0[k]) * weight;
        let metal = |k: usize| self.base[k] + (one - self.base[k]) * weight;
        let channel = |k: usize| {
            let fresnel = (one - self.metallic) * dielectric(k) + self.metallic * metal(k);
            self.diffuse[k] * diffuse_fresnel * cos_theta + fresnel * specular
        };
        [channel(0), channel(1), channel(2)]
    }

    /// f_r cos(theta_i) of `lobes` (the diffuse part, the specular part or
    /// both) for unit directions `wi` (lanes), unit `n` and `wo` splat;
    /// `cos_theta` = n . wi, > 0 where it is used.
    #[inline(always)]
    #[must_use]
    pub fn f_cos(&self, n: &V3, wo: &V3, wi: &V3, cos_theta: f32x4, lobes: Lobes) -> V3 {
        let zero = f32x4::ZERO;
        let h = [wo[0] + wi[0], wo[1] + wi[1], wo[2] + wi[2]];
        let length = dot3(&h, &h).sqrt();
        // wi = -wo: no half-vector; the lobe is 0 there (n . wi <= 0 anyway
        // for a view above the surface).
        let safe = length.cmp_gt(zero);
        let inverse = safe.blend(f32x4::ONE / length, zero);
        let h = [h[0] * inverse, h[1] * inverse, h[2] * inverse];
        // sin^2 from the cross product (`distribution_of_sine`); 1 where h
        // is below the normal, as D at the clamped n.h = 0 was.
        let cross = [n[1] * h[2] - n[2] * h[1], n[2] * h[0] - n[0] * h[2], n[0] * h[1] - n[1] * h[0]];
        let above = dot3(n, &h).cmp_gt(zero);
        let sin2_h = above.blend(dot3(&cross, &cross).fast_min(f32x4::ONE), f32x4::ONE);
        let v_dot_h = dot3(wo, &h).fast_max(zero).fast_min(f32x4::ONE);
        let l = cos_theta.fast_max(zero);
        let specular = distribution_of_sine(sin2_h, self.alpha2) * visibility_cos(l, self.n_dot_v, self.alpha2);
        let specular = if lobes.glossy && self.glossy { specular } else { zero };
        let weight = schlick_weight(v_dot_h);
        let f_d = [0, 1, 2].map(|k| self.f0[k] + (self.f90 - self.f0[k]) * weight);
        let max_f = f_d[0].fast_max(f_d[1]).fast_max(f_d[2]);
        let diffuse_fresnel = if lobes.diffuse { f32x4::ONE - max_f } else { zero };
        let base = self.combine(l, specular, weight, diffuse_fresnel);
        if !self.is_layered() {
            return base;
        }
        self.layers(base, l, sin2_h, wi, &h, lobes)
    }

    /// Whether a clear coat or a sheen lies over the base.
    #[inline(always)]
    #[must_use]
    pub fn is_layered(&self) -> bool {
        self.coat.is_some() || self.sheen.is_some() || self.under_coat.to_array()[0] != 1.0
    }

    /// The layers over the base lobes `base` (f cos, per channel), towards
    /// unit directions `wi` at n.l `l` with unit half-vectors `h` at sin^2
    /// `sin2_h` to n (KHR_materials_clearcoat over KHR_materials_sheen
    /// over the base; docs/design.md §5.10):
    ///
    ///   f = (1 - c F_c(n_c.v)) (f_sheen + f_base min(1 - s E(n.v), 1 - s E(n.l)))
    ///       + c F_c(n_c.v) D_c V_c
    ///
    /// with s = max(sheen colour), f_sheen the Charlie lobe (`sheen`) and
    /// the coat's D and V GGX's of its own alpha about its own normal n_c.
    /// The sheen is a diffuse lobe here (broad; drawn by the cosine), the
    /// coat a glossy one.
    #[inline(never)]
    fn layers(&self, base: V3, l: f32x4, sin2_h: f32x4, wi: &V3, h: &V3, lobes: Lobes) -> V3 {
        let (l_lanes, sin2_lanes) = (l.to_array(), sin2_h.to_array());
        let mut scale = self.under_coat;
        let mut sheen_f = [f32x4::ZERO; 3];
        if let Some(sheen) = &self.sheen {
            let per_lane =
                |f: &dyn Fn(f32, f32) -> f32| f32x4::from([0, 1, 2, 3].map(|k| f(l_lanes[k], sin2_lanes[k])));
            let scaling =
                per_lane(&|l, _| 1.0 - sheen.strongest * sheen.albedo_v.max(sheen::albedo(l, sheen.roughness)));
            scale *= scaling;
            if lobes.diffuse {
                let lobe = per_lane(&|l, s| sheen::f_cos(s, l, self.n_dot_v, sheen.lambda_v, sheen.roughness));
                sheen_f = [0, 1, 2].map(|k| self.under_coat * f32x4::splat(sheen.colour[k]) * lobe);
            }
        }
        let coat = match self.coat.filter(|_| lobes.glossy) {
            Some(c) => {
                let n = &c.n;
                let cross = [n[1] * h[2] - n[2] * h[1], n[2] * h[0] - n[0] * h[2], n[0] * h[1] - n[1] * h[0]];
                let zero = f32x4::ZERO;
                let sin2 = dot3(n, h).cmp_gt(zero).blend(dot3(&cross, &cross).fast_min(f32x4::ONE), f32x4::ONE);
                let l_c = dot3(n, wi).fast_max(zero);
                c.weight * distribution_of_sine(sin2, c.alpha2) * visibility_cos(l_c, c.n_dot_v, c.alpha2)
            }
            None => f32x4::ZERO,
        };
        [0, 1, 2].map(|k| base[k] * scale + sheen_f[k] + coat)
    }

    /// The same layers' bound over directions whose n.l is at most `l`
    /// (n_c.l at most `coat.0`) and whose half-vectors' n_c.h is at most
    /// `coat.1` (the cut's bound, docs/design.md §8.3): the base's bound
    /// `base` times 1 - c F_c(n_c.v) and 1 - s E(n.v) (the smaller of the
    /// scalings is at most it), the sheen's peak D over (4 n.v (1 +
    /// Lambda(n.v) + Lambda(l))) (Lambda falls with the cosine), the
    /// coat's D and V at its bounding cosines, each a little enlarged for
    /// roundings.
    #[inline(never)]
    #[must_use]
    pub fn layers_bound(&self, base: V3, l: f32x4, coat: (f32x4, f32x4), lobes: Lobes) -> V3 {
        const SLACK: f32 = 1.0 + 1e-3;
        let mut scale = self.under_coat * f32x4::splat(SLACK);
        let mut sheen_f = [f32x4::ZERO; 3];
        if let Some(sheen) = &self.sheen {
            scale *= f32x4::splat(1.0 - sheen.strongest * sheen.albedo_v);
            if lobes.diffuse {
                let peak = sheen::peak_distribution(sheen.roughness);
                let lobe = f32x4::from(l.to_array().map(|l| {
                    let view = 4.0 * self.n_dot_v * (1.0 + sheen.lambda_v + sheen::lambda(l, sheen.roughness));
                    if l > 0.0 {
                        SLACK * peak / view
                    } else {
                        0.0
                    }
                }));
                sheen_f = [0, 1, 2].map(|k| self.under_coat * f32x4::splat(sheen.colour[k]) * lobe);
            }
        }
        let coat = match self.coat.filter(|_| lobes.glossy) {
            Some(c) => {
                let (l_c, n_dot_h) = coat;
                c.weight
                    * distribution(n_dot_h, c.alpha2)
                    * visibility_cos(l_c, c.n_dot_v, c.alpha2)
                    * f32x4::splat(SLACK)
            }
            None => f32x4::ZERO,
        };
        [0, 1, 2].map(|k| base[k] * scale + sheen_f[k] + coat)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::util::sampling::Rng;

    /// The specification's formulas, written out again in f64 from
    /// Appendix B (and KHR_materials_specular's dielectric), one direction
    /// at a time: the lanes must agree to f32 precision.
    fn reference(p: &Pbr, n: Vec3, coat_n: Vec3, wo: Vec3, wi: Vec3) -> [f64; 3] {
        let (n, v, l) = (n.as_dvec3(), wo.as_dvec3(), wi.as_dvec3());
        let n_c = coat_n.as_dvec3();
        let (nl_c, nv_c, nh_c) = (n_c.dot(l).max(0.0), n_c.dot(v), n_c.dot((v + l).normalize()));
        let h = (v + l).normalize();
        let (nl, nv, nh, vh) = (n.dot(l), n.dot(v).max(f64::from(MIN_COS_VIEW)), n.dot(h), v.dot(h));
        if nl <= 0.0 {
            return [0.0; 3];
        }
        let a2 = f64::from(p.alpha).powi(2);
        let d = a2 / (std::f64::consts::PI * (nh * nh * (a2 - 1.0) + 1.0).powi(2));
        let vis = 0.5 / (nl * (nv * nv * (1.0 - a2) + a2).sqrt() + nv * (nl * nl * (1.0 - a2) + a2).sqrt());
        let w = (1.0 - vh).powi(5);
        let (base, f0, f90, m) = (p.base.as_dvec3(), p.f0.as_dvec3(), f64::from(p.f90), f64::from(p.metallic));
        let f_d = f0 + (f90 - f0) * w;
        let f_m = base + (glam::DVec3::ONE - base) * w;
        let dielectric = base / std::f64::consts::PI * (1.0 - f_d.max_element()) + f_d * d * vis;
        let metal = f_m * d * vis;
        let f_base = dielectric * (1.0 - m) + metal * m;
        // KHR_materials_sheen's and KHR_materials_clearcoat's layers.
        let r = p.sheen_roughness;
        let e = |cos: f64| f64::from(sheen::albedo(cos as f32, r));
        let s = f64::from(p.sheen.max_element());
        let scaling = (1.0 - s * e(nv)).min(1.0 - s * e(nl));
        let charlie = (2.0 + 1.0 / f64::from(r)) * (1.0 - nh * nh).max(0.0).powf(0.5 / f64::from(r))
            / (2.0 * std::f64::consts::PI);
        let lambda = |cos: f64| f64::from(sheen::lambda(cos as f32, r));
        let f_sheen = p.sheen.as_dvec3() * charlie / ((1.0 + lambda(nv) + lambda(nl)) * 4.0 * nv * nl);
        let blend = f64::from(p.clearcoat) * (0.04 + 0.96 * (1.0 - nv_c.clamp(0.0, 1.0)).powi(5));
        let nv_c = nv_c.max(f64::from(MIN_COS_VIEW));
        let ac2 = f64::from(p.clearcoat_alpha.max(MIN_ALPHA)).powi(2);
        let nh_c = nh_c.max(0.0);
        let d_coat = ac2 / (std::f64::consts::PI * (nh_c * nh_c * (ac2 - 1.0) + 1.0).powi(2));
        let vis_coat = 0.5 * nl_c
            / (nl_c * (nv_c * nv_c * (1.0 - ac2) + ac2).sqrt() + nv_c * (nl_c * nl_c * (1.0 - ac2) + ac2).sqrt());
        let coat = if p.coat_is_smooth() || nl_c <= 0.0 { 0.0 } else { blend * d_coat * vis_coat };
        ((f_sheen + f_base * scaling) * (1.0 - blend) * nl + glam::DVec3::splat(coat)).to_array()
    }

    /// A base of random parameters with, half the time each, a clear coat
    /// (rough, at times smooth) and a sheen.
    fn random_pbr(rng: &mut Rng) -> Pbr {
        let base = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
        let metallic = [0.0, 1.0, rng.next_f32()][rng.below(3) as usize];
        let roughness = rng.range_f32(0.1, 1.0);
        let specular_colour = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0;
        let mut p = Pbr::new(base, metallic, roughness, rng.next_f32(), specular_colour);
        if rng.next_f32() < 0.5 {
            p.clearcoat = rng.next_f32();
            p.clearcoat_alpha = [0.0, 0.01, rng.range_f32(0.1, 1.0)][rng.below(3) as usize];
        }
        if rng.next_f32() < 0.5 {
            p.sheen = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            p.sheen_roughness = rng.range_f32(MIN_SHEEN_ROUGHNESS, 1.0);
        }
        p
    }

    fn unit(rng: &mut Rng) -> Vec3 {
        loop {
            let v = Vec3::new(rng.range_f32(-1.0, 1.0), rng.range_f32(-1.0, 1.0), rng.range_f32(-1.0, 1.0));
            if v.length_squared() > 1e-3 && v.length_squared() <= 1.0 {
                return v.normalize();
            }
        }
    }

    #[test]
    fn the_lanes_follow_the_specification() {
        let mut rng = Rng::seeded(5);
        let mut worst = 0.0f64;
        for _ in 0..20_000 {
            let p = random_pbr(&mut rng);
            let n = unit(&mut rng);
            let (mut wo, mut wi) = (unit(&mut rng), unit(&mut rng));
            if wo.dot(n) < 0.05 {
                wo = (wo - 1.1 * wo.dot(n) * n + 0.05 * n).normalize();
            }
            if wi.dot(n) < 0.0 {
                wi = -wi;
            }
            // Half the coats have a normal of their own, tilted from n
            // (but still facing the view).
            let mut coat_n = if rng.next_f32() < 0.5 { n } else { (n + 0.4 * unit(&mut rng)).normalize() };
            if coat_n.dot(wo) < 0.05 {
                coat_n = n;
            }
            let lanes = PbrLanes::new(&p, n.dot(wo), coat_n, coat_n.dot(wo));
            let f = lanes.f_cos(&splat3(n), &splat3(wo), &splat3(wi), f32x4::splat(n.dot(wi)), Lobes::ALL);
            let expected = reference(&p, n, coat_n, wo, wi);
            for k in 0..3 {
                let got = f64::from(f[k].to_array()[0]);
                let error = (got - expected[k]).abs() / expected[k].abs().max(1e-3);
                worst = worst.max(error);
                assert!(error < 2e-3, "channel {k}: {got} vs {}, {p:?} n={n} wo={wo} wi={wi}", expected[k]);
            }
        }
        assert!(worst > 0.0);
    }

    /// Energy: a white surface reflects at most all the light (the
    /// hemispherical integral of f cos is <= 1), and a smooth white metal
    /// nearly all. GGX without multiple scattering, the spec's model, loses
    /// energy as roughness grows: at roughness 1 (alpha 1, D = 1 / pi, V n.l
    /// = 0.5 n.l / (n.l + n.v)) a white metal seen at n.v = 0.958 reflects
    /// 1 - 0.958 ln(1.958 / 0.958) = 0.315, which the integral must find.
    #[test]
    fn the_hemispherical_reflectance_is_at_most_one() {
        let coated = |metallic: f32, roughness: f32, coat_alpha: f32| Pbr {
            clearcoat: 1.0,
            clearcoat_alpha: coat_alpha,
            ..Pbr::new(Vec3::ONE, metallic, roughness, 1.0, Vec3::ONE)
        };
        let sheen = |roughness: f32, sheen_roughness: f32| Pbr {
            sheen: Vec3::ONE,
            sheen_roughness,
            ..Pbr::new(Vec3::ONE, 0.0, roughness, 1.0, Vec3::ONE)
        };
        let plain = |metallic: f32, roughness: f32| Pbr::new(Vec3::ONE, metallic, roughness, 1.0, Vec3::ONE);
        let cases = [
            (plain(0.0, 0.5), 0.8),
            (plain(0.0, 1.0), 0.8),
            (plain(1.0, 0.3), 0.9),
            (plain(1.0, 1.0), 0.3),
            (coated(0.0, 0.5, 0.05), 0.8),
            (coated(1.0, 0.3, 0.3), 0.85),
            (sheen(0.5, 0.3), 0.8),
            (sheen(0.5, 1.0), 0.8),
            (Pbr { clearcoat: 1.0, clearcoat_alpha: 0.1, ..sheen(0.8, MIN_SHEEN_ROUGHNESS) }, 0.8),
        ];
        let n = Vec3::Z;
        for (p, least) in cases {
            let (metallic, roughness) = (p.metallic, p.alpha.sqrt());
            let wo = Vec3::new(0.3, 0.0, 1.0).normalize();
            let lanes = PbrLanes::new(&p, n.dot(wo), n, n.dot(wo));
            // Midpoint rule: f cos dw = (f cos) d(cos theta) d(phi).
            let steps = 500;
            let mut sum = 0.0f64;
            for i in 0..steps {
                let c = (i as f32 + 0.5) / steps as f32;
                let s = (1.0 - c * c).sqrt();
                for j in 0..steps {
                    let phi = (j as f32 + 0.5) / steps as f32 * 2.0 * PI;
                    let wi = Vec3::new(s * phi.cos(), s * phi.sin(), c);
                    let f = lanes.f_cos(&splat3(n), &splat3(wo), &splat3(wi), f32x4::splat(c), Lobes::ALL);
                    sum += f64::from(f[1].to_array()[0]);
                }
            }
            let albedo = sum / f64::from(steps) * (2.0 * std::f64::consts::PI / f64::from(steps));
            assert!(
                (least..=1.01).contains(&albedo),
                "metallic {metallic}, roughness {roughness}, {p:?}: albedo {albedo}"
            );
        }
    }
}
