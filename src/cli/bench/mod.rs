//! `lightcuts bench ...`: benchmarks that print measured figures (a table,
//! or JSON with --json). Targets are checked by reading them, never by
//! timed assertions. The measurements sit beside the commands that print
//! them: `tree` (build time, memory, quality) and `rays` (throughput).

use clap::{Args, Subcommand, ValueEnum};
use serde::Serialize;

pub mod rays;
pub mod switch;
pub mod tree;

use super::CliError;
use crate::light::LightKind;
use tree::{measure_build, measure_quality, random_lights, BuildFigure, Distribution, QualityFigure};

#[derive(Debug, Args)]
pub struct BenchArgs {
    #[command(subcommand)]
    pub bench: Bench,
}

// Parsed once per process: the size of its variants costs nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Subcommand)]
pub enum Bench {
    /// Light-tree build time, memory and quality.
    Tree(TreeArgs),
    /// Shadow-ray throughput: Embree alone, the lightcuts pass, the exact pass.
    Rays(RaysArgs),
    /// Where a cut starts to pay: the exact render against the bounded cut
    /// with every tree cut, on grids of more and more lights.
    Switch(SwitchArgs),
}

#[derive(Debug, Args)]
pub struct SwitchArgs {
    /// Light counts (each rounded to a square grid), comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [25usize, 49, 100, 144, 196, 256, 324, 400])]
    pub lights: Vec<usize>,
    /// Worker threads (0: one per CPU; at most 1024).
    #[arg(long, default_value_t = 0, value_parser = crate::cli::args::parse_threads)]
    pub threads: usize,
    /// Renders per mode and count; the fastest is reported.
    #[arg(long, default_value_t = 3)]
    pub repeat: usize,
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Args)]
pub struct RaysArgs {
    pub scene: std::path::PathBuf,
    /// The lightcut mode whose pass is measured (`--method exact` is the pass (c)).
    #[command(flatten)]
    pub mode: super::args::ModeArgs,
    /// Samples per pixel, overriding the scene's.
    #[arg(long, value_name = "N")]
    pub spp: Option<u32>,
    #[command(flatten)]
    pub pass: super::args::PassArgs,
    #[command(flatten)]
    pub knobs: super::args::CutKnobs,
    #[arg(long)]
    pub json: bool,
    #[arg(long, short)]
    pub quiet: bool,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum KindArg {
    Omni,
    Oriented,
    Directional,
    Spot,
}

impl From<KindArg> for LightKind {
    fn from(k: KindArg) -> Self {
        match k {
            KindArg::Omni => Self::Omni,
            KindArg::Oriented => Self::Oriented,
            KindArg::Directional => Self::Directional,
            KindArg::Spot => Self::Spot,
        }
    }
}

#[derive(Debug, Args)]
pub struct TreeArgs {
    /// Light counts to build, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [10_000usize, 100_000, 1_000_000, 4_000_000])]
    pub lights: Vec<usize>,
    #[arg(long, value_enum, default_value = "omni")]
    pub kind: KindArg,
    /// Lights for the quality comparison against the greedy tree (O(n^2)).
    #[arg(long, default_value_t = 10_000)]
    pub quality_lights: usize,
    /// Worker threads (0: one per CPU; at most 1024); the tree does not depend on it.
    #[arg(long, default_value_t = 0, value_parser = crate::cli::args::parse_threads)]
    pub threads: usize,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Builds per size; the fastest is reported (this machine is shared and
    /// noisy: the minimum is the most repeatable figure), with the largest peak.
    #[arg(long, default_value_t = 3)]
    pub repeat: usize,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Serialize)]
struct TreeReport {
    threads: usize,
    repeat: usize,
    builds: Vec<BuildFigure>,
    quality: Vec<QualityFigure>,
}

pub fn run(args: &BenchArgs) -> Result<(), CliError> {
    match &args.bench {
        Bench::Tree(t) => tree(t),
        Bench::Rays(r) => rays(r),
        Bench::Switch(s) => switch(s),
    }
}

fn switch(args: &SwitchArgs) -> Result<(), CliError> {
    if args.lights.iter().any(|&n| n == 0 || n > 1 << 20) {
        return Err(CliError::Usage { flag: "--lights", message: "every count must be between 1 and 2^20".into() });
    }
    let figures = switch::measure(&args.lights, args.threads, args.repeat)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&figures).expect("plain data serialises"));
        return Ok(());
    }
    println!(
        "{:>7} {:>10} {:>10} {:>7} {:>8} {:>12} {:>12}",
        "lights", "exact (s)", "cut (s)", "ratio", "avg cut", "exact rays", "cut rays"
    );
    for f in &figures {
        println!(
            "{:>7} {:>10.3} {:>10.3} {:>7.2} {:>8.1} {:>12.1} {:>12.1}",
            f.lights,
            f.exact_seconds,
            f.cut_seconds,
            f.ratio,
            f.average_cut,
            f.exact_shadow_rays_per_pixel,
            f.cut_shadow_rays_per_pixel
        );
    }
    Ok(())
}

fn rays(args: &RaysArgs) -> Result<(), CliError> {
    let scene = args.pass.load(&args.scene)?;
    let settings = args.pass.settings(&scene, args.spp)?;
    let mode = args.mode.mode(settings.spp, &args.knobs)?;
    if mode.cut().is_none() {
        return Err(CliError::Usage {
            flag: "--method",
            message: "bench rays measures a lightcut method against the exact pass: not --method exact".into(),
        });
    }
    let session = crate::render::session::Session::try_new(&scene, args.pass.threads)?;
    let f = rays::measure(&session, &settings, mode, args.quiet)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&f).expect("plain data serialises"));
        return Ok(());
    }
    println!("shadow-ray throughput on {} ({} threads)", scene.path.display(), f.threads);
    println!("  (a) Embree alone, {} recorded exact shadow rays", f.recorded_rays);
    println!("      single-ray calls       {:>8.2} Mrays/s", f.embree_single_mrays_per_s);
    println!("      batch calls (256)      {:>8.2} Mrays/s", f.embree_batch_mrays_per_s);
    println!("      packets of 4           {:>8.2} Mrays/s", f.embree_packet4_mrays_per_s);
    println!("      packets of 8           {:>8.2} Mrays/s", f.embree_packet8_mrays_per_s);
    println!("      packets of 16          {:>8.2} Mrays/s", f.embree_packet16_mrays_per_s);
    println!(
        "  (b) lightcuts pass         {:>8.2} Mrays/s ({} rays in {:.3} s)",
        f.lightcuts_mrays_per_s, f.lightcuts_shadow_rays, f.lightcuts_seconds
    );
    println!(
        "  (c) exact pass             {:>8.2} Mrays/s ({} rays in {:.3} s)",
        f.exact_mrays_per_s, f.exact_shadow_rays, f.exact_seconds
    );
    println!("  (b) / (a, batch)           {:>8.2}", f.lightcuts_over_embree);
    println!("  (b) / (a, packets of 8)    {:>8.2}", f.lightcuts_over_embree_packets);
    println!("  (c) / (a, batch)           {:>8.2}", f.exact_over_embree);
    println!(
        "  (b) / Embree on (b)'s rays {:>8.2} (a timed pass: {:.3} s in Embree)",
        f.lightcuts_over_embree_own_rays, f.lightcuts_timed_embree_seconds
    );
    Ok(())
}

fn tree(args: &TreeArgs) -> Result<(), CliError> {
    if args.lights.iter().any(|&n| n == 0 || n >= 1 << 31) {
        return Err(CliError::Usage { flag: "--lights", message: "every count must be between 1 and 2^31 - 1".into() });
    }
    let pool = crate::render::thread_pool(args.threads)
        .map_err(|source| CliError::Threads { threads: args.threads, source })?;
    let kind = LightKind::from(args.kind);
    let mut builds = Vec::new();
    for distribution in [Distribution::Uniform, Distribution::Clustered] {
        let mut previous: Option<(usize, f64)> = None;
        for &n in &args.lights {
            let lights = random_lights(kind, n, distribution, args.seed);
            let mut figure: Option<BuildFigure> = None;
            for _ in 0..args.repeat.max(1) {
                let (f, tree) = pool.install(|| measure_build(kind, distribution, &lights, args.seed));
                drop(tree);
                figure = Some(match figure {
                    None => f,
                    Some(best) => BuildFigure {
                        build_seconds: best.build_seconds.min(f.build_seconds),
                        peak_build_mib: [best.peak_build_mib, f.peak_build_mib].into_iter().flatten().reduce(f64::max),
                        ..best
                    },
                });
            }
            let mut figure = figure.expect("at least one build");
            if let Some((pn, pt)) = previous {
                figure.growth = Some(figure.build_seconds / pt);
                figure.growth_per_light = Some((figure.build_seconds / n as f64) / (pt / pn as f64));
            }
            previous = Some((n, figure.build_seconds));
            if !args.json {
                print_build(&figure);
            }
            builds.push(figure);
        }
    }
    let mut quality = Vec::new();
    if args.quality_lights > 0 {
        for distribution in [Distribution::Uniform, Distribution::Clustered] {
            let q = pool.install(|| measure_quality(kind, distribution, args.quality_lights, args.seed))?;
            if !args.json {
                print_quality(&q);
            }
            quality.push(q);
        }
    }
    if args.json {
        let report = TreeReport { threads: pool.current_num_threads(), repeat: args.repeat.max(1), builds, quality };
        println!("{}", serde_json::to_string_pretty(&report).expect("plain data serialises"));
    }
    Ok(())
}

fn print_build(f: &BuildFigure) {
    let growth = f.growth.map_or(String::from("-"), |g| format!("{g:.2}x"));
    let per_light = f.growth_per_light.map_or(String::from("-"), |g| format!("{g:.2}"));
    let peak = f.peak_build_mib.map_or(String::from("n/a"), |m| format!("{m:.0} MiB"));
    println!(
        "tree build  {:<11} {:<9} {:>9} lights  {:>8.3} s  growth {:>7} (per light {:>5})  peak {:>9}  {:>5.1} B/light  \
         layout {:.3} s {:>5.1} B/light",
        f.kind,
        format!("{:?}", f.distribution).to_lowercase(),
        f.lights,
        f.build_seconds,
        growth,
        per_light,
        peak,
        f.tree_bytes_per_light,
        f.layout_seconds,
        f.layout_bytes_per_light
    );
}

fn print_quality(q: &QualityFigure) {
    println!(
        "quality     {:<11} {:<9} {:>9} lights  cluster size PLOC {:.4e} greedy {:.4e}  average cut at 2% PLOC {:.1} greedy {:.1} ({:+.1}%)",
        q.kind,
        format!("{:?}", q.distribution).to_lowercase(),
        q.lights,
        q.ploc_total_cluster_size,
        q.greedy_total_cluster_size,
        q.ploc_average_cut,
        q.greedy_average_cut,
        100.0 * q.cut_excess
    );
}
