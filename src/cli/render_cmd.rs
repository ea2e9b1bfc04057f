//! `lightcuts render`: load, build, render, write EXR (and PNG), print statistics.

use std::path::PathBuf;

use clap::Args;

use super::progress::Progress;
use super::{parse_pixel_bounds, parse_resolution, CliError};
use crate::lightcut::stochastic::{STOCHASTIC_DEFAULTS, STOCHASTIC_FROM_SPP};
use crate::lightcut::{CutSettings, GroupError};
use crate::output::exr::{write_exr, Aovs, ExrChannels, ExrMetadata};
use crate::output::preview::write_png;
use crate::render::session::{Mode, PassResult, Session};
use crate::render::{PassSettings, PixelBounds};
use crate::scene::{check_resolution, Scene};

#[derive(Debug, Args)]
pub struct RenderArgs {
    /// Scene file (TOML, or JSON by its .json extension).
    pub scene: PathBuf,
    /// Output OpenEXR file.
    #[arg(short, long, value_name = "OUT.exr")]
    pub output: PathBuf,
    #[command(flatten)]
    pub mode: ModeArgs,
    /// Samples per pixel, overriding the scene's.
    #[arg(long, value_name = "N")]
    pub spp: Option<u32>,
    #[command(flatten)]
    pub pass: PassArgs,
    /// Write the beauty (R, G, B, A) as 16-bit half floats.
    #[arg(long)]
    pub half: bool,
    /// The AOV layers to write beside the beauty: a comma-separated list of
    /// albedo, N, Z, lightcuts (the cut's size and shadow rays; cut modes
    /// only), groups (Combined_<group>.R/G/B per light group; scenes with
    /// groups), cryptomatte, or none. Default: all but cryptomatte.
    #[arg(long, value_name = "LIST", value_parser = Aovs::parse)]
    pub aovs: Option<Aovs>,
    /// Also write Cryptomatte's object and material ID mattes
    /// (CryptoObject00..02, CryptoMaterial00..02).
    #[arg(long)]
    pub cryptomatte: bool,
    /// A transparent background: where a camera ray hits nothing the pixel
    /// gets RGB 0 and alpha 0 (premultiplied, ready for "over" onto a
    /// plate) instead of the environment with alpha 1. The environment
    /// still lights the scene and shows in mirrors.
    #[arg(long)]
    pub transparent: bool,
    /// Also write a tone-mapped sRGB PNG preview.
    #[arg(long, value_name = "PREVIEW.png")]
    pub png: Option<PathBuf>,
    /// Preview exposure in stops (the EXR is never scaled).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f32,
    /// No progress output.
    #[arg(long, short)]
    pub quiet: bool,
    /// The full statistics block: cut-size histogram, share of time in
    /// Embree (times every ray query), peak memory.
    #[arg(long)]
    pub stats: bool,
    /// Render tile I of N (I from 0): the horizontal band of rows
    /// floor(I H / N) to floor((I + 1) H / N), every column; the EXR's data
    /// window is the band, its display window the frame (see `assemble`).
    #[arg(long, value_name = "I/N", value_parser = parse_tile, conflicts_with = "pixel_bounds")]
    pub tile: Option<(u32, u32)>,
    /// Skip the render when the output exists, and claim the output
    /// atomically (OUT.exr.claim, created exclusively) before rendering, so
    /// that two processes never render the same file and a re-run renders
    /// only what is missing.
    #[arg(long)]
    pub no_overwrite: bool,
}

/// Parses `I/N` with 0 <= I < N.
pub fn parse_tile(s: &str) -> Result<(u32, u32), String> {
    let (i, n) = s.split_once('/').ok_or_else(|| format!("expected I/N, got '{s}'"))?;
    let i: u32 = i.trim().parse().map_err(|_| format!("'{i}' is not a non-negative integer"))?;
    let n: u32 = n.trim().parse().map_err(|_| format!("'{n}' is not a positive integer"))?;
    if n == 0 || i >= n {
        return Err(format!("need 0 <= I < N, got {i}/{n}"));
    }
    Ok((i, n))
}

/// Rows `[y0, y1)` of tile `index` of `count` horizontal bands of a frame
/// `height` pixels high: floor(I H / N) to floor((I + 1) H / N).
#[must_use]
pub fn tile_rows(index: u32, count: u32, height: u32) -> (u32, u32) {
    let row = |i: u32| (u64::from(i) * u64::from(height) / u64::from(count)) as u32;
    (row(index), row(index + 1))
}

/// An output claimed by this process (`OUT.exr.claim`, created exclusively):
/// removed when dropped, and by the interrupt handler, so that a failed or
/// cancelled render leaves the tile to the next attempt.
struct Claim(PathBuf);

impl Claim {
    /// Claims `output`; None when another process holds the claim.
    fn take(output: &std::path::Path) -> Result<Option<Self>, CliError> {
        let mut name = output.as_os_str().to_owned();
        name.push(".claim");
        let path = PathBuf::from(name);
        match std::fs::OpenOptions::new().write(true).create_new(true).open(&path) {
            Ok(mut file) => {
                use std::io::Write as _;
                crate::output::temporary::register(&path);
                // Who holds it, for a farm operator reading a stale claim.
                let _ = writeln!(file, "pid {} on {}", std::process::id(), hostname());
                Ok(Some(Self(path)))
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Ok(None),
            Err(e) => Err(crate::output::OutputError::io(&path, "create the claim file")(e).into()),
        }
    }
}

impl Drop for Claim {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
        crate::output::temporary::unregister(&self.0);
    }
}

fn hostname() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname").map_or_else(|_| "?".into(), |h| h.trim().to_string())
}

/// A hash of every file the scene read (in order), as 16 hex digits: what
/// `assemble` requires its tiles to share.
pub fn scene_hash(scene: &Scene) -> Result<String, CliError> {
    let hashes = scene.inputs.iter().map(|p| super::sweep_cmd::hash_file(p)).collect::<Result<Vec<_>, _>>()?;
    Ok(crate::util::hash::combined_hex(hashes))
}

/// How direct light is computed. Without a mode flag, the mode that gave
/// the smaller error for the time at the samples per pixel asked for (see
/// [`default_mode`]).
#[derive(Debug, Args)]
pub struct ModeArgs {
    /// Reference mode: every light, one shadow ray each.
    #[arg(long, conflicts_with_all = ["bounded", "stochastic", "error", "max_cut"])]
    pub exact: bool,
    /// Lightcuts [LC05]: each cluster's error is bounded, its representative
    /// fixed when the tree is built.
    #[arg(long, conflicts_with = "stochastic")]
    pub bounded: bool,
    /// Stochastic lightcuts [SLC19]: each cut node's light is drawn per
    /// sample, so the error falls with samples per pixel.
    #[arg(long)]
    pub stochastic: bool,
    /// Relative error threshold: a cluster is split while its bound exceeds
    /// this fraction of the point's total (bounded: of the estimate, default
    /// 0.02; stochastic: of the summed bounds, default in `lightcut::stochastic`).
    /// 0 splits every cluster, reproducing --exact (bounded) when max-cut allows.
    #[arg(long)]
    pub error: Option<f64>,
    /// Largest cut per shading point, in nodes (bounded default 1000; per
    /// light group with --group-error group).
    #[arg(long)]
    pub max_cut: Option<usize>,
    /// In a scene with light groups, what each cluster's error is held to:
    /// `group` (a cut per group, relative to the group's own light: every
    /// group layer as accurate as the beauty) or `pixel` (one cut through
    /// every group's trees, relative to the pixel's total: cheaper, dim
    /// groups' layers less accurate). Both cut modes.
    #[arg(long, value_name = "group|pixel", value_parser = parse_group_error, conflicts_with = "exact")]
    pub group_error: Option<GroupError>,
}

/// Parses `--group-error`.
pub fn parse_group_error(s: &str) -> Result<GroupError, String> {
    match s {
        "group" => Ok(GroupError::Group),
        "pixel" => Ok(GroupError::Pixel),
        _ => Err(format!("expected group or pixel, got '{s}'")),
    }
}

impl ModeArgs {
    /// The mode these flags ask for, at `spp` samples per pixel.
    pub fn mode(&self, spp: u32) -> Result<Mode, CliError> {
        let stochastic = if self.exact {
            return Ok(Mode::Exact);
        } else if self.bounded || self.stochastic {
            self.stochastic
        } else {
            matches!(default_mode(spp), Mode::Stochastic(_))
        };
        let defaults = if stochastic { STOCHASTIC_DEFAULTS } else { CutSettings::default() };
        let mut cut = cut_settings(self.error.unwrap_or(defaults.error), self.max_cut.unwrap_or(defaults.max_cut))?;
        cut.group_error = self.group_error.unwrap_or(defaults.group_error);
        Ok(if stochastic { Mode::Stochastic(cut) } else { Mode::Bounded(cut) })
    }
}

/// The mode a render uses when no mode flag is given, at `spp` samples per
/// pixel, with its default settings.
#[must_use]
pub fn default_mode(spp: u32) -> Mode {
    if spp >= STOCHASTIC_FROM_SPP {
        Mode::Stochastic(STOCHASTIC_DEFAULTS)
    } else {
        Mode::Bounded(CutSettings::default())
    }
}

/// The options every rendering command shares (pbrt-style overrides).
#[derive(Debug, Args)]
pub struct PassArgs {
    /// Film size, overriding the scene's.
    #[arg(long, value_name = "WxH", value_parser = parse_resolution)]
    pub resolution: Option<(u32, u32)>,
    /// Seed of every random choice (sample positions, representatives, VPLs).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Worker threads (0: one per CPU). The image does not depend on it.
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// Render only this half-open window of the full frame, in pixels.
    #[arg(long, value_name = "x0,x1,y0,y1", value_parser = parse_pixel_bounds)]
    pub pixel_bounds: Option<[u32; 4]>,
    /// Render through the glTF camera of this name (the scene's first camera
    /// otherwise; overrides a TOML's [camera]).
    #[arg(long, value_name = "NAME")]
    pub camera: Option<String>,
}

impl PassArgs {
    /// Loads the scene (through `--camera` when given) and prints its
    /// warnings, one line each.
    pub fn load(&self, path: &std::path::Path) -> Result<Scene, CliError> {
        let scene = Scene::load_with_camera(path, self.camera.as_deref())?;
        for warning in &scene.warnings {
            eprintln!("warning: {warning}");
        }
        Ok(scene)
    }

    /// The pass these options describe for `scene`, at `spp` samples per
    /// pixel (None: the scene's).
    pub fn settings(&self, scene: &Scene, spp: Option<u32>) -> Result<PassSettings, CliError> {
        pass_settings(scene, self.resolution, spp, self.seed, self.pixel_bounds)
    }
}

/// Film size, samples and window after applying the command-line overrides.
pub fn pass_settings(
    scene: &Scene,
    resolution: Option<(u32, u32)>,
    spp: Option<u32>,
    seed: u64,
    pixel_bounds: Option<[u32; 4]>,
) -> Result<PassSettings, CliError> {
    let (width, height) = resolution.unwrap_or((scene.film.width, scene.film.height));
    check_resolution(&scene.path, "--resolution", width, height)?;
    let spp = spp.unwrap_or(scene.film.spp);
    if spp == 0 {
        return Err(CliError::Usage { flag: "--spp", message: "must be at least 1".into() });
    }
    let bounds = match pixel_bounds {
        None => PixelBounds::full(width, height),
        Some([x0, x1, y0, y1]) => {
            if x0 >= x1 || y0 >= y1 || x1 > width || y1 > height {
                return Err(CliError::Usage {
                    flag: "--pixel-bounds",
                    message: format!("{x0},{x1},{y0},{y1} is not a non-empty window inside the {width}x{height} frame"),
                });
            }
            PixelBounds { x0, x1, y0, y1 }
        }
    };
    Ok(PassSettings { width, height, spp, seed, bounds, cryptomatte: false, transparent: false })
}

/// The cut settings of a lightcuts render, validated.
pub fn cut_settings(error: f64, max_cut: usize) -> Result<CutSettings, CliError> {
    if !(error.is_finite() && error >= 0.0) {
        return Err(CliError::Usage { flag: "--error", message: format!("must be finite and >= 0, got {error}") });
    }
    if max_cut == 0 {
        return Err(CliError::Usage { flag: "--max-cut", message: "must be at least 1".into() });
    }
    Ok(CutSettings { error, max_cut, ..CutSettings::default() })
}

pub fn run(args: &RenderArgs) -> Result<(), CliError> {
    let _claim = if args.no_overwrite {
        if args.output.exists() {
            println!("{}: exists, skipped (--no-overwrite)", args.output.display());
            return Ok(());
        }
        match Claim::take(&args.output)? {
            Some(claim) => Some(claim),
            None => {
                println!("{}: claimed by another process, skipped (--no-overwrite)", args.output.display());
                return Ok(());
            }
        }
    } else {
        None
    };
    let scene = args.pass.load(&args.scene)?;
    let mut settings = args.pass.settings(&scene, args.spp)?;
    if let Some((index, count)) = args.tile {
        if count > settings.height {
            return Err(CliError::Usage {
                flag: "--tile",
                message: format!("{count} tiles of a frame {} rows high: at most one tile per row", settings.height),
            });
        }
        let (y0, y1) = tile_rows(index, count, settings.height);
        settings.bounds = PixelBounds { x0: 0, x1: settings.width, y0, y1 };
    }
    let scene_hash = scene_hash(&scene)?;
    let mode = args.mode.mode(settings.spp)?;
    let mut aovs = args.aovs.unwrap_or(Aovs::all(mode.cut().is_some()));
    aovs.cryptomatte |= args.cryptomatte;
    settings.cryptomatte = aovs.cryptomatte;
    settings.transparent = args.transparent;
    if aovs.lightcuts && mode.cut().is_none() {
        return Err(CliError::Usage {
            flag: "--aovs",
            message: "lightcuts (the cut's size and shadow rays) needs a cut mode, not --exact".into(),
        });
    }
    if !args.exposure.is_finite() {
        return Err(CliError::Usage { flag: "--exposure", message: format!("must be finite, got {}", args.exposure) });
    }
    let session = Session::try_new(&scene, args.pass.threads)?;
    let progress = Progress::for_stderr("render", args.quiet);
    crate::embree::set_timing(args.stats);
    let cpu_before = super::process::cpu_seconds();
    let PassResult { film, stats, seconds, trees, tree_bytes, vpls, vpl_time, lights, refused_rays } =
        session.render(&settings, mode, aovs.groups, &|event| progress.report(event))?;
    if refused_rays > 0 {
        eprintln!(
            "warning: {refused_rays} rays had a non-finite or out-of-range component and were not traced \
             (shadow rays among them counted as blocked): the scene holds a degenerate value"
        );
    }
    let cpu_seconds = super::process::cpu_seconds().zip(cpu_before).map(|(after, before)| after - before);
    let cut = mode.cut();
    let mode = mode.describe();

    let meta = ExrMetadata {
        scene_file: scene.path.clone(),
        render_mode: mode.clone(),
        render_seconds: seconds,
        lights: lights.iter().sum::<usize>() as u64,
        spp: settings.spp,
        seed: settings.seed,
        scene_hash,
        world_to_camera: Some(scene.camera(settings.width, settings.height).world_to_camera().to_cols_array()),
        world_to_ndc: Some(scene.camera(settings.width, settings.height).world_to_ndc().to_cols_array()),
    };
    write_exr(&args.output, &film, ExrChannels { half_beauty: args.half, aovs }, &meta)?;
    if let Some(png) = &args.png {
        write_png(png, &film, args.exposure)?;
    }

    let rays = stats.shading.shadow_rays;
    let b = settings.bounds;
    let (major, minor, patch) = crate::embree::version();
    let pixels = b.area().max(1) as f64;
    println!("lightcuts {} (Embree {major}.{minor}.{patch})", env!("CARGO_PKG_VERSION"));
    println!("  scene            {}", scene.path.display());
    println!(
        "  lights           {} (omni {}, oriented {}, directional {}, spot {})",
        lights.iter().sum::<usize>(),
        lights[0],
        lights[1],
        lights[2],
        lights[3]
    );
    if scene.groups.named() {
        let layers = if aovs.groups { "a layer each" } else { "no layers: --aovs leaves out groups" };
        println!("  light groups     {} ({layers})", scene.groups.names.join(", "));
    }
    if vpls > 0 {
        println!("  indirect         {vpls} virtual point lights traced in {:.3} s", vpl_time.as_secs_f64());
    }
    println!("  triangles        {}", scene.triangle_count());
    println!(
        "  image            {}x{}, window {}x{} at ({}, {}), {} spp",
        settings.width,
        settings.height,
        b.width(),
        b.height(),
        b.x0,
        b.y0,
        settings.spp
    );
    println!("  mode             {mode}");
    for (group, kind, lights, time) in &trees {
        let group = group.as_ref().map_or_else(String::new, |g| format!("{g}: "));
        println!("  tree build       {group}{} {lights} lights in {:.3} s", kind.name(), time.as_secs_f64());
    }
    println!("  render time      {seconds:.3} s (including tree build)");
    println!("  camera rays      {}", stats.camera_rays);
    println!("  shadow rays      {rays} ({:.1} per pixel)", rays as f64 / pixels);
    println!("  shadow rays/s    {:.2} M", rays as f64 / stats.time.as_secs_f64().max(1e-9) / 1e6);
    if cut.is_some() {
        let points = stats.shading.shading_points.max(1) as f64;
        println!(
            "  cut size         average {:.1}, maximum {}",
            stats.shading.cut_nodes as f64 / points,
            stats.shading.max_cut
        );
    }
    if args.stats {
        print_full_stats(&stats, cpu_seconds, tree_bytes, session.pool.current_num_threads());
    }
    println!("  output           {}", args.output.display());
    Ok(())
}

fn print_full_stats(stats: &crate::render::PassStats, cpu_seconds: Option<f64>, tree_bytes: usize, threads: usize) {
    let embree = crate::embree::timed_nanos() as f64 * 1e-9;
    println!("  statistics (--stats)");
    println!("    render pass    {:.3} s wall on {threads} threads", stats.time.as_secs_f64());
    // Both sides in wall-clock thread-time: with more threads than cores a
    // descheduled thread's clock runs on in and out of Embree alike.
    let thread_seconds = stats.time.as_secs_f64() * threads as f64;
    println!(
        "    Embree         {embree:.3} s in ray queries: {:.1}% of the pass's {thread_seconds:.2} thread-seconds",
        100.0 * embree / thread_seconds.max(1e-9)
    );
    if let Some(cpu) = cpu_seconds {
        println!("    CPU time       {cpu:.2} s (user + system, whole process during the pass)");
    }
    if stats.shading.cut_nanos > 0 {
        println!(
            "    cut work       {:.1} ns per cut node ({:.3} thread-seconds choosing cuts, outside Embree)",
            stats.shading.cut_nanos as f64 / stats.shading.cut_nodes.max(1) as f64,
            stats.shading.cut_nanos as f64 * 1e-9
        );
    }
    println!("    tree memory    {:.1} MiB", tree_bytes as f64 / (1024.0 * 1024.0));
    if let Some(memory) = super::process::memory() {
        println!("    peak memory    {:.1} MiB resident", memory.peak_resident_mib);
    }
    println!("    cut size       shading points");
    let total = stats.shading.shading_points.max(1) as f64;
    for (k, &count) in stats.shading.cut_histogram.iter().enumerate() {
        if count > 0 {
            let (lo, hi) = if k == 0 { (0u64, 1u64) } else { (1u64 << k, (1u64 << (k + 1)) - 1) };
            println!("    {lo:>6} - {hi:<7} {count:>10} ({:5.1}%)", 100.0 * count as f64 / total);
        }
    }
}
