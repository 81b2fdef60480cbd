//! The paper's experiment end to end on the built-in simulator (Tables I and II).
//!
//! The data set lives in `DIR/dataset/` (the layout `presrs simulate --out` writes, see
//! [`crate::sim`]), the heavier hopper's of the load-independence test in `DIR/dataset-load1.30/`
//! (the factor is 1 + `--extra-load`). A folder whose `stamp.json` says it was made with the same
//! presrs version, seed, hops per gait, load and simulator configuration, whose files all match the
//! stamp, and whose first trial this build's simulator still makes (it is simulated again: about 2 % of
//! the simulation time; a development build whose simulator changed without a version change is caught
//! there) is read back instead of simulated; otherwise the reason is printed and the data set is
//! simulated afresh and written there (the stamp last, so an interrupted run never leaves a stamp claiming
//! a complete data set). [`ReproduceOptions::resimulate`] always simulates. Both sources give the same trials (the movies
//! hold integer counts, the truth round-trips through JSON exactly), hence the same results.

mod markdown;
mod results;

use std::collections::BTreeMap;
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
use presrs_sim::{DatasetSpec, SimConfig, SimulatedDataset, TrialOutput, VelocityTable};

use crate::dataset::Sample;
use crate::error::{Context, Error, Result};
use crate::eval::{CalibrationJson, run_counted};
use crate::method::CANDIDATE_FEATURES;
use crate::progress::Progress;
use crate::report::{PAPER_TABLE2, SimulationReportData, write_simulation_report};
use crate::sim::{DatasetKey, check_simulator, read_dataset, write_dataset_with};
use crate::train::split_images;
use presrs_io::message::{Message, Opt};

use markdown::write_markdown;
pub use results::{ComparisonSummary, DatasetOrigin, Draw, LoadCheck, Results, SegmentationCheck};

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
    let draw = check_and_prepare(args, &sim_config)?;

    // 1-3. The data set, Table I and the samples.
    let mut spec = DatasetSpec::paper(args.seed);
    spec.hops_per_gait = args.hops_per_gait;
    let stances = main_stances(&sim_config, &spec, args, progress, started, &mut timings)?;
    let images_per_gait = images_per_gait(&stances.samples);
    let gaits: Vec<String> = images_per_gait.keys().cloned().collect();

    // 4-6. Table II, the gait matrix, load independence and the other methods.
    let simulator = (&sim_config, &spec);
    let measured = measure(
        &stances.samples,
        &gaits,
        simulator,
        draw,
        args,
        progress,
        &mut timings,
    )?;
    let (table2, load, rows) = (measured.table2, measured.load, measured.rows);
    let mut datasets = BTreeMap::from([("main".to_owned(), stances.origin)]);
    if let Some(origin) = load.origin {
        datasets.insert("load".to_owned(), origin);
    }
    timings.insert("total".to_owned(), started.elapsed().as_secs_f64());

    // 7. Results files.
    let (table1, table1_paper) = table1_maps(&stances.table);
    let results = Results {
        seed: args.seed,
        repeats: args.repeats,
        draw,
        presrs_version: env!("CARGO_PKG_VERSION"),
        table1,
        table1_paper,
        table2: table2.mean,
        table2_std: table2.std,
        table2_paper: PAPER_TABLE2
            .iter()
            .map(|(k, v)| ((*k).to_owned(), *v))
            .collect(),
        median_classify_ns: table2.median_classify_ns,
        paper_classify_ns: PAPER_CLASSIFY_NS,
        table2_calibration: table2.calibration,
        train_test_matrix: measured.matrix,
        images_per_gait,
        segmentation: stances.segmentation,
        datasets,
        load_independence: load.check,
        comparison: rows.iter().map(ComparisonSummary::of).collect(),
        evaluations: measured.evaluations,
        timings_s: timings,
    };
    let table1_text = stances.table.format_with_paper();
    let (json_path, markdown_path, report_path) = write_results(
        &results,
        &table1_text,
        stances.report_data.as_ref(),
        &sim_config,
        args,
        progress,
    )?;
    Ok(Reproduction {
        results,
        table1_text,
        comparison: rows,
        load_dataset_note: load.note,
        load_error: load.error,
        json_path,
        markdown_path,
        report_path,
    })
}

/// What the experiment measured on the samples.
struct Measured {
    /// The evaluation of every training gait.
    evaluations: BTreeMap<String, EvalReport>,
    table2: Table2,
    /// Train gait -> tested gait -> accuracy.
    matrix: BTreeMap<String, BTreeMap<String, f64>>,
    load: LoadTest,
    /// The other methods (empty without the comparison).
    rows: Vec<ComparisonRow>,
}

/// Table II and the train-gait x test-gait matrix, load independence (on the heavier hopper of
/// `simulator`) and the other methods (every feature family x classifier with Table II's protocol and
/// draws); each step's time goes into `timings`.
fn measure(
    samples: &[Sample],
    gaits: &[String],
    (sim_config, spec): (&SimConfig, &DatasetSpec),
    draw: Draw,
    args: &ReproduceOptions,
    progress: &dyn Progress,
    timings: &mut BTreeMap<String, f64>,
) -> Result<Measured> {
    let eval_samples: Vec<LabeledImage<'_>> = samples.iter().map(eval_sample).collect();
    let config = TrainConfig::default().check()?;
    let evaluations = timed(timings, "evaluate", || {
        evaluate_each_gait(&eval_samples, gaits, &config, args, progress)
    })?;
    let table2 = Table2::of(&evaluations)?;
    let matrix = train_test_matrix(&evaluations, gaits);
    let load = timed(timings, "load_independence", || {
        load_test(sim_config, spec, samples, &config, args, progress)
    })?;
    let mut rows = Vec::new();
    if args.comparison {
        rows = timed(timings, "comparison", || {
            compare_methods(&eval_samples, draw, args, progress)
        })?;
    }
    Ok(Measured {
        evaluations,
        table2,
        matrix,
        load,
        rows,
    })
}

/// Checks the options and makes the output folder; returns the training draw.
fn check_and_prepare(args: &ReproduceOptions, sim_config: &SimConfig) -> Result<Draw> {
    check_options(args, sim_config).map_err(Error::invalid)?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create the output folder {}", args.out.display()))?;
    Ok(Draw {
        per_class: args.per_class,
        validation: args.validation,
    })
}

/// Table II: what the models trained on G2 found, per tested gait and overall.
struct Table2 {
    mean: BTreeMap<String, f64>,
    std: BTreeMap<String, f64>,
    median_classify_ns: u64,
    calibration: CalibrationJson,
}

impl Table2 {
    fn of(evaluations: &BTreeMap<String, EvalReport>) -> Result<Self> {
        let main = evaluations
            .get("G2")
            .ok_or_else(|| Error::data("the simulated data set has no gait G2 to train on"))?;
        let mut table2: BTreeMap<String, MeanStd> = main.per_condition.clone();
        table2.insert("overall".to_owned(), main.overall);
        Ok(Self {
            mean: table2.iter().map(|(k, v)| (k.clone(), v.mean)).collect(),
            std: table2.iter().map(|(k, v)| (k.clone(), v.std)).collect(),
            median_classify_ns: main.median_classify_ns,
            calibration: CalibrationJson::new(&main.reliability),
        })
    }
}

/// Runs `step`, recording how long it took under `name` when it succeeds.
fn timed<T>(
    timings: &mut BTreeMap<String, f64>,
    name: &str,
    step: impl FnOnce() -> Result<T>,
) -> Result<T> {
    let start = Instant::now();
    let value = step()?;
    timings.insert(name.to_owned(), start.elapsed().as_secs_f64());
    Ok(value)
}

/// What the experiment keeps of the main data set once its movies are dropped.
struct MainStances {
    origin: DatasetOrigin,
    /// Table I.
    table: VelocityTable,
    /// The mid-stance frame of every complete stance the segmentation finds.
    samples: Vec<Sample>,
    segmentation: SegmentationCheck,
    /// What the report needs from the data set (with `--report`).
    report_data: Option<SimulationReportData>,
}

/// The main data set (read back from DIR/dataset when it is the one this run would simulate), its
/// Table I and its stance samples; `started` is when the run began (the data set's time counts from it).
fn main_stances(
    sim_config: &SimConfig,
    spec: &DatasetSpec,
    args: &ReproduceOptions,
    progress: &dyn Progress,
    started: Instant,
    timings: &mut BTreeMap<String, f64>,
) -> Result<MainStances> {
    let (dataset, origin) = obtain_dataset(
        sim_config,
        spec,
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
    let table = dataset.velocity_table();
    let (samples, segmentation) = timed(timings, "segment", || stance_samples(&dataset.trials))?;
    // What the report needs from the data set; then the movies go (hundreds of MB; the heavier
    // hopper's data set would otherwise be held next to them).
    let report_data = if args.report {
        Some(SimulationReportData::from_dataset(&dataset)?)
    } else {
        None
    };
    drop(dataset);
    Ok(MainStances {
        origin,
        table,
        samples,
        segmentation,
        report_data,
    })
}

/// Sample images per gait (the sample's condition).
fn images_per_gait(samples: &[Sample]) -> BTreeMap<String, usize> {
    let mut images_per_gait = BTreeMap::new();
    for sample in samples {
        *images_per_gait
            .entry(sample.condition.clone().unwrap_or_default())
            .or_insert(0) += 1;
    }
    images_per_gait
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

/// Every feature family x classifier of the automatic choice with Table II's protocol and draws (the
/// classifiers that do not join it, such as ridge for the whole-stance features, are left out).
fn compare_methods(
    samples: &[LabeledImage<'_>],
    draw: Draw,
    args: &ReproduceOptions,
    progress: &dyn Progress,
) -> Result<Vec<ComparisonRow>> {
    let mut configs = Vec::new();
    for kinds in CANDIDATE_FEATURES {
        for kind in ClassifierKind::auto_candidates() {
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
) -> std::result::Result<(SimulatedDataset, DatasetOrigin), (Option<String>, Error)> {
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
