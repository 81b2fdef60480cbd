//! The error type of `presrs-core`.

/// Everything that can go wrong in the algorithms of this crate.
#[derive(Debug, thiserror::Error)]
pub enum CoreError {
    /// Two things that must agree in shape do not.
    #[error("shape mismatch: {what}: expected {expected}, got {got}")]
    Shape {
        what: &'static str,
        expected: String,
        got: String,
    },
    /// A parameter is outside its valid range.
    #[error("invalid parameter {name}: {reason}")]
    Param { name: &'static str, reason: String },
    /// Not enough data to do what was asked.
    #[error("not enough data: {0}")]
    NotEnoughData(String),
}

pub type Result<T, E = CoreError> = std::result::Result<T, E>;

/// `Ok` when a buffer or vector has the `expected` length, else a [`CoreError::Shape`] naming `what`.
pub(crate) fn check_len(what: &'static str, expected: usize, got: usize) -> Result<()> {
    if expected == got {
        Ok(())
    } else {
        Err(CoreError::Shape {
            what,
            expected: expected.to_string(),
            got: got.to_string(),
        })
    }
}

/// The member of `all` whose name (`as_str`) is `text`, trimmed and case-insensitive; else a
/// [`CoreError::Param`] for `param` that says it is an unknown `what` and lists the known names.
pub(crate) fn parse_name<T: Copy, const N: usize>(
    text: &str,
    all: [T; N],
    as_str: fn(T) -> &'static str,
    param: &'static str,
    what: &str,
) -> Result<T> {
    let wanted = text.trim().to_ascii_lowercase();
    all.into_iter()
        .find(|&item| as_str(item) == wanted)
        .ok_or_else(|| CoreError::Param {
            name: param,
            reason: format!(
                "unknown {what} {text:?}; known: {}",
                all.map(as_str).join(", ")
            ),
        })
}
