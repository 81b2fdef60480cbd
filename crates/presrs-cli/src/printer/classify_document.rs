//! The `presrs classify --json` document: every sample classified, and the files that could not be.

use presrs::classify::Classified;
use serde::Serialize;

/// A file that could not be classified.
#[derive(Debug, Serialize)]
pub struct FileError {
    pub file: String,
    pub error: String,
}

/// The `--json` document.
#[derive(Debug, Serialize)]
pub struct ClassifyJson {
    /// The model file's path.
    pub model: String,
    pub results: Vec<Classified>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub errors: Vec<FileError>,
}
