//! Writing images: the HDR OpenEXR (beauty plus AOVs), a tone-mapped PNG
//! preview, and comparison metrics. Every file is written to a temporary name
//! in the destination directory and renamed into place, so a reader never sees
//! a half-written image under the output name.

pub mod compare;
pub mod exr;
pub mod plot;
pub mod preview;
pub mod read;
pub mod temporary;

use std::path::{Path, PathBuf};

/// Failure to write an output file. Caused by the environment (missing
/// directory, full disk, permissions) or by an encoder error.
#[derive(Debug, thiserror::Error)]
#[error("{}: {message}", path.display())]
pub struct OutputError {
    pub path: PathBuf,
    pub message: String,
}

impl OutputError {
    pub fn new(path: &Path, message: impl Into<String>) -> Self {
        Self { path: path.to_path_buf(), message: message.into() }
    }
}

/// Writes a file through `write` at a temporary path beside `path`, then
/// renames it into place; on any failure the temporary file is removed and
/// nothing appears under `path`.
pub fn write_atomically(path: &Path, write: impl FnOnce(&Path) -> Result<(), String>) -> Result<(), OutputError> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if !dir.is_dir() {
        return Err(OutputError::new(path, format!("the directory '{}' does not exist", dir.display())));
    }
    let name = path.file_name().ok_or_else(|| OutputError::new(path, "not a file name"))?;
    let temporary = dir.join(format!(".{}.{}.partial", name.to_string_lossy(), std::process::id()));
    temporary::register(&temporary);
    let result = write(&temporary).and_then(|()| std::fs::rename(&temporary, path).map_err(|e| e.to_string()));
    if result.is_err() {
        let _ = std::fs::remove_file(&temporary);
    }
    temporary::unregister(&temporary);
    result.map_err(|m| OutputError::new(path, m))
}
