//! Rendering on a farm: the band of rows a tile is, and the claim that
//! keeps two processes from rendering the same output (`--no-overwrite`).

use std::path::{Path, PathBuf};

use super::CliError;

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
pub struct Claim(PathBuf);

impl Claim {
    /// Claims `output`; None when another process holds the claim.
    pub fn take(output: &Path) -> Result<Option<Self>, CliError> {
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
