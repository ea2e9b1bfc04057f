//! Writing images: the HDR OpenEXR (beauty plus AOVs), a tone-mapped PNG
//! preview, and comparison metrics. Every file is written to a temporary name
//! in the destination directory and renamed into place, so a reader never sees
//! a half-written image under the output name.

pub mod assemble;
pub mod compare;
pub mod exr;
pub mod plot;
pub mod preview;
pub mod read;
pub mod temporary;

use std::fs::File;
use std::path::{Path, PathBuf};

/// Failure to write (or read back) an output file. Each variant names the
/// file; the cause is the environment (missing directory, full disk,
/// permissions, a missing font) or an image that is not what the command
/// needs (a missing channel, windows that differ).
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The directory an output was to be written in does not exist.
    #[error("{}: the directory '{}' does not exist", path.display(), directory.display())]
    NoDirectory { path: PathBuf, directory: PathBuf },
    /// Creating, writing, renaming or reading a file failed.
    #[error("{}: cannot {action}: {source}", path.display())]
    Io {
        path: PathBuf,
        /// What was being done, e.g. "create the temporary file".
        action: &'static str,
        #[source]
        source: std::io::Error,
    },
    /// The EXR encoder failed, or the decoder rejected a file.
    #[error("{}: cannot {action} EXR: {source}", path.display())]
    Exr {
        path: PathBuf,
        /// "read" or "write".
        action: &'static str,
        #[source]
        source: ::exr::error::Error,
    },
    /// The PNG encoder failed.
    #[error("{}: cannot write PNG: {source}", path.display())]
    Png {
        path: PathBuf,
        #[source]
        source: png::EncodingError,
    },
    /// The CSV writer failed.
    #[error("{}: cannot write CSV: {source}", path.display())]
    Csv {
        path: PathBuf,
        #[source]
        source: csv::Error,
    },
    /// Drawing a plot failed.
    #[error("{}: cannot draw the plot: {source}", path.display())]
    Plot {
        path: PathBuf,
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// No font to draw a plot's text with.
    #[error(
        "{}: no font for the plot's text: none of {tried} is a readable font; install fonts-dejavu-core \
         (ci/setup.sh does) or set LIGHTCUTS_FONT to a TrueType font",
        path.display()
    )]
    NoFont { path: PathBuf, tried: String },
    /// An image lacks a channel the command needs.
    #[error("{}: channel '{channel}' missing (has {available})", path.display())]
    MissingChannel { path: PathBuf, channel: String, available: String },
    /// A tile to assemble disagrees with the first tile.
    #[error("{}: {what} is '{found}', but {} has '{expected}': tiles of different renders", path.display(), reference.display())]
    TileMismatch { path: PathBuf, reference: PathBuf, what: String, found: String, expected: String },
    /// A tile's data window reaches outside its display window (a file
    /// another tool wrote: ours are bands of the frame).
    #[error(
        "{}: its data window x {}..{}, y {}..{} is not inside its display window x {}..{}, y {}..{}: a tile must be \
         a part of the frame",
        path.display(), window[0], window[1], window[2], window[3], display[0], display[1], display[2], display[3]
    )]
    TileOutsideFrame { path: PathBuf, window: [i64; 4], display: [i64; 4] },
    /// A tile's display window does not start at (0, 0), where every frame
    /// lightcuts renders starts (and where `assemble` writes the frame).
    #[error("{}: its display window starts at ({x}, {y}): tiles of a lightcuts frame start at (0, 0)", path.display())]
    DisplayWindowOrigin { path: PathBuf, x: i32, y: i32 },
    /// Two tiles cover the same pixels.
    #[error(
        "{}: overlaps {} on x {}..{}, y {}..{}",
        path.display(), other.display(), window[0], window[1], window[2], window[3]
    )]
    TileOverlap { path: PathBuf, other: PathBuf, window: [u32; 4] },
    /// The tiles leave pixels of the frame uncovered.
    #[error("{}: {pixels} pixels of the frame are in no tile: {missing}", path.display())]
    TileGaps { path: PathBuf, pixels: u64, missing: String },
    /// None of the tile files to assemble exists.
    #[error("{}: none of the tiles exists: {missing}", path.display())]
    NoTiles { path: PathBuf, missing: String },
    /// Two images to compare do not cover the same pixels.
    #[error(
        "{}: data window {}x{} at ({}, {}) differs from the reference's {}x{} at ({}, {}) ({})",
        path.display(), window[2], window[3], window[0], window[1],
        reference_window[2], reference_window[3], reference_window[0], reference_window[1], reference.display()
    )]
    WindowMismatch {
        path: PathBuf,
        reference: PathBuf,
        /// x0, y0, width, height.
        window: [i64; 4],
        reference_window: [i64; 4],
    },
}

impl OutputError {
    /// An I/O failure while doing `action` to `path`.
    pub fn io<'a>(path: &'a Path, action: &'static str) -> impl FnOnce(std::io::Error) -> Self + 'a {
        move |source| Self::Io { path: path.to_path_buf(), action, source }
    }
}

/// Writes a file through `write` into a temporary file beside `path`, then
/// renames it into place; on any failure (or a SIGINT meanwhile) the
/// temporary file is removed and nothing appears under `path`.
///
/// The file gets the permissions a plain `File::create` would give it:
/// 0666 less the process's umask (the temporary file is created with that
/// mode, which the kernel masks, and the rename keeps it). A temporary
/// file's usual 0600 would lock the compositing user out of a frame the
/// farm's render user wrote.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut File) -> Result<(), OutputError>,
) -> Result<(), OutputError> {
    let directory = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if !directory.is_dir() {
        return Err(OutputError::NoDirectory { path: path.to_path_buf(), directory });
    }
    let name = path.file_name().map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
    let mut partial = tempfile::Builder::new()
        .prefix(&format!(".{name}."))
        .suffix(".partial")
        .permissions(plain_create_permissions())
        .tempfile_in(&directory)
        .map_err(OutputError::io(path, "create the temporary file"))?;
    let partial_path = partial.path().to_path_buf();
    temporary::register(&partial_path);
    // Dropping the NamedTempFile on an error removes the temporary file.
    let result = write(partial.as_file_mut()).and_then(|()| {
        partial.persist(path).map(drop).map_err(|e| OutputError::Io {
            path: path.to_path_buf(),
            action: "rename the temporary file into place",
            source: e.error,
        })
    });
    temporary::unregister(&partial_path);
    result
}

/// The mode `File::create` asks the kernel for; the kernel applies the
/// umask to it at creation, as to any `open(O_CREAT)`.
fn plain_create_permissions() -> std::fs::Permissions {
    use std::os::unix::fs::PermissionsExt as _;
    std::fs::Permissions::from_mode(0o666)
}
