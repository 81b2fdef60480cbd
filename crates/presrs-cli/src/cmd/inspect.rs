//! `presrs inspect`: what a recording file holds, and the stance phases found in it.

use std::io::Write;
use std::path::PathBuf;

use presrs::inspect::inspect;

use super::common::{SampleArgs, write_json};
use crate::printer::inspect_table::print_inspect_table;

/// Describe a recording: sensor, size, frames, period, units, load range and stance phases.
#[derive(Debug, clap::Args)]
pub struct InspectArgs {
    /// A TekScan ASCII movie/snapshot, .npy, greyscale .png, MCAP bag (its topics are listed) or text
    /// matrix.
    pub file: PathBuf,
    /// Print one JSON document instead of a table.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub samples: SampleArgs,
}

pub fn run(args: &InspectArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let report = inspect(&args.file, &args.samples.options()?)?;
    if args.json {
        return write_json(out, &report);
    }
    print_inspect_table(&report, out)
}
