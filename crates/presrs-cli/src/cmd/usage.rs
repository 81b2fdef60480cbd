//! Bad usage: parsers of option values that can be judged alone (clap reports their errors, exit code
//! 2), and [`UsageError`] for what can only be judged with other options or the configuration.

use std::net::SocketAddr;

use clap::CommandFactory;
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
        let mut cli = crate::Cli::command();
        cli.build();
        match cli.find_subcommand_mut(self.subcommand) {
            Some(sub) => sub.error(ErrorKind::ArgumentConflict, &self.message),
            None => cli.error(ErrorKind::ArgumentConflict, &self.message),
        }
    }
}

/// A whole number of at least 1.
pub fn positive_count(text: &str) -> Result<usize, String> {
    match text.trim().parse::<usize>() {
        Ok(n) if n >= 1 => Ok(n),
        _ => Err(format!(
            "expected a whole number of at least 1, got {text:?}"
        )),
    }
}

/// A finite number above 0.
pub fn positive_number(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        _ => Err(format!("expected a finite number above 0, got {text:?}")),
    }
}

/// A time limit in seconds: finite, above 0 and at most a billion (about 31 years; `Duration` cannot
/// hold every f64).
pub fn positive_seconds(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 && x <= 1e9 => Ok(x),
        _ => Err(format!(
            "expected a number of seconds above 0 and at most 1e9, got {text:?}"
        )),
    }
}

/// `IP:PORT`, e.g. 127.0.0.1:7700.
pub fn socket_addr(text: &str) -> Result<SocketAddr, String> {
    text.trim()
        .parse()
        .map_err(|_| format!("expected IP:PORT (e.g. 127.0.0.1:7700), got {text:?}"))
}

/// A loopback `IP:PORT` (what `stream --listen` serves on).
pub fn loopback_addr(text: &str) -> Result<SocketAddr, String> {
    let addr = socket_addr(text)?;
    if addr.ip().is_loopback() {
        Ok(addr)
    } else {
        Err(format!(
            "{text}: only loopback addresses are served (127.0.0.1 or [::1])"
        ))
    }
}

/// `NAME=VALUE` with neither side empty (both trimmed); `what` names the form in the message.
pub fn name_value(text: &str, what: &str) -> Result<(String, String), String> {
    text.split_once('=')
        .map(|(n, v)| (n.trim(), v.trim()))
        .filter(|(n, v)| !n.is_empty() && !v.is_empty())
        .map(|(n, v)| (n.to_owned(), v.to_owned()))
        .ok_or_else(|| format!("expected {what}, got {text:?}"))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn values_are_judged_alone() {
        assert_eq!(positive_count("3").unwrap(), 3);
        for bad in ["0", "-1", "x", ""] {
            assert!(positive_count(bad).is_err(), "{bad}");
        }
        assert_eq!(positive_number("0.5").unwrap(), 0.5);
        for bad in ["0", "-5", "nan", "inf", "x"] {
            assert!(positive_number(bad).is_err(), "{bad}");
        }
        assert!(socket_addr("nonsense").is_err());
        assert!(loopback_addr("127.0.0.1:0").is_ok());
        assert!(loopback_addr("[::1]:7700").is_ok());
        let err = loopback_addr("0.0.0.0:0").unwrap_err();
        assert!(err.contains("only loopback"), "{err}");
        assert_eq!(
            name_value(" grass = G3 ", "TERRAIN=GAIT").unwrap(),
            ("grass".to_owned(), "G3".to_owned())
        );
        for bad in ["wood", "=G1", "wood=", "="] {
            assert!(name_value(bad, "TERRAIN=GAIT").is_err(), "{bad}");
        }
    }
}
