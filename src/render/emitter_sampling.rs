//! Continuous emitters (the environment, area lights' surfaces) sampled
//! through glossy lobes too sharp for their stand-in lights
//! (docs/design.md §6.1 and design.md §6.2). This module decides which points do so
//! and chooses what to draw, with the densities multiple importance
//! sampling weighs; the integrator traces the draws.

use glam::Vec3;

use crate::light::area::{AreaEmitters, AreaSample};
use crate::light::environment::{EnvironmentLight, EnvironmentSample};
use crate::light::EmitterLeaves;
use crate::scene::Scene;
use crate::shading::{Bsdf, SurfacePoint};

/// The fewest of an emitter's stand-in lights a glossy lobe must see for
/// them to light it: a lobe that sees fewer (its solid angle times their
/// density about its mirror direction) shows them as specks, and its
/// light from the continuous emitters is sampled instead (docs/design.md
/// §6.2; measured in docs/notebook/measurements.md, "Shiny surfaces under an
/// environment").
pub const LIGHTS_PER_LOBE: f32 = 128.0;

/// The fewest pairs of draws (one from the emitters, one from the lobe) a
/// pixel's samples give a sharp lobe together: below this many samples
/// per pixel each sample draws several pairs (docs/design.md §6.2).
pub const DRAWS_PER_PIXEL: u32 = 64;

/// The most pairs one sample draws at a shading point.
const MOST_DRAWS_PER_POINT: u32 = 16;

/// The environment as a light to sample: the continuous light, how many
/// directional lights it became (their density towards a direction is
/// that times the light's), and its light group.
pub struct SampledEnvironment<'a> {
    pub light: EnvironmentLight<'a>,
    pub lights: u32,
    pub group: usize,
}

/// The continuous emitters of a scene as a sharp lobe samples them, and
/// how many pairs of draws it gets per shading point.
pub struct EmitterSampling<'a> {
    pub scene: &'a Scene,
    pub environment: Option<SampledEnvironment<'a>>,
    pub area: AreaEmitters,
    pub draws: u32,
}

/// A point's odds of drawing each emitter (the environment first, when
/// there is one, then each area light), in proportion to `weights`.
#[derive(Debug, Default, Clone)]
pub struct EmitterChoice {
    weights: Vec<f32>,
    total: f32,
}

/// What the emitters' draw found: a direction towards the environment, or
/// a point on area light `emitter`.
pub enum EmitterDraw {
    Environment(EnvironmentSample),
    Area { emitter: usize, sample: AreaSample },
}

impl<'a> EmitterSampling<'a> {
    /// The scene's continuous emitters, when it has any, for a render of
    /// `spp` samples per pixel: each sample draws enough pairs that the
    /// pixel gets at least [`DRAWS_PER_PIXEL`] (at most 16 per sample), so
    /// that a few samples per pixel, the bounded mode's usual setting, do
    /// not leave a sharp lobe's reflection grainy.
    #[must_use]
    pub fn of(scene: &'a Scene, spp: u32, leaves: EmitterLeaves) -> Option<Self> {
        let environment = scene.environment.as_ref().and_then(|environment| {
            let light = EnvironmentLight::new(&environment.map)?;
            // As one light beside the trees it has no stand-ins: every
            // glossy lobe is sharp for it.
            let lights = if leaves == EmitterLeaves::Whole { 0 } else { environment.samples };
            Some(SampledEnvironment { light, lights, group: scene.groups.environment })
        });
        let area = AreaEmitters::of(scene, leaves);
        if environment.is_none() && area.is_empty() {
            return None;
        }
        let draws = DRAWS_PER_PIXEL.div_ceil(spp.max(1)).clamp(1, MOST_DRAWS_PER_POINT);
        Some(Self { scene, environment, area, draws })
    }

    /// The environment when it is one light beside the trees
    /// (`EmitterLeaves::Whole`: no stand-ins in them), which every vertex
    /// samples for the lobes the sharp lobe's draws leave
    /// (docs/design.md §6.2, "One light beside the trees").
    #[must_use]
    pub fn environment_alone(&self) -> Option<&SampledEnvironment<'a>> {
        self.environment.as_ref().filter(|e| e.lights == 0)
    }

    /// The BSDF at `sp` when its glossy lobe is too sharp for some
    /// emitter's stand-in lights (it sees fewer than [`LIGHTS_PER_LOBE`] of
    /// them): that lobe's light from every continuous emitter is then
    /// sampled, and the stand-ins light the rest. For the environment the
    /// lights' density is taken about the mirror direction; for an area
    /// light it is at most its points per unit area times the squared
    /// distance to its box (the density seen from its nearest point,
    /// head-on: never above the true one, so a doubtful lobe is sampled).
    #[must_use]
    pub fn sharp_lobe(&self, sp: &SurfacePoint<'_>) -> Option<Bsdf> {
        let bsdf = Bsdf::new(sp);
        let solid_angle = bsdf.glossy_solid_angle()?;
        let environment = self.environment.as_ref().map(|e| e.lights as f32 * e.light.pdf(sp.r));
        let area = self
            .area
            .emitters
            .iter()
            .filter(|e| e.above(sp.p, sp.n))
            .map(|e| e.points as f32 * e.distance_squared(sp.p) / e.area);
        let fewest = environment.into_iter().chain(area).fold(f32::INFINITY, f32::min);
        (solid_angle * fewest < LIGHTS_PER_LOBE).then_some(bsdf)
    }

    /// Weighs the emitters for a draw at `sp` into `choice`: the
    /// environment by pi times its mean luminance (the irradiance of as
    /// bright a uniform sky), an area light by its estimated irradiance
    /// ([`crate::light::area::AreaEmitter::weight`]), 0 when its box lies
    /// wholly behind the shading normal's plane.
    /// A fibre is lit from every side (docs/design.md §5.7): no emitter is
    /// behind it.
    pub fn weigh(&self, sp: &SurfacePoint<'_>, choice: &mut EmitterChoice) {
        self.weigh_at(sp.p, sp.fibre.is_none().then_some(sp.n), choice);
    }

    /// [`EmitterSampling::weigh`] at point `p` of shading normal `n` (None:
    /// lit from every side).
    pub fn weigh_at(&self, p: Vec3, n: Option<Vec3>, choice: &mut EmitterChoice) {
        choice.weights.clear();
        if let Some(e) = &self.environment {
            choice.weights.push(std::f32::consts::PI * e.light.mean_luminance());
        }
        for e in &self.area.emitters {
            let faces = n.is_none_or(|n| e.above(p, n));
            choice.weights.push(if faces { e.weight(p) } else { 0.0 });
        }
        choice.total = choice.weights.iter().sum();
    }

    /// An emitter drawn by `choice` with `u[0]`, and a direction or point
    /// from it with `u[0]` (rescaled within the emitter's share) and the
    /// other two numbers; with the probability of the emitter.
    #[must_use]
    pub fn draw(&self, choice: &EmitterChoice, u: [f32; 3]) -> Option<(EmitterDraw, f32)> {
        if !(choice.total > 0.0 && choice.total.is_finite()) {
            return None;
        }
        let target = u[0] * choice.total;
        let mut below = 0.0;
        let last = choice.weights.iter().rposition(|&w| w > 0.0)?;
        for (k, &w) in choice.weights.iter().enumerate() {
            if w <= 0.0 || (below + w <= target && k != last) {
                below += w;
                continue;
            }
            let rescaled = ((target - below) / w).clamp(0.0, 1.0 - f32::EPSILON / 2.0);
            let probability = w / choice.total;
            let u = [rescaled, u[1], u[2]];
            let environment = usize::from(self.environment.is_some());
            return if k < environment {
                let e = self.environment.as_ref()?;
                e.light.sample(u).map(|s| (EmitterDraw::Environment(s), probability))
            } else {
                let emitter = k - environment;
                let sample = self.area.emitters[emitter].sample(self.scene, u);
                Some((EmitterDraw::Area { emitter, sample }, probability))
            };
        }
        None
    }

    /// The probability that `choice` draws the environment.
    #[must_use]
    pub fn environment_probability(&self, choice: &EmitterChoice) -> f32 {
        match self.environment {
            Some(_) if choice.total > 0.0 => choice.weights[0] / choice.total,
            _ => 0.0,
        }
    }

    /// The probability that `choice` draws area light `emitter`.
    #[must_use]
    pub fn area_probability(&self, choice: &EmitterChoice, emitter: usize) -> f32 {
        let k = emitter + usize::from(self.environment.is_some());
        if choice.total > 0.0 {
            choice.weights[k] / choice.total
        } else {
            0.0
        }
    }

    /// The density per steradian, at a shading point, of the emitters'
    /// draw reaching point `y` of area light `emitter` along unit `wi`
    /// (`cos_light` the cosine at `y` between its surface and `wi`, `d2`
    /// the squared distance): P(emitter) / area * d^2 / |cos| (the area
    /// density over the solid angle the surface element subtends).
    #[must_use]
    pub fn area_pdf(&self, choice: &EmitterChoice, emitter: usize, d2: f32, cos_light: f32) -> f32 {
        let p = self.area_probability(choice, emitter);
        if p <= 0.0 || cos_light.abs() <= 0.0 {
            return 0.0;
        }
        p / self.area.emitters[emitter].area * d2 / cos_light.abs()
    }

    /// The light of a direction that leaves the scene (the environment's
    /// radiance) and the emitters' draw's density for it.
    #[must_use]
    pub fn escaped(&self, choice: &EmitterChoice, wi: Vec3) -> Option<(Vec3, f32, usize)> {
        let e = self.environment.as_ref()?;
        Some((e.light.radiance(wi), self.environment_probability(choice) * e.light.pdf(wi), e.group))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::util::sampling::Rng;

    /// A sky and two area lights of different sizes and radiances.
    fn scene() -> Scene {
        let text = r#"
[[lights]]
type = "area"
corner = [-1, 2, -0.5]
u = [2, 0, 0]
v = [0, 0, 1]
radiance = [3, 3, 3]
[[lights]]
type = "area"
corner = [2, 1, -0.25]
u = [0, 0, 0.5]
v = [0, 0.5, 0]
radiance = [20, 10, 5]
[environment]
radiance = [0.2, 0.2, 0.2]
"#;
        crate::scene::with_lights_only(text)
    }

    /// What MIS weighs a path with must be the density that draws it: the
    /// emitters' draws at a point fall on each emitter as often as
    /// `environment_probability` and `area_probability` say (which
    /// `escaped` and `area_pdf` use), and on an area light's halves as
    /// their areas (its density 1 / A). A draw that skipped an emitter of
    /// weight 0, or picked by index, fails this.
    #[test]
    fn draws_fall_on_each_emitter_as_its_probability_says() {
        let scene = scene();
        let sampling = EmitterSampling::of(&scene, 64, EmitterLeaves::Parts).unwrap();
        assert_eq!(sampling.area.emitters.len(), 2);
        let choose = |p: Vec3, n: Vec3| -> EmitterChoice {
            let mut choice = EmitterChoice::default();
            sampling.weigh_at(p, Some(n), &mut choice);
            choice
        };
        for (p, n) in [(Vec3::ZERO, Vec3::Y), (Vec3::new(1.5, 0.5, 0.0), Vec3::X), (Vec3::new(0.0, 3.0, 0.0), Vec3::Y)]
        {
            let choice = choose(p, n);
            let want = [
                sampling.environment_probability(&choice),
                sampling.area_probability(&choice, 0),
                sampling.area_probability(&choice, 1),
            ];
            assert!((want.iter().sum::<f32>() - 1.0).abs() < 1e-5, "{want:?}");
            let mut rng = Rng::seeded(7);
            let n_draws = 200_000;
            let mut counts = [0usize; 3];
            let mut left_half = 0usize;
            for _ in 0..n_draws {
                let u = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
                match sampling.draw(&choice, u) {
                    Some((EmitterDraw::Environment(_), probability)) => {
                        assert_eq!(probability, want[0]);
                        counts[0] += 1;
                    }
                    Some((EmitterDraw::Area { emitter, sample }, probability)) => {
                        assert_eq!(probability, want[emitter + 1]);
                        counts[emitter + 1] += 1;
                        left_half += usize::from(emitter == 0 && sample.point.x < 0.0);
                    }
                    None => panic!("no draw"),
                }
            }
            for k in 0..3 {
                let got = counts[k] as f32 / n_draws as f32;
                assert!((got - want[k]).abs() < 0.005, "at {p}: emitter {k} drawn {got}, its probability {}", want[k]);
            }
            if counts[1] > 10_000 {
                let half = left_half as f32 / counts[1] as f32;
                assert!((half - 0.5).abs() < 0.02, "{half}");
            }
            // Above the big light, it is behind the plane: weight 0, never drawn.
            if p.y > 2.0 {
                assert_eq!((want[1], counts[1]), (0.0, 0));
            }
        }
    }
}
