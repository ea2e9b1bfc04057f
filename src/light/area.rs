//! Area lights as surfaces to sample (docs/design.md §6.1). Their points
//! (`LightKind::Area`) light the broad lobes; a glossy lobe too sharp for
//! those points samples the surfaces themselves: a point drawn uniformly
//! by area on an emitter, beside a direction drawn from the lobe, weighted
//! by multiple importance sampling. This module draws points and gives the
//! density of a point, so that a lobe's ray that hits an emitter can be
//! weighted against the draw that could have made it.

use glam::{Vec2, Vec3};

use super::EmitterLeaves;
use crate::scene::{LightSource, Scene};
use crate::util::color::luminance;

/// One area light's surface in world space.
#[derive(Debug, Clone)]
pub struct AreaEmitter {
    /// The scene's mesh the emitter is (its triangles are in world space).
    pub mesh: usize,
    /// Running sums of the triangles' areas, m^2: the last is the total.
    cumulative: Vec<f64>,
    /// Total area, m^2.
    pub area: f32,
    /// Area-weighted centroid and bounding box, metres.
    pub centroid: Vec3,
    pub lo: Vec3,
    pub hi: Vec3,
    /// Luminance of the emission factor (before any texture), W/(m^2 sr).
    pub luminance: f32,
    /// How many of the light tree's points stand for one side of it.
    pub points: u32,
    /// Its light group.
    pub group: usize,
}

/// A point drawn on an emitter: the triangle and its barycentric
/// coordinates (a, b), p = p0 + a (p1 - p0) + b (p2 - p0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AreaSample {
    pub point: Vec3,
    /// The triangle's unit normal by its winding.
    pub normal: Vec3,
    pub triangle: usize,
    pub ab: Vec2,
}

impl AreaEmitter {
    /// A point drawn with the numbers `u`: the first picks the triangle
    /// (in proportion to area), the other two the point in it (uniform in
    /// area), so the point is uniform over the emitter: density 1 / area.
    #[must_use]
    pub fn sample(&self, scene: &Scene, u: [f32; 3]) -> AreaSample {
        let mesh = &scene.meshes[self.mesh];
        let target = f64::from(u[0]) * f64::from(self.area);
        let triangle = self.cumulative.partition_point(|&c| c <= target).min(self.cumulative.len() - 1);
        // Fold the unit square onto the triangle (uniform in area).
        let (mut a, mut b) = (u[1], u[2]);
        if a + b > 1.0 {
            a = 1.0 - a;
            b = 1.0 - b;
        }
        let [p0, p1, p2] = mesh.triangles[triangle].map(|i| mesh.positions[i as usize]);
        let normal = crate::util::triangle::normal([p0, p1, p2]);
        AreaSample { point: p0 + a * (p1 - p0) + b * (p2 - p0), normal, triangle, ab: Vec2::new(a, b) }
    }

    /// The radiance leaving the drawn point `at` towards `towards` (a
    /// point), W/(m^2 sr): the material's emission (texel by texel) on the
    /// side its winding faces, or on both sides when it emits from both;
    /// as a ray that hits it reads it.
    #[must_use]
    pub fn radiance(&self, scene: &Scene, at: &AreaSample, towards: Vec3) -> Vec3 {
        let mesh = &scene.meshes[self.mesh];
        let material = &scene.materials[mesh.material];
        let front = at.normal.dot(towards - at.point) > 0.0;
        if !(front || material.emits_both_sides) {
            return Vec3::ZERO;
        }
        material.emission_at(&mesh.tex_coords(at.triangle, at.ab.x, at.ab.y), &scene.textures)
    }

    /// The squared distance from `p` to the emitter's box (0 inside it).
    #[must_use]
    pub fn distance_squared(&self, p: Vec3) -> f32 {
        (self.lo - p).max(p - self.hi).max(Vec3::ZERO).length_squared()
    }

    /// Whether some of the emitter's box lies above the plane through `p`
    /// with normal `n` (where light can come from).
    #[must_use]
    pub fn above(&self, p: Vec3, n: Vec3) -> bool {
        let (c, h) = (0.5 * (self.lo + self.hi) - p, 0.5 * (self.hi - self.lo));
        c.dot(n) + h.dot(n.abs()) > 0.0
    }

    /// How strongly the light strategy picks this emitter at `p`: an
    /// estimate of its irradiance there, L A / max(d^2, A / pi) with d the
    /// distance to its centroid (at most pi L, a hemisphere of L). Any
    /// positive weight keeps the estimate unbiased; this one only spends
    /// draws where light is likely.
    #[must_use]
    pub fn weight(&self, p: Vec3) -> f32 {
        let d2 = (self.centroid - p).length_squared();
        self.luminance * self.area / d2.max(self.area / std::f32::consts::PI)
    }
}

/// The scene's area lights as surfaces, and which mesh is which.
#[derive(Debug, Clone, Default)]
pub struct AreaEmitters {
    pub emitters: Vec<AreaEmitter>,
    /// The emitter each mesh is, if any.
    of_mesh: Vec<Option<u32>>,
}

impl AreaEmitters {
    /// The area lights of `scene` that emit and have area, with as many
    /// stand-in lights per side as `leaves` makes of them.
    #[must_use]
    pub fn of(scene: &Scene, leaves: EmitterLeaves) -> Self {
        let mut found = Self { emitters: Vec::new(), of_mesh: vec![None; scene.meshes.len()] };
        for (i, source) in scene.lights.iter().enumerate() {
            let LightSource::Area { mesh: m, samples, .. } = *source else { continue };
            let mesh = &scene.meshes[m];
            let emission = scene.materials[mesh.material].emission;
            let mut cumulative = Vec::with_capacity(mesh.triangles.len());
            let (mut total, mut weighted) = (0.0f64, Vec3::ZERO.as_dvec3());
            let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
            for t in &mesh.triangles {
                let [p0, p1, p2] = t.map(|i| mesh.positions[i as usize]);
                let area = crate::util::triangle::area([p0, p1, p2]);
                total += area;
                weighted += ((p0 + p1 + p2) / 3.0).as_dvec3() * area;
                cumulative.push(total);
                lo = lo.min(p0).min(p1).min(p2);
                hi = hi.max(p0).max(p1).max(p2);
            }
            let luminance = luminance(emission);
            if !(total > 0.0 && luminance > 0.0 && total.is_finite()) || samples == 0 {
                continue;
            }
            let textured = scene.materials[mesh.material].emissive_texture.is_some();
            let points = match leaves {
                EmitterLeaves::Whole if !textured => mesh.triangles.len() as u32,
                _ => samples,
            };
            found.of_mesh[m] = Some(found.emitters.len() as u32);
            found.emitters.push(AreaEmitter {
                mesh: m,
                cumulative,
                area: total as f32,
                centroid: (weighted / total).as_vec3(),
                lo,
                hi,
                luminance,
                points,
                group: scene.groups.of_light.get(i).copied().unwrap_or(0),
            });
        }
        found
    }

    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.emitters.is_empty()
    }

    /// The emitter mesh `mesh` is, if any.
    #[must_use]
    pub fn of_mesh(&self, mesh: usize) -> Option<usize> {
        self.of_mesh.get(mesh).copied().flatten().map(|e| e as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad_scene() -> Scene {
        let text = r#"
[[lights]]
type = "area"
corner = [-1, 2, -0.5]
u = [2, 0, 0]
v = [0, 0, 1]
radiance = [1, 2, 3]
samples = 16
"#;
        crate::scene::with_lights_only(text)
    }

    #[test]
    fn points_are_uniform_over_the_surface_and_emit_on_the_front_only() {
        let scene = quad_scene();
        let emitters = AreaEmitters::of(&scene, EmitterLeaves::Parts);
        let [e] = emitters.emitters.as_slice() else { panic!("one emitter") };
        assert!((e.area - 2.0).abs() < 1e-6);
        assert_eq!(emitters.of_mesh(e.mesh), Some(0));
        // The fraction of points with x < 0 is the fraction of area there:
        // a draw by triangle count alone, or an unfolded square, misses it.
        let n = 40_000u64;
        let mut left = 0;
        let mut quadrant = 0;
        for i in 0..n {
            let fraction = |k: u64| (k % n) as f32 / n as f32;
            let u = [(i as f32 + 0.5) / n as f32, fraction(i * 7919), fraction(i * 104_729)];
            let s = e.sample(&scene, u);
            assert!(
                (s.point.y - 2.0).abs() < 1e-6 && s.point.x.abs() <= 1.0 + 1e-6 && s.point.z.abs() <= 0.5 + 1e-6,
                "{s:?}"
            );
            left += usize::from(s.point.x < 0.0);
            quadrant += usize::from(s.point.x > 0.5 && s.point.z > 0.0);
        }
        assert!((left as f64 / n as f64 - 0.5).abs() < 0.01, "{left}");
        assert!((quadrant as f64 / n as f64 - 0.125).abs() < 0.01, "{quadrant}");
        // u x v = x x z = -y: the front faces down.
        let s = e.sample(&scene, [0.3, 0.2, 0.1]);
        assert_eq!(e.radiance(&scene, &s, Vec3::ZERO), Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(e.radiance(&scene, &s, Vec3::new(0.0, 4.0, 0.0)), Vec3::ZERO);
    }
}
