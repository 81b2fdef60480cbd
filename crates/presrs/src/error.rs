//! The error type of the `presrs` library: the lower crates' errors, plus what a workflow finds wrong
//! with the data or the options, each message saying what to try.
//!
//! The options a message names are data ([`Message`], [`Opt`](presrs_io::message::Opt)):
//! [`Error::render`] spells them in a face's words (`--per-class 10` on the command line,
//! `per_class=10` in Python); `Display` uses the command line's.

use presrs_core::CoreError;
use presrs_io::IoError;
use presrs_io::message::{Face, Message};
use presrs_report::ReportError;
use presrs_sim::SimError;

/// Everything a workflow can fail with.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Reading or writing a file (names the file, and the line for a parse error).
    #[error(transparent)]
    Io(#[from] IoError),
    /// An algorithm refused its input (shape, parameter, not enough data).
    #[error(transparent)]
    Core(#[from] CoreError),
    /// The simulator refused its configuration or failed.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// A figure or the report could not be drawn.
    #[error(transparent)]
    Report(#[from] ReportError),
    /// The operating system refused a file operation (the context says which file).
    #[error(transparent)]
    File(#[from] std::io::Error),
    /// A JSON document could not be read or written (the context says which).
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    /// The data do not fit what was asked (no sample, an unknown condition, a missing column); the
    /// message says why and what to try.
    #[error("{0}")]
    Data(Message),
    /// An option that cannot be used as given.
    #[error("{0}")]
    Invalid(Message),
    /// The operating system refused an operation that is not on a named file (a socket, a pipe).
    #[error("{what}: {source}")]
    System {
        what: String,
        #[source]
        source: std::io::Error,
    },
    /// What was being done when `source` went wrong.
    #[error("{context}: {source}")]
    Context {
        context: String,
        #[source]
        source: Box<Error>,
    },
}

impl Error {
    /// The data do not fit what was asked.
    pub fn data(message: impl Into<Message>) -> Self {
        Self::Data(message.into())
    }

    /// An option that cannot be used as given.
    pub fn invalid(message: impl Into<Message>) -> Self {
        Self::Invalid(message.into())
    }

    /// The error and its causes in `face`'s words: what `Display` says, with the options the messages
    /// name spelled as `face` spells them.
    pub fn render(&self, face: Face) -> String {
        match self {
            Self::Data(message) | Self::Invalid(message) => message.render(face),
            Self::Io(err) => err.render(face),
            Self::Context { context, source } => format!("{context}: {}", source.render(face)),
            Self::Core(_)
            | Self::Sim(_)
            | Self::Report(_)
            | Self::File(_)
            | Self::Json(_)
            | Self::System { .. } => self.to_string(),
        }
    }

    /// An operating-system error on something that is not a named file.
    pub fn system(what: impl Into<String>, source: std::io::Error) -> Self {
        Self::System {
            what: what.into(),
            source,
        }
    }

    /// The I/O error underneath, if any (a closed pipe is not a failure for a command line).
    pub fn io_kind(&self) -> Option<std::io::ErrorKind> {
        let mut current: Option<&(dyn std::error::Error + 'static)> = Some(self);
        while let Some(err) = current {
            if let Some(io) = err.downcast_ref::<std::io::Error>() {
                return Some(io.kind());
            }
            current = err.source();
        }
        None
    }
}

/// `Result` with [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Adds what was being done to an error, as anyhow's `Context` does, for the library's own error type.
pub trait Context<T> {
    /// Wraps the error with `context`.
    fn context(self, context: impl Into<String>) -> Result<T>;
    /// Wraps the error with the context `f` makes (only on error).
    fn with_context<S: Into<String>>(self, f: impl FnOnce() -> S) -> Result<T>;
}

impl<T, E: Into<Error>> Context<T> for std::result::Result<T, E> {
    fn context(self, context: impl Into<String>) -> Result<T> {
        self.map_err(|err| Error::Context {
            context: context.into(),
            source: Box::new(err.into()),
        })
    }

    fn with_context<S: Into<String>>(self, f: impl FnOnce() -> S) -> Result<T> {
        self.map_err(|err| Error::Context {
            context: f().into(),
            source: Box::new(err.into()),
        })
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use presrs_io::message::Opt;

    use super::*;

    #[test]
    fn render_spells_options_in_each_face_through_contexts_and_io_errors() {
        let invalid = Error::invalid(Message::new().opt_is(Opt::Dims, 40).text(": too many"));
        let err: Result<()> = Err(invalid).context("a.csv: training failed");
        let err = err.unwrap_err();
        assert_eq!(
            err.to_string(),
            "a.csv: training failed: --dims 40: too many"
        );
        assert_eq!(err.render(Face::Cli), err.to_string());
        assert_eq!(
            err.render(Face::Python),
            "a.csv: training failed: dims=40: too many"
        );
        let io = Error::from(IoError::format(
            "b.mcap",
            Message::from("choose ").opt(Opt::Topic),
        ));
        assert_eq!(io.render(Face::Cli), "b.mcap: choose --topic");
        assert_eq!(io.render(Face::Python), "b.mcap: choose topic=");
    }
}
