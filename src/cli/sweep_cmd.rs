//! `lightcuts sweep`: the speed/accuracy trade over a list of error
//! thresholds, for each cut mode (bounded, stochastic) and each number of
//! samples per pixel, every render measured against the exact render of the
//! same scene, settings, seed and samples per pixel (the camera samples are
//! identical, so only the light estimate differs). Each reference is
//! rendered once, and reused from DIR when it matches.

use std::io::Write as _;
use std::path::{Path, PathBuf};

use clap::{Args, ValueEnum};
use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::args::{cut_settings, PassArgs};
use super::progress::Progress;
use super::CliError;
use crate::lightcut::multidimensional::MULTIDIMENSIONAL_DEFAULTS;
use crate::lightcut::stochastic::STOCHASTIC_DEFAULTS;
use crate::lightcut::CutSettings;
use crate::output::compare::compare_rgb;
use crate::output::exr::{write_exr, ExrMetadata};
use crate::output::plot::{Plot, Series};
use crate::output::read::read_exr;
use crate::output::{write_atomically, OutputError};
use crate::render::session::{Mode, PassResult, Session};
use crate::render::{Aovs, Film, PassSettings};
use crate::scene::Scene;

/// A lightcut mode a sweep measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SweepMode {
    Bounded,
    Stochastic,
    Multidimensional,
}

impl SweepMode {
    fn mode(self, cut: CutSettings) -> Mode {
        match self {
            Self::Bounded => Mode::Bounded(cut),
            Self::Stochastic => Mode::Stochastic(cut),
            Self::Multidimensional => Mode::Multidimensional(cut),
        }
    }

    fn name(self) -> &'static str {
        match self {
            Self::Bounded => "bounded",
            Self::Stochastic => "stochastic",
            Self::Multidimensional => "multidimensional",
        }
    }
}

#[derive(Debug, Args)]
pub struct SweepArgs {
    pub scene: PathBuf,
    /// Error thresholds, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [0.001, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2])]
    pub errors: Vec<f64>,
    /// Cut modes, comma-separated.
    #[arg(long, value_delimiter = ',', value_enum, default_values_t = [SweepMode::Bounded])]
    pub modes: Vec<SweepMode>,
    /// Samples per pixel, comma-separated (default: the scene's); each is
    /// measured against the exact render at the same samples per pixel.
    #[arg(long = "spp", value_name = "N,N,...", value_delimiter = ',')]
    pub spps: Vec<u32>,
    /// Directory for the references, the renders, sweep.csv and the plots.
    #[arg(long)]
    pub out: PathBuf,
    /// Largest cut per shading point (default: each mode's).
    #[arg(long)]
    pub max_cut: Option<usize>,
    #[command(flatten)]
    pub pass: PassArgs,
    /// Print the rows as JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    #[arg(long, short)]
    pub quiet: bool,
}

/// What identifies a reference render: reused only when all of it matches.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct ReferenceKey {
    scene: String,
    /// Every file the scene read (the scene file, meshes, textures, the
    /// environment map) with a SplitMix hash of its bytes: a changed texture
    /// must not reuse a reference rendered with the old one.
    inputs: Vec<(String, u64)>,
    /// The renderer's version and a hash of its executable: a rebuilt binary
    /// may render differently, so it renders its own reference.
    renderer: String,
    width: u32,
    height: u32,
    spp: u32,
    seed: u64,
    bounds: [u32; 4],
    /// The glTF camera asked for by name (--camera).
    #[serde(default)]
    camera: Option<String>,
    /// What the command line added to or changed in the scene (an
    /// environment, a sun, the indirect method and depth, the shutter...):
    /// a reference rendered without paths must not be reused for a sweep
    /// with them.
    #[serde(default)]
    additions: Vec<String>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
struct ReferenceRecord {
    key: ReferenceKey,
    seconds: f64,
    shadow_rays: u64,
}

#[derive(Debug, Clone, Serialize)]
pub struct SweepRow {
    pub mode: SweepMode,
    pub spp: u32,
    pub threshold: f64,
    pub seconds: f64,
    pub speedup: f64,
    pub average_cut: f64,
    pub max_cut: u64,
    pub shadow_rays_per_pixel: f64,
    pub mean_relative_error: f64,
    pub p99_relative_error: f64,
    pub max_relative_error: f64,
    pub fraction_above_2_percent: f64,
}

fn hash_file(path: &Path) -> Result<u64, OutputError> {
    crate::util::hash::hash_file(path).map_err(OutputError::io(path, "read the file to hash it"))
}

/// `lightcuts VERSION EXE-HASH`: the running binary, exactly.
fn renderer_identity() -> Result<String, OutputError> {
    let exe =
        std::env::current_exe().map_err(OutputError::io(Path::new("lightcuts"), "find the running executable"))?;
    Ok(format!("lightcuts {} {:016x}", env!("CARGO_PKG_VERSION"), hash_file(&exe)?))
}

fn rgb(film: &Film) -> Vec<DVec3> {
    film.rgb().iter().map(|p| DVec3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2]))).collect()
}

fn metadata(
    scene: &Scene,
    key: &ReferenceKey,
    settings: &PassSettings,
    mode: String,
    result: &PassResult,
) -> ExrMetadata {
    ExrMetadata {
        scene_file: scene.path.clone(),
        render_mode: mode,
        render_seconds: result.seconds,
        lights: (result.lights.iter().sum::<usize>() + result.moving_lights) as u64,
        spp: settings.spp,
        seed: settings.seed,
        scene_hash: crate::util::hash::combined_hex(
            key.inputs
                .iter()
                .map(|(_, h)| *h)
                .chain(key.additions.iter().map(|a| crate::util::hash::hash_bytes(a.as_bytes()))),
        ),
        world_to_camera: Some(scene.camera(settings.width, settings.height).world_to_camera().to_cols_array()),
        world_to_ndc: Some(scene.camera(settings.width, settings.height).world_to_ndc().to_cols_array()),
    }
}

/// The exact reference at `key.spp` samples per pixel: reused from `dir`
/// when its record matches `key`.
fn reference(
    session: &Session<'_>,
    settings: &PassSettings,
    key: &ReferenceKey,
    dir: &Path,
    quiet: bool,
) -> Result<(Vec<DVec3>, ReferenceRecord), CliError> {
    let name = format!("reference-spp{}", key.spp);
    let (exr_path, record_path) = (dir.join(format!("{name}.exr")), dir.join(format!("{name}.json")));
    if let Ok(text) = std::fs::read_to_string(&record_path) {
        if let Ok(record) = serde_json::from_str::<ReferenceRecord>(&text) {
            if record.key == *key {
                if let Ok(image) = read_exr(&exr_path) {
                    let (r, g, b) = (
                        image.channel(&exr_path, "R")?,
                        image.channel(&exr_path, "G")?,
                        image.channel(&exr_path, "B")?,
                    );
                    let pixels =
                        (0..r.len()).map(|i| DVec3::new(f64::from(r[i]), f64::from(g[i]), f64::from(b[i]))).collect();
                    if !quiet {
                        eprintln!("sweep: reusing {}", exr_path.display());
                    }
                    return Ok((pixels, record));
                }
            }
        }
    }
    let progress = Progress::for_stderr("exact", quiet);
    let result = session.render(settings, Mode::Exact, &|event| progress.report(event))?;
    for warning in result.warnings() {
        eprintln!("warning: {warning}");
    }
    let meta = metadata(session.scene, key, settings, "exact".into(), &result);
    write_exr(&exr_path, &result.film, false, &meta)?;
    let record =
        ReferenceRecord { key: key.clone(), seconds: result.seconds, shadow_rays: result.stats.shading.shadow_rays };
    let text = serde_json::to_string_pretty(&record).expect("plain data serialises");
    write_atomically(&record_path, |file| {
        file.write_all(text.as_bytes()).map_err(OutputError::io(&record_path, "write"))
    })?;
    Ok((rgb(&result.film), record))
}

pub fn run(args: &SweepArgs) -> Result<(), CliError> {
    let scene = args.pass.load(&args.scene)?;
    if args.errors.is_empty() || args.modes.is_empty() {
        return Err(CliError::Usage { flag: "--errors", message: "give at least one threshold and one mode".into() });
    }
    let spps = if args.spps.is_empty() { vec![scene.film.spp] } else { args.spps.clone() };
    std::fs::create_dir_all(&args.out).map_err(OutputError::io(&args.out, "create the directory"))?;
    let inputs = scene
        .inputs
        .iter()
        .map(|path| Ok((path.display().to_string(), hash_file(path)?)))
        .collect::<Result<Vec<_>, OutputError>>()?;
    let renderer = renderer_identity()?;
    let session = Session::try_new(&scene, args.pass.threads)?;
    let mut rows = Vec::new();
    let mut references = Vec::new();
    for &spp in &spps {
        // The reference's AOVs are the exact mode's; the cut modes' add the cut's.
        let mut settings = args.pass.settings(&scene, Some(spp))?;
        let b = settings.bounds;
        let key = ReferenceKey {
            scene: std::fs::canonicalize(&scene.path).unwrap_or_else(|_| scene.path.clone()).display().to_string(),
            inputs: inputs.clone(),
            renderer: renderer.clone(),
            width: settings.width,
            height: settings.height,
            spp: settings.spp,
            seed: settings.seed,
            bounds: [b.x0, b.x1, b.y0, b.y1],
            camera: args.pass.camera.clone(),
            additions: scene.additions.clone(),
        };
        let (reference_rgb, record) = reference(&session, &settings, &key, &args.out, args.quiet)?;
        settings.aovs = Aovs::all(true);
        let pixels = b.area().max(1) as f64;
        for &sweep_mode in &args.modes {
            let defaults = match sweep_mode {
                SweepMode::Bounded => CutSettings::default(),
                SweepMode::Stochastic => STOCHASTIC_DEFAULTS,
                SweepMode::Multidimensional => MULTIDIMENSIONAL_DEFAULTS,
            };
            for &error in &args.errors {
                let cut = cut_settings(error, args.max_cut.unwrap_or(defaults.max_cut))?;
                let mode = sweep_mode.mode(cut);
                let progress =
                    Progress::for_stderr(&format!("{} {spp} spp error {error}", sweep_mode.name()), args.quiet);
                let result = session.render(&settings, mode, &|event| progress.report(event))?;
                for warning in result.warnings() {
                    eprintln!("warning: {warning}");
                }
                let comparison =
                    compare_rgb(&rgb(&result.film), &reference_rgb, b.width() as usize, b.height() as usize).summary;
                let path = args.out.join(format!("{}-spp{spp}-error-{error}.exr", sweep_mode.name()));
                let meta = metadata(&scene, &key, &settings, mode.describe(), &result);
                write_exr(&path, &result.film, false, &meta)?;
                let shading = &result.stats.shading;
                rows.push(SweepRow {
                    mode: sweep_mode,
                    spp,
                    threshold: cut.error,
                    seconds: result.seconds,
                    speedup: record.seconds / result.seconds.max(1e-9),
                    average_cut: shading.cut_nodes as f64 / shading.shading_points.max(1) as f64,
                    max_cut: shading.max_cut,
                    shadow_rays_per_pixel: shading.shadow_rays as f64 / pixels,
                    mean_relative_error: comparison.mean_relative_error,
                    p99_relative_error: comparison.p99_relative_error,
                    max_relative_error: comparison.max_relative_error,
                    fraction_above_2_percent: comparison.fraction_above_2_percent,
                });
            }
        }
        references.push((spp, record, pixels));
    }
    write_csv(&args.out.join("sweep.csv"), &rows)?;
    for (statistic, file) in [(Statistic::Mean, "sweep"), (Statistic::P99, "sweep-p99")] {
        let plot = plot(&scene, &rows, &references, statistic);
        plot.write_svg(&args.out.join(format!("{file}.svg")))?;
        plot.write_png(&args.out.join(format!("{file}.png")))?;
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&rows).expect("plain data serialises"));
        return Ok(());
    }
    print_table(&references, &rows);
    println!("wrote {}/sweep.csv, sweep.svg, sweep.png, sweep-p99.svg, sweep-p99.png", args.out.display());
    Ok(())
}

/// The references' figures, then a row per render.
fn print_table(references: &[(u32, ReferenceRecord, f64)], rows: &[SweepRow]) {
    for (spp, record, pixels) in references {
        println!(
            "exact reference at {spp} spp: {:.3} s, {:.1} shadow rays per pixel",
            record.seconds,
            record.shadow_rays as f64 / pixels
        );
    }
    println!(
        "{:>10} {:>5} {:>9} {:>9} {:>8} {:>8} {:>7} {:>9} {:>9} {:>9} {:>9} {:>8}",
        "mode",
        "spp",
        "threshold",
        "time (s)",
        "speedup",
        "avg cut",
        "max cut",
        "rays/px",
        "mean err",
        "p99 err",
        "max err",
        "> 2%"
    );
    for r in rows {
        println!(
            "{:>10} {:>5} {:>9} {:>9.3} {:>7.1}x {:>8.1} {:>7} {:>9.1} {:>8.3}% {:>8.2}% {:>8.2}% {:>7.2}%",
            r.mode.name(),
            r.spp,
            r.threshold,
            r.seconds,
            r.speedup,
            r.average_cut,
            r.max_cut,
            r.shadow_rays_per_pixel,
            100.0 * r.mean_relative_error,
            100.0 * r.p99_relative_error,
            100.0 * r.max_relative_error,
            100.0 * r.fraction_above_2_percent
        );
    }
}

/// One CSV row per threshold, with the columns of [`SweepRow`].
fn write_csv(path: &Path, rows: &[SweepRow]) -> Result<(), OutputError> {
    let csv_error = |source| OutputError::Csv { path: path.to_path_buf(), source };
    write_atomically(path, |file| {
        let mut writer = csv::Writer::from_writer(file);
        for row in rows {
            writer.serialize(row).map_err(csv_error)?;
        }
        writer.flush().map_err(OutputError::io(path, "write"))
    })
}

/// Which error statistic a plot shows.
#[derive(Debug, Clone, Copy)]
enum Statistic {
    Mean,
    P99,
}

/// Error against time, one series per (mode, spp): colour by samples per
/// pixel, dashed for the stochastic mode; each point labelled with its
/// threshold.
fn plot(scene: &Scene, rows: &[SweepRow], references: &[(u32, ReferenceRecord, f64)], statistic: Statistic) -> Plot {
    const COLOURS: [[u8; 3]; 6] =
        [[200, 40, 40], [40, 80, 200], [30, 150, 60], [150, 60, 180], [220, 130, 0], [0, 0, 0]];
    let label = |t: f64| format!("{}%", 100.0 * t);
    let value = |r: &SweepRow| match statistic {
        Statistic::Mean => r.mean_relative_error,
        Statistic::P99 => r.p99_relative_error,
    };
    let mut series = Vec::new();
    for (i, (spp, record, _)) in references.iter().enumerate() {
        for mode in [SweepMode::Bounded, SweepMode::Stochastic, SweepMode::Multidimensional] {
            let points: Vec<_> = rows
                .iter()
                .filter(|r| r.spp == *spp && r.mode == mode)
                .map(|r| (r.seconds, 100.0 * value(r), label(r.threshold)))
                .collect();
            if !points.is_empty() {
                series.push(Series {
                    name: format!("{} {spp} spp (exact {:.1} s)", mode.name(), record.seconds),
                    colour: COLOURS[i % COLOURS.len()],
                    dashed: mode != SweepMode::Bounded,
                    points,
                });
            }
        }
    }
    let name = scene.path.file_stem().map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned());
    let what = match statistic {
        Statistic::Mean => "mean",
        Statistic::P99 => "99th percentile",
    };
    Plot {
        title: format!("{name}: lightcuts' {what} relative error against time"),
        x_label: "render time (s)".into(),
        y_label: format!("{what} relative error (%)"),
        series,
    }
}
