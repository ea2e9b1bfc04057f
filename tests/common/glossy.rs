//! A glossy unit sphere seen head-on, and what it should look like:
//! glTF's metallic-roughness BRDF (its Appendix B, written out again here
//! in f64) integrated over the sphere of directions by quadrature, never
//! read from the renderer (tests/environment.rs, tests/area_lights.rs).

use std::f64::consts::PI;

use glam::DVec3;

use super::{channel, ExrImage};

/// The film's width and height, pixels.
pub const SIZE: usize = 48;
/// The camera: at (0, 0, 4) looking down -z at the unit sphere.
pub const EYE: DVec3 = DVec3::new(0.0, 0.0, 4.0);
pub const FOV_Y_DEGREES: f64 = 32.0;

/// A metallic-roughness material: roughness, metallic, base colour (grey).
#[derive(Clone, Copy, Debug)]
pub struct Material {
    pub roughness: f64,
    pub metallic: f64,
    pub base: f64,
}

impl Material {
    /// Below alpha = 1e-3 the renderer takes the lobe as a perfect mirror
    /// (docs/design.md §5.6), and so does the quadrature.
    pub fn is_smooth(&self) -> bool {
        self.roughness * self.roughness < 1e-3
    }

    /// f cos(theta_l) of glTF's metallic-roughness BRDF (Appendix B; f0 =
    /// 0.04, f90 = 1, KHR_materials_specular's defaults) for unit `v` and
    /// `l` about the normal +z; the specular lobe alone for a smooth one's
    /// diffuse part (its mirror is added by `mirror`).
    pub fn f_cos(&self, v: DVec3, l: DVec3) -> f64 {
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
    pub fn mirror(&self, mu: f64) -> f64 {
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
    pub fn reflected(&self, v: DVec3, n: DVec3, radiance: &dyn Fn(DVec3) -> f64) -> f64 {
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

/// The sphere's point, normal and view direction seen through the film
/// position (x, y) in pixels (fractional), if the ray hits it.
pub fn sphere_point(x: f64, y: f64) -> Option<(DVec3, DVec3)> {
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
pub fn expected(sub: usize, shade: &(dyn Fn(DVec3, DVec3) -> f64 + Sync)) -> (Vec<f64>, Vec<f64>) {
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
pub fn block_error(image: &ExrImage, want: &[f64], cover: &[f64]) -> (f64, f64) {
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
