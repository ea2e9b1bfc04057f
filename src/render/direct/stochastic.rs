//! The stochastic method: a stochastic lightcut ([SLC19]; docs/design.md
//! §10) at every vertex, its lights drawn per sample, the camera hits'
//! cut kept over a pixel's samples (design §10.9), and with reuse between
//! pixels (design §10.11) each camera hit lit by the draws of its whole
//! pixel block.

use glam::DVec3;

use super::{timed_cut, DirectLight, DirectWorker, Frame, Vertex};
use crate::embree::{Hit, Ray};
use crate::light_tree::LightTrees;
use crate::lightcut::reuse::ReuseScratch;
use crate::lightcut::{self, CutResult, CutSettings, StochasticScratch};
use crate::render::stats::ShadingStats;
use crate::render::tracer::{SampleKey, Tracer};
use crate::render::{PixelBounds, PixelRays};
use crate::shading::{BatchBuffers, Choices, LightEvaluator};
use crate::util::streams::Stream;

/// The most nodes a stochastic cut has at a path's vertex past a sampled
/// bounce. Any cut is unbiased ([SLC19]; docs/design.md §10.4); a path's
/// noise is mostly its bounces', so a small cut there buys more paths for
/// the time: 16 nodes reached the full cut's error in 61% of its time on
/// the Cornell box and 81% on shiny, where 4 nodes let glossy vertices
/// pick lights badly (docs/notebook/measurements.md).
const SECONDARY_MAX_CUT: usize = 16;

/// Stochastic lightcuts: each cut node's light drawn per sample.
pub struct Stochastic<'a> {
    pub trees: &'a LightTrees,
    pub settings: CutSettings,
}

impl<'a> DirectLight<'a> for Stochastic<'_> {
    fn worker<'m>(&'m self) -> Box<dyn DirectWorker<'a> + 'm>
    where
        'a: 'm,
    {
        Box::new(StochasticWorker {
            method: self,
            cut: StochasticScratch::default(),
            batch: BatchBuffers::default(),
            reuse_cuts: Vec::new(),
            reuse_drawn: Vec::new(),
            reuse: ReuseScratch::default(),
            reused: BlockSamples::default(),
        })
    }
}

struct StochasticWorker<'m, 't> {
    method: &'m Stochastic<'t>,
    cut: StochasticScratch,
    batch: BatchBuffers,
    /// Reuse between pixels (docs/design.md §10.11): a stochastic cut's
    /// buffers per pixel of a block (each keeps its pixel's cuts over the
    /// pixel's samples), the block's draws, and the tile's camera samples
    /// as their blocks traced and lit them, a slot per pixel and sample.
    reuse_cuts: Vec<StochasticScratch>,
    reuse_drawn: Vec<Choices>,
    reuse: ReuseScratch,
    reused: BlockSamples,
}

impl<'a> DirectWorker<'a> for StochasticWorker<'_, '_> {
    /// Forgets the pixel cuts (docs/design.md §10.9, the blocks' too);
    /// with reuse, traces and lights every camera sample of the tile by
    /// its pixel block (design §10.11).
    fn start_tile(
        &mut self,
        tracer: &Tracer<'a>,
        frame: Frame<'_>,
        tile: PixelBounds,
        stats: &mut ShadingStats,
    ) -> u64 {
        self.cut.forget_pixel_cuts();
        self.reuse_cuts.iter_mut().for_each(StochasticScratch::forget_pixel_cuts);
        self.reused.clear();
        match self.method.settings.reuse_block {
            0 => 0,
            block => self.reuse_blocks(tracer, frame, tile, block, stats),
        }
    }

    fn traced(&mut self, sample: SampleKey) -> Option<(Ray, Option<Hit>)> {
        self.reused.slot(sample).and_then(|b| b.as_ref()).map(|b| (b.ray, b.hit))
    }

    fn light(&mut self, tracer: &Tracer<'a>, vertex: &Vertex<'_, 'a>, stats: &mut ShadingStats) -> Option<CutResult> {
        let (Stochastic { trees, settings }, sp) = (self.method, vertex.sp);
        let (sample, depth) = (vertex.sample, vertex.depth);
        let (groups, embree) = (tracer.group_slots(), &tracer.geometry.embree);
        let mut found = timed_cut(stats, || {
            // Found by the hit's pixel block (design §10.11).
            let reused = self.reused.slot(sample).filter(|_| depth == 0).and_then(|b| b.as_mut()?.light.take());
            reused.unwrap_or_else(|| {
                let [seed, x, y, s] = sample;
                let mut rng = Stream::Stochastic.rng(&[seed, x, y, s, u64::from(depth)]);
                let mut settings = *settings;
                if !vertex.primary {
                    settings.max_cut = settings.max_cut.min(SECONDARY_MAX_CUT);
                }
                // A pixel's cut is its camera hits' (design §10.9): a
                // later vertex's points are spread over the scene.
                settings.pixel_cut &= depth == 0;
                lightcut::stochastic::evaluate(trees, sp, embree, &settings, &mut rng, &mut self.cut, groups)
            })
        });
        let moving = tracer.moving_light(sp, DVec3::ONE, &mut self.batch, &mut found);
        found.radiance += moving;
        Some(found)
    }
}

impl StochasticWorker<'_, '_> {
    /// Reuse between pixels (docs/design.md §10.11): every camera sample
    /// of `tile` traced and its hit lit by its `block` x `block` pixel
    /// block at its sample index, kept for [`DirectWorker::traced`] and
    /// [`DirectWorker::light`] to take (so the pixel loop traces no camera
    /// ray again). Blocks are fixed by the film (their corners at
    /// multiples of `block`, cut by its edges), not by the tile: a tile
    /// that holds part of a block casts the whole block's rays, so each
    /// pixel's light is the same in any tile split. What the other pixels'
    /// rays cost counts in the pass's totals (`stats`), not in a pixel's
    /// AOVs. Returns the camera rays cast.
    fn reuse_blocks(
        &mut self,
        tracer: &Tracer<'_>,
        frame: Frame<'_>,
        tile: PixelBounds,
        block: u32,
        stats: &mut ShadingStats,
    ) -> u64 {
        let Frame { camera, settings } = frame;
        let mut camera_rays = 0;
        let mut pixels = Vec::new();
        self.reused.start(tile, settings.spp);
        for by in (tile.y0 / block * block..tile.y1).step_by(block as usize) {
            for bx in (tile.x0 / block * block..tile.x1).step_by(block as usize) {
                pixels.clear();
                for y in by..(by + block).min(settings.height) {
                    for x in bx..(bx + block).min(settings.width) {
                        pixels.push(PixelRays::new(camera, settings, x, y));
                    }
                }
                for s in 0..settings.spp {
                    let mut rays: Vec<Ray> = pixels.iter().map(|p| p.sample(s)).collect();
                    let keys: Vec<_> =
                        pixels.iter().map(|p| [settings.seed, u64::from(p.x), u64::from(p.y), u64::from(s)]).collect();
                    camera_rays += rays.len() as u64;
                    let found = timed_cut(stats, || self.block_light(tracer, &mut rays, &keys));
                    for (key, found) in keys.into_iter().zip(found) {
                        self.reused.insert(key, found);
                    }
                }
            }
        }
        camera_rays
    }

    /// The direct light of the camera hits of one pixel block at one
    /// sample index, `rays[k]` the camera ray of the sample of key
    /// `keys[k]`. Each hit draws its stochastic cut's lights, and each is
    /// lit by every hit's draws (`lightcut::reuse`). Returns, per pixel,
    /// its camera ray as traced, the ray's first hit, and the hit's direct
    /// light from the trees (None: nothing to shade), as the method would
    /// find it at that hit with its own cut alone, but from all the
    /// block's draws.
    fn block_light(&mut self, tracer: &Tracer<'_>, rays: &mut [Ray], keys: &[SampleKey]) -> Vec<BlockSample> {
        let Stochastic { trees, settings } = self.method;
        let groups = tracer.group_slots();
        let n = rays.len();
        self.reuse_cuts.resize_with(n, StochasticScratch::default);
        self.reuse_drawn.resize_with(n, Choices::default);
        let block_key = reuse_block_key(settings.reuse_block, keys[0]);
        let mut points = Vec::with_capacity(n);
        let mut hits = Vec::with_capacity(n);
        for (k, (ray, &key)) in rays.iter_mut().zip(keys).enumerate() {
            let hit = tracer.first_hit(ray);
            hits.push(hit);
            let mut point = hit.map(|hit| tracer.vertex(ray, &hit, key, 0).0).filter(|sp| !sp.material.unlit);
            if let Some(sp) = &mut point {
                // The block's stratified set (design §10.11).
                sp.sample = Some(lightcut::reuse::block_sample(block_key, n, k, key[3] as u32, tracer.spp));
            }
            points.push(point);
        }
        let embree = &tracer.geometry.embree;
        let mut results: Vec<CutResult> = Vec::with_capacity(n);
        for (k, (point, &[seed, x, y, s])) in points.iter().zip(keys).enumerate() {
            self.reuse_drawn[k].clear();
            let found = match point {
                Some(sp) => {
                    // The stream `light` draws a camera hit's cut from.
                    let mut rng = Stream::Stochastic.rng(&[seed, x, y, s, 0]);
                    let (cut, drawn) = (&mut self.reuse_cuts[k], &mut self.reuse_drawn[k]);
                    lightcut::stochastic::draw_lights(trees, sp, embree, settings, &mut rng, cut, groups, drawn)
                }
                None => CutResult::with_groups(groups),
            };
            results.push(found);
        }
        let evaluators: Vec<_> = points.iter().map(|p| p.as_ref().map(LightEvaluator::new)).collect();
        let same = lightcut::reuse::same_surfaces(&points.iter().map(Option::as_ref).collect::<Vec<_>>());
        crate::util::simd::best(
            #[inline(always)]
            || lightcut::reuse::estimate(&evaluators, &same, &self.reuse_drawn, embree, &mut results, &mut self.reuse),
        );
        let lit = points.iter().zip(results).map(|(p, r)| p.as_ref().map(|_| r));
        rays.iter().zip(hits).zip(lit).map(|((&ray, hit), light)| BlockSample { ray, hit, light }).collect()
    }
}

/// The key of the stratified set of the reuse block (of edge `block`)
/// holding the pixel of sample key `key` (`lightcut::reuse::block_sample`):
/// the seed and the block's corner, so the same for any tile split.
fn reuse_block_key(block: u32, [seed, x, y, _]: SampleKey) -> u64 {
    let block = u64::from(block);
    Stream::ReuseBlock.rng(&[seed, x / block * block, y / block * block, block]).next_u64()
}

/// The camera samples of one tile as their reuse blocks found them, a
/// slot per pixel and sample index of the tile.
#[derive(Debug, Default)]
struct BlockSamples {
    tile: Option<PixelBounds>,
    spp: usize,
    slots: Vec<Option<BlockSample>>,
}

impl BlockSamples {
    /// Empty slots for every sample of `tile` at `spp` samples a pixel.
    fn start(&mut self, tile: PixelBounds, spp: u32) {
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

    /// Keeps `sample` for the pixel loop (dropped outside the tile).
    fn insert(&mut self, key: SampleKey, sample: BlockSample) {
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
/// unlit one).
#[derive(Debug, Clone)]
struct BlockSample {
    ray: Ray,
    hit: Option<Hit>,
    light: Option<CutResult>,
}
