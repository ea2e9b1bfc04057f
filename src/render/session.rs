//! One scene ready to render: its worker pool and its Embree geometry, with
//! passes in either mode. Shared by `render`, `sweep` and the benchmarks.

use std::time::{Duration, Instant};

use super::geometry::{Geometry, GeometryError};
use super::integrator::{DirectLighting, Integrator};
use super::progress::Progress;
use super::{render, thread_pool, vpl, Film, PassSettings, PassStats};
use crate::embree::{Device, EmbreeError};
use crate::light_tree::LightKind;
use crate::lightcut::cut::{CutSettings, LightTrees};
use crate::scene::Scene;

/// Failure to prepare a scene for rendering.
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    /// Embree failed (out of memory, unsupported CPU).
    #[error(transparent)]
    Embree(#[from] EmbreeError),
    /// A shape could not be handed to Embree.
    #[error("{file}: {source}")]
    Geometry { file: std::path::PathBuf, source: GeometryError },
    /// The worker threads could not start.
    #[error("cannot start {threads} worker threads: {message}")]
    Threads { threads: usize, message: String },
}

pub struct Session<'s> {
    pub scene: &'s Scene,
    pub pool: rayon::ThreadPool,
    pub geometry: Geometry<'s>,
}

/// A finished pass.
pub struct PassResult {
    pub film: Film,
    pub stats: PassStats,
    /// Wall time of the pass including the tree build, seconds.
    pub seconds: f64,
    /// Per tree built: kind, lights, build time.
    pub trees: Vec<(LightKind, usize, Duration)>,
    pub tree_bytes: usize,
    /// Virtual point lights traced for indirect light, and the time it took.
    pub vpls: usize,
    pub vpl_time: Duration,
    /// Lights of the pass, by kind (the scene's plus the VPLs): omni, oriented, directional.
    pub lights: [usize; 3],
}

impl<'s> Session<'s> {
    /// `threads`: 0 for one per CPU.
    pub fn try_new(scene: &'s Scene, threads: usize) -> Result<Self, SessionError> {
        let pool = thread_pool(threads).map_err(|e| SessionError::Threads { threads, message: e.to_string() })?;
        let device = Device::try_new()?;
        let geometry = Geometry::try_new(&device, scene)
            .map_err(|source| SessionError::Geometry { file: scene.path.clone(), source })?;
        Ok(Self { scene, pool, geometry })
    }

    /// Renders one pass: exact when `cut` is None, else lightcuts (building
    /// the light trees first, timed as part of the pass).
    pub fn render(&self, settings: &PassSettings, cut: Option<CutSettings>, progress: &Progress) -> PassResult {
        let start = Instant::now();
        // Indirect light: VPLs for this seed, added to the scene's oriented lights.
        let (lights, vpls) = match self.scene.indirect {
            Some(indirect) => {
                let vpls =
                    self.pool.install(|| vpl::trace(&self.geometry, &self.scene.lights, indirect, settings.seed));
                let count = vpls.len();
                let mut lights = self.scene.lights.clone();
                lights.oriented.extend(vpls);
                (std::borrow::Cow::Owned(lights), count)
            }
            None => (std::borrow::Cow::Borrowed(&self.scene.lights), 0),
        };
        let vpl_time = start.elapsed();
        let trees = cut.map(|_| self.pool.install(|| LightTrees::build(&lights, settings.seed)));
        let direct = match (&trees, cut) {
            (Some(trees), Some(settings)) => DirectLighting::Lightcuts { trees, settings },
            _ => DirectLighting::Exact,
        };
        let integrator = Integrator {
            geometry: &self.geometry,
            lights: &lights,
            direct,
            max_mirror_depth: self.scene.max_mirror_depth,
        };
        let camera = self.scene.camera(settings.width, settings.height);
        let (film, stats) = self.pool.install(|| render(&integrator, &camera, settings, progress));
        let seconds = start.elapsed().as_secs_f64();
        let (tree_list, tree_bytes) = match &trees {
            Some(t) => (
                t.trees.iter().zip(&t.build_times).map(|(tree, time)| (tree.kind, tree.light_count(), *time)).collect(),
                t.memory_bytes(),
            ),
            None => (Vec::new(), 0),
        };
        let counts = [lights.omni.len(), lights.oriented.len(), lights.directional.len()];
        PassResult { film, stats, seconds, trees: tree_list, tree_bytes, vpls, vpl_time, lights: counts }
    }
}
