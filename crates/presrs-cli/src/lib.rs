//! The `presrs` command line: thin — parse, call the libraries, print. The binary (`main.rs`) only
//! calls [`run`]; the commands are in `cmd/`, what they print in `printer/`, option values checked from
//! their text in `args/`.

/// `eprintln!` that ignores a failed write: a closed or full stderr (`presrs ... 2>&1 | head -1`) must not
/// turn a run into a panic, and there is nowhere left to report it.
macro_rules! stderr_line {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}

mod args;
mod cmd;
mod printer;

use std::io::Write;
use std::process::ExitCode;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

/// Terrain identification from high-resolution pressure images (PreSRS).
#[derive(Debug, Parser)]
#[command(
    name = "presrs",
    bin_name = "presrs",
    version,
    about,
    long_about = None,
    after_help = "Examples (a simulated data set, a model, its accuracy, a live stream; \
docs/tutorial.md walks through them):
  presrs simulate --out sim --seed 7 --hops-per-gait 6
  presrs inspect sim/recordings/wood_G2_000.asf
  presrs train --manifest sim/manifest.csv --out g2.model.json \\
    --train-condition G2
  presrs eval --manifest sim/manifest.csv --train-condition G2
  presrs classify --model g2.model.json sim/recordings/wood_G1_000.asf
  presrs stream --model g2.model.json < sim/recordings/wood_G2_000.asf"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Simulate the hopper on the paper's terrains and gaits; write TekScan movies and a manifest.
    #[command(after_help = "Example:\n  presrs simulate --out sim --seed 7")]
    Simulate(cmd::simulate::SimulateArgs),
    /// Describe a recording: sensor, size, frames, period, units, load and the stance phases found (or
    /// a model file).
    #[command(
        after_help = "Examples (sim/ made by `presrs simulate --out sim`; or any recording of yours):
  presrs inspect sim/recordings/wood_G2_000.asf
  presrs inspect my-walk.asf --json"
    )]
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
    #[command(after_help = "Examples:
  presrs stream --model g2.model.json --calibrate sim/manifest.csv \\
    < sim/recordings/wood_G2_000.asf
  presrs stream --model g2.model.json --listen 127.0.0.1:7700")]
    Stream(cmd::stream::StreamArgs),
    /// Send a recording to `presrs stream --listen` as a live stream.
    #[command(after_help = "Example (to a `presrs stream --listen 127.0.0.1:7700`):
  presrs replay sim/recordings/grass_G2_000.asf \\
    --connect 127.0.0.1:7700 --rate 100")]
    Replay(cmd::replay::ReplayArgs),
    /// Replay a recording in the live view in the browser (through the online classifier with --model).
    View(cmd::view::ViewArgs),
    /// Draw a pressure image (PNG/SVG heat map in physical units) or a recording's movie (GIF).
    Plot(cmd::plot::PlotArgs),
    /// Write an HTML report with figures (pressure images, spectra, load curves, PCA, accuracy).
    Report(cmd::report::ReportArgs),
    /// Convert a recording to a ROS 2 bag (MCAP) of sensor_msgs/msg/Image.
    Convert(cmd::convert::ConvertArgs),
    /// Run as a ROS 2 node: pressure frames from a topic in, terrain decisions out.
    Ros2(cmd::ros2::Ros2Args),
}

/// Parses the command line, runs the command and says how it went: 0 done (or the reader of stdout went
/// away), 1 failed (the reason on stderr), 2 bad usage (as clap reports it).
pub fn run() -> ExitCode {
    let cli = Cli::from_arg_matches(&command().get_matches()).unwrap_or_else(|err| err.exit());
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
        Command::View(args) => cmd::view::run(args, &mut out),
        Command::Plot(args) => cmd::plot::run(args, &mut out),
        Command::Report(args) => cmd::report::run(args, &mut out),
        Command::Convert(args) => cmd::convert::run(args, &mut out),
        Command::Ros2(args) => cmd::ros2::run(args, &mut out),
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

/// The command line as parsed: every option that takes a value takes a negative number too, so that
/// `--frame-period -0.01` reaches the option's own check ("expected a positive number") instead of
/// clap's hint about an unknown `-0` argument.
pub(crate) fn command() -> clap::Command {
    fn numbers_reach_parsers(command: clap::Command) -> clap::Command {
        command
            .mut_args(|arg| {
                let takes_values = arg.get_action().takes_values();
                arg.allow_negative_numbers(takes_values)
            })
            .mut_subcommands(numbers_reach_parsers)
    }
    numbers_reach_parsers(Cli::command())
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

/// Whether any cause of `err` is a closed pipe. serde_json's error hides the io error it wraps from the
/// chain (its `source` skips it), so it is asked for the io error's kind itself.
fn is_broken_pipe(err: &anyhow::Error) -> bool {
    err.chain().any(|cause| {
        let kind = if let Some(io) = cause.downcast_ref::<std::io::Error>() {
            Some(io.kind())
        } else {
            cause
                .downcast_ref::<serde_json::Error>()
                .and_then(serde_json::Error::io_error_kind)
        };
        kind == Some(std::io::ErrorKind::BrokenPipe)
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

    use super::*;

    /// The help of the program and of every subcommand, rendered for an 80-column terminal.
    fn helps() -> Vec<(String, String)> {
        let mut root = command().term_width(80);
        root.build();
        let mut helps = vec![("presrs".to_owned(), root.render_long_help().to_string())];
        for sub in root.get_subcommands_mut() {
            let name = sub.get_name().to_owned();
            if name != "help" {
                helps.push((name, sub.render_long_help().to_string()));
            }
        }
        helps
    }

    /// The example commands of a help text: the indented lines under a heading that starts with
    /// "Example", up to a blank line, with `\` continuations joined.
    fn examples(help: &str) -> Vec<String> {
        let mut commands = Vec::new();
        let mut lines = help.lines();
        while let Some(line) = lines.next() {
            if !line.starts_with("Example") {
                continue;
            }
            // The heading may wrap: it ends with its colon.
            let mut heading = line.to_owned();
            while !heading.trim_end().ends_with(':') {
                heading = lines
                    .next()
                    .expect("an example heading ends with ':'")
                    .to_owned();
            }
            let mut pending = String::new();
            for line in lines.by_ref().take_while(|l| !l.trim().is_empty()) {
                assert!(
                    line.starts_with("  "),
                    "an example line is not indented: {line:?}"
                );
                pending.push_str(line.trim());
                match pending.strip_suffix('\\') {
                    Some(head) => pending = head.to_owned(),
                    None => commands.push(std::mem::take(&mut pending)),
                }
            }
            assert!(
                pending.is_empty(),
                "an example ends with a continuation: {pending:?}"
            );
        }
        commands
    }

    /// The arguments of an example command line: words up to a redirection, pipe or comment.
    fn words(command: &str) -> Vec<&str> {
        command
            .split_whitespace()
            .take_while(|w| !matches!(*w, "<" | ">" | "|" | "#"))
            .collect()
    }

    #[test]
    fn every_help_has_examples_that_are_complete_commands() {
        for (name, help) in helps() {
            let commands = examples(&help);
            assert!(!commands.is_empty(), "{name}: no example in\n{help}");
            for command in commands {
                let words = words(&command);
                assert_eq!(words.first(), Some(&"presrs"), "{name}: {command:?}");
                if let Err(err) = Cli::try_parse_from(&words) {
                    panic!("{name}: the example {command:?} does not parse: {err}");
                }
            }
        }
    }

    /// Every option that names a value, or has a default other than a flag's, takes a value: clap makes
    /// a `bool` field a value-less flag whatever its parser (`--novelty on|off` once refused `off`).
    #[test]
    fn every_option_that_names_a_value_takes_one() {
        fn check(command: &clap::Command, path: &str) {
            for arg in command.get_arguments() {
                if arg.get_action().takes_values() || arg.is_positional() {
                    continue;
                }
                let name = format!("{path} --{}", arg.get_long().unwrap_or_default());
                // (the derive names every field's value after it; another name was given on purpose)
                let derived = arg.get_id().as_str().to_uppercase();
                let named = arg
                    .get_value_names()
                    .is_some_and(|names| names.iter().any(|n| n.as_str() != derived));
                assert!(!named, "{name} names a value but is a flag");
                let flag_defaults = arg
                    .get_default_values()
                    .iter()
                    .all(|v| v == "false" || v == "true");
                assert!(flag_defaults, "{name} has a default value but is a flag");
            }
            for sub in command.get_subcommands() {
                check(sub, &format!("{path} {}", sub.get_name()));
            }
        }
        check(&command(), "presrs");
    }

    #[test]
    fn help_points_to_nothing_a_user_does_not_have() {
        for (name, help) in helps() {
            assert!(!help.contains("../shared"), "{name}: {help}");
        }
    }

    /// The detector's settings that `presrs features walk.asf` with the stance options `options` gives.
    fn stance_params(options: &[&str]) -> anyhow::Result<presrs_core::stance::ValidSegmentParams> {
        let words = [&["presrs", "features", "walk.asf"], options].concat();
        match Cli::try_parse_from(words).unwrap().command {
            Command::Features(args) => args.samples.stance.segment_params(),
            other => panic!("parsed as {other:?}"),
        }
    }

    #[test]
    fn stance_options_not_given_keep_the_defaults_and_a_gap_bridges_one_frame_less() {
        let default = presrs_core::stance::SegmentParams::default();
        assert_eq!(stance_params(&[]).unwrap(), default.check().unwrap());
        let gap = stance_params(&["--stance-min-gap", "5"]).unwrap();
        assert_eq!(gap.params().max_gap_frames, 4);
        let clash = ["--stance-threshold", "0.05", "--stance-hysteresis", "0.5"];
        let err = error_message(&stance_params(&clash).unwrap_err());
        assert!(
            err.starts_with("the --stance-* options do not fit together: "),
            "{err}"
        );
    }

    #[test]
    fn a_closed_pipe_in_a_json_error_is_recognised() {
        let closed = std::io::Error::from(std::io::ErrorKind::BrokenPipe);
        let json = serde_json::Error::io(closed);
        let err = anyhow::Error::from(json).context("cannot write JSON");
        assert!(is_broken_pipe(&err));
        let other = anyhow::Error::from(std::io::Error::other("disk full")).context("cannot write");
        assert!(!is_broken_pipe(&other));
    }
}
