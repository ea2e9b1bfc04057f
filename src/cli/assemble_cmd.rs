//! `lightcuts assemble`: one frame from the tiles of `render --tile I/N`
//! (or any `--pixel-bounds` windows that cover the frame once).

use std::path::PathBuf;

use clap::Args;

use super::CliError;
use crate::output::assemble::{assemble, MUST_AGREE};

#[derive(Debug, Args)]
pub struct AssembleArgs {
    /// The assembled frame (written atomically).
    #[arg(value_name = "OUT.exr")]
    pub output: PathBuf,
    /// The tiles: EXRs of the same render whose data windows cover the
    /// frame (their display window) exactly once.
    #[arg(value_name = "TILE.exr", required = true)]
    pub tiles: Vec<PathBuf>,
}

pub fn run(args: &AssembleArgs) -> Result<(), CliError> {
    crate::output::check_outputs(&[args.output.as_path()], &args.tiles)?;
    let done = assemble(&args.output, &args.tiles)?;
    println!(
        "{}: {}x{} from {} tiles (checked: {}; render time {:.3} s in all)",
        args.output.display(),
        done.width,
        done.height,
        done.tiles,
        MUST_AGREE.join(", "),
        done.render_seconds
    );
    Ok(())
}
