//! The path loop: radiance along a camera path, from the camera's hit
//! through mirrors (and with the path method through sampled bounces,
//! with Russian roulette), each vertex lit by next-event estimation
//! (`super::next_event`) through the pass's direct-light method
//! (`super::direct`), which the loop never names.
//!
//! Radiance is accumulated in f64: a product M * G * I with intensities up to
//! 1e30 W/sr and G up to 1/epsilon^2 overflows f32. Values are clamped to
//! finite f32 only when a pixel is stored (`render::film::film_value`, which
//! counts every non-finite value it meets).

use glam::{DVec3, Vec3};

use super::direct::{DirectLight, DirectWorker, Vertex};
use super::next_event::{light_vertex, NextEventScratch};
use super::stats::ShadingStats;
use super::tracer::{SampleKey, Tracer};
use crate::shading::{Bsdf, Lobes, SurfacePoint};
use crate::util::color::luminance;
use crate::util::streams::Stream;

/// The path method's vertices before Russian roulette may end a path
/// (pbrt-v4 starts it after its second bounce too).
const RUSSIAN_ROULETTE_DEPTH: u32 = 3;

/// The delta transmissions a camera path follows without the path
/// method beyond its mirror depth: Cycles' default transmission bounces
/// (docs/design.md §5.8). A pane of glass takes 2 and a glass with a
/// drink in it 4 or more, which the 4 mirror bounces would cut short.
const MAX_TRANSMISSIONS: u32 = 12;

/// Where a path goes from a vertex: the ray, what the path's throughput is
/// multiplied by, and whether it is a delta bounce (a mirror's or a
/// transmission's, whose emission the next vertex counts) and a
/// transmission.
struct Bounce {
    ray: crate::embree::Ray,
    weight: DVec3,
    delta: bool,
    transmitted: bool,
}

/// What the first hit of a camera sample reports to the AOVs.
#[derive(Debug, Clone, Copy)]
pub struct FirstHit {
    pub albedo: Vec3,
    pub normal: Vec3,
    pub distance: f32,
}

pub struct SampleResult {
    pub radiance: DVec3,
    /// Whether the sample counts in the pixel's alpha: it hit a surface,
    /// or saw the environment through an opaque film.
    pub opaque: bool,
    /// The object and material names of the first hit, by index into the
    /// scene's objects and materials (Cryptomatte).
    pub first_ids: Option<(usize, usize)>,
    pub first_hit: Option<FirstHit>,
    pub stats: ShadingStats,
    /// The camera rays the sample cast: 0 when the method had traced its
    /// camera ray already.
    pub camera_rays: u64,
}

pub struct Integrator<'a> {
    /// The scene as the paths see it.
    pub tracer: Tracer<'a>,
    /// How each vertex's light is chosen (`session::Mode::method`).
    pub direct: &'a dyn DirectLight<'a>,
    pub max_mirror_depth: u32,
    /// The light group of each mesh's emission (`Scene::emission_groups`).
    pub emission_group: &'a [usize],
    /// The path method's `max_depth` (docs/design.md §6.7); None: camera
    /// paths follow mirrors only, to `max_mirror_depth`.
    pub path_depth: Option<u32>,
}

/// A worker thread's state: next-event estimation's buffers and the
/// direct-light method's worker, whose tile and pixel hooks the tiles
/// call (`render::render_tile`).
pub struct Scratch<'m, 'a> {
    next_event: NextEventScratch,
    pub direct: Box<dyn DirectWorker<'a> + 'm>,
}

impl<'a> Integrator<'a> {
    /// A worker thread's state for this pass.
    #[must_use]
    pub fn scratch(&self) -> Scratch<'a, 'a> {
        Scratch { next_event: NextEventScratch::default(), direct: self.direct.worker() }
    }

    /// Number of light groups the radiance is split into (0: no split).
    #[must_use]
    pub fn group_slots(&self) -> usize {
        self.tracer.group_slots()
    }

    /// Radiance arriving at the camera along `ray`. Without the path
    /// method, camera paths bounce only off mirrors and every other surface
    /// is shaded by direct light; with it (`path_depth`), each vertex is
    /// lit by next-event estimation and the path goes on by sampling the
    /// BSDF (docs/design.md §6.7). Each light group's share is added to
    /// `groups[g]` (`groups` has [`Integrator::group_slots`] entries):
    /// emitters and the environment seen directly count in their own
    /// groups. With `transparent`, the environment is not seen where the
    /// camera ray itself hits nothing (the film's background is RGB 0,
    /// alpha 0); mirrors still show it. A method may defer its light to
    /// the pixel's end (`DirectWorker::finish_pixel`).
    pub fn trace(
        &self,
        mut ray: crate::embree::Ray,
        sample: SampleKey,
        transparent: bool,
        scratch: &mut Scratch<'_, 'a>,
        groups: &mut [DVec3],
    ) -> SampleResult {
        let mut result = SampleResult {
            radiance: DVec3::ZERO,
            opaque: false,
            first_ids: None,
            first_hit: None,
            stats: ShadingStats::default(),
            camera_rays: 0,
        };
        let mut throughput = DVec3::ONE;
        let tracer = &self.tracer;
        let scene = tracer.geometry.scene;
        let vertices = self.path_depth.unwrap_or(self.max_mirror_depth + 1);
        // Whether this vertex's ray counts the emission it finds: at the
        // camera and after mirrors, yes; after a sampled bounce, no: the
        // vertex before lit itself by every emitter already (next-event
        // estimation, design.md §6.7).
        let mut sees_emitters = true;
        // Delta transmissions followed past the mirror depth.
        let mut passes = 0;
        for depth in 0.. {
            // A camera ray the method traced already (reuse between
            // pixels, design §10.11).
            let traced = if depth == 0 { scratch.direct.traced(sample) } else { None };
            let hit = match traced {
                Some((traced, hit)) => {
                    ray = traced;
                    hit
                }
                None => {
                    result.camera_rays += u64::from(depth == 0);
                    tracer.first_hit(&mut ray)
                }
            };
            let Some(hit) = hit else {
                // The environment, seen directly or in a mirror.
                let seen_directly = depth == 0;
                let environment =
                    scene.environment.as_ref().filter(|_| sees_emitters && !(seen_directly && transparent));
                if let Some(environment) = environment {
                    result.opaque |= seen_directly;
                    let seen = throughput * environment.map.radiance(ray.direction.normalize()).as_dvec3();
                    result.radiance += seen;
                    if let Some(slot) = groups.get_mut(scene.groups.environment) {
                        *slot += seen;
                    }
                }
                break;
            };
            let (sp, sharp) = tracer.vertex(&ray, &hit, sample, depth);
            result.stats.path_vertices += 1;
            // Absorbed on the way through a solid (docs/design.md §5.8).
            throughput *= sp.interior_transmittance.as_dvec3();
            let mesh = tracer.geometry.mesh_of(&hit);
            let material = scene.meshes[mesh].material;
            if depth == 0 {
                result.opaque = true;
                result.first_hit = Some(FirstHit { albedo: sp.kd, normal: sp.n, distance: sp.distance });
                result.first_ids = Some((tracer.geometry.object_of(&hit), material));
            }
            // Emitters are seen with their radiance; they reflect light too,
            // as their material says (a TOML area light's is black).
            if sp.emitted != Vec3::ZERO && sees_emitters {
                let seen = throughput * sp.emitted.as_dvec3();
                result.radiance += seen;
                if let Some(slot) = groups.get_mut(self.emission_group[mesh]) {
                    *slot += seen;
                }
            }
            if sp.material.unlit {
                break;
            }
            let vertex = Vertex { sp: &sp, sample, depth, primary: sees_emitters, material, throughput };
            let (radiance, stats) = (&mut result.radiance, &mut result.stats);
            light_vertex(
                tracer,
                &mut *scratch.direct,
                &vertex,
                &sharp,
                &mut scratch.next_event,
                groups,
                radiance,
                stats,
            );
            if depth + 1 >= vertices + passes {
                break;
            }
            let bsdf = sharp.map(|(_, bsdf)| bsdf);
            let Some(bounce) = self.bounce(&sp, bsdf, sample, depth, throughput) else { break };
            if bounce.transmitted && self.path_depth.is_none() {
                if passes == MAX_TRANSMISSIONS {
                    break;
                }
                passes += 1;
            }
            result.stats.bounce_rays += 1;
            throughput *= bounce.weight;
            sees_emitters = bounce.delta;
            ray = bounce.ray;
        }
        result
    }

    /// Where the path goes from `sp`, its `depth`-th vertex: without the
    /// path method, along the mirror or the transmitted ray (if any;
    /// `delta_bounce`); with it, and inside a rough solid, where no light
    /// reaches its reflection (docs/design.md §5.8), along either or a
    /// direction the BSDF draws (all its lobes), chosen in proportion to
    /// their reflectance, then, with the path method past the first
    /// vertices, through Russian roulette on the path's `throughput` so
    /// far (docs/design.md §6.7). `bsdf` is the point's BSDF when the
    /// caller built it already. None: the path ends.
    fn bounce(
        &self,
        sp: &SurfacePoint<'_>,
        bsdf: Option<Bsdf>,
        sample: SampleKey,
        depth: u32,
        throughput: DVec3,
    ) -> Option<Bounce> {
        if self.path_depth.is_none() && !sp.inside_rough_solid() {
            return delta_bounce(sp, sample, depth);
        }
        let u = path_numbers(sample, depth);
        let bsdf = bsdf.unwrap_or_else(|| Bsdf::new(sp));
        let (mirror_weight, bsdf_weight) = (luminance(sp.mirror), bsdf.reflectance_weight());
        let transmission_weight = luminance(sp.transmission);
        let total = mirror_weight + bsdf_weight + transmission_weight;
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let (p_mirror, p_transmission) = (mirror_weight / total, transmission_weight / total);
        let mut bounce = if u[0] < p_mirror {
            mirrored(sp, p_mirror)
        } else if u[0] < p_mirror + p_transmission {
            transmitted(sp, p_transmission, [u[1], u[2]])?
        } else {
            let s = bsdf.sample([u[1], u[2], u[3]], Lobes::ALL)?;
            let weight = s.f_cos.as_dvec3() / (f64::from(s.pdf) * f64::from(1.0 - p_mirror - p_transmission));
            Bounce { ray: sp.ray_towards(s.wi), weight, delta: false, transmitted: false }
        };
        if !(bounce.weight.max_element() > 0.0 && bounce.weight.is_finite()) {
            return None;
        }
        // Russian roulette (pbrt-v4's rule): past the first vertices, a
        // path whose throughput has fallen below 1 goes on with
        // probability equal to its largest component and is divided by it
        // when it does, so that its expected value is unchanged.
        if self.path_depth.is_some() && depth + 1 >= RUSSIAN_ROULETTE_DEPTH {
            let survive = (throughput * bounce.weight).max_element().min(1.0);
            if f64::from(u[4]) >= survive {
                return None;
            }
            bounce.weight /= survive;
        }
        Some(bounce)
    }
}

/// The path stream's numbers at a sample's `depth`-th vertex: which
/// bounce (u[0]), the BSDF's direction (u[1..4]) and Russian roulette
/// (u[4]).
fn path_numbers(sample: SampleKey, depth: u32) -> [f32; 5] {
    let [seed, x, y, s] = sample;
    let mut rng = Stream::Path.rng(&[seed, x, y, s, u64::from(depth)]);
    std::array::from_fn(|_| rng.next_f32())
}

/// The mirror bounce, chosen with probability `p`.
fn mirrored(sp: &SurfacePoint<'_>, p: f32) -> Bounce {
    Bounce { ray: sp.mirror_ray(), weight: sp.mirror.as_dvec3() / f64::from(p), delta: true, transmitted: false }
}

/// The transmitted bounce, chosen with probability `p`, a rough
/// surface's drawn from the uniform numbers `u` (docs/design.md §5.8). It
/// counts the emission it meets, as a mirror's does: the lights light no
/// transmission lobe (shadow rays stop at glass). None: the draw went
/// nowhere.
fn transmitted(sp: &SurfacePoint<'_>, p: f32, u: [f32; 2]) -> Option<Bounce> {
    let (ray, weight) = sp.transmit(u)?;
    Some(Bounce { ray, weight: weight.as_dvec3() / f64::from(p), delta: true, transmitted: true })
}

/// Without the path method, a camera path follows a vertex's delta lobes
/// alone: its mirror, or its transmission, or, where it has both (glass),
/// one of them chosen in proportion to their reflectance by the path
/// stream's first number (docs/design.md §5.8). None: the path ends.
fn delta_bounce(sp: &SurfacePoint<'_>, sample: SampleKey, depth: u32) -> Option<Bounce> {
    let (mirror, transmission) = (luminance(sp.mirror), luminance(sp.transmission));
    if transmission <= 0.0 {
        // No numbers drawn: a mirror's path is what it always was.
        return (sp.mirror != Vec3::ZERO).then(|| mirrored(sp, 1.0));
    }
    let p_mirror = mirror / (mirror + transmission);
    if !p_mirror.is_finite() {
        return None;
    }
    let u = path_numbers(sample, depth);
    if u[0] < p_mirror {
        Some(mirrored(sp, p_mirror))
    } else {
        transmitted(sp, 1.0 - p_mirror, [u[1], u[2]])
    }
}
