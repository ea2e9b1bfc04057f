//! The command line. This is the only place an error becomes an exit code:
//! everything below returns `Result`s.

mod assemble_cmd;
pub mod bench;
mod compare_cmd;
mod process;
mod progress;
mod render_cmd;
mod sweep_cmd;

use clap::{Parser, Subcommand};

use crate::embree::EmbreeError;
use crate::output::OutputError;
use crate::render::session::SessionError;
use crate::scene::SceneError;

#[derive(Debug, Parser)]
#[command(name = "lightcuts", version, about = "A many-light renderer: Lightcuts (Walter et al. 2005) on Intel Embree")]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Render a scene to an OpenEXR image (beauty + AOVs).
    Render(render_cmd::RenderArgs),
    /// Compare a render against a reference on luminance (relative error).
    Compare(compare_cmd::CompareArgs),
    /// Speed against accuracy over a list of error thresholds.
    Sweep(sweep_cmd::SweepArgs),
    /// Benchmarks that print measured figures (--json for machines).
    Bench(bench::BenchArgs),
    /// Assemble one frame from the tiles of `render --tile I/N`.
    Assemble(assemble_cmd::AssembleArgs),
}

/// Everything that can stop a command, each naming its cause.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// The scene file (or a file it names) is wrong: the user's input.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// An output file could not be written: the environment.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// Embree failed: out of memory or an unsupported CPU.
    #[error(transparent)]
    Embree(#[from] EmbreeError),
    /// The scene could not be prepared for rendering (Embree, threads).
    #[error(transparent)]
    Session(#[from] SessionError),
    /// A command-line value is invalid: the user's input.
    #[error("{flag}: {message}")]
    Usage { flag: &'static str, message: String },
    /// The rayon thread pool could not start.
    #[error("cannot start {threads} worker threads: {source}")]
    Threads {
        threads: usize,
        #[source]
        source: rayon::ThreadPoolBuildError,
    },
}

/// Parses the command line, runs the command, and returns the exit code.
#[must_use]
pub fn main() -> i32 {
    let cli = Cli::parse();
    ctrlc_cleanup();
    let result = match cli.command {
        Command::Render(args) => render_cmd::run(&args),
        Command::Compare(args) => compare_cmd::run(&args),
        Command::Bench(args) => bench::run(&args),
        Command::Sweep(args) => sweep_cmd::run(&args),
        Command::Assemble(args) => assemble_cmd::run(&args),
    };
    match result {
        Ok(()) => 0,
        Err(error) => {
            eprintln!("error: {error}");
            1
        }
    }
}

/// On SIGINT (or SIGTERM, as Slurm's scancel sends) remove any temporary
/// output file being written and any claim held, then exit 130
/// (the shell convention for death by SIGINT).
fn ctrlc_cleanup() {
    let _ = ctrlc::set_handler(|| {
        crate::output::temporary::remove_temporaries();
        eprintln!("interrupted: no output written");
        std::process::exit(130);
    });
}

/// Parses `WxH`.
pub fn parse_resolution(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("expected WIDTHxHEIGHT, got '{s}'"))?;
    let w: u32 = w.trim().parse().map_err(|_| format!("width '{w}' is not a positive integer"))?;
    let h: u32 = h.trim().parse().map_err(|_| format!("height '{h}' is not a positive integer"))?;
    if w == 0 || h == 0 {
        return Err(format!("width and height must be at least 1, got {w}x{h}"));
    }
    Ok((w, h))
}

/// Parses `x0,x1,y0,y1`.
pub fn parse_pixel_bounds(s: &str) -> Result<[u32; 4], String> {
    let parts: Vec<&str> = s.split(',').collect();
    if parts.len() != 4 {
        return Err(format!("expected x0,x1,y0,y1, got '{s}'"));
    }
    let mut out = [0u32; 4];
    for (o, p) in out.iter_mut().zip(&parts) {
        *o = p.trim().parse().map_err(|_| format!("'{p}' is not a non-negative integer"))?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolution_and_bounds_parse_and_reject_garbage() {
        assert_eq!(parse_resolution("640x480"), Ok((640, 480)));
        assert!(parse_resolution("640").is_err());
        assert!(parse_resolution("0x480").is_err());
        assert!(parse_resolution("-3x4").is_err());
        assert_eq!(parse_pixel_bounds("1,2,3,4"), Ok([1, 2, 3, 4]));
        assert!(parse_pixel_bounds("1,2,3").is_err());
        assert!(parse_pixel_bounds("1,2,3,x").is_err());
    }
}
