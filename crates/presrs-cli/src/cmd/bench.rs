//! `presrs bench`: in-process latency of one classification and batch throughput.

use std::hint::black_box;
use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use presrs_core::Frame;
use presrs_core::pipeline::{TrainedModel, bench_fixture};
use presrs_io::model_file::load_model;
use serde::Serialize;

use super::common::write_json;

/// Time one classification (features + PCA + classifier) and batch throughput, in this process.
#[derive(Debug, clap::Args)]
#[command(after_help = "Example:\n  presrs bench --json\n  presrs bench --model g2.model.json")]
pub struct BenchArgs {
    /// A model file; without one, the paper's setting is built on simulated 44x44 mid-stance images of
    /// gait G2 (crop to 38x41, 1-D |FFT| of 1025 values, PCA 51, Parzen over 80 training vectors).
    /// Test images are simulated mid-stance images either way.
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// Use the synthetic test pattern of presrs-core instead of the simulator (no simulation needed).
    #[arg(long)]
    pub synthetic: bool,
    /// Timed single-image classifications.
    #[arg(long, default_value_t = 20_000)]
    pub iterations: usize,
    /// Images in the batch-throughput run.
    #[arg(long, default_value_t = 4096)]
    pub batch: usize,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Print one JSON document instead of text.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Serialize)]
struct BenchReport {
    model: String,
    single_image_median_ns: u64,
    single_image_p99_ns: u64,
    single_image_min_ns: u64,
    batch_images_per_s: f64,
    batch_threads: usize,
    iterations: usize,
    batch: usize,
}

/// The paper's model trained on simulated G2 mid-stance images (13 + 7 per terrain), and 64 other
/// simulated mid-stance images to classify.
fn simulated_fixture(seed: u64) -> anyhow::Result<(TrainedModel, Vec<Frame>)> {
    let mut spec = presrs_sim::DatasetSpec::paper(seed);
    spec.gaits = vec!["G2".to_owned()];
    spec.hops_per_gait = Some(40);
    let dataset = presrs_sim::simulate_dataset(&presrs_sim::SimConfig::default(), &spec)?;
    let (samples, _) = super::reproduce::stance_samples(&dataset.trials)?;
    let labels: Vec<&str> = samples.iter().map(|s| s.terrain.as_str()).collect();
    let split = presrs_core::split::stratified_split(
        &labels,
        Some(20),
        presrs_core::split::ValidationSize::Count(7),
        seed,
    )?;
    let images = |indices: &[usize]| -> Vec<presrs_core::pipeline::LabeledImage<'_>> {
        indices
            .iter()
            .map(|&i| presrs_core::pipeline::LabeledImage::new(samples[i].frame.view(), labels[i]))
            .collect()
    };
    let config = presrs_core::pipeline::TrainConfig::default().check()?;
    let model =
        presrs_core::pipeline::train(&images(&split.train), &images(&split.validation), &config)?;
    let frames = split
        .rest
        .iter()
        .take(64)
        .map(|&i| samples[i].frame.clone())
        .collect();
    Ok((model, frames))
}

pub fn run(args: &BenchArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    if args.iterations == 0 || args.batch == 0 {
        anyhow::bail!("--iterations and --batch must be positive");
    }
    let (fixture_model, frames, source) = if args.synthetic {
        let (model, frames) = bench_fixture(args.seed, 64)?;
        (model, frames, "synthetic pattern, paper settings")
    } else {
        let (model, frames) = simulated_fixture(args.seed)?;
        (model, frames, "simulated G2 images, paper settings")
    };
    let (model, source): (TrainedModel, String) = match &args.model {
        Some(path) => (load_model(path)?.model, path.display().to_string()),
        None => (fixture_model, source.to_owned()),
    };
    let mut session = model.session();
    // Warm up caches and check the images fit the model.
    for frame in &frames {
        session
            .classify(&frame.view())
            .map_err(|err| anyhow::anyhow!("the benchmark images do not fit the model: {err}"))?;
    }
    let mut times_ns = Vec::with_capacity(args.iterations);
    for i in 0..args.iterations {
        let frame = frames[i % frames.len()].view();
        let start = Instant::now();
        let prediction = session.classify(&frame);
        times_ns.push(start.elapsed().as_nanos() as u64);
        black_box(prediction.map(|p| p.class).ok());
    }
    times_ns.sort_unstable();
    let quantile = |q: f64| times_ns[((times_ns.len() - 1) as f64 * q).round() as usize];
    let batch: Vec<_> = (0..args.batch)
        .map(|i| frames[i % frames.len()].view())
        .collect();
    let start = Instant::now();
    let results = model.classify_batch(&batch);
    let elapsed = start.elapsed().as_secs_f64();
    black_box(&results);
    let report = BenchReport {
        model: source,
        single_image_median_ns: quantile(0.5),
        single_image_p99_ns: quantile(0.99),
        single_image_min_ns: times_ns[0],
        batch_images_per_s: args.batch as f64 / elapsed,
        batch_threads: rayon::current_num_threads(),
        iterations: args.iterations,
        batch: args.batch,
    };
    if args.json {
        return write_json(out, &report);
    }
    writeln!(out, "model                      {}", report.model)?;
    writeln!(
        out,
        "single image (median)      {:.2} us   (p99 {:.2} us, min {:.2} us, {} runs)",
        report.single_image_median_ns as f64 / 1e3,
        report.single_image_p99_ns as f64 / 1e3,
        report.single_image_min_ns as f64 / 1e3,
        report.iterations
    )?;
    writeln!(
        out,
        "batch throughput           {:.0} images/s on {} threads ({} images)",
        report.batch_images_per_s, report.batch_threads, report.batch
    )?;
    writeln!(out, "paper (2.67 GHz Core 2 Duo) 245 us per image")?;
    Ok(())
}
