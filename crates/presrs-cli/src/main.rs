//! The `presrs` binary: everything is in the library ([`presrs_cli::run`]).

fn main() -> std::process::ExitCode {
    presrs_cli::run()
}
