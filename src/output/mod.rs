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
    /// An output names something that is not a regular file (a device such
    /// as `/dev/null`, a directory, a FIFO), which an output never replaces.
    #[error("{}: is not a regular file; an output replaces only a regular file", path.display())]
    NotRegular { path: PathBuf },
    /// An output names a file the command reads (its scene, a texture, an
    /// environment map, a tile), or another of its outputs.
    #[error("{}: is also {what} '{}'; an output must be a file of its own", path.display(), other.display())]
    NamesAnother { path: PathBuf, what: &'static str, other: PathBuf },
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
    /// An EXR to read whose header is refused before its pixels are read
    /// (`scene::image::check_exr_header`), or that is not a regular file.
    #[error("{}: {source}", path.display())]
    ExrHeader {
        path: PathBuf,
        #[source]
        source: crate::scene::image::ImageError,
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
    stage(path, write)?.commit()
}

/// An output written in full to a temporary file beside its place, not yet
/// renamed into it: a command that writes several outputs stages them all
/// and commits them only when every one was written, so a failure of the
/// last leaves every earlier place as it was. Dropped uncommitted, the
/// temporary file is removed.
pub struct Staged {
    /// The temporary file; None once committed.
    partial: Option<tempfile::NamedTempFile>,
    path: PathBuf,
}

impl Staged {
    /// Renames the temporary file into place.
    pub fn commit(mut self) -> Result<(), OutputError> {
        let Some(partial) = self.partial.take() else { return Ok(()) };
        let partial_path = partial.path().to_path_buf();
        let result = check_replaceable(&self.path).and_then(|_| {
            partial.persist(&self.path).map(drop).map_err(|e| OutputError::Io {
                path: self.path.clone(),
                action: "rename the temporary file into place",
                source: e.error,
            })
        });
        temporary::unregister(&partial_path);
        result
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if let Some(partial) = &self.partial {
            temporary::unregister(partial.path());
        }
    }
}

/// [`write_atomically`]'s first half: the file written through `write` to a
/// temporary file beside `path`, checked to be a place an output may take.
pub fn stage(path: &Path, write: impl FnOnce(&mut File) -> Result<(), OutputError>) -> Result<Staged, OutputError> {
    let directory = check_replaceable(path)?;
    let name = path.file_name().map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
    let mut partial = tempfile::Builder::new()
        .prefix(&format!(".{name}."))
        .suffix(".partial")
        .permissions(plain_create_permissions())
        .tempfile_in(&directory)
        .map_err(OutputError::io(path, "create the temporary file"))?;
    temporary::register(partial.path());
    let staged_path = partial.path().to_path_buf();
    if let Err(e) = write(partial.as_file_mut()) {
        temporary::unregister(&staged_path);
        return Err(e);
    }
    Ok(Staged { partial: Some(partial), path: path.to_path_buf() })
}

/// The directory `path` is written in, when an output may take `path`: the
/// directory exists, and `path` is absent or a regular file (never a device,
/// a directory or a FIFO: `-o /dev/null` once replaced the device node).
fn check_replaceable(path: &Path) -> Result<PathBuf, OutputError> {
    let directory = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if !directory.is_dir() {
        return Err(OutputError::NoDirectory { path: path.to_path_buf(), directory });
    }
    match std::fs::metadata(path) {
        Ok(meta) if !meta.is_file() => Err(OutputError::NotRegular { path: path.to_path_buf() }),
        _ => Ok(directory),
    }
}

/// Checks, before any work, that each of `outputs` may be written: its
/// directory exists and takes a new file, it is absent or a regular file,
/// and it names none of `inputs` (the files the command reads) nor another
/// output. A command calls it before it renders, so that a wrong output
/// costs no render and destroys nothing.
pub fn check_outputs(outputs: &[&Path], inputs: &[PathBuf]) -> Result<(), OutputError> {
    let identity = |p: &Path| -> Option<PathBuf> {
        let directory = match p.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        Some(directory.canonicalize().ok()?.join(p.file_name()?))
    };
    for (i, &output) in outputs.iter().enumerate() {
        let directory = check_replaceable(output)?;
        // The directory takes a new file (write permission, a writable file system).
        tempfile::Builder::new()
            .prefix(".lightcuts-check.")
            .tempfile_in(&directory)
            .map_err(OutputError::io(output, "create a file in its directory"))?;
        let Some(id) = identity(output) else { continue };
        let same = |other: &Path| identity(other).is_some_and(|o| o == id) || same_file(output, other);
        if let Some(input) = inputs.iter().find(|input| same(input)) {
            return Err(OutputError::NamesAnother {
                path: output.to_path_buf(),
                what: "an input",
                other: input.clone(),
            });
        }
        if let Some(&other) = outputs[..i].iter().find(|&&other| same(other)) {
            return Err(OutputError::NamesAnother {
                path: output.to_path_buf(),
                what: "another output",
                other: other.to_path_buf(),
            });
        }
    }
    Ok(())
}

/// Whether `a` and `b` are the same existing file (one device and inode:
/// a hard link, or a symbolic link to it).
fn same_file(a: &Path, b: &Path) -> bool {
    use std::os::unix::fs::MetadataExt as _;
    match (std::fs::metadata(a), std::fs::metadata(b)) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

/// The mode `File::create` asks the kernel for; the kernel applies the
/// umask to it at creation, as to any `open(O_CREAT)`.
fn plain_create_permissions() -> std::fs::Permissions {
    use std::os::unix::fs::PermissionsExt as _;
    std::fs::Permissions::from_mode(0o666)
}
