//! The fibre BSDF: light scattered by a hair-like dielectric cylinder, after
//! Chiang, Bitterli, Tappan and Burley, "A Practical and Controllable Hair
//! and Fur Model for Production Path Tracing" (EGSR 2016), as pbrt-v4's
//! `HairBxDF` implements it (docs/design.md §5.7).
//!
//! A round curve's hit is a point of a fibre, not of a surface: light that
//! arrives from behind the fibre passes through it (the TT lobe) and comes
//! back round it (TRT). The scattering function is a sum over the paths
//! that leave after p internal segments (R, TT, TRT, and the rest):
//!
//!   f cos = sum_p M_p(theta_i, theta_o) A_p(h, theta_o) N_p(phi),   (docs/design.md §5.7, F1)
//!
//! with theta the angles to the plane normal to the fibre, phi the azimuth
//! about it, h in [-1, 1] where across the fibre the ray met it. M_p is
//! d'Eon's longitudinal lobe of variance v_p, A_p the attenuation by
//! Fresnel reflection and absorption, N_p a trimmed logistic about the
//! azimuth a path of p segments leaves at. The cosine of f cos is the one
//! the solid angle measure brings (d omega = cos theta d theta d phi): f cos
//! is the sum itself, with no 1 / cos.
//!
//! Everything that depends on the viewer is computed once per shading
//! point (`Fibre::new`); each light evaluates only the M_p and N_p terms.

use std::f32::consts::PI;

use glam::Vec3;

use crate::util::color::luminance;

/// Keratin's index of refraction (Marschner et al. 2003; pbrt-v4's default).
pub const FIBRE_IOR: f32 = 1.55;

/// The tilt of a hair's cuticle scales, degrees (pbrt-v4's default): the
/// R lobe shifts towards the root by twice it, TT and TRT the other way.
const SCALE_TILT_DEGREES: f32 = 2.0;

/// The paths followed one by one (R, TT, TRT); the rest are one lobe.
const P_MAX: usize = 3;

/// The fibre's roughness is kept within these: below the lower end the
/// longitudinal lobe's width is under a degree and f32 no longer resolves
/// its normalisation.
const MIN_BETA: f32 = 0.05;

/// Roughness a material without one is given (pbrt-v4's default).
pub const DEFAULT_BETA: f32 = 0.3;

/// A fibre's BSDF at one shading point, as seen from one viewer.
#[derive(Debug, Clone, Copy)]
pub struct Fibre {
    /// The fibre's frame: x along it, y and z across it (world space).
    x: Vec3,
    y: Vec3,
    z: Vec3,
    phi_o: f32,
    /// Where the path enters and refracts, as angles across the fibre
    /// (gamma_o = asin h, gamma_t = asin(h / eta')).
    gamma_o: f32,
    gamma_t: f32,
    /// Per lobe p: theta_o tilted by the scales, as (sin, cos); the
    /// longitudinal variance v_p, and ln(2 v_p sinh(1 / v_p)), M_p's
    /// normaliser.
    tilted: [(f32, f32); P_MAX + 1],
    v: [f32; P_MAX + 1],
    ln_normaliser: [f32; P_MAX + 1],
    /// The logistic's scale s, and 1 / its mass within [-pi, pi].
    s: f32,
    trimmed: f32,
    /// A_p per channel, and the probability of sampling each lobe.
    ap: [Vec3; P_MAX + 1],
    ap_pdf: [f32; P_MAX + 1],
}

impl Fibre {
    /// The fibre of unit `tangent` whose cross-section's normal at the hit
    /// is `normal`, seen from unit `wo`; `colour` its reflectance (the
    /// colour a thick mat of it shows, Chiang et al.'s eq. 9 turns into an
    /// absorption coefficient), `roughness` its longitudinal and azimuthal
    /// roughness beta (kept within [0.05, 1]). None when the tangent is
    /// not a direction.
    #[must_use]
    pub fn new(tangent: Vec3, normal: Vec3, wo: Vec3, colour: Vec3, roughness: f32) -> Option<Self> {
        let x = tangent.try_normalize()?;
        let beta = if roughness.is_finite() { roughness.clamp(MIN_BETA, 1.0) } else { DEFAULT_BETA };
        // y, z across the fibre; h = sin(phi_o - phi_n), the side of the
        // axis the view meets it on (docs/design.md §5.7).
        let (y, z) = x.any_orthonormal_pair();
        let across = |v: Vec3| (v - x * x.dot(v)).normalize_or_zero();
        let h = across(normal).cross(across(wo)).dot(x).clamp(-1.0, 1.0);
        let sin_theta_o = wo.dot(x).clamp(-1.0, 1.0);
        let cos_theta_o = safe_sqrt(1.0 - sin_theta_o * sin_theta_o);
        let phi_o = wo.dot(z).atan2(wo.dot(y));
        let gamma_o = h.asin();
        // The refracted ray: its longitudinal angle (Bravais' index for the
        // azimuth, eta' = sqrt(eta^2 - sin^2 theta_o) / cos theta_o).
        let sin_theta_t = sin_theta_o / FIBRE_IOR;
        let cos_theta_t = safe_sqrt(1.0 - sin_theta_t * sin_theta_t);
        let eta_prime = safe_sqrt(FIBRE_IOR * FIBRE_IOR - sin_theta_o * sin_theta_o) / cos_theta_o.max(1e-6);
        let sin_gamma_t = (h / eta_prime).clamp(-1.0, 1.0);
        let cos_gamma_t = safe_sqrt(1.0 - sin_gamma_t * sin_gamma_t);
        let gamma_t = sin_gamma_t.asin();
        // One pass through the cylinder: exp(-sigma_a 2 cos gamma_t / cos theta_t).
        let sigma_a = absorption_of_reflectance(colour, beta);
        let transmittance = (-sigma_a * (2.0 * cos_gamma_t / cos_theta_t.max(1e-6))).exp();
        let ap = attenuations(cos_theta_o * safe_sqrt(1.0 - h * h), transmittance);
        let weights = ap.map(|a| (a.x + a.y + a.z) / 3.0);
        let total: f32 = weights.iter().sum();
        let ap_pdf = if total > 0.0 { weights.map(|w| w / total) } else { [0.25; P_MAX + 1] };
        let (v, s) = variances(beta, beta);
        // ln(2 v sinh(1 / v)) = ln v + 1 / v + ln(1 - e^(-2/v)).
        let ln_normaliser = v.map(|v| v.ln() + 1.0 / v + (-(-2.0 / v).exp()).ln_1p());
        Some(Self {
            x,
            y,
            z,
            phi_o,
            gamma_o,
            gamma_t,
            tilted: tilts(sin_theta_o, cos_theta_o),
            v,
            ln_normaliser,
            s,
            trimmed: 1.0 / (logistic_cdf(PI, s) - logistic_cdf(-PI, s)),
            ap,
            ap_pdf,
        })
    }

    /// The unit direction along the fibre.
    #[must_use]
    pub fn axis(&self) -> Vec3 {
        self.x
    }

    /// f cos towards unit `wi` (world space), per channel (eq. F1).
    #[must_use]
    pub fn f_cos(&self, wi: Vec3) -> Vec3 {
        let (sin_theta_i, cos_theta_i, phi) = self.incident(wi);
        let mut sum = Vec3::ZERO;
        for p in 0..P_MAX {
            let (sin_o, cos_o) = self.tilted[p];
            sum += self.ap[p] * (self.mp(p, cos_theta_i, sin_theta_i, cos_o, sin_o) * self.np(phi, p));
        }
        let (sin_o, cos_o) = self.tilted[P_MAX];
        sum + self.ap[P_MAX] * (self.mp(P_MAX, cos_theta_i, sin_theta_i, cos_o, sin_o) / (2.0 * PI))
    }

    /// The density, per steradian, with which `sample` draws unit `wi`.
    #[must_use]
    pub fn pdf(&self, wi: Vec3) -> f32 {
        let (sin_theta_i, cos_theta_i, phi) = self.incident(wi);
        let mut pdf = 0.0;
        for p in 0..P_MAX {
            let (sin_o, cos_o) = self.tilted[p];
            pdf += self.ap_pdf[p] * self.mp(p, cos_theta_i, sin_theta_i, cos_o, sin_o) * self.np(phi, p);
        }
        let (sin_o, cos_o) = self.tilted[P_MAX];
        pdf + self.ap_pdf[P_MAX] * self.mp(P_MAX, cos_theta_i, sin_theta_i, cos_o, sin_o) / (2.0 * PI)
    }

    /// A direction drawn with the uniform numbers `u`: the first picks the
    /// lobe p by A_p (and, rescaled, the azimuth about its centre), the
    /// others the longitudinal angle from M_p (d'Eon's inversion, as
    /// pbrt-v4's `HairBxDF::Sample_f`). With its density (`pdf`); None for
    /// a density of 0.
    #[must_use]
    pub fn sample(&self, u: [f32; 3]) -> Option<(Vec3, f32)> {
        let (mut p, mut below) = (P_MAX, 0.0);
        for (k, &w) in self.ap_pdf.iter().enumerate() {
            if u[0] < below + w || k == P_MAX {
                p = k;
                break;
            }
            below += w;
        }
        let share = self.ap_pdf[p];
        let uc = if share > 0.0 { ((u[0] - below) / share).clamp(0.0, 1.0 - f32::EPSILON) } else { 0.5 };
        let (sin_o, cos_o) = self.tilted[p];
        let v = self.v[p];
        let cos_theta = 1.0 + v * (u[1].max(1e-5) + (1.0 - u[1]) * (-2.0 / v).exp()).ln();
        let sin_theta = safe_sqrt(1.0 - cos_theta * cos_theta);
        let cos_phi = (2.0 * PI * u[2]).cos();
        let sin_theta_i = (-cos_theta * sin_o + sin_theta * cos_phi * cos_o).clamp(-1.0, 1.0);
        let cos_theta_i = safe_sqrt(1.0 - sin_theta_i * sin_theta_i);
        let dphi = if p < P_MAX { self.centre(p) + sample_trimmed_logistic(uc, self.s) } else { 2.0 * PI * uc };
        let phi_i = self.phi_o + dphi;
        let local = Vec3::new(sin_theta_i, cos_theta_i * phi_i.cos(), cos_theta_i * phi_i.sin());
        let wi = (self.x * local.x + self.y * local.y + self.z * local.z).normalize_or_zero();
        let pdf = self.pdf(wi);
        (pdf > 0.0 && pdf.is_finite() && wi != Vec3::ZERO).then_some((wi, pdf))
    }

    /// An upper bound of `f_cos` over every direction, per channel (the
    /// cut's material bound, docs/design.md §5.7): the sum over the lobes
    /// of A_p (exact) times the largest M_p times the largest N_p. N_p's
    /// is the logistic's peak 1 / (4 s) over its trimmed mass (the rest's
    /// 1 / (2 pi)). M_p is unimodal in theta_i (d'Eon's lobe is the
    /// longitudinal marginal of a spherical Gaussian about -theta_o'), so
    /// a golden-section search finds its peak. One percent is added for
    /// the search's and the exponent's roundings.
    #[must_use]
    pub fn peak(&self) -> Vec3 {
        let np = self.trimmed / (4.0 * self.s);
        let mut sum = self.ap[P_MAX] * (self.mp_peak(P_MAX) / (2.0 * PI));
        for p in 0..P_MAX {
            sum += self.ap[p] * (self.mp_peak(p) * np);
        }
        sum * 1.01
    }

    /// The largest M_p over theta_i in [-pi/2, pi/2]: a golden-section
    /// search of its logarithm (M_p itself underflows to 0 away from a
    /// narrow lobe, where the search would see no slope).
    fn mp_peak(&self, p: usize) -> f32 {
        let (sin_o, cos_o) = self.tilted[p];
        let m = |theta: f32| {
            let (s, c) = theta.sin_cos();
            self.ln_mp(p, c, s, cos_o, sin_o)
        };
        let ratio = 0.5 * (5.0f32.sqrt() - 1.0);
        let (mut lo, mut hi) = (-0.5 * PI, 0.5 * PI);
        let mut a = hi - ratio * (hi - lo);
        let mut b = lo + ratio * (hi - lo);
        let (mut ma, mut mb) = (m(a), m(b));
        let mut best = m(lo).max(m(hi)).max(ma).max(mb);
        for _ in 0..40 {
            if ma < mb {
                lo = a;
                a = b;
                ma = mb;
                b = lo + ratio * (hi - lo);
                mb = m(b);
            } else {
                hi = b;
                b = a;
                mb = ma;
                a = hi - ratio * (hi - lo);
                ma = m(a);
            }
            best = best.max(ma).max(mb);
        }
        best.exp()
    }

    /// An estimate of the fibre's reflectance (luminance of the A_p), which
    /// weighs its BSDF against a mirror layer's when a path continues.
    #[must_use]
    pub fn weight(&self) -> f32 {
        self.ap.iter().map(|a| luminance(*a)).sum()
    }

    /// sin theta_i, cos theta_i and phi_i - phi_o of unit `wi`.
    fn incident(&self, wi: Vec3) -> (f32, f32, f32) {
        let sin_theta_i = wi.dot(self.x).clamp(-1.0, 1.0);
        let cos_theta_i = safe_sqrt(1.0 - sin_theta_i * sin_theta_i);
        let phi_i = wi.dot(self.z).atan2(wi.dot(self.y));
        (sin_theta_i, cos_theta_i, phi_i - self.phi_o)
    }

    /// d'Eon's longitudinal lobe M_p = e^(-b) I_0(a) / (2 v sinh(1 / v)),
    /// a = cos theta_i cos theta_o' / v, b = sin theta_i sin theta_o' / v,
    /// in logarithms so that a narrow lobe's e^(1/v) does not overflow.
    fn mp(&self, p: usize, cos_i: f32, sin_i: f32, cos_o: f32, sin_o: f32) -> f32 {
        self.ln_mp(p, cos_i, sin_i, cos_o, sin_o).exp()
    }

    fn ln_mp(&self, p: usize, cos_i: f32, sin_i: f32, cos_o: f32, sin_o: f32) -> f32 {
        let v = self.v[p];
        let (a, b) = (cos_i * cos_o.abs() / v, sin_i * sin_o / v);
        ln_i0(a) - b - self.ln_normaliser[p]
    }

    /// N_p at relative azimuth `phi`: the trimmed logistic about the
    /// azimuth Phi(p) = 2 p gamma_t - 2 gamma_o + p pi that p segments
    /// leave at.
    fn np(&self, phi: f32, p: usize) -> f32 {
        let d = wrap_pi(phi - self.centre(p));
        logistic(d, self.s) * self.trimmed
    }

    fn centre(&self, p: usize) -> f32 {
        let p = p as f32;
        2.0 * p * self.gamma_t - 2.0 * self.gamma_o + p * PI
    }
}

/// The absorption coefficient (per fibre diameter) that gives a mat of
/// fibres of roughness `beta_n` the reflectance `colour`: Chiang et al.
/// 2016, eq. 9, sigma_a = (ln c / (5.969 - 0.215 b + 2.532 b^2 - 10.73 b^3
/// + 5.574 b^4 + 0.245 b^5))^2.
fn absorption_of_reflectance(colour: Vec3, beta_n: f32) -> Vec3 {
    let b = beta_n;
    let d = 5.969 - 0.215 * b + 2.532 * b * b - 10.73 * b.powi(3) + 5.574 * b.powi(4) + 0.245 * b.powi(5);
    let c = colour.clamp(Vec3::splat(1e-3), Vec3::ONE);
    let l = Vec3::new(c.x.ln(), c.y.ln(), c.z.ln()) / d;
    l * l
}

/// A_p for a path entering at cos gamma = `cos_gamma` (cos theta_o cos
/// gamma_o) with one pass's transmittance `t`: A_0 = F, A_1 = (1 - F)^2 T,
/// A_p = A_(p-1) T F, and the rest's geometric series A_(p-1) F T / (1 - F T).
fn attenuations(cos_gamma: f32, t: Vec3) -> [Vec3; P_MAX + 1] {
    let f = fresnel_dielectric(cos_gamma, FIBRE_IOR);
    let mut ap = [Vec3::ZERO; P_MAX + 1];
    ap[0] = Vec3::splat(f);
    ap[1] = (1.0 - f) * (1.0 - f) * t;
    for p in 2..P_MAX {
        ap[p] = ap[p - 1] * t * f;
    }
    let tf = t * f;
    let rest = Vec3::ONE - tf;
    ap[P_MAX] = Vec3::select(rest.cmpgt(Vec3::ZERO), ap[P_MAX - 1] * tf / rest.max(Vec3::splat(1e-30)), Vec3::ZERO);
    ap
}

/// The longitudinal variances v_p and the azimuthal logistic scale s of
/// roughnesses beta_m and beta_n (Chiang et al. 2016, eqs. 7 and 8): v_0 =
/// (0.726 b + 0.812 b^2 + 3.7 b^20)^2, v_1 = v_0 / 4, v_2 and the rest 4
/// v_0; s = sqrt(pi / 8) (0.265 b + 1.194 b^2 + 5.372 b^22).
fn variances(beta_m: f32, beta_n: f32) -> ([f32; P_MAX + 1], f32) {
    let root = 0.726 * beta_m + 0.812 * beta_m * beta_m + 3.7 * beta_m.powi(20);
    let v0 = root * root;
    let s = 0.626_657_07 * (0.265 * beta_n + 1.194 * beta_n * beta_n + 5.372 * beta_n.powi(22));
    ([v0, 0.25 * v0, 4.0 * v0, 4.0 * v0], s)
}

/// theta_o tilted by the scales, per lobe: R by -2 alpha, TT by alpha,
/// TRT by 4 alpha, the rest not (pbrt-v4's signs), as (sin, cos).
fn tilts(sin_o: f32, cos_o: f32) -> [(f32, f32); P_MAX + 1] {
    let alpha = SCALE_TILT_DEGREES.to_radians();
    let tilt = |angle: f32| {
        let (s, c) = angle.sin_cos();
        (sin_o * c + cos_o * s, (cos_o * c - sin_o * s).abs())
    };
    [tilt(-2.0 * alpha), tilt(alpha), tilt(4.0 * alpha), (sin_o, cos_o)]
}

/// The Fresnel reflectance of unpolarised light arriving at cosine `cos_i`
/// on a dielectric of relative index `eta` (1 past the critical angle).
fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = safe_sqrt(1.0 - sin2_t);
    let parallel = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let perpendicular = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (parallel * parallel + perpendicular * perpendicular)
}

/// ln I_0(x) for x >= 0, the modified Bessel function of the first kind
/// (Abramowitz and Stegun 9.8.1 and 9.8.2, relative error below 2e-7).
fn ln_i0(x: f32) -> f32 {
    let x = x.max(0.0);
    if x < 3.75 {
        let t = (x / 3.75) * (x / 3.75);
        let poly = 1.0
            + t * (3.515_622_9
                + t * (3.089_942_4 + t * (1.206_749_2 + t * (0.265_973_2 + t * (0.036_076_8 + t * 0.004_581_3)))));
        return poly.ln();
    }
    let t = 3.75 / x;
    let poly = 0.398_942_3
        + t * (0.013_285_92
            + t * (0.002_253_19
                + t * (-0.001_575_65
                    + t * (0.009_162_81
                        + t * (-0.020_577_06 + t * (0.026_355_37 + t * (-0.016_476_33 + t * 0.003_923_77)))))));
    x - 0.5 * x.ln() + poly.ln()
}

/// The logistic density of scale `s` at `x`: e^(-|x|/s) / (s (1 + e^(-|x|/s))^2).
fn logistic(x: f32, s: f32) -> f32 {
    let e = (-x.abs() / s).exp();
    e / (s * (1.0 + e) * (1.0 + e))
}

fn logistic_cdf(x: f32, s: f32) -> f32 {
    1.0 / (1.0 + (-x / s).exp())
}

/// A logistic deviate of scale `s` trimmed to [-pi, pi], from uniform `u`
/// (the inverse of its CDF over the trimmed mass).
fn sample_trimmed_logistic(u: f32, s: f32) -> f32 {
    let (lo, hi) = (logistic_cdf(-PI, s), logistic_cdf(PI, s));
    let u = lo + u * (hi - lo);
    (-s * (1.0 / u - 1.0).ln()).clamp(-PI, PI)
}

/// `x` moved into [-pi, pi] by whole turns.
fn wrap_pi(x: f32) -> f32 {
    let turns = ((x + PI) / (2.0 * PI)).floor();
    x - turns * 2.0 * PI
}

fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

#[cfg(test)]
mod tests;
