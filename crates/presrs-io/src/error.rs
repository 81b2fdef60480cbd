//! The error type of `presrs-io`.
//!
//! Every variant names the file it is about. Parse errors in line-oriented formats also carry the 1-based
//! line number, and their message says what was expected and what was found, e.g.
//! `FrasP01L.asf line 58: frame 3 has 43 values in row 12, expected 21 (COLS)`.

use std::path::{Path, PathBuf};

use presrs_core::CoreError;

use crate::message::{Face, Message};

/// Everything that can go wrong reading or writing files in this crate.
#[derive(Debug, thiserror::Error)]
pub enum IoError {
    /// The operating system refused an operation on a file (open, read, write, rename, ...).
    #[error("cannot {action} {}: {source}", path.display())]
    Io {
        /// What was being done, e.g. `read`, `write`, `create a temporary file next to`.
        action: &'static str,
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// Bad content at a known line of a text file.
    #[error("{file} line {line}: {message}")]
    Parse {
        /// The file name as given by the caller (a path, or a label for in-memory text).
        file: String,
        /// 1-based line number.
        line: usize,
        /// What was expected and what was found.
        message: Message,
    },
    /// Bad content that has no line number (binary formats, or a problem with the file as a whole).
    #[error("{file}: {message}")]
    Format { file: String, message: Message },
    /// The file is well formed but holds something this crate does not support (a colour PNG, a complex
    /// NumPy dtype, ...). The message suggests what to do instead.
    #[error("{file}: {message}")]
    Unsupported { file: String, message: Message },
    /// The data read could not be assembled into a recording (the data model rejected it).
    #[error("{file}: {source}")]
    Model {
        file: String,
        #[source]
        source: CoreError,
    },
}

impl IoError {
    /// An I/O error on `path`.
    pub fn io(action: &'static str, path: &Path, source: std::io::Error) -> Self {
        Self::Io {
            action,
            path: path.to_path_buf(),
            source,
        }
    }

    /// A parse error at 1-based `line` of `file`.
    pub fn parse(file: &str, line: usize, message: impl Into<Message>) -> Self {
        Self::Parse {
            file: file.to_owned(),
            line,
            message: message.into(),
        }
    }

    /// A content error without a line number.
    pub fn format(file: &str, message: impl Into<Message>) -> Self {
        Self::Format {
            file: file.to_owned(),
            message: message.into(),
        }
    }

    /// Well-formed content this crate does not support.
    pub fn unsupported(file: &str, message: impl Into<Message>) -> Self {
        Self::Unsupported {
            file: file.to_owned(),
            message: message.into(),
        }
    }

    /// The error in `face`'s words (`Display` is the command line's): the options a message names
    /// are spelled as `face` spells them.
    pub fn render(&self, face: Face) -> String {
        match self {
            Self::Parse {
                file,
                line,
                message,
            } => format!("{file} line {line}: {}", message.render(face)),
            Self::Format { file, message } | Self::Unsupported { file, message } => {
                format!("{file}: {}", message.render(face))
            }
            Self::Io { .. } | Self::Model { .. } => self.to_string(),
        }
    }

    /// The 1-based line number the error is about, when there is one.
    pub fn line(&self) -> Option<usize> {
        match self {
            Self::Parse { line, .. } => Some(*line),
            _ => None,
        }
    }
}

/// The name used for `path` in error messages: the path as the caller gave it.
pub fn display_name(path: &Path) -> String {
    path.display().to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_name_file_line_and_cause() {
        let err = IoError::parse(
            "a.asf",
            58,
            "frame 3 has 43 values in row 12, expected 44 (COLS)",
        );
        assert_eq!(
            err.to_string(),
            "a.asf line 58: frame 3 has 43 values in row 12, expected 44 (COLS)"
        );
        assert_eq!(err.line(), Some(58));
        let err = IoError::io(
            "read",
            Path::new("/x/y.npy"),
            std::io::Error::new(std::io::ErrorKind::NotFound, "gone"),
        );
        assert_eq!(err.to_string(), "cannot read /x/y.npy: gone");
        assert_eq!(err.line(), None);
    }
}
