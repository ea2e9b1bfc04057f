//! Radiance along camera paths: direct light from every point light
//! ([LC05] eq. 1) or from a lightcut, plus perfect mirror bounces.
//!
//! Radiance is accumulated in f64: a product M * G * I with intensities up to
//! 1e30 W/sr and G up to 1/epsilon^2 overflows f32. Values are clamped to
//! finite f32 only when a pixel is stored (`render::film::film_value`, which
//! counts every non-finite value it meets).

use std::time::Instant;

use glam::{DVec3, Vec3};

use super::emitter_sampling::{EmitterChoice, EmitterDraw, EmitterSampling};
use super::film::PixelBounds;
use crate::light::Lights;
use crate::light_tree::LightTrees;
use crate::lightcut::multidimensional::{GatherPoint, GatherScratch};
use crate::lightcut::reconstruction::{AnchorBlock, AnchorCut, ReconstructionScratch, ANCHORS};
use crate::lightcut::reuse::ReuseScratch;
use crate::lightcut::{self, CutResult, CutScratch, CutSettings, StochasticScratch};
use crate::shading::{
    BatchBuffers, Bsdf, Choices, Geometry, LightBatch, LightEvaluator, Lobes, SurfaceKey, SurfacePoint,
};
use crate::util::color::luminance;
use crate::util::sampling::{PixelSample, Rng};

/// How direct light is computed at each shading point.
#[derive(Clone, Copy)]
pub enum DirectLighting<'a> {
    /// Every light, one shadow ray each: the reference.
    Exact,
    /// A bounded lightcut ([LC05]) through the scene's light trees.
    Lightcuts { trees: &'a LightTrees, settings: CutSettings },
    /// A stochastic lightcut ([SLC19]): lights drawn per sample.
    StochasticLightcuts { trees: &'a LightTrees, settings: CutSettings },
    /// A multidimensional lightcut ([MDLC06]) per pixel: camera paths only
    /// gather their shading points ([`Integrator::trace`]'s `gather`), and
    /// [`Integrator::gathered_light`] lights them all at once.
    Multidimensional { trees: &'a LightTrees, settings: CutSettings },
}

/// The random stream of a camera sample's shading points: (seed, pixel x,
/// pixel y, sample index), and the bounce is added per point.
pub type SampleKey = [u64; 4];

/// Keeps the stochastic cut's stream apart from the camera's jitter, which
/// is keyed by the same sample.
const STOCHASTIC_STREAM: u64 = 0x5107_c4a5;

/// The key of a pixel's shifts (`PixelSample`), apart from every stream of
/// its samples.
const PIXEL_SAMPLE_STREAM: u64 = 0x91c5_e15a;

/// The key of a reuse block's shifts (`reuse_block_key`), apart
/// from its pixels' (`PIXEL_SAMPLE_STREAM`).
const REUSE_STREAM: u64 = 0x4e05_e0b1;

/// The key of the stratified set of the reuse block (of edge `block`)
/// holding the pixel of sample key `key` (`lightcut::reuse::block_sample`):
/// the seed and the block's corner, so the same for any tile split.
fn reuse_block_key(block: u32, [seed, x, y, _]: SampleKey) -> u64 {
    let block = u64::from(block);
    Rng::from_key(&[seed, x / block * block, y / block * block, block, REUSE_STREAM]).next_u64()
}

/// Keeps the suns' directions apart from the other streams of a sample's
/// shading point.
const SUN_STREAM: u64 = 0x50d1_5c00;

/// The most directions one camera sample draws from a sun's disc at a
/// shading point.
const MOST_SUN_DRAWS: u32 = 16;

/// Keeps the emitters' sampling apart from the other streams of a
/// sample's shading point.
const EMITTER_STREAM: u64 = 0xe4f1_5a3b;

/// The most nodes a stochastic cut has at a path's vertex past a sampled
/// bounce. Any cut is unbiased ([SLC19]; design.md §10.4); a path's noise
/// is mostly its bounces', so a small cut there buys more paths for the
/// time: 16 nodes reached the full cut's error in 61% of its time on the
/// Cornell box and 81% on shiny, where 4 nodes let glossy vertices pick
/// lights badly (docs/notebook/measurements.md).
const SECONDARY_MAX_CUT: usize = 16;

/// Keeps a path's bounces apart from the other streams of its vertex.
const PATH_STREAM: u64 = 0xba7_4ce5;

/// The path method's vertices before Russian roulette may end a path
/// (pbrt-v4 starts it after its second bounce too).
const RUSSIAN_ROULETTE_DEPTH: u32 = 3;

/// Where a path goes from a vertex: the ray, what the path's throughput is
/// multiplied by, and whether it is a mirror's (a delta bounce, whose
/// emission the next vertex counts).
struct Bounce {
    ray: crate::embree::Ray,
    weight: DVec3,
    mirror: bool,
}

/// Most culled back faces a camera or mirror ray passes through before it
/// is taken to see nothing (a bound on a hostile stack of coplanar faces).
const MAX_CULLED_FACES: usize = 64;

/// Reusable per-thread buffers (no allocation per shading point).
#[derive(Default)]
pub struct Scratch {
    batch: BatchBuffers,
    cut: CutScratch,
    stochastic: StochasticScratch,
    gather: GatherScratch,
    choice: EmitterChoice,
    reconstruction: ReconstructionScratch,
    pub(super) anchors: Anchors,
    /// Reuse between pixels (docs/design.md §10.11): a stochastic cut's
    /// buffers per pixel of a block (each keeps its pixel's cuts over the
    /// pixel's samples), the block's draws, and the tile's camera samples
    /// as their blocks traced and lit them, a slot per pixel and sample.
    reuse_cuts: Vec<StochasticScratch>,
    reuse_drawn: Vec<Choices>,
    reuse: ReuseScratch,
    pub(super) reused: BlockSamples,
}

/// The camera samples of one tile as their reuse blocks found them, a
/// slot per pixel and sample index of the tile.
#[derive(Debug, Default)]
pub struct BlockSamples {
    tile: Option<PixelBounds>,
    spp: usize,
    slots: Vec<Option<BlockSample>>,
}

impl BlockSamples {
    /// Empty slots for every sample of `tile` at `spp` samples a pixel.
    pub fn start(&mut self, tile: PixelBounds, spp: u32) {
        self.tile = Some(tile);
        self.spp = spp as usize;
        self.slots.clear();
        self.slots.resize(tile.area() * self.spp, None);
    }

    /// The slot of the sample of key (seed, x, y, s): None outside the tile.
    fn slot(&mut self, [_, x, y, s]: SampleKey) -> Option<&mut Option<BlockSample>> {
        let tile = self.tile?;
        let dx = x.checked_sub(u64::from(tile.x0)).filter(|&dx| dx < u64::from(tile.width()))?;
        let dy = y.checked_sub(u64::from(tile.y0)).filter(|&dy| dy < u64::from(tile.height()))?;
        let s = (s < self.spp as u64).then_some(s)?;
        let index = usize::try_from((dy * u64::from(tile.width()) + dx) * self.spp as u64 + s).ok()?;
        self.slots.get_mut(index)
    }

    /// Keeps `sample` for [`Integrator::trace`] (dropped outside the tile).
    pub fn insert(&mut self, key: SampleKey, sample: BlockSample) {
        if let Some(slot) = self.slot(key) {
            *slot = Some(sample);
        }
    }

    fn clear(&mut self) {
        self.tile = None;
        self.slots.clear();
    }
}

/// A camera sample as its reuse block found it (docs/design.md §10.11):
/// the camera ray as traced (its start past any culled faces), its first
/// hit, and the hit's direct light from the trees (None: no hit, or an
/// unlit one). [`Integrator::trace`] takes the hit rather than trace the
/// same ray again.
#[derive(Debug, Clone)]
pub struct BlockSample {
    ray: crate::embree::Ray,
    hit: Option<crate::embree::Hit>,
    light: Option<CutResult>,
}

impl Scratch {
    /// Forgets what a tile keeps between its pixels: reconstruction cuts'
    /// anchors (the tile's own, made as its pixels need them, so that they
    /// depend on the image alone: docs/design.md §9.6), the stochastic
    /// cut's pixel cuts (docs/design.md §10.9, the blocks' too) and the
    /// light the blocks found (design §10.11).
    pub fn start_tile(&mut self) {
        self.anchors.clear();
        self.stochastic.forget_pixel_cuts();
        self.reuse_cuts.iter_mut().for_each(StochasticScratch::forget_pixel_cuts);
        self.reused.clear();
    }
}

/// A full cut at a corner of a pixel block (reconstruction cuts,
/// docs/design.md §9.6): where it hit, and what it found.
pub struct Anchor {
    surface: SurfaceKey,
    cut: AnchorCut,
}

/// The anchors of a tile (keyed by their corners in image pixels), and the
/// four of the pixel being shaded.
#[derive(Default)]
pub struct Anchors {
    corners: std::collections::HashMap<(u32, u32), Option<usize>>,
    anchors: Vec<Anchor>,
    /// Each block's anchors merged (by their indices), made when a pixel
    /// of the block is first shaded.
    blocks: std::collections::HashMap<[usize; ANCHORS], AnchorBlock>,
    /// The pixel's block corners' anchors; None where a corner saw no
    /// surface (the pixel's points are then cut in full).
    current: Option<[usize; ANCHORS]>,
}

impl Anchors {
    /// Forgets every anchor (a new tile).
    pub fn clear(&mut self) {
        self.corners.clear();
        self.anchors.clear();
        self.blocks.clear();
        self.current = None;
    }

    /// The pixel's anchors, if all four are on the surface of `sp`
    /// (material `material`; `SurfaceKey::holds`).
    fn fitting(&self, material: usize, sp: &SurfacePoint<'_>) -> Option<[usize; ANCHORS]> {
        let current = self.current?;
        current.iter().all(|&i| self.anchors[i].surface.holds(material, sp)).then_some(current)
    }
}

/// Buckets of the cut-size histogram: bucket k counts cuts of 2^k to
/// 2^(k+1) - 1 nodes (bucket 0: cuts of 0 or 1 node).
pub const CUT_HISTOGRAM_BUCKETS: usize = 24;

/// Counters for one shading point or summed over many.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ShadingStats {
    pub shadow_rays: u64,
    pub shading_points: u64,
    /// Sum of cut sizes over shading points (the exact mode's cut is every light).
    pub cut_nodes: u64,
    pub max_cut: u64,
    /// Shading points by cut size (see [`CUT_HISTOGRAM_BUCKETS`]).
    pub cut_histogram: [u64; CUT_HISTOGRAM_BUCKETS],
    /// Surfaces camera paths met (the camera's hit, mirrors' and the path
    /// method's bounces): per camera ray, the mean path length.
    pub path_vertices: u64,
    /// Rays that continued camera paths past a surface (mirrors' and the
    /// path method's bounces).
    pub bounce_rays: u64,
    /// Gather points and gather-tree nodes (the multidimensional mode:
    /// its "shading points" are pixels, its cut nodes (gather, light) pairs).
    pub gather_points: u64,
    pub gather_nodes: u64,
    /// Thread-time spent choosing cuts (in `lightcut::evaluate`, outside
    /// Embree's queries), nanoseconds; counted only while Embree's queries
    /// are timed (`render --stats`).
    pub cut_nanos: u64,
}

impl ShadingStats {
    pub fn add(&mut self, other: &Self) {
        self.shadow_rays += other.shadow_rays;
        self.shading_points += other.shading_points;
        self.cut_nodes += other.cut_nodes;
        self.max_cut = self.max_cut.max(other.max_cut);
        self.cut_nanos += other.cut_nanos;
        self.gather_points += other.gather_points;
        self.gather_nodes += other.gather_nodes;
        self.path_vertices += other.path_vertices;
        self.bounce_rays += other.bounce_rays;
        for (a, b) in self.cut_histogram.iter_mut().zip(&other.cut_histogram) {
            *a += b;
        }
    }

    /// Records one shading point: its cut of `nodes` nodes and its shadow rays.
    pub fn record_point(&mut self, nodes: u64, shadow_rays: u64) {
        self.shading_points += 1;
        self.shadow_rays += shadow_rays;
        self.cut_nodes += nodes;
        self.max_cut = self.max_cut.max(nodes);
        let bucket = (63 - nodes.max(1).leading_zeros()) as usize;
        self.cut_histogram[bucket.min(CUT_HISTOGRAM_BUCKETS - 1)] += 1;
    }
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
}

pub struct Integrator<'a> {
    pub geometry: &'a Geometry<'a>,
    /// The lights of each light group (one entry when the scene names none).
    pub lights: &'a [Lights],
    pub direct: DirectLighting<'a>,
    pub max_mirror_depth: u32,
    /// Whether radiance is also split by light group ([`Integrator::trace`]'s
    /// `groups`): only when the scene names groups.
    pub split_groups: bool,
    /// The light group of each mesh's emission (`Scene::emission_groups`).
    pub emission_group: &'a [usize],
    /// The continuous emitters (environment, area lights) as sharp lobes
    /// sample them, when the scene has any.
    pub emitters: Option<&'a EmitterSampling<'a>>,
    /// Samples per pixel (how many directions each sample draws from a
    /// sun's disc depends on it).
    pub spp: u32,
    /// The path method's `max_depth` (docs/design.md §6.7); None: camera
    /// paths follow mirrors only, to `max_mirror_depth`.
    pub path_depth: Option<u32>,
    /// The camera's pixel footprint, which filters the textures a camera
    /// path reads (docs/design.md §5.3, "MIP maps"); None reads them
    /// unfiltered.
    pub footprint: Option<crate::scene::PixelFootprint>,
}

impl<'a> Integrator<'a> {
    /// Number of light groups the radiance is split into (0: no split).
    #[must_use]
    pub fn group_slots(&self) -> usize {
        if self.split_groups {
            self.lights.len()
        } else {
            0
        }
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
    /// alpha 0); mirrors still show it. In the multidimensional mode,
    /// direct light is not computed here: each shading point joins
    /// `gather` with its path's throughput.
    pub fn trace(
        &self,
        mut ray: crate::embree::Ray,
        sample: SampleKey,
        transparent: bool,
        scratch: &mut Scratch,
        groups: &mut [DVec3],
        gather: &mut Vec<GatherPoint<'a>>,
    ) -> SampleResult {
        let mut result = SampleResult {
            radiance: DVec3::ZERO,
            opaque: false,
            first_ids: None,
            first_hit: None,
            stats: ShadingStats::default(),
        };
        let mut throughput = DVec3::ONE;
        let scene = self.geometry.scene;
        let vertices = self.path_depth.unwrap_or(self.max_mirror_depth + 1);
        // Whether this vertex's ray counts the emission it finds: at the
        // camera and after mirrors, yes; after a sampled bounce, no: the
        // vertex before lit itself by every emitter already (next-event
        // estimation, design.md §6.7).
        let mut sees_emitters = true;
        for depth in 0..vertices {
            // A camera ray its reuse block traced already (design §10.11).
            let block_hit = if depth == 0 {
                scratch.reused.slot(sample).and_then(|b| b.as_ref()).map(|b| (b.ray, b.hit))
            } else {
                None
            };
            let hit = match block_hit {
                Some((traced, hit)) => {
                    ray = traced;
                    hit
                }
                None => self.first_hit(&mut ray),
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
            let (sp, sharp) = self.vertex(&ray, &hit, sample, depth);
            result.stats.path_vertices += 1;
            let mesh = self.geometry.mesh_of(&hit);
            let material = scene.meshes[mesh].material;
            if depth == 0 {
                result.opaque = true;
                result.first_hit = Some(FirstHit { albedo: sp.kd, normal: sp.n, distance: sp.distance });
                result.first_ids = Some((self.geometry.object_of(&hit), material));
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
            // Reconstruction cuts read the pixel's anchors at the camera's hit.
            let anchors = if depth == 0 { scratch.anchors.fitting(material, &sp) } else { None };
            self.next_event(
                &sp,
                sharp,
                sample,
                depth,
                sees_emitters,
                anchors,
                throughput,
                scratch,
                groups,
                gather,
                &mut result,
            );
            if depth + 1 == vertices {
                break;
            }
            let bsdf = sharp.map(|(_, bsdf)| bsdf);
            let Some(bounce) = self.bounce(&sp, bsdf, sample, depth, throughput) else { break };
            result.stats.bounce_rays += 1;
            throughput *= bounce.weight;
            sees_emitters = bounce.mirror;
            ray = bounce.ray;
        }
        result
    }

    /// The shading point where `ray`, the `depth`-th ray of the camera path
    /// of `sample`, hit, and the emitters' sampling with the point's BSDF
    /// when its glossy lobe is too sharp for their stand-in lights.
    fn vertex(
        &self,
        ray: &crate::embree::Ray,
        hit: &crate::embree::Hit,
        sample: SampleKey,
        depth: u32,
    ) -> (SurfacePoint<'a>, Option<(&'a EmitterSampling<'a>, Bsdf)>) {
        let mut sp = self.geometry.surface_seen(ray, hit, self.footprint.as_ref());
        // What the point draws (the stochastic cut's lights, points on
        // triangle lights) is stratified over the pixel's samples
        // (docs/design.md §10.8); keyed by the bounce too.
        sp.sample = Some(self.pixel_sample(sample, depth));
        // A glossy lobe too sharp for some emitter's stand-in lights:
        // they light the diffuse lobe, and the glossy one's light from
        // the continuous emitters is sampled (in every mode alike).
        let sharp = self.emitters.and_then(|e| e.sharp_lobe(&sp).map(|bsdf| (e, bsdf)));
        if sharp.is_some() {
            sp.emitter_lobes = Lobes::DIFFUSE;
        }
        (sp, sharp)
    }

    /// The block edge of reuse between pixels, when the pass uses it (the
    /// stochastic mode with `--reuse`).
    #[must_use]
    pub fn reuse_block(&self) -> Option<u32> {
        match self.direct {
            DirectLighting::StochasticLightcuts { settings, .. } if settings.reuse_block > 0 => {
                Some(settings.reuse_block)
            }
            _ => None,
        }
    }

    /// Reuse between pixels (docs/design.md §10.11): the direct light of
    /// the camera hits of one pixel block at one sample index, `rays[k]`
    /// the camera ray of the sample of key `keys[k]`. Each hit draws its
    /// stochastic cut's lights, and each is lit by every hit's draws
    /// (`lightcut::reuse`). Returns, per pixel, its camera ray as traced,
    /// the ray's first hit, and the hit's direct light from the trees
    /// (None: nothing to shade), as [`Integrator::trace`] would find it at
    /// that hit with its own cut alone, but from all the block's draws.
    pub fn reuse_block_light(
        &self,
        rays: &mut [crate::embree::Ray],
        keys: &[SampleKey],
        scratch: &mut Scratch,
        stats: &mut ShadingStats,
    ) -> Vec<BlockSample> {
        let DirectLighting::StochasticLightcuts { trees, settings } = self.direct else {
            let traced = |ray: &mut crate::embree::Ray| {
                let hit = self.first_hit(ray);
                BlockSample { ray: *ray, hit, light: None }
            };
            return rays.iter_mut().map(traced).collect();
        };
        let timed = crate::embree::timing().then(|| (Instant::now(), crate::embree::thread_timed_nanos()));
        let groups = self.group_slots();
        let n = rays.len();
        scratch.reuse_cuts.resize_with(n, StochasticScratch::default);
        scratch.reuse_drawn.resize_with(n, Choices::default);
        let block_key = reuse_block_key(settings.reuse_block, keys[0]);
        let mut points = Vec::with_capacity(n);
        let mut hits = Vec::with_capacity(n);
        for (k, (ray, &key)) in rays.iter_mut().zip(keys).enumerate() {
            let hit = self.first_hit(ray);
            hits.push(hit);
            let mut point = hit.map(|hit| self.vertex(ray, &hit, key, 0).0).filter(|sp| !sp.material.unlit);
            if let Some(sp) = &mut point {
                // The block's stratified set (design §10.11).
                sp.sample = Some(lightcut::reuse::block_sample(block_key, n, k, key[3] as u32, self.spp));
            }
            points.push(point);
        }
        let embree = &self.geometry.embree;
        let mut results: Vec<CutResult> = Vec::with_capacity(n);
        for (k, (point, &[seed, x, y, s])) in points.iter().zip(keys).enumerate() {
            scratch.reuse_drawn[k].clear();
            let found = match point {
                Some(sp) => {
                    // The stream direct_light draws a camera hit's cut from.
                    let mut rng = Rng::from_key(&[seed, x, y, s, 0, STOCHASTIC_STREAM]);
                    let (cut, drawn) = (&mut scratch.reuse_cuts[k], &mut scratch.reuse_drawn[k]);
                    lightcut::stochastic::draw_lights(trees, sp, embree, &settings, &mut rng, cut, groups, drawn)
                }
                None => CutResult::with_groups(groups),
            };
            results.push(found);
        }
        let evaluators: Vec<_> = points.iter().map(|p| p.as_ref().map(LightEvaluator::new)).collect();
        let same = lightcut::reuse::same_surfaces(&points.iter().map(Option::as_ref).collect::<Vec<_>>());
        crate::util::simd::best(
            #[inline(always)]
            || {
                lightcut::reuse::estimate(
                    &evaluators,
                    &same,
                    &scratch.reuse_drawn,
                    embree,
                    &mut results,
                    &mut scratch.reuse,
                )
            },
        );
        if let Some((start, embree_before)) = timed {
            let embree = crate::embree::thread_timed_nanos() - embree_before;
            stats.cut_nanos += (start.elapsed().as_nanos() as u64).saturating_sub(embree);
        }
        let lit = points.iter().zip(results).map(|(p, r)| p.as_ref().map(|_| r));
        rays.iter().zip(hits).zip(lit).map(|((&ray, hit), light)| BlockSample { ray, hit, light }).collect()
    }

    /// The pixel sample of a camera path's `depth`-th vertex: its pixel's
    /// key (the seed, the pixel and the bounce) and its index among the
    /// pixel's samples.
    fn pixel_sample(&self, [seed, x, y, s]: SampleKey, depth: u32) -> PixelSample {
        let pixel = Rng::from_key(&[seed, x, y, u64::from(depth), PIXEL_SAMPLE_STREAM]).next_u64();
        PixelSample { pixel, index: s as u32, count: self.spp.max(1) }
    }

    /// Lights `sp`, the `depth`-th vertex of a camera path of `throughput`,
    /// by next-event estimation: the cut (or every light, or the gather
    /// cut's gather point), the suns' discs and, for a lobe too `sharp`
    /// for the emitters' stand-ins, the emitters' sampling. Vertices the
    /// camera sees directly or through mirrors (`primary`) draw as many
    /// directions from a sun's disc and the emitters as the pixel's samples
    /// leave them; vertices after a sampled bounce draw one.
    #[allow(clippy::too_many_arguments)]
    fn next_event(
        &self,
        sp: &SurfacePoint<'a>,
        sharp: Option<(&EmitterSampling<'_>, Bsdf)>,
        sample: SampleKey,
        depth: u32,
        primary: bool,
        anchors: Option<[usize; ANCHORS]>,
        throughput: DVec3,
        scratch: &mut Scratch,
        groups: &mut [DVec3],
        gather: &mut Vec<GatherPoint<'a>>,
        result: &mut SampleResult,
    ) {
        if let DirectLighting::Multidimensional { .. } = self.direct {
            gather.push(GatherPoint { sp: sp.clone(), strength: throughput });
        } else {
            let direct =
                self.direct_light(sp, sample, depth, primary, anchors, groups.len(), scratch, &mut result.stats);
            result.stats.record_point(direct.nodes, direct.shadow_rays);
            direct.add_scaled_to(throughput, &mut result.radiance, groups);
        }
        let mut credit = |group: usize, radiance: DVec3| {
            let seen = throughput * radiance;
            result.radiance += seen;
            if let Some(slot) = groups.get_mut(group) {
                *slot += seen;
            }
        };
        let mut rays = 0;
        if self.lights.iter().any(|group| !group.suns.is_empty()) {
            rays += self.sun_light(sp, sample, depth, primary, &mut scratch.batch, &mut credit);
        }
        if let Some((emitters, bsdf)) = &sharp {
            // The pixel's samples (and each sample's draws) take
            // consecutive points of one rotated Kronecker sequence
            // (`kronecker6`): stratified across them, so the sampled
            // lobe's noise falls faster.
            let [seed, x, y, s] = sample;
            let mut rng = Rng::from_key(&[seed, x, y, u64::from(depth), EMITTER_STREAM]);
            let shift: [f32; 6] = std::array::from_fn(|_| rng.next_f32());
            let draws = if primary { emitters.draws } else { 1 };
            emitters.weigh(sp, &mut scratch.choice);
            let scale = 1.0 / f64::from(draws);
            let mut credit = |group: usize, value: DVec3| credit(group, scale * value);
            for j in 0..draws {
                let index = (s as u32).wrapping_mul(draws).wrapping_add(j);
                let u = crate::util::sampling::kronecker6(index, shift);
                rays += self.sampled_emitters(emitters, &scratch.choice, sp, bsdf, u, &mut credit);
            }
        }
        result.stats.shadow_rays += rays;
    }

    /// Where the path goes from `sp`, its `depth`-th vertex: without the
    /// path method, along the mirror (if any); with it, along the mirror
    /// or a direction the BSDF draws (all its lobes), chosen in proportion
    /// to their reflectance, then, past the first vertices, through Russian
    /// roulette on the path's `throughput` so far (docs/design.md §6.7).
    /// `bsdf` is the point's BSDF when the caller built it already. None:
    /// the path ends.
    fn bounce(
        &self,
        sp: &SurfacePoint<'_>,
        bsdf: Option<Bsdf>,
        sample: SampleKey,
        depth: u32,
        throughput: DVec3,
    ) -> Option<Bounce> {
        let mirror = sp.mirror.as_dvec3();
        if self.path_depth.is_none() {
            return (mirror != DVec3::ZERO).then(|| Bounce { ray: sp.mirror_ray(), weight: mirror, mirror: true });
        }
        let [seed, x, y, s] = sample;
        let mut rng = Rng::from_key(&[seed, x, y, s, u64::from(depth), PATH_STREAM]);
        let u: [f32; 5] = std::array::from_fn(|_| rng.next_f32());
        let bsdf = bsdf.unwrap_or_else(|| Bsdf::new(sp));
        let (mirror_weight, bsdf_weight) = (luminance(sp.mirror), bsdf.reflectance_weight());
        let total = mirror_weight + bsdf_weight;
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let p_mirror = mirror_weight / total;
        let mut bounce = if u[0] < p_mirror {
            Bounce { ray: sp.mirror_ray(), weight: mirror / f64::from(p_mirror), mirror: true }
        } else {
            let s = bsdf.sample([u[1], u[2], u[3]], Lobes::ALL)?;
            let weight = s.f_cos.as_dvec3() / (f64::from(s.pdf) * f64::from(1.0 - p_mirror));
            Bounce { ray: sp.ray_towards(s.wi), weight, mirror: false }
        };
        if !(bounce.weight.max_element() > 0.0 && bounce.weight.is_finite()) {
            return None;
        }
        // Russian roulette (pbrt-v4's rule): past the first vertices, a
        // path whose throughput has fallen below 1 goes on with
        // probability equal to its largest component and is divided by it
        // when it does, so that its expected value is unchanged.
        if depth + 1 >= RUSSIAN_ROULETTE_DEPTH {
            let survive = (throughput * bounce.weight).max_element().min(1.0);
            if f64::from(u[4]) >= survive {
                return None;
            }
            bounce.weight /= survive;
        }
        Some(bounce)
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
        &self,
        emitters: &EmitterSampling<'_>,
        choice: &EmitterChoice,
        sp: &SurfacePoint<'_>,
        bsdf: &Bsdf,
        u: [f32; 6],
        credit: &mut impl FnMut(usize, DVec3),
    ) -> u64 {
        let lobes = Lobes::GLOSSY;
        let embree = &self.geometry.embree;
        let mut rays = 0;
        // f cos * L * weight / pdf, for a path found unblocked.
        let value = |f_cos: Vec3, light: Vec3, pdf: f32, other: f32| {
            (f_cos * light).as_dvec3() * (power_heuristic(pdf, other) / f64::from(pdf))
        };
        match emitters.draw(choice, [u[0], u[1], u[2]]) {
            Some((EmitterDraw::Environment(s), probability)) => {
                let f_cos = bsdf.eval(s.wi, lobes);
                if f_cos != Vec3::ZERO && s.radiance != Vec3::ZERO {
                    rays += 1;
                    if !embree.occluded(&sp.shadow_ray_towards(s.wi).to_ray()) {
                        let group = emitters.environment.as_ref().map_or(0, |e| e.group);
                        credit(group, value(f_cos, s.radiance, probability * s.pdf, bsdf.pdf(s.wi, lobes)));
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
                            credit(e.group, value(f_cos, light, pdf, bsdf.pdf(wi, lobes)));
                        }
                    }
                }
            }
            None => {}
        }
        if let Some(s) = bsdf.sample([u[3], u[4], u[5]], lobes) {
            rays += 1;
            let mut ray = sp.ray_towards(s.wi);
            match self.first_hit(&mut ray) {
                None => {
                    if let Some((light, pdf, group)) = emitters.escaped(choice, s.wi) {
                        if light != Vec3::ZERO {
                            credit(group, value(s.f_cos, light, s.pdf, pdf));
                        }
                    }
                }
                Some(hit) => {
                    if let Some(emitter) = emitters.area.of_mesh(self.geometry.mesh_of(&hit)) {
                        let seen = self.geometry.surface(&ray, &hit);
                        if seen.emitted != Vec3::ZERO {
                            let d2 = seen.distance * seen.distance;
                            let pdf = emitters.area_pdf(choice, emitter, d2, seen.ng.dot(s.wi));
                            let group = emitters.area.emitters[emitter].group;
                            credit(group, value(s.f_cos, seen.emitted, s.pdf, pdf));
                        }
                    }
                }
            }
        }
        rays
    }

    /// The first surface `ray` sees: back faces that cull are passed
    /// through (moving the ray's start past them), up to
    /// `MAX_CULLED_FACES` of them.
    fn first_hit(&self, ray: &mut crate::embree::Ray) -> Option<crate::embree::Hit> {
        for _ in 0..MAX_CULLED_FACES {
            let hit = self.geometry.embree.intersect(ray)?;
            if !self.geometry.culls(ray, &hit) {
                return Some(hit);
            }
            // Past the culled triangle: the next float after its distance.
            ray.t_near = f32::from_bits(hit.t.to_bits() + 1).max(hit.t * (1.0 + 1e-6));
        }
        None
    }

    /// The block edge of reconstruction cuts, in pixels, when the pass
    /// uses them (the bounded mode with `--reconstruct`).
    #[must_use]
    pub fn reconstruction_block(&self) -> Option<u32> {
        match self.direct {
            DirectLighting::Lightcuts { settings, .. } if settings.reconstruction_block > 0 => {
                Some(settings.reconstruction_block)
            }
            _ => None,
        }
    }

    /// Makes sure the anchors of the block corners `corners` are in
    /// `scratch.anchors`, each cut in full where camera ray `ray_at(corner)`
    /// first hits a lit surface, and makes them the current pixel's (None
    /// when one of them saw no surface). What the new anchors cost is
    /// counted in `stats` (each is a shading point). `seed` keys each
    /// anchor's point as it keys a camera sample's at the corner. Returns
    /// the camera rays cast.
    pub fn set_anchors(
        &self,
        corners: [(u32, u32); ANCHORS],
        ray_at: impl Fn(u32, u32) -> crate::embree::Ray,
        seed: u64,
        scratch: &mut Scratch,
        stats: &mut ShadingStats,
    ) -> u64 {
        let DirectLighting::Lightcuts { trees, settings } = self.direct else { return 0 };
        let mut camera_rays = 0;
        let mut found = [0usize; ANCHORS];
        let mut all = true;
        for (slot, &(cx, cy)) in found.iter_mut().zip(&corners) {
            let index = match scratch.anchors.corners.get(&(cx, cy)) {
                Some(&index) => index,
                None => {
                    camera_rays += 1;
                    let mut ray = ray_at(cx, cy);
                    let anchor = self.first_hit(&mut ray).and_then(|hit| {
                        let mut sp = self.geometry.surface_seen(&ray, &hit, self.footprint.as_ref());
                        let material = self.geometry.scene.meshes[self.geometry.mesh_of(&hit)].material;
                        if sp.material.unlit {
                            return None;
                        }
                        // The same point as a camera sample there would be.
                        sp.sample = Some(self.pixel_sample([seed, u64::from(cx), u64::from(cy), 0], 0));
                        if self.emitters.and_then(|e| e.sharp_lobe(&sp)).is_some() {
                            sp.emitter_lobes = Lobes::DIFFUSE;
                        }
                        let mut cut = AnchorCut::default();
                        let groups = self.group_slots();
                        let embree = &self.geometry.embree;
                        let result = lightcut::cut::evaluate_anchor(
                            trees,
                            &sp,
                            embree,
                            &settings,
                            &mut scratch.cut,
                            groups,
                            &mut cut,
                        );
                        stats.record_point(result.nodes, result.shadow_rays);
                        Some(Anchor { surface: SurfaceKey::of(material, &sp), cut })
                    });
                    let index = anchor.map(|a| {
                        scratch.anchors.anchors.push(a);
                        scratch.anchors.anchors.len() - 1
                    });
                    scratch.anchors.corners.insert((cx, cy), index);
                    index
                }
            };
            match index {
                Some(i) => *slot = i,
                None => all = false,
            }
        }
        let anchors = &mut scratch.anchors;
        anchors.current = all.then_some(found);
        if all && !anchors.blocks.contains_key(&found) {
            let block = AnchorBlock::merge(found.map(|i| &anchors.anchors[i].cut));
            anchors.blocks.insert(found, block);
        }
        camera_rays
    }

    /// The direct light of a pixel's gather points (from [`Integrator::trace`]
    /// in the multidimensional mode), summed with their strengths, each
    /// group's share added to `groups`; None in the other modes. `pixel` is
    /// (seed, x, y).
    pub fn gathered_light(
        &self,
        points: &[GatherPoint<'a>],
        pixel: [u64; 3],
        scratch: &mut Scratch,
        groups: &mut [DVec3],
        stats: &mut ShadingStats,
    ) -> Option<DVec3> {
        let DirectLighting::Multidimensional { trees, settings } = self.direct else { return None };
        let timed = crate::embree::timing().then(|| (Instant::now(), crate::embree::thread_timed_nanos()));
        let embree = &self.geometry.embree;
        let mut found = lightcut::multidimensional::evaluate(
            trees,
            points,
            embree,
            &settings,
            pixel,
            &mut scratch.gather,
            groups.len(),
        );
        if let Some((start, embree_before)) = timed {
            let embree = crate::embree::thread_timed_nanos() - embree_before;
            stats.cut_nanos += (start.elapsed().as_nanos() as u64).saturating_sub(embree);
        }
        let mut moving = DVec3::ZERO;
        if self.lights.iter().any(|group| !group.moving.is_empty()) {
            for point in points {
                moving += self.moving_light(&point.sp, point.strength, &mut scratch.batch, &mut found.cut);
            }
        }
        found.cut.radiance += moving;
        stats.record_point(found.cut.nodes, found.cut.shadow_rays);
        stats.gather_points += points.len() as u64;
        stats.gather_nodes += found.gather_nodes;
        let mut radiance = DVec3::ZERO;
        found.cut.add_scaled_to(DVec3::ONE, &mut radiance, groups);
        Some(radiance)
    }

    /// The direct light at `sp` by the pass's mode, with `groups` group
    /// slots (0: not split by group); the time spent choosing a cut is
    /// added to `stats`. Past a sampled bounce (not `primary`) a
    /// stochastic cut has at most `SECONDARY_MAX_CUT` nodes. With
    /// `anchors` (a camera hit whose pixel's anchors fit it), the bounded
    /// cut is reconstructed from theirs.
    #[allow(clippy::too_many_arguments)]
    fn direct_light(
        &self,
        sp: &SurfacePoint<'_>,
        sample: SampleKey,
        depth: u32,
        primary: bool,
        anchors: Option<[usize; ANCHORS]>,
        groups: usize,
        scratch: &mut Scratch,
        stats: &mut ShadingStats,
    ) -> CutResult {
        match self.direct {
            DirectLighting::Exact => {
                // Every light, one shadow ray each, in batches; summed group
                // by group, in light order (omni, oriented, directional,
                // spot) within each: deterministic.
                // Run in the CPU's best instruction set (docs/design.md §4).
                crate::util::simd::best(
                    #[inline(always)]
                    || {
                        let mut found = CutResult::with_groups(groups);
                        let mut radiance = DVec3::ZERO;
                        for (g, group) in self.lights.iter().enumerate() {
                            let mut batch = LightBatch::new(&self.geometry.embree, sp, &mut scratch.batch);
                            group.for_each(
                                #[inline(always)]
                                |light| batch.add(&light),
                            );
                            for light in &group.moving {
                                batch.add(&light.at(sp.time));
                            }
                            radiance += found.count_batch(g, &batch.finish());
                        }
                        found.radiance = radiance;
                        found
                    },
                )
            }
            // Its points are gathered, never lit one by one.
            DirectLighting::Multidimensional { .. } => CutResult::with_groups(groups),
            DirectLighting::Lightcuts { trees, settings } | DirectLighting::StochasticLightcuts { trees, settings } => {
                let timed = crate::embree::timing().then(|| (Instant::now(), crate::embree::thread_timed_nanos()));
                let embree = &self.geometry.embree;
                let mut found = if let DirectLighting::Lightcuts { .. } = self.direct {
                    match anchors {
                        Some(found) => {
                            let block = &scratch.anchors.blocks[&found];
                            let scratch = &mut scratch.reconstruction;
                            lightcut::reconstruction::evaluate(trees, sp, embree, &settings, block, scratch, groups)
                        }
                        None => lightcut::evaluate(trees, sp, embree, &settings, &mut scratch.cut, groups),
                    }
                } else if let Some(found) =
                    scratch.reused.slot(sample).filter(|_| depth == 0).and_then(|b| b.as_mut()?.light.take())
                {
                    // Found by the hit's pixel block (design §10.11).
                    found
                } else {
                    let [seed, x, y, s] = sample;
                    let mut rng = Rng::from_key(&[seed, x, y, s, u64::from(depth), STOCHASTIC_STREAM]);
                    let scratch = &mut scratch.stochastic;
                    let mut settings = settings;
                    if !primary {
                        settings.max_cut = settings.max_cut.min(SECONDARY_MAX_CUT);
                    }
                    // A pixel's cut is its camera hits' (design §10.9): a
                    // later vertex's points are spread over the scene.
                    settings.pixel_cut &= depth == 0;
                    lightcut::stochastic::evaluate(trees, sp, embree, &settings, &mut rng, scratch, groups)
                };
                if let Some((start, embree_before)) = timed {
                    let embree = crate::embree::thread_timed_nanos() - embree_before;
                    stats.cut_nanos += (start.elapsed().as_nanos() as u64).saturating_sub(embree);
                }
                let moving = self.moving_light(sp, DVec3::ONE, &mut scratch.batch, &mut found);
                found.radiance += moving;
                found
            }
        }
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
        &self,
        sp: &SurfacePoint<'_>,
        sample: SampleKey,
        depth: u32,
        primary: bool,
        buffers: &mut BatchBuffers,
        credit: &mut impl FnMut(usize, DVec3),
    ) -> u64 {
        let [seed, x, y, s] = sample;
        let mut shadow_rays = 0;
        for (g, group) in self.lights.iter().enumerate().filter(|(_, group)| !group.suns.is_empty()) {
            let mut batch = LightBatch::new(&self.geometry.embree, sp, buffers);
            for (i, sun) in group.suns.iter().enumerate() {
                let key = [seed, x, y, u64::from(depth), SUN_STREAM, g as u64, i as u64];
                let mut rng = Rng::from_key(&key);
                let shift: [f32; 6] = std::array::from_fn(|_| rng.next_f32());
                let draws = if primary { sun.samples.div_ceil(self.spp.max(1)).clamp(1, MOST_SUN_DRAWS) } else { 1 };
                let irradiance = sun.irradiance / draws as f32;
                for j in 0..draws {
                    let index = (s as u32).wrapping_mul(draws).wrapping_add(j);
                    let u = crate::util::sampling::kronecker6(index, shift);
                    let direction = sun.direction_at([u[0], u[1]]);
                    batch.add(&crate::light::Light::Directional(crate::light::DirectionalLight {
                        direction,
                        irradiance,
                    }));
                }
            }
            let batch = batch.finish();
            credit(g, batch.radiance);
            shadow_rays += batch.shadow_rays;
        }
        shadow_rays
    }

    /// The light of the moving lights (in no tree: docs/design.md §13.6)
    /// at `sp`, each where it is at the point's time with a shadow ray of
    /// its own, times `strength`: counted into `found` (each group's share
    /// credited to its slot); returns the radiance, which the caller adds.
    fn moving_light(
        &self,
        sp: &SurfacePoint<'_>,
        strength: DVec3,
        buffers: &mut BatchBuffers,
        found: &mut CutResult,
    ) -> DVec3 {
        let mut radiance = DVec3::ZERO;
        for (g, group) in self.lights.iter().enumerate().filter(|(_, group)| !group.moving.is_empty()) {
            let mut batch = LightBatch::new(&self.geometry.embree, sp, buffers);
            for light in &group.moving {
                batch.add(&light.at(sp.time));
            }
            let mut batch = batch.finish();
            batch.radiance *= strength;
            radiance += found.count_batch(g, &batch);
        }
        radiance
    }
}

/// The power heuristic's weight (Veach and Guibas 1995, exponent 2) of a
/// direction drawn with density `pdf` by one strategy, against `other`'s
/// density for it by the other: pdf^2 / (pdf^2 + other^2).
#[must_use]
pub fn power_heuristic(pdf: f32, other: f32) -> f64 {
    let (a, b) = (f64::from(pdf), f64::from(other));
    a * a / (a * a + b * b)
}
