//! The error type of `presrs-sim`.

/// Everything that can go wrong while simulating.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// A configuration value is outside its valid range.
    #[error("invalid simulator parameter {name}: {reason}")]
    Param { name: String, reason: String },
    /// The integrator could not reach the requested accuracy.
    #[error("integrator failed at t = {t_s:.6} s: {reason}")]
    Integrator { t_s: f64, reason: String },
    /// The hopper fell (no flight phase, leg through the ground, body on the ground...).
    #[error(
        "the hopper fell during hop {hop} ({reason}); the gait/terrain parameters give no stable hopping"
    )]
    Fell { hop: usize, reason: String },
    /// The contact solver did not converge.
    #[error("skin contact solver did not converge: {0}")]
    Contact(String),
    /// An error from the core data model.
    #[error(transparent)]
    Core(#[from] presrs_core::CoreError),
}

pub type Result<T, E = SimError> = std::result::Result<T, E>;

pub(crate) fn param(name: &str, reason: impl Into<String>) -> SimError {
    SimError::Param {
        name: name.to_owned(),
        reason: reason.into(),
    }
}
