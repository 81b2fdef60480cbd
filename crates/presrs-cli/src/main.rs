//! The `presrs` command line: thin — parse, call the libraries, print.

/// `eprintln!` that ignores a failed write: a closed or full stderr (`presrs ... 2>&1 | head -1`) must not
/// turn a run into a panic, and there is nowhere left to report it.
macro_rules! stderr_line {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}

mod cmd;

use std::io::Write;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Terrain identification from high-resolution pressure images (PreSRS).
#[derive(Debug, Parser)]
#[command(name = "presrs", bin_name = "presrs", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Simulate the hopper on the paper's terrains and gaits; write TekScan movies and a manifest.
    #[command(after_help = "Example:\n  presrs simulate --out sim --seed 7")]
    Simulate(cmd::simulate::SimulateArgs),
    /// Describe a recording: sensor, size, frames, period, units, load and the stance phases found.
    #[command(after_help = "Example:\n  presrs inspect ../shared/data/tekscan/FrasP01L.asf --json")]
    Inspect(cmd::inspect::InspectArgs),
    /// Print feature vectors of a recording's frames as CSV.
    Features(cmd::features::FeaturesArgs),
    /// Train a classifier from a dataset manifest and write a model file.
    Train(cmd::train::TrainArgs),
    /// Classify recordings with a trained model.
    Classify(cmd::classify::ClassifyArgs),
    /// Evaluate the pipeline on a manifest (train on one condition, or leave one group out).
    Eval(cmd::eval::EvalArgs),
    /// The paper's experiment end to end on the built-in simulator: Tables I and II.
    Reproduce(cmd::reproduce::ReproduceArgs),
    /// Measure classification latency and batch throughput in this process.
    Bench(cmd::bench::BenchArgs),
    /// Classify a live frame stream online (stdin or TCP clients); JSON lines out.
    #[command(
        after_help = "Examples:\n  presrs stream --model g2.json --calibrate sim/manifest.csv < sim/recordings/wood_G2_000.asf\n  presrs stream --model g2.json --listen 127.0.0.1:7700"
    )]
    Stream(cmd::stream::StreamArgs),
    /// Send a recording to `presrs stream --listen` as a live stream.
    #[command(
        after_help = "Example:\n  presrs replay sim/recordings/grass_G2_000.asf --connect 127.0.0.1:7700 --rate 100"
    )]
    Replay(cmd::replay::ReplayArgs),
    /// Draw a pressure image (PNG/SVG heat map in physical units) or a recording's movie (GIF).
    Plot(cmd::plot::PlotArgs),
    /// Write an HTML report with figures (pressure images, spectra, load curves, PCA, accuracy).
    Report(cmd::report::ReportArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let stdout = std::io::stdout();
    let mut out = std::io::BufWriter::new(stdout.lock());
    let result = match &cli.command {
        Command::Simulate(args) => cmd::simulate::run(args, &mut out),
        Command::Inspect(args) => cmd::inspect::run(args, &mut out),
        Command::Features(args) => cmd::features::run(args, &mut out),
        Command::Train(args) => cmd::train::run(args, &mut out),
        Command::Classify(args) => cmd::classify::run(args, &mut out),
        Command::Eval(args) => cmd::eval::run(args, &mut out),
        Command::Reproduce(args) => cmd::reproduce::run(args, &mut out),
        Command::Bench(args) => cmd::bench::run(args, &mut out),
        Command::Stream(args) => cmd::stream::run(args, &mut out),
        Command::Replay(args) => cmd::replay::run(args, &mut out),
        Command::Plot(args) => cmd::plot::run(args, &mut out),
        Command::Report(args) => cmd::report::run(args, &mut out),
    }
    .and_then(|()| out.flush().map_err(anyhow::Error::from));
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // `presrs ... | head`: the reader went away; that is not an error.
        Err(err) if is_broken_pipe(&err) => ExitCode::SUCCESS,
        Err(err) if err.downcast_ref::<cmd::usage::UsageError>().is_some() => {
            let _ = out.flush();
            if let Some(usage) = err.downcast_ref::<cmd::usage::UsageError>() {
                let _ = usage.to_clap().print();
            }
            ExitCode::from(2)
        }
        Err(err) => {
            // What was printed before the failure comes first, then the reason.
            let _ = out.flush();
            stderr_line!("error: {}", error_message(&err));
            ExitCode::from(1)
        }
    }
}

/// The error and its causes in one sentence, skipping causes whose text the message already contains
/// (our error types print their source inline).
fn error_message(err: &anyhow::Error) -> String {
    let mut message = String::new();
    for cause in err.chain() {
        let text = cause.to_string();
        if !message.contains(&text) {
            if !message.is_empty() {
                message.push_str(": ");
            }
            message.push_str(&text);
        }
    }
    message
}

fn is_broken_pipe(err: &anyhow::Error) -> bool {
    err.chain().any(|cause| {
        cause
            .downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}
