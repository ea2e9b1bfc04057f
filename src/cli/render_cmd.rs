//! `lightcuts render`: load, build, render, write EXR (and PNG), print statistics.

use super::args::RenderArgs;
use super::farm::Claim;
use super::progress::Progress;
use super::CliError;
use crate::light::LightKind;
use crate::output::exr::{stage_exr, ExrMetadata};
use crate::output::preview::stage_png;
use crate::output::{check_outputs, Staged};
use crate::render::session::{Mode, PassResult, Session};
use crate::render::PassSettings;
use crate::scene::{Indirect, Scene};

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
    let outputs: Vec<&std::path::Path> = std::iter::once(args.output.as_path()).chain(args.png.as_deref()).collect();
    // Before the render: a wrong output costs no render and destroys nothing.
    check_outputs(&outputs, &scene.inputs)?;
    let (settings, mode) = args.resolve(&scene)?;
    let scene_hash = scene.content_hash()?;
    let session = Session::try_new(&scene, args.pass.threads)?;
    let progress = Progress::for_stderr("render", args.quiet);
    crate::embree::set_timing(args.stats);
    let cpu_before = super::process::cpu_seconds();
    let result = session.render(&settings, mode, &|event| progress.report(event))?;
    for warning in result.warnings() {
        eprintln!("warning: {warning}");
    }
    let cpu_seconds = super::process::cpu_seconds().zip(cpu_before).map(|(after, before)| after - before);
    let camera = scene.camera(settings.width, settings.height);
    let meta = ExrMetadata {
        scene_file: scene.path.clone(),
        render_mode: mode.describe(),
        render_seconds: result.seconds,
        lights: (result.lights.iter().sum::<usize>() + result.moving_lights) as u64,
        spp: settings.spp,
        seed: settings.seed,
        scene_hash,
        world_to_camera: Some(camera.world_to_camera().to_cols_array()),
        world_to_ndc: Some(camera.world_to_ndc().to_cols_array()),
    };
    // Both written before either is put in place: a PNG that cannot be
    // written leaves the EXR's place as it was.
    let exr = stage_exr(&args.output, &result.film, args.half, &meta)?;
    let png = args.png.as_ref().map(|png| stage_png(png, &result.film, args.exposure)).transpose()?;
    exr.commit()?;
    png.map(Staged::commit).transpose()?;
    print_summary(&scene, &settings, mode, &result);
    if args.stats {
        print_full_stats(&result.stats, cpu_seconds, result.tree_bytes, session.pool.current_num_threads());
    }
    println!("  output           {}", args.output.display());
    Ok(())
}

/// The statistics block every render ends with.
fn print_summary(scene: &Scene, settings: &PassSettings, mode: Mode, result: &PassResult) {
    let PassResult { stats, seconds, trees, vpls, vpl_time, lights, moving_lights, sun_discs, .. } = result;
    let rays = stats.shading.shadow_rays;
    let b = settings.bounds;
    let (major, minor, patch) = crate::embree::version();
    let pixels = b.area().max(1) as f64;
    println!("lightcuts {} (Embree {major}.{minor}.{patch})", env!("CARGO_PKG_VERSION"));
    println!("  scene            {}", scene.path.display());
    let moving = if *moving_lights > 0 { format!(", moving {moving_lights}") } else { String::new() };
    let suns = if *sun_discs > 0 { format!(", sun discs {sun_discs}") } else { String::new() };
    let kinds: Vec<String> =
        LightKind::ALL.iter().zip(lights).map(|(kind, n)| format!("{} {n}", kind.name())).collect();
    println!(
        "  lights           {} ({}{moving}{suns})",
        lights.iter().sum::<usize>() + moving_lights + sun_discs,
        kinds.join(", ")
    );
    if scene.groups.named() {
        let layers = if settings.aovs.groups { "a layer each" } else { "no layers: --aovs leaves out groups" };
        println!("  light groups     {} ({layers})", scene.groups.names.join(", "));
    }
    match scene.indirect {
        Some(Indirect::Vpl(_)) => {
            println!("  indirect         {vpls} virtual point lights traced in {:.3} s", vpl_time.as_secs_f64());
        }
        Some(Indirect::Path(path)) => {
            let samples = stats.camera_rays.max(1) as f64;
            let rays = (stats.camera_rays + stats.shading.bounce_rays + stats.shading.shadow_rays) as f64;
            println!(
                "  indirect         paths of at most {} vertices: {:.2} vertices per camera sample, {:.1} rays per \
                 sample",
                path.max_depth,
                stats.shading.path_vertices as f64 / samples,
                rays / samples
            );
        }
        None => {}
    }
    let (drawn, stored) = (scene.triangle_count(), scene.stored_triangle_count());
    if drawn == stored {
        println!("  triangles        {drawn}");
    } else {
        let instances = scene.objects.iter().filter(|o| o.transform.is_some()).count();
        println!("  triangles        {drawn} drawn, {stored} stored ({instances} instances)");
    }
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
    println!("  mode             {}", mode.describe());
    if let Some(played) = &scene.animation {
        let [open, close] = played.shutter;
        let when = if open < close { format!("over {open} to {close} s") } else { format!("posed at {open} s") };
        println!("  animation        '{}' {when}", played.name);
    }
    for (group, kind, lights, time) in trees {
        let group = group.as_ref().map_or_else(String::new, |g| format!("{g}: "));
        println!("  tree build       {group}{} {lights} lights in {:.3} s", kind.name(), time.as_secs_f64());
    }
    println!("  render time      {seconds:.3} s (including tree build)");
    println!("  camera rays      {}", stats.camera_rays);
    println!("  shadow rays      {rays} ({:.1} per pixel)", rays as f64 / pixels);
    println!("  shadow rays/s    {:.2} M", rays as f64 / stats.time.as_secs_f64().max(1e-9) / 1e6);
    println!("  non-finite       {} values (NaN or Inf before the film stored them)", result.non_finite_values());
    if let Mode::Multidimensional(_) = mode {
        // Its cuts are per pixel, through (gather cluster, light cluster) pairs.
        let cut_pixels = stats.shading.shading_points.max(1) as f64;
        println!(
            "  cut size         average {:.1} pairs per pixel, maximum {}",
            stats.shading.cut_nodes as f64 / cut_pixels,
            stats.shading.max_cut
        );
        println!(
            "  gather tree      average {:.1} gather points, {:.1} nodes per pixel",
            stats.shading.gather_points as f64 / cut_pixels,
            stats.shading.gather_nodes as f64 / cut_pixels
        );
    } else if mode.cut().is_some() {
        let points = stats.shading.shading_points.max(1) as f64;
        println!(
            "  cut size         average {:.1}, maximum {}",
            stats.shading.cut_nodes as f64 / points,
            stats.shading.max_cut
        );
    }
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
            "    cut work       {:.1} ns per cut node ({:.3} thread-seconds choosing cuts, outside Embree; {} nodes \
             at {} shading points)",
            stats.shading.cut_nanos as f64 / stats.shading.cut_nodes.max(1) as f64,
            stats.shading.cut_nanos as f64 * 1e-9,
            stats.shading.cut_nodes,
            stats.shading.shading_points
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
