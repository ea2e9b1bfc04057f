//! Rendering: camera samples over tiles on rayon, shaded by the integrator
//! into a film of beauty and AOVs.
//!
//! Determinism: every sample's position is a pure function of (seed, pixel,
//! sample index), each pixel is computed by one thread in a fixed order, and
//! tiles are assembled in a fixed order, so the image is bit-identical for any
//! thread count, tile order and pixel window.

pub mod cryptomatte;
pub mod direct;
pub mod emitter_sampling;
pub mod film;
pub mod integrator;
pub mod next_event;
pub mod session;
pub mod stats;
pub mod tracer;
pub mod vpl;

use std::time::{Duration, Instant};

use glam::{DVec3, Vec2};
use rayon::prelude::*;

use crate::embree::{EmbreeError, Ray};
use crate::scene::{Camera, Scene};
use crate::util::sampling;
use crate::util::streams::Stream;
use cryptomatte::{Coverage, CryptoType};
use direct::Frame;
use film::film_value;
pub use film::{Aovs, Film, FilmChannel, PixelBounds, BACKGROUND_DEPTH, BEAUTY};
use integrator::{Integrator, Scratch};
pub use stats::ShadingStats;

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
    /// The AOV layers to fill beside the beauty. Without `groups`, a scene
    /// with light groups is rendered as one group (one cut).
    pub aovs: Aovs,
    /// A transparent film (`render --transparent`): camera rays that hit
    /// nothing give RGB 0 and alpha 0 instead of the environment and
    /// alpha 1. The environment still lights the scene and shows in mirrors.
    pub transparent: bool,
    /// How a camera path's textures are read.
    pub texture_filter: TextureFilter,
}

/// How a camera path's textures are read (docs/design.md §5.3, "MIP maps").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TextureFilter {
    /// Through the MIP map, over the camera pixel's footprint.
    #[default]
    Mip,
    /// The image itself at each hit (bilinear, or the nearest texel): what
    /// aliases where a texel is smaller than a pixel.
    Off,
}

impl TextureFilter {
    /// `mip` or `off` (`render --texture-filter`).
    pub fn parse(s: &str) -> Result<Self, String> {
        match s {
            "mip" => Ok(Self::Mip),
            "off" => Ok(Self::Off),
            _ => Err(format!("expected mip or off, got '{s}'")),
        }
    }
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

/// The channels a pass fills, in the film's order, and where each part's
/// values sit among a pixel's values.
struct Layout {
    names: Vec<String>,
    /// Offsets of the fixed AOVs a pass writes (None: not written).
    albedo: Option<usize>,
    normal: Option<usize>,
    depth: Option<usize>,
    lightcuts: Option<usize>,
    /// Offset of the first light group's channels, and the light groups the
    /// radiance is split into (0: none).
    groups: usize,
    group_count: usize,
    /// Offset of Cryptomatte's channels, and the IDs of each mesh's object
    /// name and each material's name, when the pass writes mattes.
    cryptomatte: usize,
    ids: Option<(Vec<f32>, Vec<f32>)>,
}

impl Layout {
    fn new(integrator: &Integrator<'_>, aovs: Aovs) -> Self {
        let scene = integrator.tracer.geometry.scene;
        let mut names: Vec<String> = BEAUTY.iter().map(|c| (*c).to_string()).collect();
        let mut add = |wanted: bool, channels: &[&str]| {
            wanted.then(|| {
                names.extend(channels.iter().map(|c| (*c).to_string()));
                names.len() - channels.len()
            })
        };
        let albedo = add(aovs.albedo, &["albedo.R", "albedo.G", "albedo.B"]);
        let normal = add(aovs.normal, &["N.X", "N.Y", "N.Z"]);
        let depth = add(aovs.depth, &["Z"]);
        let lightcuts = add(aovs.lightcuts, &["lightcuts.cut_size", "lightcuts.shadow_rays"]);
        let (groups, group_count) = (names.len(), integrator.group_slots());
        for group in &scene.groups.names[..group_count] {
            names.extend(["R", "G", "B"].map(|c| format!("Combined_{group}.{c}")));
        }
        let cryptomatte = names.len();
        let ids = aovs.cryptomatte.then(|| {
            names.extend(CryptoType::ALL.iter().flat_map(|t| t.channels()));
            let objects = scene.objects.iter().map(|o| cryptomatte::id_of(&o.name)).collect();
            let materials = scene.materials.iter().map(|m| cryptomatte::id_of(&m.name)).collect();
            (objects, materials)
        });
        Self { names, albedo, normal, depth, lightcuts, groups, group_count, cryptomatte, ids }
    }

    /// Cryptomatte's header attributes: each type's manifest lists every
    /// name of the scene, once.
    fn attributes(&self, scene: &Scene) -> Vec<(String, String)> {
        if self.ids.is_none() {
            return Vec::new();
        }
        // The manifests are maps: each name once, however many objects share it.
        let objects: Vec<String> = scene.objects.iter().map(|o| o.name.clone()).collect();
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
    let layout = Layout::new(integrator, settings.aovs);
    let tile_list = tiles(settings.bounds, TILE);
    progress(PassProgress::Started { tiles: tile_list.len() as u64 });
    let embree = &integrator.tracer.geometry.embree;
    let rendered: Vec<(Vec<f32>, Vec<u64>, PassStats)> = tile_list
        .par_iter()
        .map_init(
            || integrator.scratch(),
            |scratch, tile| {
                let result = render_tile(integrator, camera, settings, &layout, *tile, scratch);
                embree.take_error("tracing a tile's rays")?;
                progress(PassProgress::TileDone);
                Ok(result)
            },
        )
        .collect::<Result<_, EmbreeError>>()?;
    progress(PassProgress::Finished);

    let b = settings.bounds;
    let count = layout.names.len();
    let mut film = Film {
        full_width: settings.width,
        full_height: settings.height,
        bounds: b,
        channels: layout
            .names
            .iter()
            .map(|name| FilmChannel { name: name.clone(), values: vec![0.0; b.area()], non_finite: 0 })
            .collect(),
        attributes: layout.attributes(integrator.tracer.geometry.scene),
    };
    let mut stats = PassStats::default();
    for (tile, (values, non_finite, tile_stats)) in tile_list.iter().zip(rendered) {
        stats.camera_rays += tile_stats.camera_rays;
        stats.shading.add(&tile_stats.shading);
        for (channel, count) in film.channels.iter_mut().zip(non_finite) {
            channel.non_finite += count;
        }
        for (i, pixel) in values.chunks_exact(count).enumerate() {
            let x = tile.x0 + i as u32 % tile.width();
            let y = tile.y0 + i as u32 / tile.width();
            let at = (y - b.y0) as usize * b.width() as usize + (x - b.x0) as usize;
            for (channel, &value) in film.channels.iter_mut().zip(pixel) {
                channel.values[at] = value;
            }
        }
    }
    stats.time = start.elapsed();
    Ok((film, stats))
}

/// A tile's values (pixel by pixel, each pixel's channels in `layout`'s
/// order), how many values of each channel were NaN or infinite before
/// they were stored (see [`film_value`]), and its counters.
fn render_tile<'a>(
    integrator: &Integrator<'a>,
    camera: &Camera,
    settings: &PassSettings,
    layout: &Layout,
    tile: PixelBounds,
    scratch: &mut Scratch<'_, 'a>,
) -> (Vec<f32>, Vec<u64>, PassStats) {
    let count = layout.names.len();
    let mut values = vec![0.0f32; tile.area() * count];
    let mut non_finite = vec![0u64; count];
    let mut stats = PassStats::default();
    let inv_spp = 1.0 / f64::from(settings.spp);
    let mut groups = vec![DVec3::ZERO; layout.group_count];
    let (mut objects, mut materials) = (Coverage::default(), Coverage::default());
    let frame = Frame { camera, settings };
    stats.camera_rays += scratch.direct.start_tile(&integrator.tracer, frame, tile, &mut stats.shading);
    for (i, pixel) in values.chunks_exact_mut(count).enumerate() {
        let (x, y) = (tile.x0 + i as u32 % tile.width(), tile.y0 + i as u32 / tile.width());
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
        stats.camera_rays += scratch.direct.start_pixel(&integrator.tracer, frame, (x, y), &mut stats.shading);
        let pixel_ray = PixelRays::new(camera, settings, x, y);
        for s in 0..settings.spp {
            let ray = pixel_ray.sample(s);
            let key = [settings.seed, u64::from(x), u64::from(y), u64::from(s)];
            let sample = integrator.trace(ray, key, settings.transparent, scratch, &mut groups);
            // A camera ray the method traced (reuse) it counted.
            stats.camera_rays += sample.camera_rays;
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
            if let (Some((object_ids, material_ids)), Some((object, material))) = (&layout.ids, sample.first_ids) {
                objects.add(object_ids[object], inv_spp);
                materials.add(material_ids[material], inv_spp);
            }
        }
        let pixel_key = [settings.seed, u64::from(x), u64::from(y)];
        let tracer = &integrator.tracer;
        if let Some(direct) = scratch.direct.finish_pixel(tracer, pixel_key, &mut groups, &mut pixel_stats) {
            radiance += direct;
        }
        stats.shading.add(&pixel_stats);
        // Every value the integrator summed in f64 reaches the film
        // through here: a non-finite one is counted for its channel.
        let mut put = |pixel: &mut [f32], at: usize, v: DVec3, scale: f64| {
            for (k, x) in (v * scale).to_array().into_iter().enumerate() {
                pixel[at + k] = film_value(x, &mut non_finite[at + k]);
            }
        };
        let hit_scale = if hits > 0 { 1.0 / f64::from(hits) } else { 0.0 };
        put(pixel, 0, radiance, inv_spp);
        pixel[3] = (f64::from(opaque) * inv_spp) as f32;
        if let Some(at) = layout.albedo {
            put(pixel, at, albedo, hit_scale);
        }
        if let Some(at) = layout.normal {
            put(pixel, at, normal, hit_scale);
        }
        if let Some(at) = layout.depth {
            pixel[at] = if z.is_finite() { z } else { BACKGROUND_DEPTH };
        }
        if let Some(at) = layout.lightcuts {
            let points = pixel_stats.shading_points;
            pixel[at] = if points > 0 { (pixel_stats.cut_nodes as f64 / points as f64) as f32 } else { 0.0 };
            pixel[at + 1] = pixel_stats.shadow_rays as f32;
        }
        for (g, group) in groups.iter().enumerate() {
            put(pixel, layout.groups + 3 * g, *group, inv_spp);
        }
        if layout.ids.is_some() {
            let ranks = [&mut objects, &mut materials].map(|coverage| coverage.ranks());
            let flat = ranks.iter().flat_map(|r| r.iter().flat_map(|&(id, weight)| [id, weight]));
            for (slot, v) in pixel[layout.cryptomatte..].iter_mut().zip(flat) {
                *slot = v;
            }
        }
    }
    (values, non_finite, stats)
}

/// The camera rays of one pixel's samples: through the pixel's jittered
/// points, the lens and the shutter stratified per pixel.
pub(crate) struct PixelRays<'c> {
    camera: &'c Camera,
    settings: &'c PassSettings,
    pub(crate) x: u32,
    pub(crate) y: u32,
    lens_shift: Option<[f32; 2]>,
    time_shift: Option<f32>,
}

impl<'c> PixelRays<'c> {
    pub(crate) fn new(camera: &'c Camera, settings: &'c PassSettings, x: u32, y: u32) -> Self {
        let lens_shift = camera.has_lens().then(|| {
            let mut rng = Stream::Lens.rng(&[settings.seed, u64::from(x), u64::from(y)]);
            [rng.next_f32(), rng.next_f32()]
        });
        let time_shift =
            camera.shutter_open().then(|| Stream::Shutter.rng(&[settings.seed, u64::from(x), u64::from(y)]).next_f32());
        Self { camera, settings, x, y, lens_shift, time_shift }
    }

    /// Sample `s`'s camera ray.
    pub(crate) fn sample(&self, s: u32) -> Ray {
        let Self { camera, settings, x, y, lens_shift, .. } = *self;
        match self.time_shift {
            None => camera_ray(camera, settings, x, y, s, lens_shift),
            // The sample's time, stratified per pixel like the lens
            // (docs/design.md §13.6).
            Some(shift) => camera_ray(&camera.at(sampling::shutter_time(s, shift)), settings, x, y, s, lens_shift),
        }
    }
}

/// Camera sample `s` of pixel (x, y): a point of the pixel drawn from the
/// sample's own stream (the same in every mode), and on a thin lens the
/// sample's point of the pixel's rotated Hammersley set mapped onto the
/// disc (`lens_shift`, the pixel's rotation): the lens is stratified per
/// pixel, and deterministic per seed (docs/design.md §13.1).
fn camera_ray(camera: &Camera, settings: &PassSettings, x: u32, y: u32, s: u32, lens_shift: Option<[f32; 2]>) -> Ray {
    let mut rng = Stream::CameraJitter.rng(&[settings.seed, u64::from(x), u64::from(y), u64::from(s)]);
    let (fx, fy) = (x as f32 + rng.next_f32(), y as f32 + rng.next_f32());
    match lens_shift {
        None => camera.ray(fx, fy),
        Some(shift) => {
            let lens = sampling::concentric_disc(sampling::hammersley(s, settings.spp, shift));
            camera.lens_ray(fx, fy, Vec2::from(lens))
        }
    }
}

/// The most worker threads a render may ask for: far above any machine's
/// cores, where each thread's share of a tile is still worth its start.
/// (20,000 threads took over a minute for a 32 x 24 frame.)
pub const MAX_THREADS: usize = 1024;

/// A rayon pool of `threads` workers (0: one per CPU), each with Embree's
/// recommended flush-to-zero and denormals-are-zero modes set.
pub fn thread_pool(threads: usize) -> Result<rayon::ThreadPool, rayon::ThreadPoolBuildError> {
    rayon::ThreadPoolBuilder::new().num_threads(threads).start_handler(|_| crate::embree::set_flush_denormals()).build()
}
