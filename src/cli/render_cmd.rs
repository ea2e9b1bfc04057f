//! `lightcuts render`: load, build, render, write EXR (and PNG), print statistics.

use std::path::PathBuf;

use clap::Args;

use super::args::{parse_tile, ModeArgs, PassArgs};
use super::farm::{tile_rows, Claim};
use super::progress::Progress;
use super::CliError;
use crate::output::exr::{write_exr, ExrMetadata};
use crate::output::preview::write_png;
use crate::render::session::{PassResult, Session};
use crate::render::{Aovs, PixelBounds};

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
    let scene_hash = scene.content_hash()?;
    let mode = args.mode.mode(settings.spp)?;
    let mut aovs = args.aovs.unwrap_or(Aovs::all(mode.cut().is_some()));
    aovs.cryptomatte |= args.cryptomatte;
    settings.aovs = aovs;
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
        session.render(&settings, mode, &|event| progress.report(event))?;
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
    write_exr(&args.output, &film, args.half, &meta)?;
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
