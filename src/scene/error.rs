//! Errors in a scene file: every one names the file and the field (or line).

use std::path::{Path, PathBuf};

/// Something wrong with a scene or a file it refers to. Caused by the user's
/// input; the message names the file and the field path (e.g.
/// `lights[3].intensity`) or the line and column.
#[derive(Debug, thiserror::Error)]
#[error("{}: {location}: {message}", file.display())]
pub struct SceneError {
    /// The file at fault: the scene file, or a mesh or texture it names.
    pub file: PathBuf,
    /// Field path (`shapes[2].radius`) or position (`line 4, column 9`).
    pub location: String,
    /// What is wrong, with the offending value where there is one.
    pub message: String,
}

impl SceneError {
    /// The message is folded onto one line (parsers' messages span several):
    /// one error, one line.
    pub fn new(file: &Path, location: impl Into<String>, message: impl Into<String>) -> Self {
        let fold = |text: String| text.lines().map(str::trim).filter(|l| !l.is_empty()).collect::<Vec<_>>().join("; ");
        // A location can quote the file (a malformed path a stage authors).
        Self { file: file.to_path_buf(), location: fold(location.into()), message: fold(message.into()) }
    }
}
