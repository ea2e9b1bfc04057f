//! Direct light behind one interface (docs/design.md §2.1): each way of
//! lighting a path's vertex from the scene's lights is a [`DirectLight`],
//! and the integrator calls it without knowing which. A method keeps its
//! own settings; each worker thread has its [`DirectWorker`], which owns
//! the method's scratch state and answers the hooks a tile, a pixel and a
//! vertex need. Everything else at a vertex (the suns' discs, the
//! emitters' sampling for sharp lobes, the path's bounce) is the
//! integrator's, the same for every method.
//!
//! Adding a method is a module here that implements the two traits, and a
//! line in `session::Mode::method` (or none, for a method only a test
//! uses: the uniform light sampling of this module's tests is 33 lines of
//! code).

pub mod bounded;
pub mod exact;
pub mod multidimensional;
pub mod stochastic;

use std::time::Instant;

use glam::DVec3;

use super::stats::ShadingStats;
use super::tracer::{SampleKey, Tracer};
use super::PassSettings;
use crate::embree::{Hit, Ray};
use crate::lightcut::CutResult;
use crate::scene::Camera;
use crate::shading::SurfacePoint;

/// One way of choosing the lights that light a vertex.
pub trait DirectLight<'a>: Sync {
    /// A worker thread's state for this method: its scratch buffers, and
    /// what it keeps over a tile (anchors, reuse blocks) or a pixel (its
    /// cut, its gather points).
    fn worker<'m>(&'m self) -> Box<dyn DirectWorker<'a> + 'm>
    where
        'a: 'm;
}

/// What a tile's hooks see of the pass: its camera and its settings.
#[derive(Clone, Copy)]
pub struct Frame<'f> {
    pub camera: &'f Camera,
    pub settings: &'f PassSettings,
}

/// A vertex of a camera path, as the integrator hands it to a method.
/// A point in a medium (no normal, a phase function) will be another
/// kind of vertex here; the methods light points through `SurfacePoint`'s
/// light evaluator, which is what it will have to provide.
pub struct Vertex<'v, 'a> {
    pub sp: &'v SurfacePoint<'a>,
    /// The sample whose path this is, and the vertex's bounce (0: the
    /// camera's hit).
    pub sample: SampleKey,
    pub depth: u32,
    /// Seen by the camera directly or through mirrors (a path past a
    /// sampled bounce is not: its methods may spend less there).
    pub primary: bool,
    /// The material index of the surface the vertex is on.
    pub material: usize,
    /// The path's throughput up to the vertex, which the integrator scales
    /// a method's light by (a method that defers its light to the pixel's
    /// end scales it itself).
    pub throughput: DVec3,
}

/// A worker thread's instance of a [`DirectLight`] method. The hooks are
/// called in order: [`start_tile`](Self::start_tile) before a tile's
/// first pixel, [`start_pixel`](Self::start_pixel) before a pixel's
/// samples, [`light`](Self::light) at every vertex of their paths,
/// [`finish_pixel`](Self::finish_pixel) after them. Each may cast camera
/// rays of its own (returned, to count in the pass's totals) and counts
/// what its shading points cost in `stats`.
pub trait DirectWorker<'a> {
    /// Before the first pixel of `tile`: forgets what the previous tile
    /// kept. Returns the camera rays cast.
    fn start_tile(
        &mut self,
        tracer: &Tracer<'a>,
        frame: Frame<'_>,
        tile: super::PixelBounds,
        stats: &mut ShadingStats,
    ) -> u64 {
        let _ = (tracer, frame, tile, stats);
        0
    }

    /// Before the samples of pixel `(x, y)`. Returns the camera rays cast.
    fn start_pixel(
        &mut self,
        tracer: &Tracer<'a>,
        frame: Frame<'_>,
        pixel: (u32, u32),
        stats: &mut ShadingStats,
    ) -> u64 {
        let _ = (tracer, frame, pixel, stats);
        0
    }

    /// The camera ray of `sample` as the method traced it already (its
    /// start past culled faces) and its first hit, when it did.
    fn traced(&mut self, sample: SampleKey) -> Option<(Ray, Option<Hit>)> {
        let _ = sample;
        None
    }

    /// The direct light at `vertex` towards the path (before its
    /// throughput), with what it cost; None when the method defers it to
    /// [`finish_pixel`](Self::finish_pixel).
    fn light(&mut self, tracer: &Tracer<'a>, vertex: &Vertex<'_, 'a>, stats: &mut ShadingStats) -> Option<CutResult>;

    /// After the samples of a pixel, `pixel` (seed, x, y): the light the
    /// method deferred, summed with the paths' throughputs, each group's
    /// share added to `groups`.
    fn finish_pixel(
        &mut self,
        tracer: &Tracer<'a>,
        pixel: [u64; 3],
        groups: &mut [DVec3],
        stats: &mut ShadingStats,
    ) -> Option<DVec3> {
        let _ = (tracer, pixel, groups, stats);
        None
    }
}

/// `f()`, its thread-time outside Embree's queries added to
/// `stats.cut_nanos` while Embree's queries are timed (`render --stats`):
/// the time spent choosing cuts.
pub(crate) fn timed_cut<R>(stats: &mut ShadingStats, f: impl FnOnce() -> R) -> R {
    let timed = crate::embree::timing().then(|| (Instant::now(), crate::embree::thread_timed_nanos()));
    let result = f();
    if let Some((start, embree_before)) = timed {
        let embree = crate::embree::thread_timed_nanos() - embree_before;
        stats.cut_nanos += (start.elapsed().as_nanos() as u64).saturating_sub(embree);
    }
    result
}

#[cfg(test)]
mod tests;
