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
pub fn check_len(what: &'static str, expected: usize, got: usize) -> Result<()> {
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
