//! Rendering: camera samples over tiles on rayon, shaded by the integrator
//! into a film of beauty and AOVs.
//!
//! Determinism: every sample's position is a pure function of (seed, pixel,
//! sample index), each pixel is computed by one thread in a fixed order, and
//! tiles are assembled in a fixed order, so the image is bit-identical for any
//! thread count, tile order and pixel window.

pub mod cryptomatte;
pub mod film;
pub mod integrator;
pub mod session;
pub mod vpl;

use std::time::{Duration, Instant};

use glam::DVec3;
use rayon::prelude::*;

use crate::embree::EmbreeError;
use crate::scene::{Camera, Scene};
use crate::util::sampling::Rng;
use cryptomatte::{Coverage, CryptoType};
pub use film::{Film, FilmChannel, Pixel, PixelBounds, BACKGROUND_DEPTH};
use integrator::{film_value, Integrator, Scratch};
pub use integrator::{DirectLighting, ShadingStats};

/// Tile edge in pixels: small enough to balance load across threads.
pub const TILE: u32 = 16;

/// Settings of one render pass.
#[derive(Debug, Clone, Copy)]
pub struct PassSettings {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub seed: u64,
    pub bounds: PixelBounds,
    /// Whether to write Cryptomatte's object and material mattes.
    pub cryptomatte: bool,
    /// A transparent film (`render --transparent`): camera rays that hit
    /// nothing give RGB 0 and alpha 0 instead of the environment and
    /// alpha 1. The environment still lights the scene and shows in mirrors.
    pub transparent: bool,
}

/// What a pass reports while it runs, through the caller's callback (the
/// command line draws it). Called from the worker threads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PassProgress {
    /// Before the first tile: how many tiles the pass has.
    Started { tiles: u64 },
    /// One more tile is done.
    TileDone,
    /// Every tile is done.
    Finished,
}

/// Counters and times of a finished pass.
#[derive(Debug, Clone, Copy, Default)]
pub struct PassStats {
    pub camera_rays: u64,
    pub shading: ShadingStats,
    pub time: Duration,
}

/// The tiles covering a window, in scanline order of tiles.
#[must_use]
pub fn tiles(bounds: PixelBounds, tile: u32) -> Vec<PixelBounds> {
    let mut out = Vec::new();
    let mut y = bounds.y0;
    while y < bounds.y1 {
        let mut x = bounds.x0;
        while x < bounds.x1 {
            out.push(PixelBounds { x0: x, x1: (x + tile).min(bounds.x1), y0: y, y1: (y + tile).min(bounds.y1) });
            x += tile;
        }
        y += tile;
    }
    out
}

/// The channels a pass writes beside the beauty and the fixed AOVs, and
/// what it needs to fill them.
struct Extra {
    names: Vec<String>,
    /// Light groups the radiance is split into (0: none).
    groups: usize,
    /// Cryptomatte IDs of each mesh's object name and each material's
    /// name, when the pass writes mattes.
    ids: Option<(Vec<f32>, Vec<f32>)>,
}

impl Extra {
    fn new(integrator: &Integrator<'_>, cryptomatte: bool) -> Self {
        let scene = integrator.geometry.scene;
        let groups = integrator.group_slots();
        let mut names: Vec<String> = Vec::new();
        for g in 0..groups {
            let group = &scene.groups.names[g];
            names.extend(["R", "G", "B"].map(|c| format!("Combined_{group}.{c}")));
        }
        let ids = cryptomatte.then(|| {
            names.extend(CryptoType::ALL.iter().flat_map(|t| t.channels()));
            let objects = scene.meshes.iter().map(|m| cryptomatte::id_of(&m.name)).collect();
            let materials = scene.materials.iter().map(|m| cryptomatte::id_of(&m.name)).collect();
            (objects, materials)
        });
        Self { names, groups, ids }
    }

    /// Cryptomatte's header attributes: each type's manifest lists every
    /// name of the scene, once.
    fn attributes(&self, scene: &Scene) -> Vec<(String, String)> {
        if self.ids.is_none() {
            return Vec::new();
        }
        // The manifests are maps: each name once, however many meshes share it.
        let objects: Vec<String> = scene.meshes.iter().map(|m| m.name.clone()).collect();
        let materials: Vec<String> = scene.materials.iter().map(|m| m.name.clone()).collect();
        let mut out = CryptoType::Object.header(&objects);
        out.extend(CryptoType::Material.header(&materials));
        out
    }
}

/// Renders the window `settings.bounds` on the current rayon pool,
/// reporting each finished tile to `progress`. Fails when Embree reported
/// an error while a tile was traced: its ray queries report none
/// themselves, and a failed query reads as "not occluded", so each tile
/// checks the device once it is done and the pass stops at the first error.
pub fn render(
    integrator: &Integrator<'_>,
    camera: &Camera,
    settings: &PassSettings,
    progress: &(dyn Fn(PassProgress) + Sync),
) -> Result<(Film, PassStats), EmbreeError> {
    let start = Instant::now();
    let extra = Extra::new(integrator, settings.cryptomatte);
    let tile_list = tiles(settings.bounds, TILE);
    progress(PassProgress::Started { tiles: tile_list.len() as u64 });
    let embree = &integrator.geometry.embree;
    let rendered: Vec<(Vec<Pixel>, Vec<f32>, PassStats)> = tile_list
        .par_iter()
        .map_init(Scratch::default, |scratch, tile| {
            let result = render_tile(integrator, camera, settings, &extra, *tile, scratch);
            embree.take_error("tracing a tile's rays")?;
            progress(PassProgress::TileDone);
            Ok(result)
        })
        .collect::<Result<_, EmbreeError>>()?;
    progress(PassProgress::Finished);

    let b = settings.bounds;
    let channel_count = extra.names.len();
    let mut film = Film {
        full_width: settings.width,
        full_height: settings.height,
        bounds: b,
        pixels: vec![Pixel::default(); b.area()],
        channels: extra
            .names
            .iter()
            .map(|name| FilmChannel { name: name.clone(), values: vec![0.0; b.area()] })
            .collect(),
        attributes: extra.attributes(integrator.geometry.scene),
    };
    let mut stats = PassStats::default();
    for (tile, (pixels, values, tile_stats)) in tile_list.iter().zip(rendered) {
        stats.camera_rays += tile_stats.camera_rays;
        stats.shading.add(&tile_stats.shading);
        for (i, pixel) in pixels.into_iter().enumerate() {
            let x = tile.x0 + i as u32 % tile.width();
            let y = tile.y0 + i as u32 / tile.width();
            let at = (y - b.y0) as usize * b.width() as usize + (x - b.x0) as usize;
            film.pixels[at] = pixel;
            for (c, channel) in film.channels.iter_mut().enumerate() {
                channel.values[at] = values[i * channel_count + c];
            }
        }
    }
    stats.time = start.elapsed();
    Ok((film, stats))
}

/// A tile's pixels, its extra channels' values (pixel by pixel, each
/// pixel's channels in `extra.names` order) and its counters.
fn render_tile(
    integrator: &Integrator<'_>,
    camera: &Camera,
    settings: &PassSettings,
    extra: &Extra,
    tile: PixelBounds,
    scratch: &mut Scratch,
) -> (Vec<Pixel>, Vec<f32>, PassStats) {
    let mut pixels = Vec::with_capacity(tile.area());
    let mut values = Vec::with_capacity(tile.area() * extra.names.len());
    let mut stats = PassStats::default();
    let inv_spp = 1.0 / f64::from(settings.spp);
    let mut groups = vec![DVec3::ZERO; extra.groups];
    let (mut objects, mut materials) = (Coverage::default(), Coverage::default());
    for y in tile.y0..tile.y1 {
        for x in tile.x0..tile.x1 {
            let mut radiance = DVec3::ZERO;
            let mut albedo = DVec3::ZERO;
            let mut normal = DVec3::ZERO;
            let mut hits = 0u32;
            let mut opaque = 0u32;
            let mut z = f32::INFINITY;
            let mut pixel_stats = ShadingStats::default();
            groups.fill(DVec3::ZERO);
            objects.clear();
            materials.clear();
            for s in 0..settings.spp {
                let mut rng = Rng::from_key(&[settings.seed, u64::from(x), u64::from(y), u64::from(s)]);
                let ray = camera.ray(x as f32 + rng.next_f32(), y as f32 + rng.next_f32());
                let key = [settings.seed, u64::from(x), u64::from(y), u64::from(s)];
                let sample = integrator.trace(ray, key, settings.transparent, scratch, &mut groups);
                stats.camera_rays += 1;
                radiance += sample.radiance;
                opaque += u32::from(sample.opaque);
                pixel_stats.add(&sample.stats);
                if let Some(hit) = sample.first_hit {
                    hits += 1;
                    albedo += hit.albedo.as_dvec3();
                    normal += hit.normal.as_dvec3();
                    z = z.min(hit.distance);
                }
                // Every camera sample weighs 1 / spp (the box filter the
                // beauty uses), so coverages sum to the pixel's alpha.
                if let (Some((object_ids, material_ids)), Some((mesh, material))) = (&extra.ids, sample.first_ids) {
                    objects.add(object_ids[mesh], inv_spp);
                    materials.add(material_ids[material], inv_spp);
                }
            }
            stats.shading.add(&pixel_stats);
            let value = |v: DVec3, scale: f64| (v * scale).to_array().map(film_value);
            let hit_scale = if hits > 0 { 1.0 / f64::from(hits) } else { 0.0 };
            pixels.push(Pixel {
                rgb: value(radiance, inv_spp),
                alpha: (f64::from(opaque) * inv_spp) as f32,
                albedo: value(albedo, hit_scale),
                normal: value(normal, hit_scale),
                z: if z.is_finite() { z } else { BACKGROUND_DEPTH },
                cut_size: if pixel_stats.shading_points > 0 {
                    (pixel_stats.cut_nodes as f64 / pixel_stats.shading_points as f64) as f32
                } else {
                    0.0
                },
                shadow_rays: pixel_stats.shadow_rays as f32,
            });
            for group in &groups {
                values.extend(value(*group, inv_spp));
            }
            if extra.ids.is_some() {
                for coverage in [&mut objects, &mut materials] {
                    values.extend(coverage.ranks().iter().flat_map(|&(id, weight)| [id, weight]));
                }
            }
        }
    }
    (pixels, values, stats)
}

/// A rayon pool of `threads` workers (0: one per CPU), each with Embree's
/// recommended flush-to-zero and denormals-are-zero modes set.
pub fn thread_pool(threads: usize) -> Result<rayon::ThreadPool, rayon::ThreadPoolBuildError> {
    rayon::ThreadPoolBuilder::new().num_threads(threads).start_handler(|_| crate::embree::set_flush_denormals()).build()
}
