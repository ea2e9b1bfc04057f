//! The command line. This is the only place an error becomes an exit code:
//! everything below returns `Result`s.

pub mod args;
mod assemble_cmd;
pub mod bench;
mod compare_cmd;
mod farm;
mod inspect_cmd;
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
    Render(args::RenderArgs),
    /// Compare a render against a reference on luminance (relative error).
    Compare(compare_cmd::CompareArgs),
    /// Speed against accuracy over a list of error thresholds.
    Sweep(sweep_cmd::SweepArgs),
    /// Benchmarks that print measured figures (--json for machines).
    Bench(bench::BenchArgs),
    /// Assemble one frame from the tiles of `render --tile I/N`.
    Assemble(assemble_cmd::AssembleArgs),
    /// What a scene becomes once loaded (objects, lights, camera), without rendering.
    Inspect(inspect_cmd::InspectArgs),
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
        Command::Inspect(args) => inspect_cmd::run(&args),
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
