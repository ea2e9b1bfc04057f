//! `lightcuts bench rays`: shadow-ray throughput three ways on one scene and
//! machine: (a) Embree alone on a recorded sample of the exact renderer's
//! shadow rays, by single-ray calls and by batch calls; (b) the lightcuts
//! pass, its shadow rays over its time; (c) the exact pass likewise; and,
//! from the lightcuts pass run again with Embree's queries timed, the
//! pass's rate over Embree's on the pass's own rays, traced as it traces
//! them (the share of the pass inside Embree).

use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;

use crate::cli::progress::Progress;
use crate::embree::{PacketWidth, ShadowRay};
use crate::light::Lights;
use crate::render::session::{Mode, Session, SessionError};
use crate::render::PassSettings;
use crate::shading::direct::light_intensity;
use crate::shading::{light_sample, SHADOW_BATCH};
use crate::util::streams::Stream;

/// Largest number of rays recorded for (a): enough for a stable figure,
/// small enough to keep in memory (32 bytes each).
pub const MAX_RECORDED: usize = 4_000_000;

#[derive(Debug, Clone, Serialize)]
pub struct RayFigures {
    pub recorded_rays: usize,
    pub embree_single_mrays_per_s: f64,
    pub embree_batch_mrays_per_s: f64,
    /// The same rays in packets of 4, 8 and 16 (rtcOccluded4/8/16), in the
    /// order the exact renderer casts them (one shading point's lights together).
    pub embree_packet4_mrays_per_s: f64,
    pub embree_packet8_mrays_per_s: f64,
    pub embree_packet16_mrays_per_s: f64,
    pub lightcuts_shadow_rays: u64,
    pub lightcuts_seconds: f64,
    pub lightcuts_mrays_per_s: f64,
    pub exact_shadow_rays: u64,
    pub exact_seconds: f64,
    pub exact_mrays_per_s: f64,
    /// (b) / (a, batch): the share of Embree's raw rate the lightcuts pass keeps.
    pub lightcuts_over_embree: f64,
    /// (b) / (a, packets of 8): the same against Embree's best rate here
    /// (the cut traces its rays in packets of 8).
    pub lightcuts_over_embree_packets: f64,
    /// (c) / (a, batch).
    pub exact_over_embree: f64,
    /// Seconds inside Embree's queries in a second, timed, lightcuts pass
    /// (thread-seconds; with more threads than cores, descheduled time
    /// counts in and out of Embree alike).
    pub lightcuts_timed_embree_seconds: f64,
    /// The pass's rate over Embree's on the same rays as the pass traces
    /// them (its shadow rays, and its camera rays, under 1% of them on
    /// the measuring scenes): the share of the timed pass's
    /// thread-seconds inside Embree.
    /// (a) is Embree on the exact renderer's rays, which are cheaper per
    /// ray than the cut's (docs/notebook/measurements.md, "What the speed targets
    /// leave the cut"); this is the comparison on the same rays.
    pub lightcuts_over_embree_own_rays: f64,
    pub threads: usize,
}

/// The shadow rays the exact renderer casts from the first hits of the
/// pass's camera samples (sample 0 of each pixel), for every `stride`-th pixel.
fn record(session: &Session<'_>, settings: &PassSettings, stride: usize) -> Vec<ShadowRay> {
    let scene = session.scene;
    let camera = scene.camera(settings.width, settings.height);
    let b = settings.bounds;
    let pixels: Vec<(u32, u32)> =
        (b.y0..b.y1).flat_map(|y| (b.x0..b.x1).map(move |x| (x, y))).step_by(stride.max(1)).collect();
    session.pool.install(|| {
        pixels
            .par_iter()
            .flat_map_iter(|&(x, y)| {
                let mut rng = Stream::CameraJitter.rng(&[settings.seed, u64::from(x), u64::from(y), 0]);
                let ray = camera.ray(x as f32 + rng.next_f32(), y as f32 + rng.next_f32());
                let mut rays = Vec::new();
                if let Some(hit) = session.geometry.embree.intersect(&ray) {
                    let sp = session.geometry.surface(&ray, &hit);
                    for group in &session.lights {
                        group.for_each(|light| {
                            if let Some((_, Some(r))) = light_sample(&light, &sp, light_intensity(&light)) {
                                rays.push(r);
                            }
                        });
                    }
                }
                rays
            })
            .collect()
    })
}

/// `mode`: the lightcut mode of the pass (b).
pub fn measure(
    session: &Session<'_>,
    settings: &PassSettings,
    mode: Mode,
    quiet: bool,
) -> Result<RayFigures, SessionError> {
    let threads = session.pool.current_num_threads();
    // Pixels to record so that about MAX_RECORDED rays are kept.
    let expected = settings.bounds.area() as f64 * session.lights.iter().map(Lights::len).sum::<usize>().max(1) as f64;
    let stride = (expected / MAX_RECORDED as f64).ceil().max(1.0) as usize;
    let rays = record(session, settings, stride);
    let embree = &session.geometry.embree;
    let rate = |count: usize, seconds: f64| count as f64 / seconds.max(1e-9) / 1e6;

    let start = Instant::now();
    let single: usize = session.pool.install(|| {
        rays.par_chunks(SHADOW_BATCH).map(|chunk| chunk.iter().filter(|r| embree.occluded(&r.to_ray())).count()).sum()
    });
    let single_seconds = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let batch: usize = session.pool.install(|| {
        rays.par_chunks(SHADOW_BATCH)
            .map_init(Vec::new, |occluded, chunk| {
                embree.occluded_batch(chunk, occluded);
                occluded.iter().filter(|&&o| o).count()
            })
            .sum()
    });
    let batch_seconds = start.elapsed().as_secs_f64();
    assert_eq!(single, batch, "single and batch calls disagree on occlusion");
    let packets = |width: PacketWidth| {
        let start = Instant::now();
        let blocked: usize = session.pool.install(|| {
            rays.par_chunks(SHADOW_BATCH)
                .map_init(Vec::new, |occluded, chunk| {
                    embree.occluded_packets(chunk, occluded, width);
                    occluded.iter().filter(|&&o| o).count()
                })
                .sum()
        });
        assert_eq!(blocked, single, "packets of {width:?} and single calls disagree on occlusion");
        rate(rays.len(), start.elapsed().as_secs_f64())
    };
    let (packet4, packet8, packet16) =
        (packets(PacketWidth::Four), packets(PacketWidth::Eight), packets(PacketWidth::Sixteen));
    embree.take_error("tracing the recorded shadow rays")?;

    let progress = Progress::for_stderr("lightcuts", quiet);
    let lightcuts = session.render(settings, mode, &|event| progress.report(event))?;
    let progress = Progress::for_stderr("exact", quiet);
    let exact = session.render(settings, Mode::Exact, &|event| progress.report(event))?;
    // Timing Embree's queries costs two clock reads a call, so it is a pass
    // of its own, and (b) stays untimed.
    let was_timing = crate::embree::timing();
    crate::embree::set_timing(true);
    let before = crate::embree::timed_nanos();
    let progress = Progress::for_stderr("lightcuts, timed", quiet);
    let timed = session.render(settings, mode, &|event| progress.report(event));
    let timed_embree = (crate::embree::timed_nanos() - before) as f64 * 1e-9;
    crate::embree::set_timing(was_timing);
    let timed_thread_seconds = timed?.stats.time.as_secs_f64() * threads as f64;
    let embree_batch = rate(rays.len(), batch_seconds);
    let (lc_rays, ex_rays) = (lightcuts.stats.shading.shadow_rays, exact.stats.shading.shadow_rays);
    let (lc_s, ex_s) = (lightcuts.stats.time.as_secs_f64(), exact.stats.time.as_secs_f64());
    Ok(RayFigures {
        recorded_rays: rays.len(),
        embree_single_mrays_per_s: rate(rays.len(), single_seconds),
        embree_batch_mrays_per_s: embree_batch,
        embree_packet4_mrays_per_s: packet4,
        embree_packet8_mrays_per_s: packet8,
        embree_packet16_mrays_per_s: packet16,
        lightcuts_shadow_rays: lc_rays,
        lightcuts_seconds: lc_s,
        lightcuts_mrays_per_s: rate(lc_rays as usize, lc_s),
        exact_shadow_rays: ex_rays,
        exact_seconds: ex_s,
        exact_mrays_per_s: rate(ex_rays as usize, ex_s),
        lightcuts_over_embree: rate(lc_rays as usize, lc_s) / embree_batch,
        lightcuts_over_embree_packets: rate(lc_rays as usize, lc_s) / packet8,
        exact_over_embree: rate(ex_rays as usize, ex_s) / embree_batch,
        lightcuts_timed_embree_seconds: timed_embree,
        lightcuts_over_embree_own_rays: timed_embree / timed_thread_seconds.max(1e-9),
        threads,
    })
}
