//! `lightcuts bench switch`: where a cut starts to pay. For grids of n
//! point lights over a floor and a sphere, the exact render against the
//! bounded cut with every tree cut (no tree evaluated light by light), at
//! the same samples: the break-even sets `lightcut::EXHAUSTIVE_LIGHTS`
//! (docs/design.md §7.5).

use serde::Serialize;

use crate::lightcut::CutSettings;
use crate::render::session::{Mode, Session, SessionError};
use crate::render::{PassSettings, PixelBounds, TextureFilter};
use crate::scene::builder::SceneText;
use crate::scene::{Scene, SceneError};

/// One light count's figures.
#[derive(Debug, Clone, Serialize)]
pub struct SwitchFigure {
    pub lights: usize,
    /// The fastest of the repeats, seconds (pass and tree build).
    pub exact_seconds: f64,
    pub cut_seconds: f64,
    /// cut / exact: below 1 the cut pays.
    pub ratio: f64,
    pub average_cut: f64,
    pub exact_shadow_rays_per_pixel: f64,
    pub cut_shadow_rays_per_pixel: f64,
}

/// A floor and a sphere under a `side` x `side` grid of point lights, seen
/// from above at an angle: every pixel sees a lit surface.
fn scene(side: u32) -> Result<Scene, SceneError> {
    SceneText::new(160, 120)
        .camera([0.0, 3.0, 6.0], [0.0, 0.5, 0.0], 50.0)
        .material("floor", [0.7, 0.7, 0.7], "")
        .material("glossy", [0.5, 0.3, 0.2], "specular = [0.2, 0.2, 0.2]\nexponent = 30\n")
        .floor(0.0, 6.0, "floor")
        .sphere([0.0, 0.8, 0.0], 0.8, "glossy")
        .grid([-3.0, 3.0, -3.0], [6.0, 0.0, 0.0], [0.0, 0.0, 6.0], [side, side], [0.02, 0.02, 0.02])
        .load(std::path::Path::new("bench-switch.toml"))
}

/// Measures each light count (rounded to a square grid), `repeat` times.
pub fn measure(counts: &[usize], threads: usize, repeat: usize) -> Result<Vec<SwitchFigure>, super::CliError> {
    let mut figures = Vec::new();
    for &n in counts {
        let side = ((n as f64).sqrt().round() as u32).max(1);
        let scene = scene(side)?;
        let session = Session::try_new(&scene, threads)?;
        let settings = PassSettings {
            width: 160,
            height: 120,
            spp: 1,
            seed: 0,
            bounds: PixelBounds::full(160, 120),
            aovs: crate::render::Aovs::none(),
            transparent: false,
            texture_filter: TextureFilter::Mip,
        };
        let every_tree_cut = CutSettings { exhaustive_lights: 0, ..CutSettings::default() };
        let fastest = |mode: Mode| -> Result<(f64, crate::render::PassStats), SessionError> {
            let mut best: Option<(f64, crate::render::PassStats)> = None;
            for _ in 0..repeat.max(1) {
                let result = session.render(&settings, mode, &|_| {})?;
                if best.as_ref().is_none_or(|b| result.seconds < b.0) {
                    best = Some((result.seconds, result.stats));
                }
            }
            Ok(best.expect("at least one render"))
        };
        let (exact_seconds, exact) = fastest(Mode::Exact)?;
        let (cut_seconds, cut) = fastest(Mode::Bounded(every_tree_cut))?;
        let pixels = settings.bounds.area() as f64;
        figures.push(SwitchFigure {
            lights: (side * side) as usize,
            exact_seconds,
            cut_seconds,
            ratio: cut_seconds / exact_seconds.max(1e-9),
            average_cut: cut.shading.cut_nodes as f64 / cut.shading.shading_points.max(1) as f64,
            exact_shadow_rays_per_pixel: exact.shading.shadow_rays as f64 / pixels,
            cut_shadow_rays_per_pixel: cut.shading.shadow_rays as f64 / pixels,
        });
    }
    Ok(figures)
}
