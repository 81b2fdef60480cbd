//! Helpers shared by the CLI test binaries (each binary uses a subset).
#![allow(dead_code)]

use std::process::{Command, Output, Stdio};

/// Runs the `presrs` binary with `args` and no standard input.
pub fn presrs(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_presrs"))
        .args(args)
        .stdin(Stdio::null())
        .output()
        .expect("the presrs binary runs")
}

pub fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).into_owned()
}

pub fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}
