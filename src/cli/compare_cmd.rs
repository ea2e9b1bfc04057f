//! `lightcuts compare`: relative error of a render against a reference.

use std::path::PathBuf;

use clap::Args;

use super::CliError;
use crate::output::compare::{compare_files, heat, Comparison};
use crate::output::exr::stage_diff_exr;
use crate::output::preview::stage_rgb_png;
use crate::output::{check_outputs, Staged};

#[derive(Debug, Args)]
pub struct CompareArgs {
    /// The image under test.
    pub test: PathBuf,
    /// The reference (usually a `--method exact` render of the same scene and settings).
    pub reference: PathBuf,
    /// Print the figures as JSON.
    #[arg(long)]
    pub json: bool,
    /// Write a heat map of the relative error as a PNG.
    #[arg(long, value_name = "DIFF.png")]
    pub diff: Option<PathBuf>,
    /// Write the absolute difference (R, G, B) and relative error as an EXR.
    #[arg(long, value_name = "DIFF.exr")]
    pub diff_exr: Option<PathBuf>,
    /// Also compare the mean luminance of N x N-pixel blocks, skipping
    /// blocks across silhouettes (found from a Z channel): the comparison
    /// that suits a noisy reference such as a path tracer's.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub blocks: Option<u32>,
}

pub fn run(args: &CompareArgs) -> Result<(), CliError> {
    let outputs: Vec<&std::path::Path> = args.diff.iter().chain(&args.diff_exr).map(PathBuf::as_path).collect();
    check_outputs(&outputs, &[args.test.clone(), args.reference.clone()])?;
    let result = compare_files(&args.test, &args.reference, args.blocks.map(|b| b as usize))?;
    let png = args
        .diff
        .as_ref()
        .map(|path| {
            let rgb: Vec<u8> = result.relative.iter().flat_map(|&e| heat(e)).collect();
            stage_rgb_png(path, result.width as u32, result.height as u32, &rgb)
        })
        .transpose()?;
    let exr = args.diff_exr.as_ref().map(|path| stage_diff_exr(path, &result)).transpose()?;
    png.map(Staged::commit).transpose()?;
    exr.map(Staged::commit).transpose()?;
    print_comparison(&result.summary, args.json);
    Ok(())
}

fn print_comparison(c: &Comparison, json: bool) {
    if json {
        println!("{}", serde_json::to_string_pretty(c).expect("plain numbers serialise"));
        return;
    }
    println!("pixels                 {}", c.pixels);
    println!("relative error (luminance, floor {:.3e})", c.floor);
    println!("  mean                 {:.4}%", 100.0 * c.mean_relative_error);
    println!("  median               {:.4}%", 100.0 * c.median_relative_error);
    println!("  95th percentile      {:.4}%", 100.0 * c.p95_relative_error);
    println!("  99th percentile      {:.4}%", 100.0 * c.p99_relative_error);
    println!("  maximum              {:.4}%", 100.0 * c.max_relative_error);
    println!("pixels above 1%        {:.4}%", 100.0 * c.fraction_above_1_percent);
    println!("pixels above 2%        {:.4}%", 100.0 * c.fraction_above_2_percent);
    println!("pixels above 5%        {:.4}%", 100.0 * c.fraction_above_5_percent);
    println!("RMSE                   {:.6e}", c.rmse);
    println!("relative MSE           {:.6e}", c.relative_mse);
    println!(
        "mean luminance         {:.6} vs {:.6} (ratio {:.4})",
        c.mean_luminance,
        c.reference_mean_luminance,
        c.mean_luminance / c.reference_mean_luminance.max(f64::MIN_POSITIVE)
    );
    if let Some(b) = &c.blocks {
        println!("{0}x{0} blocks            {1} compared, {2} skipped (silhouettes)", b.size, b.blocks, b.skipped);
        println!("  mean relative error  {:.4}%", 100.0 * b.mean_relative_error);
        println!("  median               {:.4}%", 100.0 * b.median_relative_error);
        println!("  95th percentile      {:.4}%", 100.0 * b.p95_relative_error);
        println!("  maximum              {:.4}%", 100.0 * b.max_relative_error);
    }
    if !c.groups.is_empty() {
        println!("light groups           mean error   99th pct.    mean luminance (test / reference)");
        for g in &c.groups {
            println!(
                "  {:<20} {:>9.4}%  {:>9.4}%    {:.6} / {:.6}",
                g.group,
                100.0 * g.mean_relative_error,
                100.0 * g.p99_relative_error,
                g.mean_luminance,
                g.reference_mean_luminance
            );
        }
    }
}
