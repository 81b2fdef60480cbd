//! `presrs inspect`: what a recording file holds, and the stance phases found in it.

use std::io::Write;
use std::path::PathBuf;

use presrs::inspect::inspect;
use presrs_io::model_file::{is_model_file, load_model};

use super::common::{SampleArgs, write_json};
use crate::printer::inspect_table::print_inspect_table;

/// Describe a recording: sensor, size, frames, period, units, load range and stance phases (or a
/// model file: what it classifies, how, and how it was chosen).
#[derive(Debug, clap::Args)]
pub struct InspectArgs {
    /// A TekScan ASCII movie/snapshot, .npy, greyscale .png, MCAP bag (its topics are listed) or text
    /// matrix; or a model file written by train.
    pub file: PathBuf,
    /// Print one JSON document instead of a table.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub samples: SampleArgs,
}

/// A model file's description, as `--json` prints it.
#[derive(serde::Serialize)]
struct ModelDescription<'a> {
    model_file: String,
    description: Vec<&'a str>,
}

pub fn run(args: &InspectArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    if is_model_file(&args.file)? {
        let text = presrs::describe_model(&load_model(&args.file)?);
        if args.json {
            let description = ModelDescription {
                model_file: args.file.display().to_string(),
                description: text.lines().collect(),
            };
            return write_json(out, &description);
        }
        write!(out, "{text}")?;
        return Ok(());
    }
    let report = inspect(&args.file, &args.samples.options()?)?;
    if args.json {
        return write_json(out, &report);
    }
    print_inspect_table(&report, out)
}
