//! The environment as one continuous light (docs/design.md §6.2), as
//! pbrt-v4's `ImageInfiniteLight` and Mitsuba 3's `envmap` emitter are:
//! directions drawn in proportion to radiance (luminance) times solid
//! angle, their density per steradian, and the radiance a ray that escapes
//! reads. A constant environment is drawn uniformly over the sphere.
//!
//! A lat-long map's distribution is piecewise constant over its pixels: a
//! pixel is chosen by the cumulative sum of the weights lum(L) x its solid
//! angle (2 pi / w (cos theta_0 - cos theta_1) for a pixel of the row
//! spanning theta_0 to theta_1), then a direction uniform in solid angle
//! within it (phi and cos theta uniform), so the density over the pixel is
//! its probability over its solid angle. The environment's directional
//! lights (`emitters::sample_environment`) are drawn from this same
//! distribution, stratified.

use std::f32::consts::PI;

use glam::Vec3;

use crate::scene::EnvironmentMap;
use crate::util::color::luminance;

/// A direction the environment drew: towards it the radiance, drawn with
/// the density, per steradian.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnvironmentSample {
    pub wi: Vec3,
    pub radiance: Vec3,
    pub pdf: f32,
}

/// How directions are drawn.
#[derive(Debug, Clone)]
enum Distribution {
    /// Uniform over the sphere: a constant environment.
    Uniform,
    /// By pixel: each pixel's weight (luminance x solid angle, f64), their
    /// total, and the normalised cumulative sum in pixel order.
    Pixels { weights: Vec<f64>, total: f64, cdf: Vec<f64> },
}

/// The environment as a light to sample (see the module's comment).
#[derive(Debug, Clone)]
pub struct EnvironmentLight<'s> {
    map: &'s EnvironmentMap,
    distribution: Distribution,
}

impl<'s> EnvironmentLight<'s> {
    /// The light of `map`; None when it emits nothing.
    #[must_use]
    pub fn new(map: &'s EnvironmentMap) -> Option<Self> {
        let distribution = match map {
            EnvironmentMap::Constant(c) => {
                if c.max_element() <= 0.0 {
                    return None;
                }
                Distribution::Uniform
            }
            EnvironmentMap::LatLong { width, height, texels, .. } => {
                let w = *width;
                let weights: Vec<f64> = (0..w * height)
                    .map(|i| f64::from(luminance(texels[i]) * pixel_solid_angle(i / w, w, *height)))
                    .collect();
                let total: f64 = weights.iter().sum();
                if !(total > 0.0 && total.is_finite()) {
                    return None;
                }
                let mut cdf = Vec::with_capacity(weights.len());
                let mut running = 0.0;
                for weight in &weights {
                    running += weight / total;
                    cdf.push(running);
                }
                Distribution::Pixels { weights, total, cdf }
            }
        };
        Some(Self { map, distribution })
    }

    /// The luminance of the radiance averaged over the sphere of
    /// directions, W/(m^2 sr): pi times it is the irradiance a surface
    /// would get from a uniform environment of the same power.
    #[must_use]
    pub fn mean_luminance(&self) -> f32 {
        match (&self.distribution, self.map) {
            (Distribution::Pixels { total, .. }, EnvironmentMap::LatLong { scale, .. }) => {
                (*total / (4.0 * std::f64::consts::PI)) as f32 * scale
            }
            (Distribution::Uniform, EnvironmentMap::Constant(c)) => luminance(*c),
            _ => 0.0,
        }
    }

    /// The radiance arriving from unit direction `wi`, W/(m^2 sr): what a
    /// ray that escapes the scene reads.
    #[must_use]
    pub fn radiance(&self, wi: Vec3) -> Vec3 {
        self.map.radiance(wi)
    }

    /// The pixel a number `u` in [0, 1) falls on in the cumulative sum,
    /// with its probability (a lat-long map only).
    pub(crate) fn pixel(&self, u: f64) -> Option<(usize, f64)> {
        let Distribution::Pixels { weights, total, cdf } = &self.distribution else { return None };
        let pixel = cdf.partition_point(|&c| c < u).min(cdf.len() - 1);
        Some((pixel, weights[pixel] / total))
    }

    /// The direction at `jitter` (two numbers in [0, 1)) within pixel
    /// (x, y) of a `w` x `h` map: uniform in phi and in cos theta, so
    /// uniform in solid angle.
    pub(crate) fn in_pixel(x: usize, y: usize, w: usize, h: usize, jitter: [f32; 2]) -> Vec3 {
        let (c0, c1) = ((PI * y as f32 / h as f32).cos(), (PI * (y + 1) as f32 / h as f32).cos());
        let cos_theta = c0 + (c1 - c0) * jitter[1];
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        let phi = 2.0 * PI * ((x as f32 + jitter[0]) / w as f32 - 0.5);
        Vec3::new(sin_theta * phi.sin(), cos_theta, -sin_theta * phi.cos())
    }

    /// A direction drawn with the numbers `u` (the first chooses the pixel,
    /// the other two the direction within it), with the radiance from it
    /// and its density. None on a pixel of probability 0 (only at u = 0
    /// before a black first pixel).
    #[must_use]
    pub fn sample(&self, u: [f32; 3]) -> Option<EnvironmentSample> {
        match (&self.distribution, self.map) {
            (Distribution::Uniform, _) => {
                let z = 1.0 - 2.0 * u[1];
                let r = (1.0 - z * z).max(0.0).sqrt();
                let phi = 2.0 * PI * u[2];
                let wi = Vec3::new(r * phi.cos(), z, r * phi.sin());
                Some(EnvironmentSample { wi, radiance: self.radiance(wi), pdf: 1.0 / (4.0 * PI) })
            }
            (Distribution::Pixels { .. }, EnvironmentMap::LatLong { width, height, .. }) => {
                let (pixel, probability) = self.pixel(f64::from(u[0]))?;
                let (x, y) = (pixel % width, pixel / width);
                let wi = Self::in_pixel(x, y, *width, *height, [u[1], u[2]]);
                let pdf = (probability / f64::from(pixel_solid_angle(y, *width, *height))) as f32;
                (pdf > 0.0 && pdf.is_finite()).then(|| EnvironmentSample { wi, radiance: self.radiance(wi), pdf })
            }
            (Distribution::Pixels { .. }, EnvironmentMap::Constant(_)) => None,
        }
    }

    /// The density, per steradian, with which `sample` draws unit `wi`.
    #[must_use]
    pub fn pdf(&self, wi: Vec3) -> f32 {
        match (&self.distribution, self.map) {
            (Distribution::Uniform, _) => 1.0 / (4.0 * PI),
            (Distribution::Pixels { weights, total, .. }, EnvironmentMap::LatLong { width, height, .. }) => {
                let (x, y) = EnvironmentMap::pixel_of(*width, *height, wi);
                (weights[y * width + x] / total / f64::from(pixel_solid_angle(y, *width, *height))) as f32
            }
            (Distribution::Pixels { .. }, EnvironmentMap::Constant(_)) => 0.0,
        }
    }
}

/// The solid angle of a pixel of row `y` of a `w` x `h` lat-long map:
/// (2 pi / w) (cos theta_0 - cos theta_1), theta_0 and theta_1 its row's
/// edges from the zenith.
#[must_use]
pub fn pixel_solid_angle(y: usize, w: usize, h: usize) -> f32 {
    let (t0, t1) = (PI * y as f32 / h as f32, PI * (y + 1) as f32 / h as f32);
    2.0 * PI / w as f32 * (t0.cos() - t1.cos())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::util::sampling::Rng;

    /// A 32 x 16 map: dim everywhere, a bright 3 x 2 patch, black rows at
    /// the bottom.
    fn map() -> EnvironmentMap {
        let (w, h) = (32, 16);
        let texels = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                if (10..13).contains(&x) && (4..6).contains(&y) {
                    Vec3::new(50.0, 40.0, 30.0)
                } else if y >= 14 {
                    Vec3::ZERO
                } else {
                    Vec3::new(0.2, 0.3, 0.4)
                }
            })
            .collect();
        EnvironmentMap::LatLong { width: w, height: h, texels, scale: 1.5 }
    }

    /// The density integrates to 1 over the sphere, is 0 exactly where the
    /// map is black, and the draws land in each pixel as often as its
    /// probability says (within 5 standard errors); every draw's density
    /// is `pdf`'s and its radiance the map's.
    #[test]
    fn draws_follow_the_density_and_the_density_integrates_to_one() {
        let map = map();
        let light = EnvironmentLight::new(&map).unwrap();
        let (w, h) = (32usize, 16usize);
        // Midpoint rule in (cos theta, phi): 4 x 4 points per pixel.
        let mut integral = 0.0f64;
        for y in 0..h * 4 {
            for x in 0..w * 4 {
                let d = EnvironmentLight::in_pixel(
                    x / 4,
                    y / 4,
                    w,
                    h,
                    [(x % 4) as f32 / 4.0 + 0.125, (y % 4) as f32 / 4.0 + 0.125],
                );
                let p = f64::from(light.pdf(d));
                if y / 4 >= 14 {
                    assert_eq!(p, 0.0, "a black pixel is never drawn");
                }
                integral += p * f64::from(pixel_solid_angle(y / 4, w, h)) / 16.0;
            }
        }
        assert!((integral - 1.0).abs() < 1e-4, "{integral}");
        let mut rng = Rng::seeded(1);
        let n = 400_000;
        let mut counts = vec![0u32; w * h];
        for _ in 0..n {
            let s = light.sample([rng.next_f32(), rng.next_f32(), rng.next_f32()]).unwrap();
            assert_eq!(s.pdf, light.pdf(s.wi));
            assert_eq!(s.radiance, map.radiance(s.wi));
            let (x, y) = EnvironmentMap::pixel_of(w, h, s.wi);
            counts[y * w + x] += 1;
        }
        for (pixel, &count) in counts.iter().enumerate() {
            let (x, y) = (pixel % w, pixel / w);
            let centre = EnvironmentLight::in_pixel(x, y, w, h, [0.5, 0.5]);
            let p = f64::from(light.pdf(centre)) * f64::from(pixel_solid_angle(y, w, h));
            let expected = p * n as f64;
            let error = (expected * (1.0 - p)).sqrt().max(1.0);
            assert!((f64::from(count) - expected).abs() < 5.0 * error, "pixel ({x}, {y}): {count} vs {expected:.1}");
        }
    }

    /// A constant environment: uniform, 1 / (4 pi), its radiance anywhere;
    /// a black one is no light.
    #[test]
    fn a_constant_environment_is_uniform() {
        let map = EnvironmentMap::Constant(Vec3::new(1.0, 2.0, 3.0));
        let light = EnvironmentLight::new(&map).unwrap();
        let mut rng = Rng::seeded(2);
        let mut mean = Vec3::ZERO;
        for _ in 0..10_000 {
            let s = light.sample([rng.next_f32(), rng.next_f32(), rng.next_f32()]).unwrap();
            assert_eq!((s.pdf, s.radiance), (1.0 / (4.0 * PI), Vec3::new(1.0, 2.0, 3.0)));
            mean += s.wi / 10_000.0;
        }
        assert!(mean.length() < 0.03, "directions spread over the sphere: mean {mean}");
        assert!(EnvironmentLight::new(&EnvironmentMap::Constant(Vec3::ZERO)).is_none());
    }
}
