//! Emitters turned into point lights ([LC05]; docs/design.md §6): area
//! lights into oriented lights, environments and the sun into directional
//! lights. Stratified and deterministic for a seed.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use super::environment::{pixel_solid_angle, EnvironmentLight};
use super::{fold, AreaLight, DirectionalLight};
use crate::scene::EnvironmentMap;
use crate::util::color::luminance;
use crate::util::sampling::Rng;

/// `n` stratified points on the unit square, one jittered point per cell of
/// equal area 1/n that together tile the square: ceil(sqrt n) rows, each of
/// as many equal cells as it holds points (the last row may hold fewer),
/// each row as tall as its share of the points. (A full n_u x n_v grid cut
/// at n points left its last cells empty: a triangle's few points, folded,
/// missed the corner at its first vertex, the centre of a fan-triangulated
/// disk, whose light came out 2.8% short with 5 points a triangle.)
fn stratified_square(n: usize, rng: &mut Rng) -> Vec<Vec2> {
    let columns = (n as f64).sqrt().ceil().max(1.0) as usize;
    let rows = n.div_ceil(columns);
    let mut points = Vec::with_capacity(n);
    let mut bottom = 0.0f32;
    for j in 0..rows {
        let cells = columns.min(n - j * columns);
        let height = cells as f32 / n as f32;
        for i in 0..cells {
            let u = (i as f32 + rng.next_f32()) / cells as f32;
            let v = bottom + height * rng.next_f32();
            points.push(Vec2::new(u, v.min(1.0)));
        }
        bottom += height;
    }
    points
}

/// One emitting triangle of an area light.
#[derive(Debug, Clone, Copy)]
pub struct EmitterTriangle {
    pub p: [Vec3; 3],
}

impl EmitterTriangle {
    #[must_use]
    pub fn area(&self) -> f32 {
        crate::util::triangle::area(self.p) as f32
    }

    /// The point at barycentric coordinates (a, b): p0 + a (p1 - p0) + b (p2 - p0).
    #[must_use]
    pub fn point(&self, ab: Vec2) -> Vec3 {
        self.p[0] + ab.x * (self.p[1] - self.p[0]) + ab.y * (self.p[2] - self.p[0])
    }

    /// Unit normal by the winding (p1 - p0) x (p2 - p0): the emitting side.
    #[must_use]
    pub fn normal(&self) -> Vec3 {
        crate::util::triangle::normal(self.p)
    }
}

/// `count` shared among `n` triangles in proportion to `weight` of each
/// (summing to `total`): largest-remainder apportionment, in order (each
/// triangle gets the rounded running total less what went before; the last
/// what is left).
fn shares(n: usize, weight: impl Fn(usize) -> f64, total: f64, count: usize) -> Vec<usize> {
    let mut assigned = 0usize;
    let mut cumulative = 0.0f64;
    (0..n)
        .map(|k| {
            cumulative += weight(k);
            let until = if k + 1 == n { count } else { ((cumulative / total) * count as f64).round() as usize };
            let share = until.saturating_sub(assigned);
            assigned += share;
            share
        })
        .collect()
}

/// `count` points on `triangles`, spread in proportion to `weight` of
/// each triangle (summing to `total`; [`shares`]) and stratified in each:
/// the triangle's index and the point's barycentric coordinates (a, b),
/// p = p0 + a (p1 - p0) + b (p2 - p0).
fn points_by(
    triangles: &[EmitterTriangle],
    weight: impl Fn(usize) -> f64,
    total: f64,
    count: usize,
    rng: &mut Rng,
) -> Vec<(usize, Vec2)> {
    let mut points = Vec::with_capacity(count);
    for (k, share) in shares(triangles.len(), weight, total, count).into_iter().enumerate() {
        for uv in stratified_square(share, rng) {
            let (a, b) = fold([uv.x, uv.y]);
            points.push((k, Vec2::new(a, b)));
        }
    }
    points
}

/// `count` points spread over `triangles` (of total area `total`) in
/// proportion to area: [`points_by`] with each triangle's area.
fn points_by_area(triangles: &[EmitterTriangle], total: f64, count: usize, rng: &mut Rng) -> Vec<(usize, Vec2)> {
    points_by(triangles, |k| f64::from(triangles[k].area()), total, count, rng)
}

fn total_area(triangles: &[EmitterTriangle]) -> f64 {
    triangles.iter().map(|t| f64::from(t.area())).sum()
}

/// An area light of radiance `radiance` (W/(m^2 sr)) emitting from the front
/// of its triangles, as about `samples` triangle lights (docs/design.md
/// §6.1): each triangle gets its share of `samples` by area (largest
/// remainder, in order, at least one) and is split into n x n equal
/// triangles, n the nearest integer to the square root of its share; each
/// part is a light of intensity Le * its area along its normal (a
/// Lambertian emitter's I(theta) = Le A cos(theta)) that shines from a
/// point drawn uniformly on it per shading point. `offset` lifts the parts
/// off the surface so shadow rays do not start inside it.
#[must_use]
pub fn sample_area_light(triangles: &[EmitterTriangle], radiance: Vec3, samples: usize, offset: f32) -> Vec<AreaLight> {
    let total = total_area(triangles);
    if total <= 0.0 || samples == 0 {
        return Vec::new();
    }
    let mut lights = Vec::with_capacity(samples.max(triangles.len()));
    let shares = shares(triangles.len(), |k| f64::from(triangles[k].area()), total, samples);
    for (t, share) in triangles.iter().zip(shares) {
        if t.area() <= 0.0 {
            continue;
        }
        let n = ((share as f64).sqrt().round() as usize).max(1);
        let normal = t.normal();
        let edges = [(t.p[1] - t.p[0]) / n as f32, (t.p[2] - t.p[0]) / n as f32];
        let intensity = radiance * (t.area() / (n * n) as f32);
        // The parts of a regular subdivision: at (i, j) the upright one,
        // corners (i, j), (i + 1, j), (i, j + 1) in units of the edges, and
        // below the far edge the inverted one beside it.
        for i in 0..n {
            for j in 0..n - i {
                let corner = t.p[0] + i as f32 * edges[0] + j as f32 * edges[1];
                let upright = corner + (edges[0] + edges[1]) / 3.0;
                lights.push(AreaLight { position: upright + normal * offset, normal, intensity, edges });
                if i + j + 1 < n {
                    let far = corner + edges[0] + edges[1];
                    let inverted = far - (edges[0] + edges[1]) / 3.0;
                    let flipped = [-edges[0], -edges[1]];
                    lights.push(AreaLight { position: inverted + normal * offset, normal, intensity, edges: flipped });
                }
            }
        }
    }
    lights
}

/// Emitting candidate points a textured emitter's samples are drawn from,
/// per sample: the draw places samples in proportion to the emitted power
/// of 16 times as many points.
const CANDIDATES_PER_SAMPLE: usize = 16;
/// Fewest candidates: they measure where and how much the emitter emits
/// (a patch's stratified area is off by its boundary's cells: the unit
/// test's patch, 5% of a quad, came out 28% off at 256 candidates, within
/// 0.5% at 16,384).
const MIN_CANDIDATES: usize = 1 << 14;
/// Most candidate points of one textured emitter (memory: 24 bytes each
/// that emits; time: one texture lookup each).
const MAX_CANDIDATES: usize = 1 << 20;

/// An area light whose radiance varies over its surface (an emissive
/// texture): `radiance_at(triangle, (a, b))` W/(m^2 sr) at barycentric
/// coordinates (a, b), as at most `samples` oriented lights placed in
/// proportion to emitted power (docs/design.md §6.1).
///
/// A first pass measures where the surface emits: points spread by area
/// (and every triangle's centroid) give each triangle's luminous power,
/// area times their mean luminance. Candidates are then spread over the
/// triangles in proportion to that power, uniform by area within each,
/// each standing for its triangle's area over its count (a_k), with its
/// own radiance; they grow (x4, up to [`MAX_CANDIDATES`]) until
/// `CANDIDATES_PER_SAMPLE` per sample carry the power, counted as the
/// effective sample size (sum w)^2 / sum w^2 of their weights w_k =
/// lum(Le_k) a_k. `samples` candidates are drawn with probability w_k / Phi
/// (Phi = sum w), stratified in the cumulative sum, and each drawn point
/// carries its own radiance: intensity Le_k a_k / (N w_k / Phi) = Le_k Phi
/// / (N lum(Le_k)), the same luminous share for every sample, whose
/// expectation over the draw is the candidates' total. A point drawn twice
/// is one light of twice the intensity. A triangle where no first-pass
/// point emits is taken as dark.
#[must_use]
pub fn sample_textured_area_light(
    triangles: &[EmitterTriangle],
    radiance_at: impl Fn(usize, Vec2) -> Vec3,
    samples: usize,
    offset: f32,
    seed: u64,
) -> Vec<AreaLight> {
    let total = total_area(triangles);
    if total <= 0.0 || samples == 0 {
        return Vec::new();
    }
    let lum = |le: Vec3| if le.is_finite() { f64::from(luminance(le)).max(0.0) } else { 0.0 };
    let mut rng = Rng::from_key(&[seed, 0x7e71]);
    let wanted = CANDIDATES_PER_SAMPLE.saturating_mul(samples).max(MIN_CANDIDATES);
    let limit = MAX_CANDIDATES.max(samples);
    // First pass: each triangle's luminous power, area x mean luminance.
    let mut seen = vec![(0.0f64, 0usize); triangles.len()];
    let centroids = (0..triangles.len()).map(|k| (k, Vec2::splat(1.0 / 3.0)));
    for (k, ab) in points_by_area(triangles, total, wanted.min(limit), &mut rng).into_iter().chain(centroids) {
        seen[k].0 += lum(radiance_at(k, ab));
        seen[k].1 += 1;
    }
    let power: Vec<f64> =
        seen.iter().zip(triangles).map(|(&(sum, n), t)| f64::from(t.area()) * sum / n as f64).collect();
    let total_power: f64 = power.iter().sum();
    if total_power <= 0.0 {
        return Vec::new();
    }
    // Candidates by power: (triangle, barycentrics, radiance, weight).
    let mut count = wanted.min(limit);
    let candidates = loop {
        let points = points_by(triangles, |k| power[k], total_power, count, &mut rng);
        let mut per_triangle = vec![0usize; triangles.len()];
        for &(k, _) in &points {
            per_triangle[k] += 1;
        }
        let candidates: Vec<(usize, Vec2, Vec3, f64)> = points
            .into_iter()
            .filter_map(|(k, ab)| {
                let le = radiance_at(k, ab);
                let w = lum(le) * f64::from(triangles[k].area()) / per_triangle[k] as f64;
                (w > 0.0).then_some((k, ab, le, w))
            })
            .collect();
        let (sum, sum_squares) = candidates.iter().fold((0.0f64, 0.0f64), |(s, q), c| (s + c.3, q + c.3 * c.3));
        if sum * sum >= wanted as f64 * sum_squares || count >= limit {
            break candidates;
        }
        count = count.saturating_mul(4).min(limit);
    };
    let phi: f64 = candidates.iter().map(|c| c.3).sum();
    if phi <= 0.0 {
        return Vec::new();
    }
    let mut lights: Vec<AreaLight> = Vec::with_capacity(samples);
    let mut running = 0.0f64;
    let mut next = 0usize;
    let mut last = usize::MAX;
    for j in 0..samples {
        let u = (j as f64 + f64::from(rng.next_f32())) / samples as f64 * phi;
        while next + 1 < candidates.len() && running + candidates[next].3 < u {
            running += candidates[next].3;
            next += 1;
        }
        let (k, ab, le, _) = candidates[next];
        let intensity = le * (phi / (samples as f64 * lum(le))) as f32;
        if next == last {
            lights.last_mut().expect("a light was drawn").intensity += intensity;
        } else {
            let t = &triangles[k];
            let normal = t.normal();
            lights.push(AreaLight {
                position: t.point(ab) + normal * offset,
                normal,
                intensity,
                edges: [Vec3::ZERO; 2],
            });
            last = next;
        }
    }
    lights
}

/// The sun: `irradiance` (W/m^2 on a surface facing it) from unit
/// `direction` (towards the sun); with an angular radius, `samples`
/// directions spread uniformly over the disc's solid angle share it.
#[must_use]
pub fn sample_sun(
    direction: Vec3,
    irradiance: Vec3,
    angular_radius_degrees: f32,
    samples: usize,
    seed: u64,
) -> Vec<DirectionalLight> {
    let d = direction.normalize();
    if angular_radius_degrees <= 0.0 || samples <= 1 {
        return vec![DirectionalLight { direction: d, irradiance }];
    }
    let cos_max = angular_radius_degrees.to_radians().cos();
    let (t, b) = d.any_orthonormal_pair();
    let mut rng = Rng::from_key(&[seed, 0x5a5]);
    stratified_square(samples, &mut rng)
        .into_iter()
        .map(|uv| {
            let cos_theta = 1.0 - uv.x * (1.0 - cos_max);
            let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
            let phi = 2.0 * PI * uv.y;
            let dir = (d * cos_theta + t * (sin_theta * phi.cos()) + b * (sin_theta * phi.sin())).normalize();
            DirectionalLight { direction: dir, irradiance: irradiance / samples as f32 }
        })
        .collect()
}

/// The environment as `samples` directional lights: stratified importance
/// sampling on luminance times each pixel's solid angle, each with
/// irradiance L(w) / (samples * pdf(w)), so their sum estimates the
/// environment's illumination (docs/design.md §6.2).
#[must_use]
pub fn sample_environment(map: &EnvironmentMap, samples: usize, seed: u64) -> Vec<DirectionalLight> {
    if samples == 0 {
        return Vec::new();
    }
    let mut rng = Rng::from_key(&[seed, 0xe4f]);
    match map {
        EnvironmentMap::Constant(c) => {
            // Uniform on the sphere, stratified in (cos theta, phi).
            stratified_square(samples, &mut rng)
                .into_iter()
                .map(|uv| {
                    let z = 1.0 - 2.0 * uv.x;
                    let r = (1.0 - z * z).max(0.0).sqrt();
                    let phi = 2.0 * PI * uv.y;
                    let direction = Vec3::new(r * phi.cos(), z, r * phi.sin());
                    DirectionalLight { direction, irradiance: *c * (4.0 * PI / samples as f32) }
                })
                .filter(|l| l.irradiance.max_element() > 0.0)
                .collect()
        }
        EnvironmentMap::LatLong { width, height, texels, scale } => {
            let (w, h) = (*width, *height);
            // The continuous light's distribution: luminance x solid angle.
            let Some(light) = EnvironmentLight::new(map) else { return Vec::new() };
            let mut lights = Vec::with_capacity(samples);
            for k in 0..samples {
                // Stratified in the CDF: sample k in [k, k+1) / samples.
                // The position inside the pixel is independent of k (a
                // jitter correlated with k biases it, as the CDF runs down
                // the rows).
                let jitter = [rng.next_f32(), rng.next_f32()];
                let u = (k as f64 + f64::from(rng.next_f32())) / samples as f64;
                let Some((pixel, probability)) = light.pixel(u) else { break };
                let (x, y) = (pixel % w, pixel / w);
                // Uniform in solid angle within the pixel: uniform in
                // phi and in cos(theta), so the pdf is constant there.
                let direction = EnvironmentLight::in_pixel(x, y, w, h, jitter);
                let pdf = probability as f32 / pixel_solid_angle(y, w, h);
                let radiance = texels[pixel] * *scale;
                lights.push(DirectionalLight { direction, irradiance: radiance / (samples as f32 * pdf) });
            }
            lights
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every count tiles the whole square at equal density: each quarter
    /// of the square holds its share of the points (within one cell's
    /// worth), and the corner the old grid left empty is covered.
    #[test]
    fn stratified_points_cover_the_square_for_any_count() {
        let mut rng = Rng::from_key(&[7]);
        for n in [1usize, 2, 3, 5, 7, 10, 17, 100, 250, 256] {
            let points = stratified_square(n, &mut rng);
            assert_eq!(points.len(), n);
            assert!(points.iter().all(|p| (0.0..=1.0).contains(&p.x) && (0.0..=1.0).contains(&p.y)));
            for (lo, hi) in [(Vec2::ZERO, Vec2::splat(0.5)), (Vec2::splat(0.5), Vec2::ONE)] {
                let inside = points.iter().filter(|p| p.x >= lo.x && p.x < hi.x && p.y >= lo.y && p.y < hi.y).count();
                let share = n as f64 / 4.0;
                // A cell straddling the quarter's edges counts on either side.
                let slack = 2.0 * (n as f64).sqrt() + 1.0;
                assert!((inside as f64 - share).abs() <= slack, "n {n}: {inside} points in {lo}..{hi}, share {share}");
            }
        }
        // Five points: a row of three cells 0.6 high, then one of two cells
        // 0.4 high, so the top right cell [0.5, 1] x [0.6, 1] holds one (the
        // old 3 x 2 grid left [2/3, 1] x [1/2, 1] empty).
        for _ in 0..20 {
            let points = stratified_square(5, &mut rng);
            assert_eq!(points.iter().filter(|p| p.x > 0.5 && p.y > 0.6).count(), 1, "{points:?}");
        }
    }

    #[test]
    fn area_light_triangles_tile_the_emitter_and_carry_its_power() {
        // A 2 x 3 quad as two triangles, radiance (1, 2, 3): power pi Le A.
        let quad = [
            EmitterTriangle { p: [Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), Vec3::new(2.0, 0.0, 3.0)] },
            EmitterTriangle { p: [Vec3::ZERO, Vec3::new(2.0, 0.0, 3.0), Vec3::new(0.0, 0.0, 3.0)] },
        ];
        let le = Vec3::new(1.0, 2.0, 3.0);
        // Shares 1, 4, 500 and 2048 per triangle: 1, 4, 484 and 2025 parts.
        for (samples, parts) in [(1, 2), (7, 8), (1000, 968), (4096, 4050)] {
            let lights = sample_area_light(&quad, le, samples, 0.0);
            assert_eq!(lights.len(), parts, "{samples} samples");
            // Each part radiates pi * I in all (cosine lobe).
            let power: Vec3 = lights.iter().map(|l| PI * l.intensity).sum();
            let expected = PI * le * 6.0;
            assert!((power - expected).abs().max_element() <= 1e-4 * expected.max_element(), "{power} vs {expected}");
            let area: f32 = lights.iter().map(|l| 0.5 * l.edges[0].cross(l.edges[1]).length()).sum();
            assert!((area - 6.0).abs() < 1e-3, "the parts' areas sum to the quad's: {area}");
            for l in &lights {
                for c in l.corners() {
                    assert!(c.x >= -1e-5 && c.x <= 2.0 + 1e-5 && c.z >= -1e-5 && c.z <= 3.0 + 1e-5, "{c}");
                }
                assert!((l.normal - Vec3::new(0.0, -1.0, 0.0)).length() < 1e-6, "winding gives the normal");
            }
        }
        // The parts tile the quad: points uniform over it fall in exactly
        // one part each (strictly inside one, away from the shared edges).
        let lights = sample_area_light(&quad, le, 50, 0.0);
        let mut rng = Rng::from_key(&[12]);
        let mut hits = vec![0usize; lights.len()];
        for _ in 0..20_000 {
            let p = Vec3::new(2.0 * rng.next_f32(), 0.0, 3.0 * rng.next_f32());
            let inside: Vec<usize> = (0..lights.len())
                .filter(|&i| {
                    let [a, b, c] = lights[i].corners();
                    let side = |u: Vec3, v: Vec3| (v - u).cross(p - u).y;
                    let s = [side(a, b), side(b, c), side(c, a)];
                    s.iter().all(|&x| x > 1e-4) || s.iter().all(|&x| x < -1e-4)
                })
                .collect();
            assert!(inside.len() <= 1, "{p} in {inside:?}");
            if let [i] = inside[..] {
                hits[i] += 1;
            }
        }
        // Equal parts of each triangle get equal shares of the points.
        let expected = 20_000.0 / lights.len() as f64;
        for h in hits {
            assert!((h as f64 - expected).abs() < 0.25 * expected, "{h} against {expected}");
        }
        // A point drawn on a part lies on it.
        for l in &lights {
            let p = l.point_at([0.9, 0.7]);
            let [a, b, c] = l.corners();
            let area = |u: Vec3, v: Vec3, w: Vec3| 0.5 * (v - u).cross(w - u).length();
            assert!((area(p, a, b) + area(p, b, c) + area(p, c, a) - area(a, b, c)).abs() < 1e-4);
        }
    }

    /// Radiance bright only on a small patch (a < 0.05 on the first
    /// triangle, 5% of the quad's area) or varying smoothly in colour:
    /// the samples land where the power is, each carries its point's
    /// colour, and their power is the emitter's.
    #[test]
    fn textured_area_light_samples_follow_emitted_power() {
        let quad = [
            EmitterTriangle { p: [Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), Vec3::new(2.0, 0.0, 3.0)] },
            EmitterTriangle { p: [Vec3::ZERO, Vec3::new(2.0, 0.0, 3.0), Vec3::new(0.0, 0.0, 3.0)] },
        ];
        let patch = |k: usize, ab: Vec2| if k == 0 && ab.x < 0.05 { Vec3::new(8.0, 4.0, 2.0) } else { Vec3::ZERO };
        // The patch's area: the first triangle (3 m^2) where a < 0.05.
        let patch_area = 3.0 * (1.0 - 0.95f32 * 0.95);
        for samples in [1, 64, 1000] {
            let lights = sample_textured_area_light(&quad, patch, samples, 0.0, 5);
            assert!(lights.len() <= samples && lights.len() >= samples * 9 / 10, "{} of {samples}", lights.len());
            let power: Vec3 = lights.iter().map(|l| PI * l.intensity).sum();
            let expected = PI * Vec3::new(8.0, 4.0, 2.0) * patch_area;
            let tolerance = 0.005;
            assert!(
                (power - expected).abs().max_element() <= tolerance * expected.max_element(),
                "{power} vs {expected}"
            );
            for l in &lights {
                // On the patch: the first triangle's points with a < 0.05
                // lie within x <= 2 and z <= 3 x / 2 of its edge a = 0.
                let t = &quad[0];
                let b = l.position.z / 3.0;
                let a = l.position.x / 2.0 - b;
                assert!((-1e-5..0.05 + 1e-5).contains(&a) && t.normal() == l.normal, "{}", l.position);
                assert!((l.intensity / l.intensity.x - Vec3::new(1.0, 0.5, 0.25)).abs().max_element() < 1e-6);
            }
        }
        // A colour that varies: each light's chroma is its point's.
        let gradient = |k: usize, ab: Vec2| Vec3::new(1.0 + ab.x, 1.0, 1.0 + k as f32);
        let lights = sample_textured_area_light(&quad, gradient, 4096, 0.0, 6);
        assert!(lights.len() > 4000);
        for l in &lights {
            let first = l.position.x / 2.0 >= l.position.z / 3.0 - 1e-5;
            let blue_over_green = l.intensity.z / l.intensity.y;
            assert!(
                (blue_over_green - if first { 1.0 } else { 2.0 }).abs() < 1e-4
                    || l.position.x / 2.0 - l.position.z / 3.0 < 1e-4
            );
        }
        // The green channel is constant: its power is pi L A exactly, up
        // to the candidates' stratification.
        let green: f32 = lights.iter().map(|l| PI * l.intensity.y).sum();
        assert!((green - PI * 6.0).abs() < 0.01 * PI * 6.0, "{green}");
        // Deterministic for a seed; nothing where nothing emits.
        assert_eq!(
            sample_textured_area_light(&quad, patch, 50, 0.0, 3),
            sample_textured_area_light(&quad, patch, 50, 0.0, 3)
        );
        assert!(sample_textured_area_light(&quad, |_, _| Vec3::ZERO, 50, 0.0, 3).is_empty());
    }

    #[test]
    fn a_constant_environment_gives_pi_l_irradiance() {
        let l = Vec3::new(0.5, 1.0, 2.0);
        let lights = sample_environment(&EnvironmentMap::Constant(l), 4096, 1);
        for n in [Vec3::Y, Vec3::X, Vec3::new(1.0, 1.0, -1.0).normalize()] {
            let e: Vec3 = lights.iter().map(|d| d.irradiance * d.direction.dot(n).max(0.0)).sum();
            let expected = PI * l;
            assert!(
                (e - expected).abs().max_element() <= 0.01 * expected.max_element(),
                "{e} vs {expected} for n = {n}"
            );
        }
    }

    #[test]
    fn a_constant_lat_long_map_gives_pi_l_too_and_sampling_follows_brightness() {
        let (w, h) = (64, 32);
        let map = EnvironmentMap::LatLong { width: w, height: h, texels: vec![Vec3::splat(2.0); w * h], scale: 1.0 };
        let lights = sample_environment(&map, 8192, 2);
        let e: f32 = lights.iter().map(|d| d.irradiance.x * d.direction.y.max(0.0)).sum();
        assert!((e - 2.0 * PI).abs() <= 0.02 * 2.0 * PI, "{e}");
        // A map bright only in its upper half sends every sample up there.
        let mut texels = vec![Vec3::ZERO; w * h];
        for t in &mut texels[..w * h / 2] {
            *t = Vec3::ONE;
        }
        let sky = EnvironmentMap::LatLong { width: w, height: h, texels, scale: 1.0 };
        assert!(sample_environment(&sky, 1000, 3).iter().all(|d| d.direction.y >= -1e-6));
        assert_eq!(sky.radiance(Vec3::Y), Vec3::ONE);
        assert_eq!(sky.radiance(-Vec3::Y), Vec3::ZERO);
    }

    #[test]
    fn sun_samples_share_the_irradiance_within_the_disc() {
        let d = Vec3::new(0.3, 1.0, 0.2).normalize();
        let lights = sample_sun(d, Vec3::splat(100.0), 0.5, 64, 1);
        assert_eq!(lights.len(), 64);
        let total: Vec3 = lights.iter().map(|l| l.irradiance).sum();
        assert!((total - Vec3::splat(100.0)).abs().max_element() < 1e-3);
        let cos_max = 0.5f32.to_radians().cos();
        assert!(lights.iter().all(|l| l.direction.dot(d) >= cos_max - 1e-6));
        assert_eq!(sample_sun(d, Vec3::ONE, 0.0, 64, 1).len(), 1);
    }
}
