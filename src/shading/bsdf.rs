//! A shading point's BSDF as a sampling strategy, as pbrt-v4's `BxDF` and
//! Mitsuba 3's `BSDF` are: `eval` (f cos), `sample` (a direction with f cos
//! and its density) and `pdf` (the density `sample` draws a direction with),
//! scalar, for every material (docs/design.md §5.6).
//!
//! - Lambert: directions by the cosine, pdf cos / pi.
//! - Phong's lobe k_s (e + 2) / (2 pi) cos^e(alpha) about the mirror
//!   direction r: directions by cos^e about r, pdf (e + 1) / (2 pi) cos^e.
//! - glTF's metallic-roughness specular lobe (GGX): the visible normals of
//!   the distribution (Heitz, "Sampling the GGX Distribution of Visible
//!   Normals", JCGT 2018), reflected: pdf D(h) G1(wo) / (4 n.wo).
//! - A fibre (`shading::fibre`): its own sampling, over the whole sphere.
//! - A rough clear coat (docs/design.md §5.10): GGX's visible normals at
//!   the coat's alpha, a third lobe; a sheen is drawn with the diffuse
//!   lobe, its albedo added to that lobe's weight.
//!
//! A material with both lobes picks one in proportion to an estimate of its
//! reflectance and returns the mixture's density (one-sample MIS over the
//! lobes), so that f cos / pdf is unbiased whichever lobe drew the
//! direction. Perfect mirrors (a material's mirror layer, a metallic-
//! roughness surface smoother than `pbr::MIN_ALPHA`) are not lobes here:
//! they are traced as mirror bounces (`SurfacePoint::mirror`). `eval`
//! computes f cos with the very code the lights are evaluated with
//! (`MaterialLanes`, lane 0), so a light and a sampled direction see the
//! same BSDF bit for bit.

use std::f32::consts::PI;

use glam::Vec3;

use super::direct::MaterialLanes;
use super::fibre::Fibre;
use super::lobes::Lobes;
use super::microfacet::sample_visible_normal;
use super::pbr::{Pbr, MIN_ALPHA, MIN_COS_VIEW};
use super::sheen;
use super::surface::SurfacePoint;
use crate::util::color::luminance;
use crate::util::simd::splat3;

/// A direction the BSDF drew: f cos towards it (of the lobes asked for)
/// and the density it was drawn with, per steradian.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BsdfSample {
    pub wi: Vec3,
    pub f_cos: Vec3,
    pub pdf: f32,
}

/// The glossy lobe a BSDF samples.
#[derive(Debug, Clone, Copy)]
enum Glossy {
    /// A fibre's lobes (docs/design.md §5.7), over the whole sphere: the
    /// BSDF is this alone.
    Fibre(Fibre),
    /// No continuous glossy lobe (none, or a perfect mirror).
    None,
    /// Phong's cos^e about the mirror direction (world space).
    Phong { exponent: f32, r: Vec3 },
    /// GGX's visible normals, of roughness^2 `alpha` (at least MIN_ALPHA).
    Ggx { alpha: f32 },
}

/// A shading point's BSDF for sampling (see the module's comment).
#[derive(Clone, Copy)]
pub struct Bsdf {
    material: MaterialLanes,
    /// The shading frame: tangent, bitangent, normal (world space).
    t: Vec3,
    b: Vec3,
    n: Vec3,
    /// The direction towards the viewer in the shading frame, its z at
    /// least MIN_COS_VIEW (a shading normal tilted away from the viewer):
    /// what the glossy lobe samples and its density are computed from.
    wo: Vec3,
    glossy: Glossy,
    /// A rough clear coat's GGX lobe (docs/design.md §5.10): a second
    /// glossy lobe, over the base's, about its own normal.
    coat: Option<CoatLobe>,
    /// Estimates of the diffuse (with a sheen's), the glossy and the
    /// coat's lobes' reflectance (luminance), which choose among them.
    diffuse_weight: f32,
    glossy_weight: f32,
    coat_weight: f32,
}

impl Bsdf {
    /// The BSDF at `sp` (its material's non-delta lobes).
    #[must_use]
    pub fn new(sp: &SurfacePoint<'_>) -> Self {
        let n = sp.n;
        let (t, b) = n.any_orthonormal_pair();
        let local = Vec3::new(sp.wo.dot(t), sp.wo.dot(b), sp.wo.dot(n));
        let wo = Vec3::new(local.x, local.y, local.z.max(MIN_COS_VIEW)).normalize_or(Vec3::Z);
        let m = sp.material;
        let (mut coat, mut coat_weight) = (None, 0.0);
        let (glossy, diffuse_weight, glossy_weight) = match (&sp.fibre, &sp.pbr) {
            (Some(fibre), _) => (Glossy::Fibre(*fibre), 0.0, fibre.weight()),
            (None, Some(pbr)) => {
                let glossy = if pbr.is_smooth() { Glossy::None } else { Glossy::Ggx { alpha: pbr.alpha } };
                let coat_cos = sp.coat_cos_view();
                if pbr.clearcoat > 0.0 && !pbr.coat_is_smooth() {
                    coat = Some(CoatLobe::new(sp, pbr.clearcoat_alpha.max(MIN_ALPHA)));
                    coat_weight = pbr.coat_blend(coat_cos);
                }
                let under = pbr.base_weight(wo.z, coat_cos);
                let sheen =
                    luminance(pbr.sheen) * sheen::albedo(wo.z, pbr.sheen_roughness) * (1.0 - pbr.coat_blend(coat_cos));
                (glossy, luminance(sp.kd) * under + sheen, ggx_weight(pbr, wo.z) * under)
            }
            (None, None) if m.has_specular() => {
                (Glossy::Phong { exponent: m.exponent, r: sp.r }, luminance(sp.kd), luminance(m.specular))
            }
            (None, None) => (Glossy::None, luminance(sp.kd), 0.0),
        };
        let glossy_weight = if matches!(glossy, Glossy::None) { 0.0 } else { glossy_weight };
        let material = MaterialLanes::new(sp);
        Self { material, t, b, n, wo, glossy, coat, diffuse_weight, glossy_weight, coat_weight }
    }

    /// f cos of `lobes` towards unit `wi` (world space), per channel: the
    /// material term the lights are evaluated with (0 below the shading or
    /// the geometric surface).
    #[must_use]
    pub fn eval(&self, wi: Vec3, lobes: Lobes) -> Vec3 {
        let m = self.material.term(&splat3(wi), lobes);
        Vec3::new(m[0].to_array()[0], m[1].to_array()[0], m[2].to_array()[0])
    }

    /// The probabilities of sampling the glossy lobe and the coat's among
    /// `lobes` (the rest goes to the diffuse lobe); None when no lobe asked
    /// for reflects anything.
    fn glossy_probability(&self, lobes: Lobes) -> Option<(f32, f32)> {
        let diffuse = if lobes.diffuse { self.diffuse_weight } else { 0.0 };
        let glossy = if lobes.glossy { self.glossy_weight } else { 0.0 };
        let coat = if lobes.glossy { self.coat_weight } else { 0.0 };
        let sum = diffuse + glossy + coat;
        (sum > 0.0 && sum.is_finite()).then(|| (glossy / sum, coat / sum))
    }

    /// The density, per steradian, with which `sample(.., lobes)` draws
    /// unit `wi` (world space).
    #[must_use]
    pub fn pdf(&self, wi: Vec3, lobes: Lobes) -> f32 {
        let Some((p_glossy, p_coat)) = self.glossy_probability(lobes) else { return 0.0 };
        let local = self.in_frame(wi);
        let mut pdf = 0.0;
        let p_diffuse = 1.0 - p_glossy - p_coat;
        if p_diffuse > 0.0 {
            pdf += p_diffuse * local.z.max(0.0) / PI;
        }
        if p_glossy > 0.0 {
            pdf += p_glossy * self.glossy_pdf(wi, local);
        }
        if let Some(coat) = self.coat.filter(|_| p_coat > 0.0) {
            pdf += p_coat * ggx_pdf(coat.wo, coat.in_frame(wi), coat.alpha);
        }
        pdf
    }

    /// A direction drawn from `lobes` with the uniform numbers `u` (the
    /// first picks the lobe, the other two the direction), with f cos of
    /// `lobes` towards it and its density (`pdf`). None when no lobe asked
    /// for reflects anything, or the draw is degenerate (a density of 0).
    /// A direction below the surface may be drawn: its f cos is 0.
    #[must_use]
    pub fn sample(&self, u: [f32; 3], lobes: Lobes) -> Option<BsdfSample> {
        let (p_glossy, p_coat) = self.glossy_probability(lobes)?;
        if let Glossy::Fibre(fibre) = &self.glossy {
            let (wi, pdf) = fibre.sample(u)?;
            return Some(BsdfSample { wi, f_cos: self.eval(wi, lobes), pdf });
        }
        let local = match self.coat {
            _ if u[0] < p_glossy => self.sample_glossy(u[1], u[2]),
            Some(coat) if u[0] < p_glossy + p_coat => {
                let d = coat.to_world(reflect(coat.wo, sample_visible_normal(coat.wo, coat.alpha, u[1], u[2])));
                self.in_frame(d.normalize())
            }
            _ => cosine_hemisphere(u[1], u[2]),
        };
        let wi = (self.t * local.x + self.b * local.y + self.n * local.z).normalize();
        let pdf = self.pdf(wi, lobes);
        (pdf > 0.0 && pdf.is_finite()).then(|| BsdfSample { wi, f_cos: self.eval(wi, lobes), pdf })
    }

    /// An estimate of the reflectance of all its lobes (luminance): what a
    /// path weighs its BSDF against its mirror layer with, choosing which
    /// one to follow (docs/design.md §6.7).
    #[must_use]
    pub fn reflectance_weight(&self) -> f32 {
        self.diffuse_weight + self.glossy_weight + self.coat_weight
    }

    /// The solid angle its glossy lobe spreads over, steradians (None
    /// without one): Phong's cos^e integrates to 2 pi / (e + 1); GGX's
    /// half-vectors spread over about pi alpha^2, its reflected directions
    /// four times that. How many of the environment's lights the lobe sees
    /// is this times their density (docs/design.md §6.2).
    #[must_use]
    pub fn glossy_solid_angle(&self) -> Option<f32> {
        let ggx = |alpha: f32| (4.0 * PI * alpha * alpha).min(2.0 * PI);
        let base = match self.glossy {
            // A fibre's lobes wrap round it: every light sees them.
            Glossy::None | Glossy::Fibre(_) => None,
            Glossy::Phong { exponent, .. } => Some(2.0 * PI / (exponent + 1.0)),
            Glossy::Ggx { alpha } => Some(ggx(alpha)),
        };
        // A coat's lobe too: the sharper of the two decides.
        base.into_iter().chain(self.coat.map(|c| ggx(c.alpha))).reduce(f32::min)
    }

    fn in_frame(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.t), v.dot(self.b), v.dot(self.n))
    }

    /// A direction of the glossy lobe, in the shading frame.
    fn sample_glossy(&self, u1: f32, u2: f32) -> Vec3 {
        match self.glossy {
            Glossy::None | Glossy::Fibre(_) => Vec3::Z,
            Glossy::Phong { exponent, r } => {
                // cos^e about r: cos alpha = u^(1 / (e + 1)).
                let cos_alpha = u1.powf(1.0 / (exponent + 1.0));
                let sin_alpha = (1.0 - cos_alpha * cos_alpha).max(0.0).sqrt();
                let phi = 2.0 * PI * u2;
                let (rt, rb) = r.any_orthonormal_pair();
                let d = r * cos_alpha + rt * (sin_alpha * phi.cos()) + rb * (sin_alpha * phi.sin());
                self.in_frame(d.normalize())
            }
            Glossy::Ggx { alpha } => {
                let h = sample_visible_normal(self.wo, alpha, u1, u2);
                reflect(self.wo, h)
            }
        }
    }

    /// The glossy lobe's density towards `wi` (world) = `local`.
    fn glossy_pdf(&self, wi: Vec3, local: Vec3) -> f32 {
        match self.glossy {
            Glossy::None => 0.0,
            Glossy::Fibre(fibre) => fibre.pdf(wi),
            Glossy::Phong { exponent, r } => {
                let cos_alpha = r.dot(wi).max(0.0);
                (exponent + 1.0) / (2.0 * PI) * cos_alpha.powf(exponent)
            }
            Glossy::Ggx { alpha } => ggx_pdf(self.wo, local, alpha),
        }
    }
}

/// A rough clear coat's lobe: GGX of roughness^2 `alpha` in the frame of
/// the coat's normal (tangent, bitangent, normal), the view in that frame
/// (its z at least MIN_COS_VIEW).
#[derive(Debug, Clone, Copy)]
struct CoatLobe {
    alpha: f32,
    t: Vec3,
    b: Vec3,
    n: Vec3,
    wo: Vec3,
}

impl CoatLobe {
    fn new(sp: &SurfacePoint<'_>, alpha: f32) -> Self {
        let n = sp.coat_n;
        let (t, b) = n.any_orthonormal_pair();
        let local = Vec3::new(sp.wo.dot(t), sp.wo.dot(b), sp.wo.dot(n).max(MIN_COS_VIEW));
        Self { alpha, t, b, n, wo: local.normalize_or(Vec3::Z) }
    }

    fn in_frame(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.t), v.dot(self.b), v.dot(self.n))
    }

    fn to_world(self, v: Vec3) -> Vec3 {
        self.t * v.x + self.b * v.y + self.n * v.z
    }
}

/// The density of GGX's visible normals reflected, from the view `wo`
/// towards `local` (both in the shading frame), for roughness^2 `alpha`:
/// D_wo(h) / (4 wo.h), D_wo(h) = G1(wo) wo.h D(h) / wo.z.
fn ggx_pdf(wo: Vec3, local: Vec3, alpha: f32) -> f32 {
    let h = (wo + local).normalize_or_zero();
    if h.z <= 0.0 || wo.dot(h) <= 0.0 {
        return 0.0;
    }
    ggx_d(h, alpha) * smith_g1(wo.z, alpha) / (4.0 * wo.z)
}

/// An estimate of a metallic-roughness specular lobe's reflectance (the
/// Fresnel term towards the mirror direction, luminance), which weighs the
/// choice of the lobe against the diffuse one.
fn ggx_weight(pbr: &Pbr, n_dot_v: f32) -> f32 {
    luminance(pbr.mirror_reflectance(n_dot_v))
}

/// A cosine-distributed direction about +z: pdf cos / pi.
fn cosine_hemisphere(u1: f32, u2: f32) -> Vec3 {
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u1).max(0.0).sqrt())
}

/// The mirror image of `v` about the unit normal `h`.
fn reflect(v: Vec3, h: Vec3) -> Vec3 {
    2.0 * v.dot(h) * h - v
}

/// Trowbridge-Reitz D of the half-vector `h` (shading frame, unit) for
/// roughness^2 `alpha`: alpha^2 / (pi (sin^2 + cos^2 alpha^2)^2), its sine
/// squared from h's x and y (1 - cos^2 in f32 resolves nothing below 6e-8,
/// where a lobe of alpha 2.5e-3 has alpha^2 = 6e-6: its density would be
/// a percent off).
fn ggx_d(h: Vec3, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let d = (h.x * h.x + h.y * h.y) + h.z * h.z * a2;
    a2 / (PI * d * d)
}

/// Smith's masking G1 of GGX for a direction at cosine `cos` to the normal:
/// 2 cos / (cos + sqrt(alpha^2 + (1 - alpha^2) cos^2)).
fn smith_g1(cos: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    2.0 * cos / (cos + (a2 + (1.0 - a2) * cos * cos).sqrt())
}

#[cfg(test)]
mod tests;
