//! Glossy surfaces under an environment (docs/design.md §6.2), against
//! answers this file computes itself: glTF's BRDF (its Appendix B, written
//! out again here in f64) integrated over the sphere of directions by
//! quadrature, never read from the renderer.

mod common;

use std::f64::consts::PI;

use common::{channel, render, s, ExrImage, TempDir};
use glam::DVec3;

/// The film's width and height, pixels.
const SIZE: usize = 48;
/// The camera: at (0, 0, 4) looking down -z at the unit sphere.
const EYE: DVec3 = DVec3::new(0.0, 0.0, 4.0);
const FOV_Y_DEGREES: f64 = 32.0;

/// A metallic-roughness material: roughness, metallic, base colour (grey).
#[derive(Clone, Copy, Debug)]
struct Material {
    roughness: f64,
    metallic: f64,
    base: f64,
}

impl Material {
    /// Below alpha = 1e-3 the renderer takes the lobe as a perfect mirror
    /// (docs/design.md §5.6), and so does the quadrature.
    fn is_smooth(&self) -> bool {
        self.roughness * self.roughness < 1e-3
    }

    /// f cos(theta_l) of glTF's metallic-roughness BRDF (Appendix B; f0 =
    /// 0.04, f90 = 1, KHR_materials_specular's defaults) for unit `v` and
    /// `l` about the normal +z; the specular lobe alone for a smooth one's
    /// diffuse part (its mirror is added by `mirror`).
    fn f_cos(&self, v: DVec3, l: DVec3) -> f64 {
        if l.z <= 0.0 || v.z <= 0.0 {
            return 0.0;
        }
        let h = (v + l).normalize();
        let w = (1.0 - v.dot(h).clamp(0.0, 1.0)).powi(5);
        let f_dielectric = 0.04 + 0.96 * w;
        let f_metal = self.base + (1.0 - self.base) * w;
        let diffuse = (1.0 - self.metallic) * self.base / PI * (1.0 - f_dielectric) * l.z;
        if self.is_smooth() {
            return diffuse;
        }
        let a2 = (self.roughness * self.roughness).powi(2);
        let sin2 = h.x * h.x + h.y * h.y;
        let d = a2 / (PI * (sin2 + h.z * h.z * a2).powi(2));
        let visibility =
            0.5 / (l.z * (v.z * v.z * (1.0 - a2) + a2).sqrt() + v.z * (l.z * l.z * (1.0 - a2) + a2).sqrt());
        let fresnel = (1.0 - self.metallic) * f_dielectric + self.metallic * f_metal;
        diffuse + fresnel * d * visibility * l.z
    }

    /// A smooth surface's mirror reflectance at n.v = `mu` (the Fresnel
    /// terms at v.h = mu); 0 for a lobe.
    fn mirror(&self, mu: f64) -> f64 {
        if !self.is_smooth() {
            return 0.0;
        }
        let w = (1.0 - mu).powi(5);
        (1.0 - self.metallic) * (0.04 + 0.96 * w) + self.metallic * (self.base + (1.0 - self.base) * w)
    }

    /// The light it reflects towards `v` (world, unit) at a point of
    /// normal `n` under `radiance`: the integral of f cos L over the
    /// sphere, by a grid about the mirror direction that is fine near it
    /// (theta = pi t^2, so a lobe of alpha 2.5e-3 spans dozens of rows),
    /// plus a smooth surface's mirror.
    fn reflected(&self, v: DVec3, n: DVec3, radiance: &dyn Fn(DVec3) -> f64) -> f64 {
        let (t, b) = n.any_orthonormal_pair();
        let local = |d: DVec3| DVec3::new(d.dot(t), d.dot(b), d.dot(n));
        let v_local = local(v);
        let r = (2.0 * v.dot(n) * n - v).normalize();
        let (rt, rb) = r.any_orthonormal_pair();
        let (rows, columns) = (600, 240);
        let mut sum = 0.0;
        for i in 0..rows {
            let u = (f64::from(i) + 0.5) / f64::from(rows);
            let theta = PI * u * u;
            let solid_angle = theta.sin() * 2.0 * PI * u / f64::from(rows) * (2.0 * PI / f64::from(columns));
            for j in 0..columns {
                let phi = (f64::from(j) + 0.5) / f64::from(columns) * 2.0 * PI;
                let l = r * theta.cos() + (rt * phi.cos() + rb * phi.sin()) * theta.sin();
                let f = self.f_cos(v_local, local(l));
                if f > 0.0 {
                    sum += f * radiance(l) * solid_angle;
                }
            }
        }
        sum + self.mirror(v.dot(n)) * radiance(r)
    }
}

/// The scene: the unit sphere of `material` under `environment` (a TOML
/// table's body), seen by the camera above.
fn scene(material: Material, environment: &str) -> String {
    let Material { roughness, metallic, base } = material;
    format!(
        "[film]\nwidth = {SIZE}\nheight = {SIZE}\nspp = 16\n\
         [camera]\neye = [0, 0, 4]\nlook_at = [0, 0, 0]\nfov_y = {FOV_Y_DEGREES}\n\
         [materials.m]\ntype = \"pbr\"\nalbedo = [{base}, {base}, {base}]\nmetallic = {metallic}\nroughness = {roughness}\n\
         [[shapes]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nsegments = 512\nmaterial = \"m\"\n\
         [environment]\n{environment}\n"
    )
}

/// The sphere's point, normal and view direction seen through the film
/// position (x, y) in pixels (fractional), if the ray hits it.
fn sphere_point(x: f64, y: f64) -> Option<(DVec3, DVec3)> {
    let half = (FOV_Y_DEGREES.to_radians() / 2.0).tan();
    let px = (x / SIZE as f64 * 2.0 - 1.0) * half;
    let py = (1.0 - y / SIZE as f64 * 2.0) * half;
    let d = DVec3::new(px, py, -1.0).normalize();
    let b = d.dot(EYE);
    let disc = b * b - (EYE.length_squared() - 1.0);
    (disc > 0.0).then(|| {
        let n = (EYE + d * (-b - disc.sqrt())).normalize();
        (n, -d)
    })
}

/// The expected image, by `shade` (of normal and view direction) at
/// `sub` x `sub` positions per pixel, and the fraction of each pixel the
/// sphere covers.
fn expected(sub: usize, shade: &(dyn Fn(DVec3, DVec3) -> f64 + Sync)) -> (Vec<f64>, Vec<f64>) {
    use rayon::prelude::*;
    let pixels: Vec<(f64, f64)> = (0..SIZE * SIZE)
        .into_par_iter()
        .map(|p| {
            let (x, y) = (p % SIZE, p / SIZE);
            let (mut value, mut cover) = (0.0, 0.0);
            for j in 0..sub {
                for i in 0..sub {
                    let fx = x as f64 + (i as f64 + 0.5) / sub as f64;
                    let fy = y as f64 + (j as f64 + 0.5) / sub as f64;
                    if let Some((n, v)) = sphere_point(fx, fy) {
                        value += shade(n, v);
                        cover += 1.0;
                    }
                }
            }
            let positions = (sub * sub) as f64;
            (value / positions, cover / positions)
        })
        .collect();
    pixels.into_iter().unzip()
}

/// The mean relative error over the 4x4 blocks the sphere covers whole,
/// of the image's mean of R, G, B against `want`; and the ratio of their
/// means.
fn block_error(image: &ExrImage, want: &[f64], cover: &[f64]) -> (f64, f64) {
    let [r, g, b] = ["R", "G", "B"].map(|c| channel(image, c));
    let got = |p: usize| (f64::from(r[p]) + f64::from(g[p]) + f64::from(b[p])) / 3.0;
    let (mut errors, mut got_sum, mut want_sum) = (Vec::new(), 0.0, 0.0);
    for by in 0..SIZE / 4 {
        for bx in 0..SIZE / 4 {
            let block: Vec<usize> = (0..16).map(|k| (by * 4 + k / 4) * SIZE + bx * 4 + k % 4).collect();
            if block.iter().any(|&p| cover[p] < 1.0) {
                continue;
            }
            let g: f64 = block.iter().map(|&p| got(p)).sum();
            let w: f64 = block.iter().map(|&p| want[p]).sum();
            errors.push((g - w).abs() / w);
            got_sum += g;
            want_sum += w;
        }
    }
    assert!(errors.len() > 40, "only {} whole blocks", errors.len());
    (errors.iter().sum::<f64>() / errors.len() as f64, got_sum / want_sum)
}

/// The white furnace: under a constant environment of radiance 1 a sphere
/// reflects, towards each view, its BRDF's directional albedo. White
/// metals from roughness 0.02 (a mirror) to 1 and a black dielectric
/// (glTF's 4% Fresnel layer alone), in the default mode: within 1% over
/// 4x4 blocks at 64 spp (the stochastic cut) and 3% at 16 (the bounded
/// one). The environment's 1,024 lights showed as specks here (54% at
/// roughness 0.1) before its sharp lobes were sampled.
#[test]
fn white_furnace_in_the_default_mode() {
    let dir = TempDir::new("furnace");
    let mut failures = Vec::new();
    for (metallic, base) in [(1.0, 1.0), (0.0, 0.0)] {
        for roughness in [0.02, 0.05, 0.1, 0.25, 0.5, 0.7, 1.0] {
            let material = Material { roughness, metallic, base };
            // The albedo is a function of n.v alone: tabulated, then
            // interpolated (finest towards grazing views).
            let steps = 64;
            let mus: Vec<f64> =
                (0..=steps).map(|i| 1e-3 + (1.0 - 1e-3) * (f64::from(i) / f64::from(steps)).sqrt()).collect();
            let albedo: Vec<f64> = {
                use rayon::prelude::*;
                mus.par_iter()
                    .map(|&mu| {
                        let v = DVec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
                        material.reflected(v, DVec3::Z, &|_| 1.0)
                    })
                    .collect()
            };
            let at = |mu: f64| {
                let k = mus.partition_point(|&m| m < mu).clamp(1, mus.len() - 1);
                let t = ((mu - mus[k - 1]) / (mus[k] - mus[k - 1])).clamp(0.0, 1.0);
                albedo[k - 1] + t * (albedo[k] - albedo[k - 1])
            };
            let (want, cover) = expected(8, &|n, v| at(n.dot(v).clamp(1e-3, 1.0)));
            let file = dir.write("furnace.toml", &scene(material, "radiance = [1, 1, 1]\nsamples = 1024"));
            for (spp, tolerance) in [("64", 0.01), ("16", 0.03)] {
                let out = dir.path("furnace.exr");
                let image = render(&file, &out, &["--spp", spp]);
                let (error, ratio) = block_error(&image, &want, &cover);
                eprintln!("{material:?} at {spp} spp: mean block error {:.2}%, ratio {ratio:.4}", 100.0 * error);
                if error > tolerance {
                    failures.push(format!("{material:?} at {spp} spp: {:.2}%", 100.0 * error));
                }
            }
        }
    }
    assert!(failures.is_empty(), "the furnace is off: {failures:?}");
}

/// An HDR environment, dim but for one bright patch, reflected by glossy
/// metal spheres: one whose lobe is sharper than the environment's lights
/// (sampled) and one broad enough that they light it where the patch is
/// (and the dim rest is sampled); both match the integral of the same map
/// by quadrature, in every mode, with no seam between the two ways.
#[test]
fn a_bright_patch_in_glossy_reflections() {
    let dir = TempDir::new("patch");
    let (width, height) = (32_usize, 16_usize);
    // The patch: 4 x 2 pixels about the direction (0.5, 0.4, 1), which the
    // sphere's upper right reflects towards the camera.
    let texel = |x: usize, y: usize| if (28..32).contains(&x) && (5..7).contains(&y) { 40.0 } else { 0.25 };
    let map = dir.path("patch.exr");
    exr::prelude::write_rgb_file(&map, width, height, |x, y| {
        let l = texel(x, y) as f32;
        (l, l, l)
    })
    .unwrap();
    // The map's radiance as the scene format defines its lat-long
    // mapping (docs/scene-format.md): nearest pixel.
    let radiance = |d: DVec3| {
        let u = 0.5 + d.x.atan2(-d.z) / (2.0 * PI);
        let v = d.y.clamp(-1.0, 1.0).acos() / PI;
        let x = ((u * width as f64) as usize) % width;
        let y = ((v * height as f64) as usize).min(height - 1);
        texel(x, y)
    };
    let mut failures = Vec::new();
    for roughness in [0.15, 0.4] {
        let material = Material { roughness, metallic: 1.0, base: 1.0 };
        let (want, cover) = expected(2, &|n, v| material.reflected(v, n, &radiance));
        let environment = format!("file = \"{}\"\nsamples = 1024", s(&map));
        let file = dir.write("patch.toml", &scene(material, &environment));
        for (flags, tolerance) in [
            (&["--spp", "64"][..], 0.02),
            (&["--spp", "16"][..], 0.04),
            (&["--spp", "16", "--exact"][..], 0.04),
            (&["--spp", "16", "--multidimensional"][..], 0.04),
        ] {
            let out = dir.path("render.exr");
            let image = render(&file, &out, flags);
            let (error, ratio) = block_error(&image, &want, &cover);
            eprintln!("roughness {roughness} {flags:?}: mean block error {:.2}%, ratio {ratio:.4}", 100.0 * error);
            if error > tolerance {
                failures.push(format!("roughness {roughness} {flags:?}: {:.2}%", 100.0 * error));
            }
        }
    }
    assert!(failures.is_empty(), "the reflection is off: {failures:?}");
}

/// Renders `scene` with each of `flags` and compares its luminance with
/// a peer's converged render `reference` (both under scenes/environment/):
/// the mean within 1% and the 8x8 blocks within 2% on average, over the
/// whole image and again over the objects alone (the blocks they cover
/// whole, by the render's depth: the background alone is easy to match).
fn matches_peer(name: &str, scene: &str, reference: &str, flags: &[&[&str]]) {
    let dir = TempDir::new(name);
    let scene = common::scenes().join("environment").join(scene);
    let reference = common::read_exr(&common::scenes().join("environment").join(reference)).unwrap();
    let luminance = |image: &ExrImage| -> Vec<f64> {
        let [r, g, b] = ["R", "G", "B"].map(|c| channel(image, c));
        (0..r.len()).map(|p| 0.2126 * f64::from(r[p]) + 0.7152 * f64::from(g[p]) + 0.0722 * f64::from(b[p])).collect()
    };
    let want = luminance(&reference);
    let (width, height) = (reference.width, reference.height);
    let blocks = |values: &[f64]| -> Vec<f64> {
        let mut sums = vec![0.0; (width / 8) * (height / 8)];
        for y in 0..height / 8 * 8 {
            for x in 0..width / 8 * 8 {
                sums[(y / 8) * (width / 8) + x / 8] += values[y * width + x];
            }
        }
        sums
    };
    let mut failures = Vec::new();
    for &flags in flags {
        let image = render(&scene, &dir.path("render.exr"), flags);
        assert_eq!((image.width, image.height), (width, height));
        let got = luminance(&image);
        let object: Vec<f64> = channel(&image, "Z").iter().map(|&z| f64::from(u8::from(z < 1e9))).collect();
        let covered: Vec<bool> = blocks(&object).iter().map(|&n| n == 64.0).collect();
        let on_objects = |values: &[f64]| -> f64 { values.iter().zip(&object).map(|(v, o)| v * o).sum() };
        let (g, w) = (blocks(&got), blocks(&want));
        let block_error = |keep: &dyn Fn(usize) -> bool| {
            let errors: Vec<f64> = (0..w.len()).filter(|&k| keep(k)).map(|k| (g[k] - w[k]).abs() / w[k]).collect();
            assert!(errors.len() >= 30, "only {} blocks to compare", errors.len());
            errors.iter().sum::<f64>() / errors.len() as f64
        };
        for (part, ratio, blocks) in [
            ("image", got.iter().sum::<f64>() / want.iter().sum::<f64>(), block_error(&|_| true)),
            ("objects", on_objects(&got) / on_objects(&want), block_error(&|k| covered[k])),
        ] {
            eprintln!("{name} {flags:?}, {part}: mean ratio {ratio:.4}, mean 8x8 block error {:.2}%", 100.0 * blocks);
            if (ratio - 1.0).abs() > 0.01 || blocks > 0.02 {
                failures.push(format!("{flags:?}, {part}: ratio {ratio:.4}, blocks {:.2}%", 100.0 * blocks));
            }
        }
    }
    assert!(failures.is_empty(), "{name} is off from its peer: {failures:?}");
}

/// Against a peer: Mitsuba 3's path tracer with max_depth 2 (direct light
/// only, as here) at 16,384 spp, on three white metals (roughness 0.1,
/// 0.25, 0.45) and a diffuse floor under a real HDR environment (Blender's
/// courtyard, CC0): scenes/environment/, with the script that rendered the
/// reference and how the two scenes correspond; at 64 spp in the default
/// mode and 128 in the bounded one.
#[test]
fn glossy_spheres_under_an_hdr_environment_match_mitsuba() {
    let flags: &[&[&str]] = &[&["--spp", "64"], &["--spp", "128", "--bounded"]];
    matches_peer("mitsuba", "spheres.toml", "mitsuba-16384.exr", flags);
}

/// Against Cycles (Blender 5.0.1, 4,096 spp, direct light only, box
/// filter) on a real asset Blender exported: the Khronos Water Bottle (its
/// metal body glossy, CC0) under the courtyard HDRI
/// (scenes/environment/make_cycles.py); at 128 spp in the default mode and
/// in the bounded one.
#[test]
fn the_water_bottle_under_an_hdr_environment_matches_cycles() {
    let flags: &[&[&str]] = &[&["--spp", "128"], &["--spp", "128", "--bounded"]];
    matches_peer("cycles", "water_bottle.toml", "water_bottle/cycles_4096.exr", flags);
}
