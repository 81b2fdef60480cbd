//! `presrs simulate`: write the built-in simulated dataset (TekScan movies + manifest + ground truth).

use std::io::Write;
use std::path::PathBuf;

/// Simulate the one-legged hopper with PreSRS on the paper's terrains and gaits.
#[derive(Debug, clap::Args)]
pub struct SimulateArgs {
    /// Output folder; receives manifest.csv and one TekScan ASCII movie per trial.
    #[arg(long)]
    pub out: PathBuf,
    /// Seed of every random choice; the same seed gives the same bytes.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

pub fn run(_args: &SimulateArgs, _out: &mut dyn Write) -> anyhow::Result<()> {
    anyhow::bail!("the simulator is not built yet")
}
