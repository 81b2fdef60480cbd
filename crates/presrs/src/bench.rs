//! In-process speed: the latency of one classification (and of each of its stages) and batch
//! throughput, on simulated, synthetic or a manifest's images (`presrs bench`).
//!
//! With [`BenchOptions::export`] it also writes what an outside implementation needs to run the same
//! pipeline on the same inputs and check its answers (used by `bench/side_by_side.sh`): the model file,
//! the test images as `.npy`, presrs's features, reduced vectors and predictions of every test image,
//! and the timings.

use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Instant;

use presrs_core::Frame;
use presrs_core::pipeline::TrainedModel;
use presrs_core::synthetic::{SYNTHETIC_CLASSES, bench_workload};
use presrs_io::model_file::{ModelFile, Provenance, load_model, save_model};
use presrs_io::npy::write_npy_f64;
use serde::Serialize;

use crate::dataset::{Dataset, SampleOptions};
use crate::error::{Context, Error, Result};
use crate::progress::Progress;
use presrs_io::message::{Message, Opt};

/// What to time.
#[derive(Clone, Debug)]
pub struct BenchOptions {
    /// A model file; without one, the paper's setting is trained on simulated 44 x 44 mid-stance
    /// images of gait G2.
    pub model: Option<PathBuf>,
    /// Time the model on a manifest's images instead (needs `model`).
    pub images: Option<PathBuf>,
    /// How the manifest's samples are taken.
    pub samples: SampleOptions,
    /// The synthetic test pattern of presrs-core instead of the simulator.
    pub synthetic: bool,
    /// Timed single-image classifications.
    pub iterations: usize,
    /// Images in the batch-throughput run, and timed batch runs.
    pub batch: usize,
    pub batch_runs: usize,
    pub seed: u64,
    /// Also write the model, images, features, reduced vectors and predictions here.
    pub export: Option<PathBuf>,
    /// The command line, for the provenance of a model made here.
    pub command: Option<String>,
}

impl Default for BenchOptions {
    fn default() -> Self {
        Self {
            model: None,
            images: None,
            samples: SampleOptions::default(),
            synthetic: false,
            iterations: 20_000,
            batch: 4096,
            batch_runs: 5,
            seed: 1,
            export: None,
            command: None,
        }
    }
}

/// What `presrs bench` measured.
#[derive(Clone, Debug, Serialize)]
pub struct BenchReport {
    pub model: String,
    pub single_image_median_ns: u64,
    /// The quartiles show a machine's phases: on a shared VM the calls can fall into a fast and a slow
    /// group (another tenant on the same core), the median landing in either.
    pub single_image_p25_ns: u64,
    pub single_image_p75_ns: u64,
    pub single_image_p99_ns: u64,
    pub single_image_min_ns: u64,
    pub batch_images_per_s: f64,
    /// Throughput of every timed batch run, in run order.
    pub batch_runs_images_per_s: Vec<f64>,
    pub batch_threads: usize,
    pub iterations: usize,
    pub batch: usize,
    /// Distinct test images (the single-image and batch runs cycle through them).
    pub test_images: usize,
    /// Where a single image's time goes: each stage timed alone over the same images (medians).
    pub stages_median_ns: StageTimes,
}

/// Median time of each stage of one classification, each timed alone over the test images: the crop,
/// preprocessing and features (`Session::fast_features`), the PCA projection, and the classifier on the
/// reduced vector.
#[derive(Clone, Debug, Serialize)]
pub struct StageTimes {
    pub features: u64,
    pub pca: u64,
    pub classifier: u64,
}

/// The median of `iterations` timings of `step(i)` in nanoseconds.
fn median_ns(iterations: usize, mut step: impl FnMut(usize)) -> u64 {
    let mut times_ns: Vec<u64> = (0..iterations)
        .map(|i| {
            let start = Instant::now();
            step(i);
            start.elapsed().as_nanos() as u64
        })
        .collect();
    times_ns.sort_unstable();
    times_ns[times_ns.len() / 2]
}

/// Times the stages of one classification (see [`StageTimes`]).
/// One image's features as classification computes them, for timing the PCA stage alone.
enum StageFeatures {
    Single(Vec<f32>),
    Double(Vec<f64>),
}

fn stage_times(model: &TrainedModel, frames: &[Frame], iterations: usize) -> Result<StageTimes> {
    let mut session = model.session();
    // Each stage as `Session::classify` runs it: the features in f32 when the frame takes the fast path
    // (the paper's 1-D |FFT|), in f64 otherwise.
    let mut features = Vec::with_capacity(frames.len());
    let mut reduced = Vec::with_capacity(frames.len());
    for frame in frames {
        let single = session
            .fast_features_f32(&frame.view())?
            .map(<[f32]>::to_vec);
        features.push(match single {
            Some(single) => StageFeatures::Single(single),
            None => StageFeatures::Double(session.fast_features(&frame.view())?.to_vec()),
        });
        reduced.push(session.reduce(&frame.view())?.to_vec());
    }
    let features_ns = median_ns(iterations, |i| {
        let frame = frames[i % frames.len()].view();
        let single = session.fast_features_f32(&frame).map(|f| f.is_some());
        if !matches!(single, Ok(true)) {
            black_box(session.fast_features(&frame).is_ok());
        }
    });
    // (no PCA step, no time: the classifier takes the features as they are)
    let pca_ns = model.pca().map_or(0, |pca| {
        let mut scratch = pca.scratch();
        let mut projected = vec![0.0; pca.n_components()];
        median_ns(iterations, |i| {
            let result = match &features[i % frames.len()] {
                StageFeatures::Single(x) => pca.project_fast_into(x, &mut scratch, &mut projected),
                StageFeatures::Double(x) => pca.project_fast_into(x, &mut scratch, &mut projected),
            };
            black_box(result.is_ok());
        })
    });
    let classifier = model.classifier();
    let mut classifier_scratch = classifier.scratch();
    let mut posteriors = vec![0.0; classifier.n_classes()];
    let classifier_ns = median_ns(iterations, |i| {
        black_box(
            classifier
                .classify_into(
                    &reduced[i % frames.len()],
                    &mut classifier_scratch,
                    &mut posteriors,
                )
                .is_ok(),
        );
    });
    Ok(StageTimes {
        features: features_ns,
        pca: pca_ns,
        classifier: classifier_ns,
    })
}

/// `presrs.json` of `--export`.
#[derive(Debug, Serialize)]
struct Export<'a> {
    format: &'static str,
    presrs_version: &'static str,
    /// The test images' file and shape (n x rows x cols, before the crop).
    images: &'static str,
    image_shape: [usize; 3],
    /// The grid after the model's crop (38 x 41 for the paper's 44 x 44 images).
    cropped_shape: [usize; 2],
    features: &'static str,
    reduced: &'static str,
    model_file: &'static str,
    class_names: &'a [String],
    /// Predicted class index of each test image, and its label.
    predictions: Vec<usize>,
    labels: Vec<&'a str>,
    /// Class posteriors of each test image (equal priors), in class-index order.
    posteriors: Vec<Vec<f64>>,
    /// The true terrain of each test image, and the condition (gait) it was recorded at.
    truth: &'a [String],
    conditions: &'a [String],
    timing: &'a BenchReport,
}

/// Test images with their true terrain and the condition (gait) they were recorded at.
struct Fixture {
    model: TrainedModel,
    frames: Vec<Frame>,
    truth: Vec<String>,
    conditions: Vec<String>,
}

/// The paper's protocol on simulated mid-stance images (40 hops per terrain and gait): the model is trained
/// on G2 (13 + 7 random images per terrain) and the test images are every other image of G1, G2 and G3.
fn simulated_fixture(seed: u64) -> Result<Fixture> {
    let mut spec = presrs_sim::DatasetSpec::paper(seed);
    spec.hops_per_gait = Some(40);
    let dataset = presrs_sim::simulate_dataset(&presrs_sim::SimConfig::default(), &spec)?;
    let (samples, _) = crate::reproduce::stance_samples(&dataset.trials)?;
    let g2: Vec<usize> = (0..samples.len())
        .filter(|&i| samples[i].condition.as_deref() == Some("G2"))
        .collect();
    let label = |sample: &crate::dataset::Sample| sample.label.clone().unwrap_or_default();
    let g2_labels: Vec<&str> = g2
        .iter()
        .map(|&i| samples[i].label.as_deref().unwrap_or_default())
        .collect();
    let split = presrs_core::split::stratified_split(
        &g2_labels,
        Some(20),
        presrs_core::split::ValidationSize::Count(7),
        seed,
    )?;
    let (train_images, validation_images) = crate::train::split_images(&split, |k| {
        presrs_core::pipeline::LabeledImage::new(samples[g2[k]].frame.view(), g2_labels[k])
    });
    let config = presrs_core::pipeline::TrainConfig::default().check()?;
    let model = presrs_core::pipeline::train(&train_images, &validation_images, &config)?;
    let trained: std::collections::HashSet<usize> = split
        .train
        .iter()
        .chain(&split.validation)
        .map(|&k| g2[k])
        .collect();
    let test: Vec<&crate::dataset::Sample> = (0..samples.len())
        .filter(|i| !trained.contains(i))
        .map(|i| &samples[i])
        .collect();
    Ok(Fixture {
        model,
        frames: test.iter().map(|s| s.frame.clone()).collect(),
        truth: test.iter().map(|s| label(s)).collect(),
        conditions: test
            .iter()
            .map(|s| s.condition.clone().unwrap_or_default())
            .collect(),
    })
}

/// The samples of a manifest as test images for `model` (their labels and conditions, if given).
fn manifest_fixture(
    model: TrainedModel,
    manifest: &Path,
    samples: &SampleOptions,
    progress: &dyn Progress,
) -> Result<Fixture> {
    let loaded = Dataset::load(manifest, samples, progress)?;
    for warning in &loaded.warnings {
        progress.warn(warning);
    }
    let samples = loaded.samples;
    Ok(Fixture {
        model,
        truth: samples
            .iter()
            .map(|s| s.label.clone().unwrap_or_default())
            .collect(),
        conditions: samples
            .iter()
            .map(|s| s.condition.clone().unwrap_or_default())
            .collect(),
        frames: samples.into_iter().map(|s| s.frame).collect(),
    })
}

/// [`bench_workload`]'s synthetic pattern, 64 test images cycling through the four classes.
fn synthetic_fixture(seed: u64) -> Result<Fixture> {
    let (model, frames) = bench_workload(seed, 64)?;
    let n = frames.len();
    Ok(Fixture {
        model,
        frames,
        truth: (0..n)
            .map(|i| SYNTHETIC_CLASSES[i % 4].to_owned())
            .collect(),
        conditions: vec![String::new(); n],
    })
}

fn provenance(args: &BenchOptions) -> Provenance {
    Provenance {
        seed: Some(args.seed),
        command: args.command.clone(),
        created_unix_s: std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .ok()
            .map(|d| d.as_secs()),
        ..Provenance::default()
    }
}

fn median(values: &[f64]) -> f64 {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let mid = sorted.len() / 2;
    if sorted.len() % 2 == 1 {
        sorted[mid]
    } else {
        0.5 * (sorted[mid - 1] + sorted[mid])
    }
}

impl BenchReport {
    /// The report as `presrs bench` prints it (a folder the inputs were exported to last).
    pub fn text(&self, export: Option<&Path>) -> String {
        use std::fmt::Write as _;
        let mut text = String::new();
        let _ = writeln!(text, "model                      {}", self.model);
        let _ = writeln!(
            text,
            "single image (median)      {:.2} us   (quartiles {:.2}-{:.2} us, p99 {:.2} us, min {:.2} us, {} runs)",
            self.single_image_median_ns as f64 / 1e3,
            self.single_image_p25_ns as f64 / 1e3,
            self.single_image_p75_ns as f64 / 1e3,
            self.single_image_p99_ns as f64 / 1e3,
            self.single_image_min_ns as f64 / 1e3,
            self.iterations
        );
        let _ = writeln!(
            text,
            "  of which (medians)       crop + features {:.2} us, PCA {:.2} us, classifier {:.2} us (each timed alone)",
            self.stages_median_ns.features as f64 / 1e3,
            self.stages_median_ns.pca as f64 / 1e3,
            self.stages_median_ns.classifier as f64 / 1e3,
        );
        let _ = writeln!(
            text,
            "batch throughput           {:.0} images/s on {} threads ({} images, median of {} runs)",
            self.batch_images_per_s,
            self.batch_threads,
            self.batch,
            self.batch_runs_images_per_s.len()
        );
        let _ = writeln!(
            text,
            "paper                      245 us per image (2.67 GHz Core 2 Duo)"
        );
        if let Some(dir) = export {
            let _ = writeln!(text, "exported to                {}", dir.display());
        }
        text
    }
}

/// Times one classification and batch throughput as `options` say (and exports the inputs and
/// answers with `options.export`).
pub fn bench(options: &BenchOptions, progress: &dyn Progress) -> Result<BenchReport> {
    let args = options;
    if args.iterations == 0 || args.batch == 0 || args.batch_runs == 0 {
        return Err(Error::invalid(
            Message::new()
                .opt(Opt::Iterations)
                .text(", ")
                .opt(Opt::Batch)
                .text(" and ")
                .opt(Opt::BatchRuns)
                .text(" must be positive"),
        ));
    }
    let (fixture, model_file, source) = match (&args.images, &args.model) {
        (Some(manifest), Some(path)) => {
            let model_file = load_model(path)?;
            let fixture =
                manifest_fixture(model_file.model.clone(), manifest, &args.samples, progress)?;
            let source = format!("{} on the images of {}", path.display(), manifest.display());
            (fixture, model_file, source)
        }
        _ => {
            let (fixture, source) = if args.synthetic {
                (
                    synthetic_fixture(args.seed)?,
                    "synthetic pattern, paper settings",
                )
            } else {
                (
                    simulated_fixture(args.seed)?,
                    "simulated images, trained on G2 with the paper's settings",
                )
            };
            match &args.model {
                Some(path) => (fixture, load_model(path)?, path.display().to_string()),
                None => {
                    let model_file = ModelFile::new(fixture.model.clone(), provenance(args));
                    (fixture, model_file, source.to_owned())
                }
            }
        }
    };
    let frames = &fixture.frames;
    let model = &model_file.model;
    let mut session = model.session();
    // Warm up caches and check the images fit the model.
    for (index, frame) in frames.iter().enumerate() {
        session.classify(&frame.view()).map_err(|err| {
            let which = match &args.images {
                Some(manifest) => format!("sample {} of {}", index + 1, manifest.display()),
                None => "the benchmark images".to_owned(),
            };
            let model = args.model.as_ref().map_or_else(
                || "the built-in model".to_owned(),
                |p| p.display().to_string(),
            );
            Error::data(format!(
                "{which} ({}) does not fit {model}: {err}",
                frame.grid()
            ))
        })?;
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
    // One untimed run starts rayon's workers and warms their sessions' caches.
    black_box(model.classify_batch(&batch[..batch.len().min(frames.len())]));
    let mut runs = Vec::with_capacity(args.batch_runs);
    for _ in 0..args.batch_runs {
        let start = Instant::now();
        let results = model.classify_batch(&batch);
        let elapsed = start.elapsed().as_secs_f64();
        black_box(&results);
        runs.push(args.batch as f64 / elapsed);
    }
    let stages = stage_times(model, frames, args.iterations)?;
    let report = BenchReport {
        model: source,
        single_image_median_ns: quantile(0.5),
        single_image_p25_ns: quantile(0.25),
        single_image_p75_ns: quantile(0.75),
        single_image_p99_ns: quantile(0.99),
        single_image_min_ns: times_ns[0],
        batch_images_per_s: median(&runs),
        batch_runs_images_per_s: runs,
        batch_threads: rayon::current_num_threads(),
        iterations: args.iterations,
        batch: args.batch,
        test_images: frames.len(),
        stages_median_ns: stages,
    };
    if let Some(dir) = &args.export {
        export(dir, &model_file, &fixture, &report)?;
    }
    Ok(report)
}

/// Writes the model, the test images, presrs's intermediate results and predictions into `dir`.
fn export(
    dir: &Path,
    model_file: &ModelFile,
    fixture: &Fixture,
    report: &BenchReport,
) -> Result<()> {
    let frames = &fixture.frames;
    std::fs::create_dir_all(dir)
        .with_context(|| format!("{}: cannot create the export folder", dir.display()))?;
    let model = &model_file.model;
    let grid = frames
        .first()
        .map(Frame::grid)
        .ok_or_else(|| Error::data("no test images to export"))?;
    if frames.iter().any(|frame| frame.grid() != grid) {
        return Err(Error::data("the test images do not all have the same grid"));
    }
    // Absent sensels as 0, which is how the pipeline reads them.
    let mut images = Vec::with_capacity(frames.len() * grid.len());
    for frame in frames {
        frame.view().extend_absent_as_zero(&mut images);
    }
    let mut session = model.session();
    let (n_features, n_components) = (model.n_features(), model.classifier_dims());
    let mut features = Vec::with_capacity(frames.len() * n_features);
    let mut reduced = Vec::with_capacity(frames.len() * n_components);
    let mut predictions = Vec::with_capacity(frames.len());
    let mut labels = Vec::with_capacity(frames.len());
    let mut posteriors = Vec::with_capacity(frames.len());
    for frame in frames {
        features.extend_from_slice(session.features(&frame.view())?);
        reduced.extend_from_slice(session.reduce(&frame.view())?);
        let prediction = session.classify(&frame.view())?;
        predictions.push(prediction.class);
        labels.push(model.class_names()[prediction.class].as_str());
        posteriors.push(prediction.posteriors.to_vec());
    }
    let write_array = |name: &str, shape: &[usize], data: &[f64]| -> Result<()> {
        let path = dir.join(name);
        presrs_io::atomic::write_atomic(&path, |w| write_npy_f64(w, shape, data))?;
        Ok(())
    };
    write_array("images.npy", &[frames.len(), grid.rows, grid.cols], &images)?;
    write_array("features.npy", &[frames.len(), n_features], &features)?;
    write_array("reduced.npy", &[frames.len(), n_components], &reduced)?;
    save_model(&dir.join("model.json"), model_file)?;
    let cropped = model.image_grid();
    let document = Export {
        format: "presrs-bench-export",
        presrs_version: env!("CARGO_PKG_VERSION"),
        images: "images.npy",
        image_shape: [frames.len(), grid.rows, grid.cols],
        cropped_shape: [cropped.rows, cropped.cols],
        features: "features.npy",
        reduced: "reduced.npy",
        model_file: "model.json",
        class_names: model.class_names(),
        predictions,
        labels,
        posteriors,
        truth: &fixture.truth,
        conditions: &fixture.conditions,
        timing: report,
    };
    let path = dir.join("presrs.json");
    presrs_io::atomic::write_atomic(&path, |w| {
        serde_json::to_writer_pretty(&mut *w, &document).map_err(std::io::Error::from)?;
        writeln!(w)
    })?;
    Ok(())
}
