//! One module per subcommand: each parses its own arguments (a clap `Args` struct) and calls the libraries.

pub mod simulate;
