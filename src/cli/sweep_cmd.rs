//! `lightcuts sweep`: the speed/accuracy trade over a list of error
//! thresholds, each measured against the exact render of the same scene and
//! settings (rendered once, and reused from DIR when it matches).

use std::io::Write as _;
use std::path::{Path, PathBuf};

use clap::Args;
use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::progress::Progress;
use super::render_cmd::{cut_settings, render_mode, PassArgs};
use super::CliError;
use crate::output::compare::compare_rgb;
use crate::output::exr::{write_exr, ExrChannels, ExrMetadata};
use crate::output::plot::{Plot, Series};
use crate::output::read::read_exr;
use crate::output::{write_atomically, OutputError};
use crate::render::session::{PassResult, Session};
use crate::render::{Film, PassSettings};
use crate::scene::Scene;

#[derive(Debug, Args)]
pub struct SweepArgs {
    pub scene: PathBuf,
    /// Error thresholds, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [0.001, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2])]
    pub errors: Vec<f64>,
    /// Directory for the reference, the renders, sweep.csv, sweep.svg and sweep.png.
    #[arg(long)]
    pub out: PathBuf,
    #[arg(long, default_value_t = 1000)]
    pub max_cut: usize,
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
}

#[derive(Debug, Clone, Serialize, Deserialize)]
struct ReferenceRecord {
    key: ReferenceKey,
    seconds: f64,
    shadow_rays: u64,
}

#[derive(Debug, Clone, Serialize)]
pub struct SweepRow {
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

fn hash_bytes(bytes: &[u8]) -> u64 {
    bytes.chunks(8).fold(0x243f_6a88_85a3_08d3, |h, c| {
        let mut word = [0u8; 8];
        word[..c.len()].copy_from_slice(c);
        crate::util::sampling::mix64(h ^ u64::from_le_bytes(word))
    })
}

fn hash_file(path: &Path) -> Result<u64, OutputError> {
    let bytes = std::fs::read(path).map_err(OutputError::io(path, "read the file to hash it"))?;
    Ok(hash_bytes(&bytes))
}

/// `lightcuts VERSION EXE-HASH`: the running binary, exactly.
fn renderer_identity() -> Result<String, OutputError> {
    let exe =
        std::env::current_exe().map_err(OutputError::io(Path::new("lightcuts"), "find the running executable"))?;
    Ok(format!("lightcuts {} {:016x}", env!("CARGO_PKG_VERSION"), hash_file(&exe)?))
}

fn rgb(film: &Film) -> Vec<DVec3> {
    film.pixels.iter().map(|p| DVec3::new(f64::from(p.rgb[0]), f64::from(p.rgb[1]), f64::from(p.rgb[2]))).collect()
}

fn metadata(scene: &Scene, settings: &PassSettings, mode: String, result: &PassResult) -> ExrMetadata {
    ExrMetadata {
        scene_file: scene.path.clone(),
        render_mode: mode,
        render_seconds: result.seconds,
        lights: result.lights.iter().sum::<usize>() as u64,
        spp: settings.spp,
        seed: settings.seed,
    }
}

/// The exact reference: reused from `dir` when its record matches `key`.
fn reference(
    session: &Session<'_>,
    settings: &PassSettings,
    key: &ReferenceKey,
    dir: &Path,
    quiet: bool,
) -> Result<(Vec<DVec3>, ReferenceRecord), CliError> {
    let (exr_path, record_path) = (dir.join("reference.exr"), dir.join("reference.json"));
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
    let result = session.render(settings, None, &|event| progress.report(event));
    let meta = metadata(session.scene, settings, "exact".into(), &result);
    write_exr(&exr_path, &result.film, ExrChannels { half_beauty: false, lightcut_aovs: false }, &meta)?;
    let record =
        ReferenceRecord { key: key.clone(), seconds: result.seconds, shadow_rays: result.stats.shading.shadow_rays };
    let text = serde_json::to_string_pretty(&record).expect("plain data serialises");
    write_atomically(&record_path, |file| {
        file.write_all(text.as_bytes()).map_err(OutputError::io(&record_path, "write"))
    })?;
    Ok((rgb(&result.film), record))
}

pub fn run(args: &SweepArgs) -> Result<(), CliError> {
    let scene = Scene::load(&args.scene)?;
    let settings = args.pass.settings(&scene)?;
    let cuts = args.errors.iter().map(|&e| cut_settings(e, args.max_cut)).collect::<Result<Vec<_>, _>>()?;
    if cuts.is_empty() {
        return Err(CliError::Usage { flag: "--errors", message: "give at least one threshold".into() });
    }
    std::fs::create_dir_all(&args.out).map_err(OutputError::io(&args.out, "create the directory"))?;
    let b = settings.bounds;
    let key = ReferenceKey {
        scene: std::fs::canonicalize(&scene.path).unwrap_or_else(|_| scene.path.clone()).display().to_string(),
        inputs: scene
            .inputs
            .iter()
            .map(|path| Ok((path.display().to_string(), hash_file(path)?)))
            .collect::<Result<_, OutputError>>()?,
        renderer: renderer_identity()?,
        width: settings.width,
        height: settings.height,
        spp: settings.spp,
        seed: settings.seed,
        bounds: [b.x0, b.x1, b.y0, b.y1],
    };
    let session = Session::try_new(&scene, args.pass.threads)?;
    let (reference_rgb, record) = reference(&session, &settings, &key, &args.out, args.quiet)?;
    let pixels = b.area().max(1) as f64;
    let mut rows = Vec::new();
    for cut in cuts {
        let progress = Progress::for_stderr(&format!("error {}", cut.error), args.quiet);
        let result = session.render(&settings, Some(cut), &|event| progress.report(event));
        let comparison =
            compare_rgb(&rgb(&result.film), &reference_rgb, b.width() as usize, b.height() as usize).summary;
        let path = args.out.join(format!("error-{}.exr", cut.error));
        let meta = metadata(&scene, &settings, render_mode(Some(cut)), &result);
        write_exr(&path, &result.film, ExrChannels { half_beauty: false, lightcut_aovs: true }, &meta)?;
        let shading = &result.stats.shading;
        rows.push(SweepRow {
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
    write_csv(&args.out.join("sweep.csv"), &rows)?;
    let plot = plot(&scene, &rows, record.seconds);
    plot.write_svg(&args.out.join("sweep.svg"))?;
    plot.write_png(&args.out.join("sweep.png"))?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&rows).expect("plain data serialises"));
    } else {
        println!(
            "exact reference: {:.3} s, {:.1} shadow rays per pixel",
            record.seconds,
            record.shadow_rays as f64 / pixels
        );
        println!(
            "{:>9} {:>9} {:>8} {:>8} {:>7} {:>9} {:>9} {:>9} {:>9} {:>8}",
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
        for r in &rows {
            println!(
                "{:>9} {:>9.3} {:>7.1}x {:>8.1} {:>7} {:>9.1} {:>8.3}% {:>8.2}% {:>8.2}% {:>7.2}%",
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
        println!("wrote {}/sweep.csv, sweep.svg, sweep.png", args.out.display());
    }
    Ok(())
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

fn plot(scene: &Scene, rows: &[SweepRow], exact_seconds: f64) -> Plot {
    let label = |t: f64| format!("{}%", 100.0 * t);
    let series = |name: &str, colour, dashed, f: &dyn Fn(&SweepRow) -> f64| Series {
        name: name.into(),
        colour,
        dashed,
        points: rows.iter().map(|r| (r.seconds, 100.0 * f(r), label(r.threshold))).collect(),
    };
    let name = scene.path.file_stem().map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned());
    Plot {
        title: format!("{name}: lightcuts error against time (exact: {exact_seconds:.2} s)"),
        x_label: "render time (s)".into(),
        y_label: "relative error (%)".into(),
        series: vec![
            series("mean", [200, 40, 40], false, &|r| r.mean_relative_error),
            series("99th percentile", [40, 80, 200], true, &|r| r.p99_relative_error),
        ],
    }
}
