//! Bad usage: parsers of option values that can be judged alone ([`crate::args::values`]; clap reports
//! their errors, exit code 2), and [`UsageError`] for what can only be judged with other options or the
//! configuration.

use clap::error::ErrorKind;

/// Options that cannot be used together (judged with each other or the configuration). `main` reports
/// it the way clap reports its own errors (the message, the subcommand's usage line, a pointer to
/// `--help`) with exit code 2, the contract's "bad usage".
#[derive(Debug)]
pub struct UsageError {
    pub subcommand: &'static str,
    pub message: String,
}

impl std::fmt::Display for UsageError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for UsageError {}

impl UsageError {
    /// The error for `subcommand`, as an `anyhow::Error` a command returns.
    pub fn error(subcommand: &'static str, message: impl std::fmt::Display) -> anyhow::Error {
        anyhow::Error::new(Self {
            subcommand,
            message: message.to_string(),
        })
    }

    /// The error as clap would have made it.
    pub fn to_clap(&self) -> clap::Error {
        let mut cli = crate::command();
        cli.build();
        match cli.find_subcommand_mut(self.subcommand) {
            Some(sub) => sub.error(ErrorKind::ArgumentConflict, &self.message),
            None => cli.error(ErrorKind::ArgumentConflict, &self.message),
        }
    }
}

pub use crate::args::values::{
    loopback_addr, name_value, positive_count, positive_number, positive_seconds, socket_addr,
};
