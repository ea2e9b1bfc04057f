//! The BSDF's sampling against its density and its value, as pbrt-v3's
//! `bsdftest` and Mitsuba's `chi2` test check theirs: for every material
//! (Lambert, Phong from exponent 1 to 1,000, glTF's metallic-roughness from
//! roughness 0.05 to 1, metals, dielectrics, a black dielectric) at views
//! from grazing to head-on and for each set of lobes, (1) the density
//! integrates to 1 over the sphere, (2) a histogram of 200,000 sampled
//! directions matches the density integrated over its cells (chi-square),
//! (3) the mean of f cos / pdf over the samples is the directional albedo
//! the quadrature of f cos gives. Each check is shown to catch a mutation.

use glam::Vec3;

use super::*;
use crate::scene::material::{Albedo, Material, PbrMaterial};
use crate::util::sampling::Rng;

/// A surface point on the plane z = 0 (normal +z) seen from `wo`.
fn point(material: &Material, wo: Vec3) -> SurfacePoint<'_> {
    let base = match material.albedo {
        Albedo::Constant(c) => c,
        Albedo::Texture(_) => unreachable!(),
    };
    let pbr = material.pbr.as_ref().map(|m| Pbr::of(m, base, &crate::scene::material::TexCoords::default(), &[]));
    let kd = pbr.map_or(base, |p| p.diffuse_albedo());
    // A coat of a normal of its own, tilted from the base's.
    let coat_n = if material.name == "tilted coat" { Vec3::new(0.3, 0.2, 1.0).normalize() } else { Vec3::Z };
    SurfacePoint { pbr, coat_n, ..SurfacePoint::bare(material, Vec3::ZERO, Vec3::Z, wo, kd) }
}

fn lambert(albedo: f32) -> Material {
    Material::diffuse("lambert", Albedo::Constant(Vec3::splat(albedo)))
}

fn phong(kd: f32, ks: f32, exponent: f32) -> Material {
    Material { specular: Vec3::splat(ks), exponent, ..lambert(kd) }
}

fn gltf(base: Vec3, metallic: f32, roughness: f32) -> Material {
    Material {
        pbr: Some(PbrMaterial::untextured(metallic, roughness)),
        ..Material::diffuse("gltf", Albedo::Constant(base))
    }
}

/// A sampling strategy under test: draw (direction, density), the density
/// of a direction, and the luminance of f cos towards a direction.
struct Strategy<'a> {
    sample: &'a dyn Fn([f32; 3]) -> Option<(Vec3, f32)>,
    pdf: &'a dyn Fn(Vec3) -> f32,
    f: &'a dyn Fn(Vec3) -> f64,
}

/// A grid over the sphere about `axis`, finer near it: ring i covers
/// theta in [pi (i / RINGS)^2, pi ((i + 1) / RINGS)^2], sector j phi in
/// [2 pi j / SECTORS, 2 pi (j + 1) / SECTORS]. A lobe as narrow as a few
/// thousandths of a radian about the axis spans many cells.
struct Grid {
    axis: Vec3,
    t: Vec3,
    b: Vec3,
}

const RINGS: usize = 48;
const SECTORS: usize = 16;
/// Quadrature points per cell and dimension.
const SUB: usize = 16;

impl Grid {
    fn new(axis: Vec3) -> Self {
        let (t, b) = axis.any_orthonormal_pair();
        Self { axis, t, b }
    }

    fn direction(&self, ring: f64, sector: f64) -> Vec3 {
        let theta = std::f64::consts::PI * ring * ring;
        let phi = 2.0 * std::f64::consts::PI * sector;
        let (s, c) = (theta.sin() as f32, theta.cos() as f32);
        (self.axis * c + self.t * (s * phi.cos() as f32) + self.b * (s * phi.sin() as f32)).normalize()
    }

    fn cell(&self, d: Vec3) -> usize {
        // In f64, the angle from the axis by atan2: acos of an f32 cosine
        // resolves no angle below 3e-4 radians.
        let (d, axis) = (d.as_dvec3(), self.axis.as_dvec3());
        let theta = d.cross(axis).length().atan2(d.dot(axis));
        let ring = (theta / std::f64::consts::PI).sqrt();
        let phi = d.dot(self.b.as_dvec3()).atan2(d.dot(self.t.as_dvec3())).rem_euclid(2.0 * std::f64::consts::PI);
        let i = ((ring * RINGS as f64) as usize).min(RINGS - 1);
        let j = ((phi / (2.0 * std::f64::consts::PI) * SECTORS as f64) as usize).min(SECTORS - 1);
        i * SECTORS + j
    }

    /// The integral of `g` over each cell: the midpoint rule in (ring,
    /// sector), times the solid angle element sin theta dtheta dphi, with
    /// `SUB` points per dimension, and with 8 times as many where twice as
    /// many change it by more than 0.2% (a grazing view's lobe has ridges
    /// narrower than a cell: Mitsuba's chi2 test integrates adaptively too).
    fn integrate(&self, g: &dyn Fn(Vec3) -> f64) -> Vec<f64> {
        let mut cells = vec![0.0; RINGS * SECTORS];
        for (k, cell) in cells.iter_mut().enumerate() {
            let (i, j) = (k / SECTORS, k % SECTORS);
            let coarse = self.integrate_cell(g, i, j, SUB);
            let finer = self.integrate_cell(g, i, j, 2 * SUB);
            *cell = if (finer - coarse).abs() > 2e-3 * finer.abs() + 1e-9 {
                self.integrate_cell(g, i, j, 8 * SUB)
            } else {
                finer
            };
        }
        cells
    }

    /// The integral of `g` over cell (ring `i`, sector `j`), `sub` x `sub`
    /// midpoints.
    fn integrate_cell(&self, g: &dyn Fn(Vec3) -> f64, i: usize, j: usize, sub: usize) -> f64 {
        let (dr, ds) = (1.0 / (RINGS * sub) as f64, 1.0 / (SECTORS * sub) as f64);
        let mut sum = 0.0;
        for a in 0..sub {
            let ring = (i * sub + a) as f64 * dr + 0.5 * dr;
            let theta = std::f64::consts::PI * ring * ring;
            // d(theta) = 2 pi ring d(ring); d(phi) = 2 pi d(sector).
            let area = theta.sin() * 2.0 * std::f64::consts::PI * ring * dr * 2.0 * std::f64::consts::PI * ds;
            for c in 0..sub {
                let sector = (j * sub + c) as f64 * ds + 0.5 * ds;
                sum += g(self.direction(ring, sector)) * area;
            }
        }
        sum
    }
}

/// The upper tail of the chi-square distribution with `k` degrees of
/// freedom at `x`, by Wilson and Hilferty's normal approximation.
fn chi_square_tail(x: f64, k: f64) -> f64 {
    let z = ((x / k).cbrt() - (1.0 - 2.0 / (9.0 * k))) / (2.0 / (9.0 * k)).sqrt();
    0.5 * erfc(z / std::f64::consts::SQRT_2)
}

/// The complementary error function (Numerical Recipes' erfcc: relative
/// error below 1.2e-7).
fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let r = t
        * (-z * z - 1.26551223
            + t * (1.00002368
                + t * (0.37409196
                    + t * (0.09678418
                        + t * (-0.18628806
                            + t * (0.27886807
                                + t * (-1.13520398 + t * (1.48851587 + t * (-0.82215223 + t * 0.17087277)))))))))
            .exp();
    if x >= 0.0 {
        r
    } else {
        2.0 - r
    }
}

const SAMPLES: usize = 200_000;

/// The three checks of the module's comment; the first that fails, named.
fn check(strategy: &Strategy<'_>, axis: Vec3, seed: u64) -> Result<(), String> {
    let grid = Grid::new(axis);
    // (1) The density integrates to 1 (the quadrature's own error, with
    // these cells, is below 1e-4 for every lobe here).
    let expected = grid.integrate(&|d| f64::from((strategy.pdf)(d)));
    let total: f64 = expected.iter().sum();
    if (total - 1.0).abs() > 2e-3 {
        return Err(format!("the density integrates to {total}"));
    }
    // Samples: counts per cell, and the mean of f / pdf.
    let mut rng = Rng::seeded(seed);
    let mut counts = vec![0u64; RINGS * SECTORS];
    let (mut sum, mut sum_squares, mut drawn) = (0.0f64, 0.0f64, 0u64);
    for _ in 0..SAMPLES {
        let u = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
        let Some((wi, pdf)) = (strategy.sample)(u) else { continue };
        drawn += 1;
        counts[grid.cell(wi)] += 1;
        let w = (strategy.f)(wi) / f64::from(pdf);
        sum += w;
        sum_squares += w * w;
    }
    // (2) Chi-square over the cells, those expecting fewer than 5 pooled.
    let n = SAMPLES as f64;
    let (mut statistic, mut degrees, mut pooled_expected, mut pooled_count) = (0.0, 0.0, 0.0, 0.0);
    for (&e, &c) in expected.iter().zip(&counts) {
        let e = e * n;
        if e < 5.0 {
            pooled_expected += e;
            pooled_count += c as f64;
        } else {
            statistic += (c as f64 - e) * (c as f64 - e) / e;
            degrees += 1.0;
        }
    }
    if pooled_expected > 0.0 {
        let e = pooled_expected.max(5.0);
        statistic += (pooled_count - e) * (pooled_count - e) / e;
        degrees += 1.0;
    }
    let tail = chi_square_tail(statistic, (degrees - 1.0f64).max(1.0));
    // Hundreds of cases run: a threshold of 1e-4 keeps false alarms rare.
    if tail < 1e-4 {
        return Err(format!("chi-square {statistic:.1} over {degrees} cells: p = {tail:.2e} ({drawn} drawn)"));
    }
    // (3) E[f / pdf] is the albedo, the integral of f.
    let albedo: f64 = grid.integrate(strategy.f).iter().sum();
    let mean = sum / n;
    let error = ((sum_squares / n - mean * mean).max(0.0) / n).sqrt();
    if (mean - albedo).abs() > 5.0 * error + 2e-3 * albedo + 1e-6 {
        return Err(format!("the estimate {mean} (standard error {error}) against the albedo {albedo}"));
    }
    Ok(())
}

/// The real BSDF at `sp` with `lobes` as a strategy; calls `run` with it.
fn with_bsdf<R>(sp: &SurfacePoint<'_>, lobes: Lobes, run: impl FnOnce(&Strategy<'_>, &Bsdf) -> R) -> R {
    let bsdf = Bsdf::new(sp);
    let sample = |u| bsdf.sample(u, lobes).map(|s| (s.wi, s.pdf));
    let pdf = |wi| bsdf.pdf(wi, lobes);
    let f = |wi| f64::from(luminance(bsdf.eval(wi, lobes)));
    run(&Strategy { sample: &sample, pdf: &pdf, f: &f }, &bsdf)
}

/// Views from grazing (n.wo = 0.05) to head-on.
fn views() -> [Vec3; 3] {
    [Vec3::new(0.9987, 0.0, 0.05).normalize(), Vec3::new(0.6, 0.0, 0.8), Vec3::Z]
}

fn materials() -> Vec<(String, Material)> {
    let mut list = vec![("lambert 0.7".to_string(), lambert(0.7))];
    for e in [1.0, 10.0, 100.0, 1000.0] {
        list.push((format!("phong e = {e}"), phong(0.4, 0.5, e)));
    }
    list.push(("phong lobe alone, e = 30".into(), phong(0.0, 0.8, 30.0)));
    for roughness in [0.05, 0.1, 0.25, 0.5, 1.0] {
        list.push((format!("white metal, roughness {roughness}"), gltf(Vec3::ONE, 1.0, roughness)));
        list.push((format!("red dielectric, roughness {roughness}"), gltf(Vec3::new(0.8, 0.1, 0.1), 0.0, roughness)));
    }
    list.push(("black dielectric, roughness 0.1".into(), gltf(Vec3::ZERO, 0.0, 0.1)));
    list.push(("half metal, roughness 0.3".into(), gltf(Vec3::new(0.9, 0.6, 0.3), 0.5, 0.3)));
    for (coat, coat_roughness, sheen, sheen_roughness) in
        [(1.0, 0.1, 0.0, 0.0), (0.6, 0.4, 0.0, 0.0), (0.0, 0.0, 0.9, 0.3), (0.0, 0.0, 1.0, 1.0), (1.0, 0.2, 0.7, 0.5)]
    {
        let mut m = gltf(Vec3::new(0.2, 0.4, 0.8), 0.0, 0.5);
        let pbr = m.pbr.as_mut().expect("a pbr material");
        pbr.clearcoat = (coat > 0.0).then_some(crate::scene::material::Clearcoat {
            factor: coat,
            texture: None,
            roughness: coat_roughness,
            roughness_texture: None,
            normal_map: None,
        });
        pbr.sheen = (sheen > 0.0).then_some(crate::scene::material::Sheen {
            colour: Vec3::new(sheen, 0.5 * sheen, 0.2),
            colour_texture: None,
            roughness: sheen_roughness,
            roughness_texture: None,
        });
        list.push((format!("coat {coat} ({coat_roughness}), sheen {sheen} ({sheen_roughness})"), m.clone()));
        if coat == 1.0 && sheen == 0.0 {
            list.push(("a coat tilted from the base's normal".into(), Material { name: "tilted coat".into(), ..m }));
        }
    }
    list
}

#[test]
fn sampling_matches_the_density_and_the_albedo_for_every_material_and_lobe() {
    let mut seed = 0;
    for (name, material) in materials() {
        for wo in views() {
            let sp = point(&material, wo);
            for lobes in [Lobes::ALL, Lobes::DIFFUSE, Lobes::GLOSSY] {
                seed += 1;
                with_bsdf(&sp, lobes, |strategy, bsdf| {
                    // Nothing to sample: nothing drawn, and no density.
                    if bsdf.glossy_probability(lobes).is_none() {
                        assert!((strategy.sample)([0.3, 0.5, 0.7]).is_none(), "{name}: drew from nothing");
                        return;
                    }
                    // The grid about the glossy lobe's axis (r), which also
                    // resolves the cosine lobe.
                    if let Err(e) = check(strategy, sp.r, seed) {
                        panic!("{name}, wo = {wo}, {lobes:?}: {e}");
                    }
                });
            }
        }
    }
}

/// The sampled direction's f cos and density are `eval`'s and `pdf`'s, and
/// directions below the surface (a lobe's tail) carry f cos = 0.
#[test]
fn a_sample_reports_eval_and_pdf_of_its_direction() {
    let mut rng = Rng::seeded(9);
    for (name, material) in materials() {
        let sp = point(&material, views()[1]);
        let bsdf = Bsdf::new(&sp);
        for _ in 0..1000 {
            let u = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
            let Some(s) = bsdf.sample(u, Lobes::ALL) else { continue };
            assert_eq!(s.f_cos, bsdf.eval(s.wi, Lobes::ALL), "{name}");
            assert_eq!(s.pdf, bsdf.pdf(s.wi, Lobes::ALL), "{name}");
            assert!((s.wi.length() - 1.0).abs() < 1e-5);
            if s.wi.z <= 0.0 {
                assert_eq!(s.f_cos, Vec3::ZERO, "{name}: light from below the surface");
            }
        }
    }
}

/// Each check fails on a strategy that is wrong in its way: a density 10%
/// too high everywhere (it integrates to 1.1), directions drawn from a lobe
/// 30% wider than the density says (chi-square), and weights f / pdf from a
/// density 5% too low where the direction is drawn (the estimate is biased
/// while the histogram still matches).
#[test]
fn each_check_catches_a_mutation() {
    let material = gltf(Vec3::new(0.9, 0.8, 0.7), 1.0, 0.3);
    let sp = point(&material, views()[1]);
    let bsdf = Bsdf::new(&sp);
    let wide = {
        let material = gltf(Vec3::new(0.9, 0.8, 0.7), 1.0, 0.3 * 1.14);
        let sp = point(&material, views()[1]);
        Bsdf::new(&sp)
    };
    let lobes = Lobes::ALL;
    let f = |wi| f64::from(luminance(bsdf.eval(wi, lobes)));
    let true_pdf = |wi| bsdf.pdf(wi, lobes);
    let true_sample = |u| bsdf.sample(u, lobes).map(|s| (s.wi, s.pdf));
    let ok = Strategy { sample: &true_sample, pdf: &true_pdf, f: &f };
    assert_eq!(check(&ok, sp.r, 1), Ok(()));
    let high = |wi| 1.1 * bsdf.pdf(wi, lobes);
    let sample_high = |u| bsdf.sample(u, lobes).map(|s| (s.wi, 1.1 * s.pdf));
    let error = check(&Strategy { sample: &sample_high, pdf: &high, f: &f }, sp.r, 1).unwrap_err();
    let integral: f64 = error.trim_start_matches("the density integrates to ").parse().expect(&error);
    assert!((integral - 1.1).abs() < 1e-3, "{error}");
    let sample_wide = |u| wide.sample(u, lobes).map(|s| (s.wi, bsdf.pdf(s.wi, lobes)));
    let error = check(&Strategy { sample: &sample_wide, pdf: &true_pdf, f: &f }, sp.r, 1).unwrap_err();
    assert!(error.contains("chi-square"), "{error}");
    let sample_low = |u| bsdf.sample(u, lobes).map(|s| (s.wi, 0.95 * s.pdf));
    let error = check(&Strategy { sample: &sample_low, pdf: &true_pdf, f: &f }, sp.r, 1).unwrap_err();
    assert!(error.contains("against the albedo"), "{error}");
}

/// The Lambert and Phong samplers' mutations are caught too: cosine-
/// weighted directions traded for uniform ones under the cosine's density,
/// and a Phong lobe drawn with half its exponent.
#[test]
fn the_diffuse_and_phong_checks_catch_a_mutation() {
    let material = phong(0.5, 0.5, 40.0);
    let sp = point(&material, views()[1]);
    let half = phong(0.5, 0.5, 20.0);
    let half_sp = point(&half, views()[1]);
    for (lobes, sampler) in [(Lobes::DIFFUSE, None), (Lobes::GLOSSY, Some(Bsdf::new(&half_sp)))] {
        let bsdf = Bsdf::new(&sp);
        let f = |wi| f64::from(luminance(bsdf.eval(wi, lobes)));
        let pdf = |wi| bsdf.pdf(wi, lobes);
        let wrong = |u: [f32; 3]| {
            let wi = match &sampler {
                // Uniform over the hemisphere: z uniform in [0, 1].
                None => {
                    let (z, phi) = (u[1], 2.0 * PI * u[2]);
                    let r = (1.0 - z * z).max(0.0).sqrt();
                    Vec3::new(r * phi.cos(), r * phi.sin(), z)
                }
                Some(other) => other.sample(u, lobes)?.wi,
            };
            Some((wi, bsdf.pdf(wi, lobes)))
        };
        let error = check(&Strategy { sample: &wrong, pdf: &pdf, f: &f }, sp.r, 2).unwrap_err();
        assert!(error.contains("chi-square"), "{lobes:?}: {error}");
    }
}

/// The lobe's solid angle: Phong's integral of cos^e, GGX's 4 pi alpha^2;
/// none for a diffuse material or a mirror-smooth one.
#[test]
fn the_glossy_lobe_s_solid_angle() {
    let wo = views()[2];
    let solid = |m: &Material| Bsdf::new(&point(m, wo)).glossy_solid_angle();
    assert_eq!(solid(&lambert(0.5)), None);
    assert_eq!(solid(&gltf(Vec3::ONE, 1.0, 0.02)), None, "roughness 0.02 is a mirror");
    let phong = solid(&phong(0.5, 0.5, 99.0)).unwrap();
    assert!((phong - 2.0 * PI / 100.0).abs() < 1e-6);
    let ggx = solid(&gltf(Vec3::ONE, 1.0, 0.1)).unwrap();
    assert!((ggx - 4.0 * PI * 1e-4).abs() < 1e-8, "{ggx}");
}

/// A fibre's BSDF (docs/design.md §5.7) through the same three checks, its
/// lobes over the whole sphere (light from behind included), with a grid
/// about the fibre's axis: light and dark fibres, narrow and wide lobes,
/// views from along the fibre to across it, hits from edge to middle.
#[test]
fn a_fibre_s_sampling_matches_its_density_and_albedo() {
    let material = lambert(0.5);
    let mut seed = 100;
    for (colour, roughness) in [(Vec3::new(0.9, 0.7, 0.5), 0.2), (Vec3::splat(0.1), 0.4), (Vec3::ONE, 0.8)] {
        for wo in [Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.7, 0.0, 0.714).normalize()] {
            for h in [-0.8f32, 0.0, 0.5] {
                seed += 1;
                let x = Vec3::X;
                let across = (wo - x * x.dot(wo)).normalize();
                let normal = glam::Quat::from_axis_angle(x, -h.asin()) * across;
                let mut sp = SurfacePoint::bare(&material, Vec3::ZERO, normal, wo, colour);
                sp.fibre = Fibre::new(x, normal, wo, colour, roughness);
                with_bsdf(&sp, Lobes::ALL, |strategy, _| {
                    if let Err(e) = check(strategy, x, seed) {
                        panic!("fibre {colour} beta {roughness}, wo = {wo}, h = {h}: {e}");
                    }
                });
            }
        }
    }
}
