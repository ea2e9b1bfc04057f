//! One scene ready to render: its lights, its worker pool and its Embree
//! geometry, with passes in either mode. Shared by `render`, `sweep` and the
//! benchmarks.

use std::sync::OnceLock;
use std::time::{Duration, Instant};

use super::direct::DirectLight;
use super::direct::{bounded::Bounded, exact::Exact, multidimensional::Multidimensional, stochastic::Stochastic};
use super::integrator::Integrator;
use super::tracer::Tracer;
use super::{render, thread_pool, vpl, Film, PassProgress, PassSettings, PassStats, TextureFilter};
use crate::embree::{Device, EmbreeError};
use crate::light::{EmitterLeaves, LightKind, Lights};
use crate::light_tree::LightTrees;
use crate::lightcut::CutSettings;
use crate::scene::{Indirect, Scene};
use crate::shading::{Geometry, GeometryError};

/// How a pass computes direct light at each shading point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Mode {
    /// Every light, one shadow ray each.
    Exact,
    /// Lightcuts with representatives fixed when the tree is built ([LC05]).
    Bounded(CutSettings),
    /// Stochastic lightcuts: lights drawn per sample ([SLC19]).
    Stochastic(CutSettings),
    /// Multidimensional lightcuts: one cut per pixel through (gather
    /// cluster, light cluster) pairs ([MDLC06]).
    Multidimensional(CutSettings),
}

impl Mode {
    /// How area lights become the trees' leaves: whole triangles drawn by
    /// solid angle for the stochastic cut, which draws a light per cut node
    /// and sample; their parts for the others, whose lights stay put over a
    /// pixel's samples (docs/design.md §6.1).
    #[must_use]
    pub fn emitter_leaves(&self) -> EmitterLeaves {
        match self {
            Self::Stochastic(_) => EmitterLeaves::Whole,
            Self::Exact | Self::Bounded(_) | Self::Multidimensional(_) => EmitterLeaves::Parts,
        }
    }

    /// The cut's settings, for the three cut modes (bounded, stochastic,
    /// multidimensional).
    #[must_use]
    pub fn cut(&self) -> Option<CutSettings> {
        match self {
            Self::Exact => None,
            Self::Bounded(c) | Self::Stochastic(c) | Self::Multidimensional(c) => Some(*c),
        }
    }

    /// A cut's settings as the header shows them (`group_error` and
    /// `cut_draws`, `resampled_rays`, `reconstruction_block` and `reuse_block` only when
    /// they are not the default).
    fn settings(c: &CutSettings) -> String {
        let mut text = format!("error={} max_cut={}", c.error, c.max_cut);
        if c.group_error == crate::lightcut::GroupError::Pixel {
            text += " group_error=pixel";
        }
        if c.cut_draws > 0 {
            text += &format!(" cut_draws={}", c.cut_draws);
        }
        if c.resampled_rays > 0 {
            text += &format!(" resampled_rays={}", c.resampled_rays);
        }
        if c.reconstruction_block > 0 {
            text += &format!(" reconstruction_block={}", c.reconstruction_block);
        }
        if c.reuse_block > 0 {
            text += &format!(" reuse_block={}", c.reuse_block);
        }
        text
    }

    /// The method as a [`DirectLight`] over `trees` (the scene's light
    /// trees, which the cut methods need): the one list of the methods.
    #[must_use]
    pub fn method<'t>(&self, trees: Option<&'t LightTrees>) -> Box<dyn for<'a> DirectLight<'a> + 't> {
        match (*self, trees) {
            (Self::Bounded(settings), Some(trees)) => Box::new(Bounded { trees, settings }),
            (Self::Stochastic(settings), Some(trees)) => Box::new(Stochastic { trees, settings }),
            (Self::Multidimensional(settings), Some(trees)) => Box::new(Multidimensional { trees, settings }),
            _ => Box::new(Exact),
        }
    }

    /// The mode as the EXR header and the reports name it.
    #[must_use]
    pub fn describe(&self) -> String {
        match self {
            Self::Exact => "exact".into(),
            Self::Bounded(c) => format!("lightcuts {}", Self::settings(c)),
            Self::Stochastic(c) if !c.pixel_cut => format!("stochastic lightcuts {} cut_per_sample", Self::settings(c)),
            Self::Stochastic(c) => format!("stochastic lightcuts {}", Self::settings(c)),
            Self::Multidimensional(c) => format!("multidimensional lightcuts {}", Self::settings(c)),
        }
    }
}

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
    #[error("cannot start {threads} worker threads: {source}")]
    Threads {
        threads: usize,
        #[source]
        source: rayon::ThreadPoolBuildError,
    },
}

pub struct Session<'s> {
    pub scene: &'s Scene,
    /// The scene's lights by light group (one entry when it names no
    /// group), without the VPLs, which each pass traces.
    pub lights: Vec<Lights>,
    /// The same with area lights as whole triangles (`EmitterLeaves::Whole`,
    /// the stochastic cut's), built by the first pass that needs them.
    whole_lights: OnceLock<Vec<Lights>>,
    pub pool: rayon::ThreadPool,
    pub geometry: Geometry<'s>,
}

/// A finished pass.
pub struct PassResult {
    pub film: Film,
    pub stats: PassStats,
    /// Wall time of the pass including the tree build, seconds.
    pub seconds: f64,
    /// Per tree built: its light group's name (None when the pass renders
    /// one group), kind, lights, build time.
    pub trees: Vec<(Option<String>, LightKind, usize, Duration)>,
    pub tree_bytes: usize,
    /// Virtual point lights traced for indirect light, and the time it took.
    pub vpls: usize,
    pub vpl_time: Duration,
    /// Lights of the pass, by kind (the scene's plus the VPLs), in
    /// `LightKind::ALL`'s order: omni, area, oriented, directional,
    /// environment, spot.
    pub lights: [usize; LightKind::ALL.len()],
    /// Lights that move over the shutter (in no tree; docs/design.md §13.6).
    pub moving_lights: usize,
    /// Suns with a disc (in no tree; docs/design.md §6.3).
    pub sun_discs: usize,
    /// Rays of the pass that Embree was not given because a component was
    /// not finite or out of its range (see [`crate::embree::refused_rays`]):
    /// shadow rays among them counted as blocked. 0 in every scene the
    /// loader accepts; the command line warns otherwise.
    pub refused_rays: u64,
}

impl PassResult {
    /// What the command line warns about after a pass, one line each:
    /// rays Embree was not given, and values that were NaN or infinite
    /// when the film stored them (each a defect; docs/design.md §5.1).
    #[must_use]
    pub fn warnings(&self) -> Vec<String> {
        let mut lines = Vec::new();
        if self.refused_rays > 0 {
            lines.push(format!(
                "{} rays had a non-finite or out-of-range component and were not traced \
                 (shadow rays among them counted as blocked): the scene holds a degenerate value",
                self.refused_rays
            ));
        }
        let non_finite = self.film.non_finite();
        if !non_finite.is_empty() {
            let total: u64 = non_finite.iter().map(|(_, n)| n).sum();
            let list: Vec<String> = non_finite.iter().map(|(name, n)| format!("{name} {n}")).collect();
            lines.push(format!(
                "{total} values were NaN or infinite before they were stored (NaN as 0, infinities as the \
                 largest finite f32), by channel: {}: a defect of the renderer, please report it",
                list.join(", ")
            ));
        }
        lines
    }

    /// Values of the film that were NaN or infinite before they were stored.
    #[must_use]
    pub fn non_finite_values(&self) -> u64 {
        self.film.channels.iter().map(|c| c.non_finite).sum()
    }
}

impl<'s> Session<'s> {
    /// `threads`: 0 for one per CPU.
    pub fn try_new(scene: &'s Scene, threads: usize) -> Result<Self, SessionError> {
        let pool = thread_pool(threads).map_err(|source| SessionError::Threads { threads, source })?;
        let lights = pool.install(|| Lights::by_group(scene));
        let device = Device::try_new()?;
        let geometry = Geometry::try_new(&device, scene, &lights)
            .map_err(|source| SessionError::Geometry { file: scene.path.clone(), source })?;
        Ok(Self { scene, lights, whole_lights: OnceLock::new(), pool, geometry })
    }

    /// The scene's lights by light group with area lights as `leaves`.
    #[must_use]
    pub fn lights_for(&self, leaves: EmitterLeaves) -> &[Lights] {
        match leaves {
            EmitterLeaves::Parts => &self.lights,
            EmitterLeaves::Whole => self
                .whole_lights
                .get_or_init(|| self.pool.install(|| Lights::by_group_with(self.scene, EmitterLeaves::Whole))),
        }
    }

    /// Renders one pass in `mode` (building the light trees first for the
    /// lightcut modes, timed as part of the pass). With the `groups` AOV, a
    /// scene with light groups is rendered group by group as well (the
    /// film's `Combined_<group>` channels, and the cuts' per-group error
    /// control); without, as one group.
    pub fn render(
        &self,
        settings: &PassSettings,
        mode: Mode,
        progress: &(dyn Fn(PassProgress) + Sync),
    ) -> Result<PassResult, SessionError> {
        let start = Instant::now();
        let refused_before = crate::embree::refused_rays();
        // Indirect light: VPLs for this seed, added to the oriented lights of
        // the group their path started from.
        // Area lights as the mode's leaves; the VPLs leave them from their
        // parts either way (a point uniform on the emitter).
        let leaves = mode.emitter_leaves();
        let (mut lights, vpls) = match self.scene.indirect {
            Some(Indirect::Vpl(indirect)) => {
                let vpls = self.pool.install(|| vpl::trace(&self.geometry, &self.lights, indirect, settings.seed));
                self.geometry.embree.take_error("tracing the light paths of the VPLs")?;
                let count = vpls.iter().map(Vec::len).sum();
                let mut lights = self.lights_for(leaves).to_vec();
                for (group, vpls) in lights.iter_mut().zip(vpls) {
                    group.oriented.extend(vpls);
                }
                (std::borrow::Cow::Owned(lights), count)
            }
            Some(Indirect::Path(_)) | None => (std::borrow::Cow::Borrowed(self.lights_for(leaves)), 0),
        };
        let split_groups = settings.aovs.groups && self.scene.groups.named();
        if !split_groups && lights.len() > 1 {
            // One group: every light in one set of trees, as a scene
            // without groups.
            let mut all = Lights::default();
            for group in lights.iter() {
                all.append(group);
            }
            lights = std::borrow::Cow::Owned(vec![all]);
        }
        let vpl_time = start.elapsed();
        let trees = mode.cut().map(|mut cut| {
            // A pixel's cut pays a tree's bounds once for all its
            // gather points: every tree is built as a tree.
            if let Mode::Multidimensional(_) = mode {
                cut.exhaustive_lights = 0;
            }
            self.pool.install(|| crate::lightcut::build_trees_with(&lights, settings.seed, &cut))
        });
        let direct = mode.method(trees.as_ref());
        let emission_group = self.scene.emission_groups();
        let emitters = super::emitter_sampling::EmitterSampling::of(self.scene, settings.spp, leaves);
        let camera = self.scene.camera(settings.width, settings.height);
        let integrator = Integrator {
            tracer: Tracer {
                geometry: &self.geometry,
                lights: &lights,
                split_groups,
                emitters: emitters.as_ref(),
                spp: settings.spp,
                footprint: (settings.texture_filter == TextureFilter::Mip)
                    .then(|| camera.pixel_footprint(settings.spp)),
            },
            direct: &*direct,
            max_mirror_depth: self.scene.max_mirror_depth,
            emission_group: &emission_group,
            path_depth: match self.scene.indirect {
                Some(Indirect::Path(path)) => Some(path.max_depth),
                _ => None,
            },
        };
        let (film, stats) = self.pool.install(|| render(&integrator, &camera, settings, progress))?;
        let seconds = start.elapsed().as_secs_f64();
        let (tree_list, tree_bytes) = match &trees {
            Some(t) => (
                t.trees
                    .iter()
                    .zip(&t.build_times)
                    .zip(&t.group_of_tree)
                    .map(|((tree, time), &g)| {
                        let group = split_groups.then(|| self.scene.groups.names[g].clone());
                        (group, tree.kind, tree.light_count(), *time)
                    })
                    .collect(),
                t.memory_bytes(),
            ),
            None => (Vec::new(), 0),
        };
        let count = |kind| lights.iter().map(|group| group.count(kind)).sum();
        let counts = LightKind::ALL.map(count);
        let refused_rays = crate::embree::refused_rays() - refused_before;
        Ok(PassResult {
            film,
            stats,
            seconds,
            trees: tree_list,
            tree_bytes,
            vpls,
            vpl_time,
            lights: counts,
            moving_lights: lights.iter().map(|group| group.moving.len()).sum(),
            sun_discs: lights.iter().map(|group| group.suns.len()).sum(),
            refused_rays,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::{Aovs, PixelBounds};
    use crate::scene::builder::SceneText;

    /// 2 x 2 pixels, all on a floor seen from above; `lights` TOML appended.
    fn scene(lights: &str) -> Scene {
        SceneText::new(2, 2)
            .raw("[camera]\neye = [0, 1, 0]\nlook_at = [0, 0, 0]\nup = [0, 0, -1]\nfov_y = 10\n")
            .material("floor", [0.5, 0.5, 0.5], "")
            .floor(0.0, 5.0, "floor")
            .raw(lights)
            .load(std::path::Path::new("stats.toml"))
            .unwrap()
    }

    /// 256 lights at one point over the floor.
    const COINCIDENT: &str = r#"
[[lights]]
type = "grid"
corner = [0, 2, 0]
u = [0, 0, 0]
v = [0, 0, 0]
count = [16, 16]
intensity = [1, 1, 1]
"#;

    fn pass(scene: &Scene, mode: Mode) -> crate::render::stats::ShadingStats {
        let session = Session::try_new(scene, 1).unwrap();
        let settings = PassSettings {
            width: 2,
            height: 2,
            spp: 1,
            seed: 0,
            bounds: PixelBounds::full(2, 2),
            aovs: Aovs::all(true),
            transparent: false,
            texture_filter: TextureFilter::Mip,
        };
        let result = session.render(&settings, mode, &|_| {}).unwrap();
        assert_eq!(result.stats.camera_rays, 4);
        result.stats.shading
    }

    #[test]
    fn exact_statistics_count_every_light_once_and_every_ray_once() {
        // One more light under the floor: evaluated (it is in the cut) but
        // it contributes nothing, so it casts no shadow ray.
        let under = "[[lights]]\ntype = \"point\"\nposition = [0, -1, 0]\nintensity = [1, 1, 1]\n";
        let stats = pass(&scene(&format!("{COINCIDENT}{under}")), Mode::Exact);
        assert_eq!(stats.shading_points, 4);
        assert_eq!(stats.cut_nodes, 4 * 257, "each point's cut is every light, once");
        assert_eq!(stats.max_cut, 257);
        assert_eq!(stats.shadow_rays, 4 * 256, "no ray for the light under the floor");
        let mut histogram = [0; crate::render::stats::CUT_HISTOGRAM_BUCKETS];
        histogram[8] = 4; // 256 <= 257 < 512
        assert_eq!(stats.cut_histogram, histogram);
    }

    #[test]
    fn lightcut_statistics_count_the_cut_and_its_rays() {
        // 256 lights at one point: the root alone is exact, one ray per point.
        let stats = pass(&scene(COINCIDENT), Mode::Bounded(CutSettings::default()));
        assert_eq!(stats.shading_points, 4);
        assert_eq!(stats.cut_nodes, 4);
        assert_eq!(stats.max_cut, 1);
        assert_eq!(stats.shadow_rays, 4);
        let mut histogram = [0; crate::render::stats::CUT_HISTOGRAM_BUCKETS];
        histogram[0] = 4;
        assert_eq!(stats.cut_histogram, histogram);
    }

    /// A NaN in one light's evaluation (a light no scene file can give:
    /// the loader refuses it) is counted where the film stores it, in
    /// every mode, and warned about; without it nothing is.
    #[test]
    fn a_nan_that_reaches_the_film_is_counted_and_warned_about() {
        let scene = scene(COINCIDENT);
        let mut session = Session::try_new(&scene, 1).unwrap();
        let settings = PassSettings {
            width: 2,
            height: 2,
            spp: 1,
            seed: 0,
            bounds: PixelBounds::full(2, 2),
            aovs: Aovs::all(true),
            transparent: false,
            texture_filter: TextureFilter::Mip,
        };
        let modes = [Mode::Exact, Mode::Bounded(CutSettings::default())];
        for mode in modes {
            let clean = session.render(&settings, mode, &|_| {}).unwrap();
            assert_eq!(clean.non_finite_values(), 0);
            assert!(clean.warnings().is_empty());
        }
        session.lights[0].omni.push(crate::light::OmniLight {
            position: glam::Vec3::new(0.0, 1.0, 0.0),
            intensity: glam::Vec3::new(1.0, f32::NAN, 1.0),
        });
        for mode in modes {
            let result = session.render(&settings, mode, &|_| {}).unwrap();
            assert!(result.film.channels.iter().all(|c| c.values.iter().all(|v| v.is_finite())));
            assert_eq!(result.film.non_finite(), vec![("G", 4)], "{mode:?}: one NaN per pixel, in G");
            assert_eq!(result.non_finite_values(), 4);
            let warnings = result.warnings();
            assert!(warnings.len() == 1 && warnings[0].contains("4 values were NaN or infinite"), "{warnings:?}");
        }
    }

    #[test]
    fn an_error_embree_reports_during_the_pass_fails_the_render() {
        // 64 x 48 pixels: 12 tiles of 16 x 16.
        let scene = scene(COINCIDENT);
        let session = Session::try_new(&scene, 1).unwrap();
        let settings = PassSettings {
            width: 64,
            height: 48,
            spp: 1,
            seed: 0,
            bounds: PixelBounds::full(64, 48),
            aovs: Aovs::all(true),
            transparent: false,
            texture_filter: TextureFilter::Mip,
        };
        let tiles = std::sync::atomic::AtomicUsize::new(0);
        // Embree reports an error after the third tile, as a failure inside
        // a ray query would (its queries report none themselves).
        let progress = |event: PassProgress| {
            if event == PassProgress::TileDone && tiles.fetch_add(1, std::sync::atomic::Ordering::Relaxed) == 2 {
                session.geometry.embree.device().provoke_error_for_tests();
            }
        };
        for mode in [Mode::Exact, Mode::Bounded(CutSettings::default())] {
            tiles.store(0, std::sync::atomic::Ordering::Relaxed);
            match session.render(&settings, mode, &progress) {
                Err(SessionError::Embree(e)) => assert!(e.to_string().contains("while tracing a tile's rays"), "{e}"),
                Err(e) => panic!("{mode:?}: another error: {e}"),
                Ok(_) => panic!("{mode:?}: the render succeeded after Embree reported an error"),
            }
            assert!(tiles.load(std::sync::atomic::Ordering::Relaxed) < 12, "the pass stops at the error");
        }
        // The error was taken: the next pass renders.
        assert!(session.render(&settings, Mode::Exact, &|_| {}).is_ok());
    }
}
