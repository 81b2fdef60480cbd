//! One module per subcommand: each parses its own arguments (a clap `Args` struct) and calls the libraries.

pub mod bench;
pub mod classify;
pub mod common;
pub mod convert;
pub mod eval;
pub mod features;
pub mod inspect;
pub mod plot;
pub mod replay;
pub mod report;
pub mod reproduce;
pub mod ros2;
pub mod simulate;
pub mod stream;
pub mod train;
pub mod usage;
pub mod view;
