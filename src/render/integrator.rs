//! Radiance along camera paths: direct light from every point light
//! ([LC05] eq. 1) or from a lightcut, plus perfect mirror bounces.
//!
//! Radiance is accumulated in f64: a product M * G * I with intensities up to
//! 1e30 W/sr and G up to 1/epsilon^2 overflows f32. Values are clamped to
//! finite f32 only when a pixel is stored (see `film_value`).

use std::time::Instant;

use glam::{DVec3, Vec3};

use crate::light::Lights;
use crate::light_tree::LightTrees;
use crate::lightcut::{self, CutScratch, CutSettings, StochasticScratch};
use crate::shading::{BatchBuffers, Geometry, LightBatch, SurfacePoint};
use crate::util::sampling::Rng;

/// How direct light is computed at each shading point.
#[derive(Clone, Copy)]
pub enum DirectLighting<'a> {
    /// Every light, one shadow ray each: the reference.
    Exact,
    /// A bounded lightcut ([LC05]) through the scene's light trees.
    Lightcuts { trees: &'a LightTrees, settings: CutSettings },
    /// A stochastic lightcut ([SLC19]): lights drawn per sample.
    StochasticLightcuts { trees: &'a LightTrees, settings: CutSettings },
}

/// The random stream of a camera sample's shading points: (seed, pixel x,
/// pixel y, sample index), and the bounce is added per point.
pub type SampleKey = [u64; 4];

/// Keeps the stochastic cut's stream apart from the camera's jitter, which
/// is keyed by the same sample.
const STOCHASTIC_STREAM: u64 = 0x5107_c4a5;

/// Reusable per-thread buffers (no allocation per shading point).
#[derive(Default)]
pub struct Scratch {
    batch: BatchBuffers,
    cut: CutScratch,
    stochastic: StochasticScratch,
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
    pub first_hit: Option<FirstHit>,
    pub stats: ShadingStats,
}

pub struct Integrator<'a> {
    pub geometry: &'a Geometry<'a>,
    pub lights: &'a Lights,
    pub direct: DirectLighting<'a>,
    pub max_mirror_depth: u32,
}

impl Integrator<'_> {
    /// Radiance arriving at the camera along `ray` (camera paths bounce only
    /// off mirrors; every other surface is shaded by direct light).
    pub fn trace(&self, mut ray: crate::embree::Ray, sample: SampleKey, scratch: &mut Scratch) -> SampleResult {
        let mut result = SampleResult { radiance: DVec3::ZERO, first_hit: None, stats: ShadingStats::default() };
        let mut throughput = DVec3::ONE;
        for depth in 0..=self.max_mirror_depth {
            let Some(hit) = self.geometry.embree.intersect(&ray) else {
                // The environment, seen directly or in a mirror.
                if let Some(environment) = &self.geometry.scene.environment {
                    result.radiance += throughput * environment.map.radiance(ray.direction.normalize()).as_dvec3();
                }
                break;
            };
            let sp = self.geometry.surface(&ray, &hit);
            if depth == 0 {
                result.first_hit = Some(FirstHit { albedo: sp.kd, normal: sp.n, distance: sp.distance });
            }
            // Emitters are seen with their radiance (they reflect nothing).
            result.radiance += throughput * sp.emitted.as_dvec3();
            let direct = self.direct_light(&sp, sample, depth, scratch, &mut result.stats);
            result.radiance += throughput * direct;
            if !sp.material.has_mirror() || depth == self.max_mirror_depth {
                break;
            }
            throughput *= sp.material.mirror.as_dvec3();
            ray = sp.mirror_ray();
        }
        result
    }

    fn direct_light(
        &self,
        sp: &SurfacePoint<'_>,
        sample: SampleKey,
        depth: u32,
        scratch: &mut Scratch,
        stats: &mut ShadingStats,
    ) -> DVec3 {
        match self.direct {
            DirectLighting::Exact => {
                // Every light, one shadow ray each, in batches; summed in
                // light order (omni, oriented, directional): deterministic.
                let mut batch = LightBatch::new(&self.geometry.embree, sp, &mut scratch.batch);
                self.lights.for_each(|light| batch.add(&light));
                let found = batch.finish();
                stats.record_point(found.lights, found.shadow_rays);
                found.radiance
            }
            DirectLighting::Lightcuts { trees, settings } | DirectLighting::StochasticLightcuts { trees, settings } => {
                let timed = crate::embree::timing().then(|| (Instant::now(), crate::embree::thread_timed_nanos()));
                let embree = &self.geometry.embree;
                let found = if let DirectLighting::Lightcuts { .. } = self.direct {
                    lightcut::evaluate(trees, sp, embree, &settings, &mut scratch.cut)
                } else {
                    let [seed, x, y, s] = sample;
                    let mut rng = Rng::from_key(&[seed, x, y, s, u64::from(depth), STOCHASTIC_STREAM]);
                    lightcut::stochastic::evaluate(trees, sp, embree, &settings, &mut rng, &mut scratch.stochastic)
                };
                if let Some((start, embree_before)) = timed {
                    let embree = crate::embree::thread_timed_nanos() - embree_before;
                    stats.cut_nanos += (start.elapsed().as_nanos() as u64).saturating_sub(embree);
                }
                stats.record_point(found.nodes, found.shadow_rays);
                found.radiance
            }
        }
    }
}

/// A finite f32 for the film: NaN becomes 0 and magnitudes beyond f32's
/// range are clamped to the largest finite value, so no NaN or Inf ever
/// reaches a pixel.
#[must_use]
pub fn film_value(x: f64) -> f32 {
    if x.is_nan() {
        0.0
    } else {
        x.clamp(f64::from(f32::MIN), f64::from(f32::MAX)) as f32
    }
}
