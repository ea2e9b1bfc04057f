//! Next-event estimation at a path's vertex (docs/design.md §6.7): the
//! direct-light method's light (whichever it is: `super::direct`), the
//! suns' discs, and for a glossy lobe too sharp for the emitters'
//! stand-in lights the emitters' own sampling, weighted against the
//! lobe's by multiple importance sampling.

use glam::{DVec3, Vec3};

use super::direct::{DirectWorker, Vertex};
use super::emitter_sampling::{EmitterChoice, EmitterDraw, EmitterSampling, SampledEnvironment};
use super::stats::ShadingStats;
use super::tracer::{SampleKey, SharpLobe, Tracer};
use crate::shading::{BatchBuffers, Bsdf, LightBatch, Lobes, SurfacePoint};
use crate::util::streams::Stream;

/// The most directions one camera sample draws from a sun's disc at a
/// shading point.
const MOST_SUN_DRAWS: u32 = 16;

/// Next-event estimation's buffers, one set per worker thread.
#[derive(Default)]
pub struct NextEventScratch {
    batch: BatchBuffers,
    choice: EmitterChoice,
}

/// Lights `vertex`, a vertex of a camera path, by next-event estimation:
/// the `direct` method's light, the suns' discs and, for a lobe too
/// `sharp` for the emitters' stand-ins, the emitters' sampling; adds it
/// times the path's throughput to `radiance`, and each group's share to
/// `groups`. Vertices the camera sees directly or through mirrors
/// (`vertex.primary`) draw as many directions from a sun's disc and the
/// emitters as the pixel's samples leave them; vertices after a sampled
/// bounce draw one.
#[allow(clippy::too_many_arguments)]
pub fn light_vertex<'a>(
    tracer: &Tracer<'a>,
    direct: &mut dyn DirectWorker<'a>,
    vertex: &Vertex<'_, 'a>,
    sharp: &SharpLobe<'_>,
    scratch: &mut NextEventScratch,
    groups: &mut [DVec3],
    radiance: &mut DVec3,
    stats: &mut ShadingStats,
) {
    let (sp, throughput) = (vertex.sp, vertex.throughput);
    if let Some(direct) = direct.light(tracer, vertex, stats) {
        stats.record_point(direct.nodes, direct.shadow_rays);
        direct.add_scaled_to(throughput, radiance, groups);
    }
    let mut credit = |group: usize, value: DVec3| {
        let seen = throughput * value;
        *radiance += seen;
        if let Some(slot) = groups.get_mut(group) {
            *slot += seen;
        }
    };
    let (sample, depth, primary) = (vertex.sample, vertex.depth, vertex.primary);
    let mut rays = 0;
    if tracer.lights.iter().any(|group| !group.suns.is_empty()) {
        rays += sun_light(tracer, sp, sample, depth, primary, &mut scratch.batch, &mut credit);
    }
    if let Some((emitters, bsdf)) = sharp {
        let draws = if primary { emitters.draws } else { 1 };
        emitters.weigh(sp, &mut scratch.choice);
        let scale = 1.0 / f64::from(draws);
        let mut credit = |group: usize, value: DVec3| credit(group, scale * value);
        for u in pair_numbers(Stream::Emitter, sample, depth, draws) {
            rays += sampled_emitters(tracer, emitters, &scratch.choice, sp, bsdf, u, &mut credit);
        }
    }
    if let Some((emitters, environment)) = tracer.emitters.and_then(|e| e.environment_alone().map(|env| (e, env))) {
        // The lobes the sharp lobe's draws leave: the diffuse one beside a
        // sharp glossy lobe, else every lobe (the glossy one, if any, is
        // sharp for an environment with no stand-ins).
        let own;
        let (bsdf, lobes) = match sharp {
            Some((_, bsdf)) => (bsdf, Lobes::DIFFUSE),
            None => {
                own = Bsdf::new(sp);
                (&own, Lobes::ALL)
            }
        };
        // As many pairs as the sharp lobe's: at least DRAWS_PER_PIXEL a
        // pixel at the camera's vertices, one past a sampled bounce.
        let draws = if primary { emitters.draws } else { 1 };
        let scale = 1.0 / f64::from(draws);
        let mut credit = |group: usize, value: DVec3| credit(group, scale * value);
        for u in pair_numbers(Stream::Environment, sample, depth, draws) {
            rays += environment_alone(tracer, environment, sp, bsdf, lobes, u, &mut credit);
        }
    }
    stats.shadow_rays += rays;
}

/// The six numbers of each of a vertex's `draws` pairs of draws (one from
/// the emitters, one from the lobes), from `stream`: the pixel's samples
/// (and each sample's draws) take consecutive points of one Kronecker
/// sequence (`kronecker6`) rotated per pixel and bounce, stratified across
/// them, so the sampled lobe's noise falls faster.
fn pair_numbers(stream: Stream, [seed, x, y, s]: SampleKey, depth: u32, draws: u32) -> impl Iterator<Item = [f32; 6]> {
    let mut rng = stream.rng(&[seed, x, y, u64::from(depth)]);
    let shift: [f32; 6] = std::array::from_fn(|_| rng.next_f32());
    (0..draws).map(move |j| crate::util::sampling::kronecker6((s as u32).wrapping_mul(draws).wrapping_add(j), shift))
}

/// A drawn direction's share of the estimate, f cos * L / pdf weighted by
/// the power heuristic against the other strategy's density `other`.
fn weighted(f_cos: Vec3, light: Vec3, pdf: f32, other: f32) -> DVec3 {
    (f_cos * light).as_dvec3() * (power_heuristic(pdf, other) / f64::from(pdf))
}

/// The environment's light at `sp` through `lobes` of `bsdf` where it is
/// one light beside the trees (docs/design.md §6.2, "One light beside the
/// trees"): one direction drawn from the environment and one from the
/// lobes, each weighted by the power heuristic against the other's
/// density (Veach and Guibas 1995), as a path tracer lights a vertex. The
/// environment's direction gets a shadow ray, the lobes' a ray that must
/// escape. Its light goes to `credit` with the environment's group;
/// returns the rays cast.
fn environment_alone(
    tracer: &Tracer<'_>,
    environment: &SampledEnvironment<'_>,
    sp: &SurfacePoint<'_>,
    bsdf: &Bsdf,
    lobes: Lobes,
    u: [f32; 6],
    credit: &mut impl FnMut(usize, DVec3),
) -> u64 {
    let mut rays = 0;
    if let Some(s) = environment.light.sample([u[0], u[1], u[2]]) {
        let f_cos = bsdf.eval(s.wi, lobes);
        if f_cos != Vec3::ZERO && s.radiance != Vec3::ZERO && s.pdf > 0.0 {
            rays += 1;
            if !tracer.geometry.embree.occluded(&sp.shadow_ray_towards(s.wi).to_ray()) {
                credit(environment.group, weighted(f_cos, s.radiance, s.pdf, bsdf.pdf(s.wi, lobes)));
            }
        }
    }
    if let Some(s) = bsdf.sample([u[3], u[4], u[5]], lobes) {
        rays += 1;
        let mut ray = sp.ray_towards(s.wi);
        if tracer.first_hit(&mut ray).is_none() {
            let light = environment.light.radiance(s.wi);
            if light != Vec3::ZERO {
                credit(environment.group, weighted(s.f_cos, light, s.pdf, environment.light.pdf(s.wi)));
            }
        }
    }
    rays
}

/// The continuous emitters' light at `sp` through the glossy lobe of
/// `bsdf`, the lobe their stand-in lights leave alone
/// (docs/design.md §6.1 and design.md §6.2): one draw from the emitters (by `choice`: a direction
/// from the environment or a point on an area light) and one direction
/// from the lobe, each weighted by the power heuristic against the
/// other's density for the same path (Veach and Guibas 1995). The
/// emitters' draw gets a shadow ray; the lobe's a ray that finds what
/// it sees (an area light, or the environment past everything). Each
/// emitter's share goes to `credit` with its light group; returns the
/// rays cast.
fn sampled_emitters(
    tracer: &Tracer<'_>,
    emitters: &EmitterSampling<'_>,
    choice: &EmitterChoice,
    sp: &SurfacePoint<'_>,
    bsdf: &Bsdf,
    u: [f32; 6],
    credit: &mut impl FnMut(usize, DVec3),
) -> u64 {
    let lobes = Lobes::GLOSSY;
    let embree = &tracer.geometry.embree;
    let mut rays = 0;
    // f cos * L * weight / pdf, for a path found unblocked.
    match emitters.draw(choice, [u[0], u[1], u[2]]) {
        Some((EmitterDraw::Environment(s), probability)) => {
            let f_cos = bsdf.eval(s.wi, lobes);
            if f_cos != Vec3::ZERO && s.radiance != Vec3::ZERO {
                rays += 1;
                if !embree.occluded(&sp.shadow_ray_towards(s.wi).to_ray()) {
                    let group = emitters.environment.as_ref().map_or(0, |e| e.group);
                    credit(group, weighted(f_cos, s.radiance, probability * s.pdf, bsdf.pdf(s.wi, lobes)));
                }
            }
        }
        Some((EmitterDraw::Area { emitter, sample }, _)) => {
            let to = sample.point - sp.p;
            let d2 = to.length_squared();
            let wi = to.normalize_or_zero();
            let f_cos = bsdf.eval(wi, lobes);
            let e = &emitters.area.emitters[emitter];
            let light = e.radiance(emitters.scene, &sample, sp.p);
            let pdf = emitters.area_pdf(choice, emitter, d2, sample.normal.dot(wi));
            if f_cos != Vec3::ZERO && light != Vec3::ZERO && pdf > 0.0 && pdf.is_finite() {
                if let Some(ray) = sp.shadow_ray_to(sample.point) {
                    rays += 1;
                    if !embree.occluded(&ray.to_ray()) {
                        credit(e.group, weighted(f_cos, light, pdf, bsdf.pdf(wi, lobes)));
                    }
                }
            }
        }
        None => {}
    }
    if let Some(s) = bsdf.sample([u[3], u[4], u[5]], lobes) {
        rays += 1;
        let mut ray = sp.ray_towards(s.wi);
        match tracer.first_hit(&mut ray) {
            None => {
                if let Some((light, pdf, group)) = emitters.escaped(choice, s.wi) {
                    if light != Vec3::ZERO {
                        credit(group, weighted(s.f_cos, light, s.pdf, pdf));
                    }
                }
            }
            Some(hit) => {
                if let Some(emitter) = emitters.area.of_mesh(tracer.geometry.mesh_of(&hit)) {
                    let seen = tracer.geometry.surface(&ray, &hit);
                    if seen.emitted != Vec3::ZERO {
                        let d2 = seen.distance * seen.distance;
                        let pdf = emitters.area_pdf(choice, emitter, d2, seen.ng.dot(s.wi));
                        let group = emitters.area.emitters[emitter].group;
                        credit(group, weighted(s.f_cos, seen.emitted, s.pdf, pdf));
                    }
                }
            }
        }
    }
    rays
}

/// The light of the suns' discs at `sp` (in no tree: docs/design.md
/// §6.3), by group: each sample draws ceil(samples / spp) directions
/// (1 to 16; one at a vertex past a sampled bounce, not `primary`)
/// uniformly over each disc's solid angle, consecutive points of a
/// Kronecker sequence over the pixel's samples rotated per pixel,
/// bounce and sun, each a directional light of the disc's irradiance
/// over the draws, evaluated (every lobe) and traced as any light is.
/// Each group's light goes to `credit`; returns the shadow rays cast.
fn sun_light(
    tracer: &Tracer<'_>,
    sp: &SurfacePoint<'_>,
    sample: SampleKey,
    depth: u32,
    primary: bool,
    buffers: &mut BatchBuffers,
    credit: &mut impl FnMut(usize, DVec3),
) -> u64 {
    let [seed, x, y, s] = sample;
    let mut shadow_rays = 0;
    for (g, group) in tracer.lights.iter().enumerate().filter(|(_, group)| !group.suns.is_empty()) {
        let mut batch = LightBatch::new(&tracer.geometry.embree, sp, buffers);
        for (i, sun) in group.suns.iter().enumerate() {
            let mut rng = Stream::Sun.rng(&[seed, x, y, u64::from(depth), g as u64, i as u64]);
            let shift: [f32; 6] = std::array::from_fn(|_| rng.next_f32());
            let draws = if primary { sun.samples.div_ceil(tracer.spp.max(1)).clamp(1, MOST_SUN_DRAWS) } else { 1 };
            let irradiance = sun.irradiance / draws as f32;
            for j in 0..draws {
                let index = (s as u32).wrapping_mul(draws).wrapping_add(j);
                let u = crate::util::sampling::kronecker6(index, shift);
                let direction = sun.direction_at([u[0], u[1]]);
                batch.add(&crate::light::Light::Directional(crate::light::DirectionalLight { direction, irradiance }));
            }
        }
        let batch = batch.finish();
        credit(g, batch.radiance);
        shadow_rays += batch.shadow_rays;
    }
    shadow_rays
}

/// The power heuristic's weight (Veach and Guibas 1995, exponent 2) of a
/// direction drawn with density `pdf` by one strategy, against `other`'s
/// density for it by the other: pdf^2 / (pdf^2 + other^2).
#[must_use]
pub fn power_heuristic(pdf: f32, other: f32) -> f64 {
    let (a, b) = (f64::from(pdf), f64::from(other));
    a * a / (a * a + b * b)
}
