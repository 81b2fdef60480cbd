//! The paper's experiment end to end on the built-in simulator (Tables I and II).
//!
//! The data set lives in `DIR/dataset/` (the layout `presrs simulate --out` writes, see
//! [`crate::simulation`]), the heavier hopper's of the load-independence test in `DIR/dataset-load1.30/`
//! (the factor is 1 + `--extra-load`). A folder whose `stamp.json` says it was made with the same
//! presrs version, seed, hops per gait, load and simulator configuration, whose files all match the
//! stamp, and whose first trial this build's simulator still makes (it is simulated again: about 2 % of
//! the simulation time; a development build whose simulator changed without a version change is caught
//! there) is read back instead of simulated; otherwise the reason is printed and the data set is
//! simulated afresh and written there (the stamp last, so an interrupted run never leaves a stamp claiming
//! a complete data set). [`ReproduceOptions::resimulate`] always simulates. Both sources give the same trials (the movies
//! hold integer counts, the truth round-trips through JSON exactly), hence the same results.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use presrs_core::classifier::ClassifierKind;
use presrs_core::evaluation::{ComparisonRow, EvalReport, MeanStd, Models, Protocol};
use presrs_core::features::FeatureConfig;
use presrs_core::pipeline::{CheckedTrainConfig, LabeledImage, TrainConfig, train};
use presrs_core::split::{ValidationSize, stratified_split};
use presrs_core::stance::{ValidSegmentParams, segment_recording};
use presrs_core::{Frame, Recording};
use presrs_io::atomic::write_atomic;
use presrs_sim::{Dataset as SimDataset, DatasetSpec, SimConfig, TrialOutput, VelocityTable};
use serde::Serialize;

use crate::dataset::Sample;
use crate::error::{Context, Error, Result};
use crate::evaluate::{CalibrationJson, calibration_line, run_counted};
use crate::method::CANDIDATE_FEATURES;
use crate::progress::Progress;
use crate::report::{PAPER_TABLE2, SimulationReportData, write_simulation_report};
use crate::simulation::{DatasetKey, check_simulator, read_dataset, write_dataset_with};
use crate::train::split_images;
use presrs_io::message::{Message, Opt};

/// The paper's classification time on a 2.67 GHz Core 2 Duo, ns.
pub const PAPER_CLASSIFY_NS: u64 = 245_000;

/// What to reproduce and where.
#[derive(Clone, Debug, PartialEq)]
pub struct ReproduceOptions {
    /// Folder for results.json, results.md, the report and the simulated data sets (`dataset/`,
    /// `dataset-load1.30/`).
    pub out: PathBuf,
    /// Seed of the simulation and of the training draws.
    pub seed: u64,
    /// Repeats of each training draw.
    pub repeats: usize,
    /// Training images drawn per terrain (the paper's 20), of which `validation` choose sigma (7).
    pub per_class: usize,
    pub validation: usize,
    /// Recorded hops per terrain and gait (default: the simulator's paper-sized experiment).
    pub hops_per_gait: Option<usize>,
    /// Write the HTML report (`out/report/index.html`).
    pub report: bool,
    /// Extra load of the load-independence test, as a fraction of the nominal body mass.
    pub extra_load: f64,
    /// Compare every feature family x classifier with Table II's draws.
    pub comparison: bool,
    /// Simulate the data sets afresh even when `out` holds matching ones.
    pub resimulate: bool,
}

impl Default for ReproduceOptions {
    fn default() -> Self {
        Self {
            out: PathBuf::from("results"),
            seed: 1,
            repeats: 10,
            per_class: 20,
            validation: 7,
            hops_per_gait: None,
            report: true,
            extra_load: 0.3,
            comparison: true,
            resimulate: false,
        }
    }
}

/// Everything a reproduction found: what `results.json` holds, and what a summary shows.
#[derive(Debug)]
pub struct Reproduction {
    pub results: Results,
    /// Table I as text, simulated beside the paper's.
    pub table1_text: String,
    /// The comparison of the other methods (empty without it).
    pub comparison: Vec<ComparisonRow>,
    /// What happened to the heavier hopper's data set (`reusing ...` / `simulating ...`), when tried.
    pub load_dataset_note: Option<String>,
    /// Why the load-independence test is missing, when it is.
    pub load_error: Option<String>,
    pub json_path: PathBuf,
    pub markdown_path: PathBuf,
    pub report_path: Option<PathBuf>,
}

/// Where a data set came from.
#[derive(Debug, Clone, Serialize)]
pub struct DatasetOrigin {
    pub path: PathBuf,
    /// `reusing DIR (seed S, presrs V)` or `simulating DIR (seed S, M kg): REASON`.
    #[serde(skip)]
    pub note: String,
    /// Read back from `path` (its stamp matched) rather than simulated.
    pub reused: bool,
    /// Why it was simulated (no data set there, a mismatch, a changed file, `--resimulate`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub simulated_because: Option<String>,
}

/// Load independence: a model trained at the nominal load tested on images recorded at a higher load,
/// as they are and scaled by nominal / actual load (the paper's "scaling factor").
#[derive(Debug, Serialize)]
pub struct LoadCheck {
    pub nominal_load_kg: f64,
    pub test_load_kg: f64,
    pub test_images: usize,
    /// Accuracy on the heavier robot's images as recorded.
    pub accuracy_unscaled: MeanStd,
    /// Accuracy after multiplying every test image by nominal / test load.
    pub accuracy_scaled: MeanStd,
    /// Accuracy of a model trained with `--normalise-load` (each image divided by its total load) on the
    /// heavier robot's images as recorded: no knowledge of the load.
    pub accuracy_normalised: MeanStd,
}

/// One feature x classifier combination of the comparison (trained on G2, 20 per terrain, 7 validating).
#[derive(Debug, Serialize)]
pub struct ComparisonSummary {
    pub features: String,
    pub classifier: String,
    /// Over every tested image (mean and spread over repeats); `None` when it could not be trained.
    pub overall: Option<MeanStd>,
    pub per_gait: BTreeMap<String, MeanStd>,
    /// Training time of one model, ms.
    pub train_ms: MeanStd,
    pub median_classify_ns: u64,
    pub error: Option<String>,
}

impl ComparisonSummary {
    pub fn of(row: &ComparisonRow) -> Self {
        let (overall, per_gait, median_classify_ns, error) = match &row.report {
            Ok(report) => (
                Some(report.overall),
                report.per_condition.clone(),
                report.median_classify_ns,
                None,
            ),
            Err(err) => (None, BTreeMap::new(), 0, Some(err.clone())),
        };
        Self {
            features: row.features.clone(),
            classifier: row.classifier.clone(),
            overall,
            per_gait,
            train_ms: MeanStd {
                mean: 1e3 * row.train_seconds.mean,
                std: 1e3 * row.train_seconds.std,
            },
            median_classify_ns,
            error,
        }
    }
}

#[derive(Debug, Serialize)]
pub struct SegmentationCheck {
    /// Hops the simulator recorded (with a stance frame) and stances the segmentation found.
    pub true_hops: usize,
    pub found_stances: usize,
    /// True hops whose stance was found with its first and last frame within one frame.
    pub matched_within_one_frame: usize,
    /// Found mid-stance frames equal to the simulator's.
    pub same_mid_frame: usize,
}

/// The training draw: images per terrain, and how many of them validate.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Draw {
    pub per_class: usize,
    pub validation: usize,
}

#[derive(Debug, Serialize)]
pub struct Results {
    pub seed: u64,
    pub repeats: usize,
    /// Training images per terrain and how many of them validate (the paper's 20 and 7).
    pub draw: Draw,
    pub presrs_version: &'static str,
    /// Forward velocity per gait and terrain, m/s.
    pub table1: BTreeMap<String, BTreeMap<String, f64>>,
    pub table1_paper: BTreeMap<String, BTreeMap<String, f64>>,
    /// Accuracy per tested gait and overall, trained on G2 (means over repeats).
    pub table2: BTreeMap<String, f64>,
    pub table2_std: BTreeMap<String, f64>,
    pub table2_paper: BTreeMap<String, f64>,
    pub median_classify_ns: u64,
    pub paper_classify_ns: u64,
    /// Table II's confidences against whether they were right, as `eval --json` gives them.
    pub table2_calibration: CalibrationJson,
    /// Train gait -> tested gait -> accuracy (means over repeats).
    pub train_test_matrix: BTreeMap<String, BTreeMap<String, f64>>,
    pub images_per_gait: BTreeMap<String, usize>,
    pub segmentation: SegmentationCheck,
    /// Where the data sets came from: `main` and (when measured) `load`.
    pub datasets: BTreeMap<String, DatasetOrigin>,
    /// `None` when the heavier hopper could not be simulated (the reason is printed).
    pub load_independence: Option<LoadCheck>,
    /// Every feature family x classifier with Table II's protocol and draws (empty with --no-comparison).
    pub comparison: Vec<ComparisonSummary>,
    /// Full reports of every training gait.
    pub evaluations: BTreeMap<String, EvalReport>,
    pub timings_s: BTreeMap<String, f64>,
}

/// The options that must agree with each other, checked before anything is simulated: some of the
/// per-class images train, and every gait records at least as many images per terrain.
pub fn check_options(
    args: &ReproduceOptions,
    config: &SimConfig,
) -> std::result::Result<(), Message> {
    if args.validation >= args.per_class {
        return Err(Message::new()
            .opt_is(Opt::Validation, args.validation)
            .text(" must be smaller than ")
            .opt_is(Opt::PerClass, args.per_class)
            .text(": some images must train; give ")
            .opt_is(Opt::Validation, args.per_class.saturating_sub(1))
            .text(" or less, or a larger ")
            .opt(Opt::PerClass));
    }
    let hops = args
        .hops_per_gait
        .unwrap_or(config.experiment.hops_per_gait);
    if hops < args.per_class {
        return Err(Message::new()
            .opt_is(Opt::HopsPerGait, hops)
            .text(format!(
                " records {hops} images per terrain and gait, fewer than the "
            ))
            .opt_is(Opt::PerClass, args.per_class)
            .text(" training images drawn per terrain from the training gait; give ")
            .opt_is(Opt::HopsPerGait, args.per_class)
            .text(" or more, or a ")
            .opt(Opt::PerClass)
            .text(format!(" of at most {hops} with a smaller "))
            .opt(Opt::Validation)
            .text(format!(" (now {})", args.validation)));
    }
    Ok(())
}

/// Runs the paper's experiment (see the module documentation) and writes `results.json`, `results.md`
/// and the report under `options.out`.
pub fn reproduce(options: &ReproduceOptions, progress: &dyn Progress) -> Result<Reproduction> {
    let args = options;
    let started = Instant::now();
    let mut timings = BTreeMap::new();
    let sim_config = SimConfig::default();
    check_options(args, &sim_config).map_err(Error::invalid)?;
    let draw = Draw {
        per_class: args.per_class,
        validation: args.validation,
    };
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create the output folder {}", args.out.display()))?;

    // 1. The data set: read back from DIR/dataset when it is the one this run would simulate.
    let mut spec = DatasetSpec::paper(args.seed);
    spec.hops_per_gait = args.hops_per_gait;
    let mut datasets = BTreeMap::new();
    let (dataset, origin) = obtain_dataset(
        &sim_config,
        &spec,
        &args.out.join("dataset"),
        args.resimulate,
        progress,
    )
    .map_err(|(_, err)| err)?;
    timings.insert(
        if origin.reused {
            "read_dataset"
        } else {
            "simulate"
        }
        .to_owned(),
        started.elapsed().as_secs_f64(),
    );
    datasets.insert("main".to_owned(), origin);

    // 2. Table I.
    let table = dataset.velocity_table();
    let (table1, table1_paper) = table1_maps(&table);

    // 3. Samples: the mid-stance frame of every complete stance the segmentation finds.
    let segment_start = Instant::now();
    let (samples, segmentation) = stance_samples(&dataset.trials)?;
    timings.insert("segment".to_owned(), segment_start.elapsed().as_secs_f64());
    // What the report needs from the data set, then the movies go (hundreds of MB; the heavier hopper's
    // data set below would otherwise be held next to them).
    let report_data = if args.report {
        Some(SimulationReportData::from_dataset(&dataset)?)
    } else {
        None
    };
    drop(dataset);
    let mut images_per_gait = BTreeMap::new();
    for sample in &samples {
        *images_per_gait
            .entry(sample.condition.clone().unwrap_or_default())
            .or_insert(0) += 1;
    }

    // 4. Table II and the train-gait x test-gait matrix.
    let eval_samples: Vec<LabeledImage<'_>> = samples.iter().map(eval_sample).collect();
    let config = TrainConfig::default().check()?;
    let gaits: Vec<String> = images_per_gait.keys().cloned().collect();
    let eval_start = Instant::now();
    let evaluations = evaluate_each_gait(&eval_samples, &gaits, &config, args, progress)?;
    timings.insert("evaluate".to_owned(), eval_start.elapsed().as_secs_f64());
    let main = evaluations
        .get("G2")
        .ok_or_else(|| Error::data("the simulated data set has no gait G2 to train on"))?;
    let mut table2: BTreeMap<String, MeanStd> = main.per_condition.clone();
    table2.insert("overall".to_owned(), main.overall);
    let matrix = train_test_matrix(&evaluations, &gaits);

    // 5. Load independence.
    let load_start = Instant::now();
    let load = load_test(&sim_config, &spec, &samples, &config, args, progress)?;
    if let Some(origin) = load.origin {
        datasets.insert("load".to_owned(), origin);
    }
    let (load_dataset_note, load_check, load_error) = (load.note, load.check, load.error);
    timings.insert(
        "load_independence".to_owned(),
        load_start.elapsed().as_secs_f64(),
    );

    // 6. Other methods: every feature family x classifier with Table II's protocol and draws.
    let mut rows = Vec::new();
    if args.comparison {
        let compare_start = Instant::now();
        rows = compare_methods(&eval_samples, draw, args, progress)?;
        timings.insert(
            "comparison".to_owned(),
            compare_start.elapsed().as_secs_f64(),
        );
    }
    timings.insert("total".to_owned(), started.elapsed().as_secs_f64());

    // 7. Results files.
    let results = Results {
        seed: args.seed,
        repeats: args.repeats,
        draw,
        presrs_version: env!("CARGO_PKG_VERSION"),
        table1,
        table1_paper,
        table2: table2.iter().map(|(k, v)| (k.clone(), v.mean)).collect(),
        table2_std: table2.iter().map(|(k, v)| (k.clone(), v.std)).collect(),
        table2_paper: PAPER_TABLE2
            .iter()
            .map(|(k, v)| ((*k).to_owned(), *v))
            .collect(),
        median_classify_ns: main.median_classify_ns,
        paper_classify_ns: PAPER_CLASSIFY_NS,
        table2_calibration: CalibrationJson::new(&main.reliability),
        train_test_matrix: matrix,
        images_per_gait,
        segmentation,
        datasets,
        load_independence: load_check,
        comparison: rows.iter().map(ComparisonSummary::of).collect(),
        evaluations,
        timings_s: timings,
    };
    let table1_text = table.format_with_paper();
    let (json_path, markdown_path, report_path) = write_results(
        &results,
        &table1_text,
        report_data.as_ref(),
        &sim_config,
        args,
        progress,
    )?;
    Ok(Reproduction {
        results,
        table1_text,
        comparison: rows,
        load_dataset_note,
        load_error,
        json_path,
        markdown_path,
        report_path,
    })
}

/// Writes `results.json`, the report (from `report_data`) and `results.md`; returns their paths.
fn write_results(
    results: &Results,
    table1_text: &str,
    report_data: Option<&SimulationReportData>,
    sim_config: &SimConfig,
    args: &ReproduceOptions,
    progress: &dyn Progress,
) -> Result<(PathBuf, PathBuf, Option<PathBuf>)> {
    let json_path = args.out.join("results.json");
    write_atomic(&json_path, |w| {
        serde_json::to_writer_pretty(&mut *w, results).map_err(std::io::Error::from)?;
        writeln!(w)
    })?;
    let report_path = match report_data {
        Some(report_data) => {
            progress.start("writing the report", None);
            let path = write_simulation_report(
                report_data,
                sim_config,
                &results.evaluations,
                args.seed,
                &args.out.join("report"),
            );
            progress.finish();
            Some(path?)
        }
        None => None,
    };
    let markdown_path = args.out.join("results.md");
    write_atomic(&markdown_path, |w| write_markdown(results, table1_text, w))?;
    Ok((json_path, markdown_path, report_path))
}

/// What the load-independence test found, and where its data set came from.
struct LoadTest {
    origin: Option<DatasetOrigin>,
    /// `reusing ...` / `simulating ...`, when the heavier hopper's data set was tried.
    note: Option<String>,
    check: Option<LoadCheck>,
    /// Why there is no check (the heavier hopper could not be simulated or segmented).
    error: Option<String>,
}

/// The load-independence test: the heavier hopper's data set (read back or simulated), and models
/// trained on the nominal G2 `samples` tested on it. A heavier hopper that cannot be had is reported,
/// not fatal: the main tables stand on their own.
fn load_test(
    sim_config: &SimConfig,
    spec: &DatasetSpec,
    samples: &[Sample],
    config: &CheckedTrainConfig,
    args: &ReproduceOptions,
    progress: &dyn Progress,
) -> Result<LoadTest> {
    let nominal_kg = sim_config.robot.body_mass_kg;
    let heavy_kg = nominal_kg * (1.0 + args.extra_load);
    let mut heavy_spec = spec.clone();
    heavy_spec.load_kg = Some(heavy_kg);
    heavy_spec.seed = args.seed.wrapping_add(1_000_003);
    let heavy_dir = args
        .out
        .join(format!("dataset-load{:.2}", 1.0 + args.extra_load));
    let (origin, note, heavy) = match obtain_dataset(
        sim_config,
        &heavy_spec,
        &heavy_dir,
        args.resimulate,
        progress,
    ) {
        Ok((heavy, origin)) => {
            let note = Some(origin.note.clone());
            let samples = stance_samples(&heavy.trials).map(|(samples, _)| samples);
            (Some(origin), note, samples)
        }
        Err((note, err)) => (None, note, Err(err)),
    };
    let heavy_samples = match heavy {
        Ok(heavy_samples) => heavy_samples,
        Err(err) => {
            return Ok(LoadTest {
                origin,
                note,
                check: None,
                error: Some(err.to_string()),
            });
        }
    };
    let training_pool: Vec<&Sample> = samples
        .iter()
        .filter(|s| s.condition.as_deref() == Some("G2"))
        .collect();
    let draw = Draw {
        per_class: args.per_class,
        validation: args.validation,
    };
    let check = load_independence(
        &training_pool,
        &heavy_samples,
        (nominal_kg, heavy_kg),
        config,
        draw,
        (args.repeats, args.seed),
    )?;
    Ok(LoadTest {
        origin,
        note,
        check: Some(check),
        error: None,
    })
}

/// Table I as maps: simulated and the paper's velocity per gait and terrain.
#[allow(clippy::type_complexity)]
fn table1_maps(
    table: &VelocityTable,
) -> (
    BTreeMap<String, BTreeMap<String, f64>>,
    BTreeMap<String, BTreeMap<String, f64>>,
) {
    let mut table1 = BTreeMap::new();
    let mut table1_paper = BTreeMap::new();
    for (g, gait) in table.gaits.iter().enumerate() {
        for (t, terrain) in table.terrains.iter().enumerate() {
            table1
                .entry(gait.clone())
                .or_insert_with(BTreeMap::new)
                .insert(terrain.clone(), table.velocity_m_per_s[g][t]);
            if let Some(paper) = VelocityTable::paper_value(gait, terrain) {
                table1_paper
                    .entry(gait.clone())
                    .or_insert_with(BTreeMap::new)
                    .insert(terrain.clone(), paper);
            }
        }
    }
    (table1, table1_paper)
}

/// A stance sample as the evaluation engine sees it (terrain label, gait condition).
fn eval_sample(sample: &Sample) -> LabeledImage<'_> {
    LabeledImage {
        frame: sample.frame.view(),
        label: sample.label.as_deref().unwrap_or_default(),
        condition: sample.condition.as_deref(),
        group: None,
    }
}

/// The paper's method trained on each gait in turn (the options' draw), tested on every other image.
fn evaluate_each_gait(
    samples: &[LabeledImage<'_>],
    gaits: &[String],
    config: &CheckedTrainConfig,
    args: &ReproduceOptions,
    progress: &dyn Progress,
) -> Result<BTreeMap<String, EvalReport>> {
    progress.start("training", Some((gaits.len() * args.repeats) as u64));
    let mut evaluations = BTreeMap::new();
    for gait in gaits {
        let protocol = Protocol::TrainCondition {
            condition: Some(gait.clone()),
            per_class: Some(args.per_class),
            validation: ValidationSize::Count(args.validation),
        };
        let report = presrs_core::evaluation::Evaluation {
            samples,
            protocol: &protocol,
            repeats: args.repeats,
            seed: args.seed,
            progress: &|| progress.advance(1),
        }
        .run(Models::Config(config))
        .with_context(|| format!("evaluation trained on {gait} failed"));
        let report = match report {
            Ok(report) => report,
            Err(err) => {
                progress.finish();
                return Err(err);
            }
        };
        evaluations.insert(gait.clone(), report);
    }
    progress.finish();
    Ok(evaluations)
}

/// Train gait -> tested gait (and overall) -> accuracy.
fn train_test_matrix(
    evaluations: &BTreeMap<String, EvalReport>,
    gaits: &[String],
) -> BTreeMap<String, BTreeMap<String, f64>> {
    let mut matrix = BTreeMap::new();
    for (train_gait, report) in evaluations {
        let mut row = BTreeMap::new();
        for gait in gaits {
            let value = report.per_condition.get(gait).map_or(f64::NAN, |m| m.mean);
            row.insert(gait.clone(), value);
        }
        row.insert("overall".to_owned(), report.overall.mean);
        matrix.insert(train_gait.clone(), row);
    }
    matrix
}

/// Every feature family x classifier with Table II's protocol and draws.
fn compare_methods(
    samples: &[LabeledImage<'_>],
    draw: Draw,
    args: &ReproduceOptions,
    progress: &dyn Progress,
) -> Result<Vec<ComparisonRow>> {
    let mut configs = Vec::new();
    for kinds in CANDIDATE_FEATURES {
        for kind in ClassifierKind::ALL {
            configs.push(
                TrainConfig {
                    features: FeatureConfig::combined(kinds),
                    classifier: kind.default_config(),
                    ..TrainConfig::default()
                }
                .check()?,
            );
        }
    }
    let protocol = Protocol::TrainCondition {
        condition: Some("G2".to_owned()),
        per_class: Some(draw.per_class),
        validation: ValidationSize::Count(draw.validation),
    };
    run_counted(
        samples,
        &protocol,
        (args.repeats, args.seed),
        ("comparing", (configs.len() * args.repeats) as u64),
        progress,
        |evaluation| evaluation.compare(&configs),
    )
    .context("the comparison of the other methods failed")
}

/// The data set `config` and `spec` describe: read back from `dir` when its stamp matches (and every
/// file is intact), else simulated and written to `dir`; its origin says which, and why it simulated.
/// An error comes with the note of what was tried, when there is one.
fn obtain_dataset(
    config: &SimConfig,
    spec: &DatasetSpec,
    dir: &Path,
    resimulate: bool,
    progress: &dyn Progress,
) -> std::result::Result<(SimDataset, DatasetOrigin), (Option<String>, Error)> {
    let wanted = DatasetKey::new(config, spec);
    let reason = if resimulate {
        "--resimulate".to_owned()
    } else {
        progress.start(&format!("reading {}", dir.display()), None);
        let read = read_dataset(dir, &wanted).and_then(|(dataset, stamp)| {
            check_simulator(config, spec, &dataset)?;
            Ok((dataset, stamp))
        });
        progress.finish();
        match read {
            Ok((dataset, _)) => {
                let origin = DatasetOrigin {
                    path: dir.to_path_buf(),
                    note: format!(
                        "reusing {} (seed {}, presrs {})",
                        dir.display(),
                        wanted.seed,
                        wanted.presrs_version
                    ),
                    reused: true,
                    simulated_because: None,
                };
                return Ok((dataset, origin));
            }
            Err(err) => err.to_string(),
        }
    };
    let note = format!(
        "simulating {} (seed {}, {} kg): {reason}",
        dir.display(),
        wanted.seed,
        wanted.load_kg
    );
    let simulated = write_dataset_with(config, spec, dir, true, progress)
        .with_context(|| {
            format!(
                "cannot simulate and write the data set {} (seed {}, {} kg)",
                dir.display(),
                wanted.seed,
                wanted.load_kg
            )
        })
        .and_then(|(_, dataset)| {
            dataset.ok_or_else(|| Error::data("the simulated trials were not kept"))
        });
    match simulated {
        Ok(dataset) => {
            let origin = DatasetOrigin {
                path: dir.to_path_buf(),
                note,
                reused: false,
                simulated_because: Some(reason),
            };
            Ok((dataset, origin))
        }
        Err(err) => Err((Some(note), err)),
    }
}

/// Trains on `pool` (`draw`; the paper's: 20 per terrain, 7 of them for validation) once per repeat and tests
/// on `heavy`, as recorded and scaled by `nominal_kg / heavy_kg`.
fn load_independence(
    pool: &[&Sample],
    heavy: &[Sample],
    (nominal_kg, heavy_kg): (f64, f64),
    config: &CheckedTrainConfig,
    draw: Draw,
    (repeats, seed): (usize, u64),
) -> Result<LoadCheck> {
    let factor = nominal_kg / heavy_kg;
    let scaled: Vec<Frame> = heavy
        .iter()
        .map(|s| {
            let mut frame = s.frame.clone();
            frame.values_mut().iter_mut().for_each(|v| *v *= factor);
            frame
        })
        .collect();
    let labels: Vec<&str> = pool
        .iter()
        .map(|s| s.label.as_deref().unwrap_or_default())
        .collect();
    let mut normalised_config = config.config().clone();
    normalised_config.preprocess.normalise_load = true;
    let normalised_config = normalised_config.check()?;
    let (mut unscaled_acc, mut scaled_acc, mut normalised_acc) =
        (Vec::new(), Vec::new(), Vec::new());
    for repeat in 0..repeats {
        let split = stratified_split(
            &labels,
            Some(draw.per_class),
            ValidationSize::Count(draw.validation),
            seed.wrapping_add(repeat as u64),
        )?;
        let (train_images, validation_images) = split_images(&split, |i| {
            LabeledImage::new(pool[i].frame.view(), labels[i])
        });
        let model = train(&train_images, &validation_images, config)?;
        let normalised = train(&train_images, &validation_images, &normalised_config)?;
        let mut session = model.session();
        let mut normalised_session = normalised.session();
        let (mut right_raw, mut right_scaled, mut right_normalised) = (0usize, 0usize, 0usize);
        for (sample, scaled_frame) in heavy.iter().zip(&scaled) {
            if session.classify(&sample.frame.view())?.label
                == sample.label.as_deref().unwrap_or_default()
            {
                right_raw += 1;
            }
            if session.classify(&scaled_frame.view())?.label
                == sample.label.as_deref().unwrap_or_default()
            {
                right_scaled += 1;
            }
            if normalised_session.classify(&sample.frame.view())?.label
                == sample.label.as_deref().unwrap_or_default()
            {
                right_normalised += 1;
            }
        }
        let n = heavy.len().max(1) as f64;
        unscaled_acc.push(right_raw as f64 / n);
        scaled_acc.push(right_scaled as f64 / n);
        normalised_acc.push(right_normalised as f64 / n);
    }
    Ok(LoadCheck {
        nominal_load_kg: nominal_kg,
        test_load_kg: heavy_kg,
        test_images: heavy.len(),
        accuracy_unscaled: MeanStd::of(&unscaled_acc),
        accuracy_scaled: MeanStd::of(&scaled_acc),
        accuracy_normalised: MeanStd::of(&normalised_acc),
    })
}

/// Segments every trial, takes the mid-stance frame of each complete stance, and checks the stances
/// against the simulator's ground truth.
pub fn stance_samples(trials: &[TrialOutput]) -> Result<(Vec<Sample>, SegmentationCheck)> {
    let params = ValidSegmentParams::default();
    let mut samples = Vec::new();
    let mut check = SegmentationCheck {
        true_hops: 0,
        found_stances: 0,
        matched_within_one_frame: 0,
        same_mid_frame: 0,
    };
    for trial in trials {
        let recording: &Recording = &trial.recording;
        let segmentation = segment_recording(recording, &params)
            .with_context(|| format!("cannot segment trial {}", trial.plan.name()))?;
        let complete: Vec<_> = segmentation.complete().collect();
        check.found_stances += complete.len();
        for hop in &trial.hops {
            let (Some(first), Some(last)) = (hop.first_stance_frame, hop.last_stance_frame) else {
                continue;
            };
            check.true_hops += 1;
            if let Some(stance) = complete
                .iter()
                .find(|s| s.start.abs_diff(first) <= 1 && (s.end() - 1).abs_diff(last) <= 1)
            {
                check.matched_within_one_frame += 1;
                if Some(stance.mid_frame()) == hop.mid_stance_frame {
                    check.same_mid_frame += 1;
                }
            }
        }
        for stance in complete {
            if let Some(frame) = recording.frame(stance.mid_frame()) {
                let mut sample = Sample::new(
                    frame.to_frame(),
                    trial.plan.terrain.clone(),
                    PathBuf::from(format!("recordings/{}.asf", trial.plan.name())),
                    stance.mid_frame(),
                );
                sample.condition = Some(trial.plan.gait.name.clone());
                sample.group = Some(trial.plan.name());
                samples.push(sample);
            }
        }
    }
    Ok((samples, check))
}

fn write_markdown(results: &Results, table1: &str, w: &mut dyn Write) -> std::io::Result<()> {
    writeln!(
        w,
        "# presrs reproduce (seed {}, {} repeats)\n",
        results.seed, results.repeats
    )?;
    writeln!(w, "## Table I: forward velocity\n\n```\n{table1}```\n")?;
    writeln!(
        w,
        "## Table II: classification accuracy, trained on G2 ({} images per terrain, {} of them \
         validating)\n",
        results.draw.per_class, results.draw.validation
    )?;
    writeln!(
        w,
        "| tested | simulated (mean ± std) | paper |\n| --- | --- | --- |"
    )?;
    for (name, paper) in PAPER_TABLE2 {
        if let (Some(mean), Some(std)) = (results.table2.get(name), results.table2_std.get(name)) {
            writeln!(
                w,
                "| {name} | {:.1} % ± {:.1} | {:.1} % |",
                100.0 * mean,
                100.0 * std,
                100.0 * paper
            )?;
        }
    }
    writeln!(
        w,
        "\nMedian classification time: {:.2} µs per image (paper: 245 µs on a 2.67 GHz Core 2 Duo).\n",
        results.median_classify_ns as f64 / 1e3
    )?;
    if let Some(line) = results
        .evaluations
        .get("G2")
        .and_then(|g2| calibration_line(&g2.reliability))
    {
        writeln!(w, "Reported {line}.\n")?;
    }
    writeln!(w, "## Train gait × test gait accuracy\n")?;
    let gaits: Vec<&String> = results.images_per_gait.keys().collect();
    write!(w, "| train |")?;
    for gait in &gaits {
        write!(w, " {gait} |")?;
    }
    writeln!(w, " overall |")?;
    writeln!(w, "|{}", " --- |".repeat(gaits.len() + 2))?;
    for (train, row) in &results.train_test_matrix {
        write!(w, "| {train} |")?;
        for gait in gaits.iter().map(|g| g.as_str()).chain(["overall"]) {
            write!(
                w,
                " {:.1} % |",
                100.0 * row.get(gait).copied().unwrap_or(f64::NAN)
            )?;
        }
        writeln!(w)?;
    }
    if let Some(l) = &results.load_independence {
        writeln!(
            w,
            "\n## Load independence\n\nTrained on G2 at {:.2} kg; tested on every gait at {:.2} kg ({} images): \
         {:.1} % ± {:.1} as recorded, {:.1} % ± {:.1} scaled by the load ratio (the load known), {:.1} % ± \
         {:.1} with `--normalise-load` (trained and tested on images divided by their total load; the load \
         unknown).",
            l.nominal_load_kg,
            l.test_load_kg,
            l.test_images,
            100.0 * l.accuracy_unscaled.mean,
            100.0 * l.accuracy_unscaled.std,
            100.0 * l.accuracy_scaled.mean,
            100.0 * l.accuracy_scaled.std,
            100.0 * l.accuracy_normalised.mean,
            100.0 * l.accuracy_normalised.std
        )?;
    }
    if !results.comparison.is_empty() {
        write_comparison_markdown(&results.comparison, results.draw, w)?;
    }
    let s = &results.segmentation;
    writeln!(
        w,
        "\nSegmentation against the simulator's truth: {} of {} stances within one frame ({} found), {} \
         with the same mid-stance frame.",
        s.matched_within_one_frame, s.true_hops, s.found_stances, s.same_mid_frame
    )
}

/// The comparison as a Markdown table: accuracy per tested gait and overall, training and classification
/// time.
fn write_comparison_markdown(
    rows: &[ComparisonSummary],
    draw: Draw,
    w: &mut dyn Write,
) -> std::io::Result<()> {
    let mut gaits: Vec<&String> = rows.iter().flat_map(|r| r.per_gait.keys()).collect();
    gaits.sort();
    gaits.dedup();
    writeln!(
        w,
        "\n## Other methods\n\nEvery feature family × classifier, trained on G2 ({} images per terrain, {} of \
         them validating), tested on every other image, with the same draws as Table II (mean ± std over \
         the repeats). The paper's method is fft1d + pwe.\n",
        draw.per_class, draw.validation
    )?;
    write!(w, "| features | classifier |")?;
    for gait in &gaits {
        write!(w, " {gait} |")?;
    }
    writeln!(w, " overall | train ms | classify µs |")?;
    writeln!(w, "|{}", " --- |".repeat(gaits.len() + 5))?;
    let cell = |m: &MeanStd| format!("{:.1} ± {:.1}", 100.0 * m.mean, 100.0 * m.std);
    for row in rows {
        write!(w, "| {} | {} |", row.features, row.classifier)?;
        match (&row.overall, &row.error) {
            (Some(overall), _) => {
                for gait in &gaits {
                    write!(
                        w,
                        " {} |",
                        row.per_gait.get(*gait).map_or_else(|| "-".to_owned(), cell)
                    )?;
                }
                writeln!(
                    w,
                    " {} | {:.1} | {:.1} |",
                    cell(overall),
                    row.train_ms.mean,
                    row.median_classify_ns as f64 / 1e3
                )?;
            }
            (None, error) => {
                for _ in &gaits {
                    write!(w, " - |")?;
                }
                writeln!(
                    w,
                    " failed: {} | | |",
                    error.as_deref().unwrap_or("unknown error")
                )?;
            }
        }
    }
    Ok(())
}
