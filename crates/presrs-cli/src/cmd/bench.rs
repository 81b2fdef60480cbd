//! `presrs bench`: in-process latency of one classification and batch throughput
//! ([`presrs::bench`]).

use std::io::Write;
use std::path::PathBuf;

use presrs::bench::{BenchOptions, bench};

use super::common::{SampleArgs, TerminalProgress, write_json};

/// Time one classification (features + PCA + classifier) and batch throughput, in this process.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Examples (the third times your model on your images; the fourth writes the model, \
images and predictions for bench/side_by_side.sh):
  presrs bench --json
  presrs bench --model g2.model.json
  presrs bench --model my.model.json --images my-data/manifest.csv
  presrs bench --export bench-inputs/"
)]
pub struct BenchArgs {
    /// A model file; without one, the paper's setting is built on simulated 44x44 mid-stance images of
    /// gait G2 (crop to 38x41, 1-D |FFT| of 1025 values, PCA 51, Parzen over 80 training vectors).
    /// Test images are simulated mid-stance images unless --images gives others.
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// Time the model on these images instead of simulated ones: a manifest (the samples `presrs eval`
    /// would take from it; labels optional). Needs --model.
    #[arg(
        long,
        value_name = "MANIFEST",
        requires = "model",
        conflicts_with = "synthetic"
    )]
    pub images: Option<PathBuf>,
    #[command(flatten)]
    pub samples: SampleArgs,
    /// Use the synthetic test pattern of presrs-core instead of the simulator (no simulation needed).
    #[arg(long)]
    pub synthetic: bool,
    /// Timed single-image classifications (at least 1).
    #[arg(long, default_value_t = 20_000, value_parser = super::usage::positive_count)]
    pub iterations: usize,
    /// Images in the batch-throughput run (at least 1).
    #[arg(long, default_value_t = 4096, value_parser = super::usage::positive_count)]
    pub batch: usize,
    /// Timed batch runs (at least 1); the median throughput is reported.
    #[arg(long, default_value_t = 5, value_parser = super::usage::positive_count)]
    pub batch_runs: usize,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Also write into this folder (created if needed) the model (`model.json`), the test images
    /// (`images.npy`, n x rows x cols, absent sensels as 0), presrs's features (`features.npy`) and
    /// PCA-reduced vectors (`reduced.npy`) of each test image, and `presrs.json` with the predictions,
    /// posteriors and timings, so another implementation can be checked and timed on the same inputs.
    #[arg(long, value_name = "DIR")]
    pub export: Option<PathBuf>,
    /// Print one JSON document instead of text.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &BenchArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    args.export
        .as_deref()
        .map(presrs_io::output_path::check_output_dir)
        .transpose()?;
    let options = BenchOptions {
        model: args.model.clone(),
        images: args.images.clone(),
        samples: args.samples.options()?,
        synthetic: args.synthetic,
        iterations: args.iterations,
        batch: args.batch,
        batch_runs: args.batch_runs,
        seed: args.seed,
        export: args.export.clone(),
        command: Some(std::env::args().collect::<Vec<_>>().join(" ")),
    };
    let report = bench(&options, &TerminalProgress::default())?;
    if args.json {
        return write_json(out, &report);
    }
    write!(out, "{}", report.text(args.export.as_deref()))?;
    Ok(())
}
