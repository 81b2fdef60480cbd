//! `presrs reproduce`: the paper's experiment end to end on the built-in simulator (Tables I and II).
//!
//! The data set lives in `DIR/dataset/` (the layout `presrs simulate --out` writes, see
//! [`super::simulate`]), the heavier hopper's of the load-independence test in `DIR/dataset-load1.30/`
//! (the factor is 1 + `--extra-load`). A folder whose `stamp.json` says it was made with the same
//! presrs version, seed, hops per gait, load and simulator configuration, whose files all match the
//! stamp, and whose first trial this build's simulator still makes (it is simulated again: about 2 % of
//! the simulation time; a development build whose simulator changed without a version change is caught
//! there) is read back instead of simulated; otherwise the reason is printed and the data set is
//! simulated afresh and written there (the stamp last, so an interrupted run never leaves a stamp claiming
//! a complete data set). `--resimulate` always simulates. Both sources give the same trials (the movies
//! hold integer counts, the truth round-trips through JSON exactly), hence the same results.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use presrs_core::classifier::ClassifierKind;
use presrs_core::evaluation::{
    ComparisonRow, EvalReport, EvalSample, Evaluation, MeanStd, Models, Protocol,
};
use presrs_core::features::FeatureConfig;
use presrs_core::pipeline::TrainConfig;
use presrs_core::pipeline::{CheckedTrainConfig, LabeledImage, train};
use presrs_core::split::{ValidationSize, stratified_split};
use presrs_core::stance::{ValidSegmentParams, segment_recording};
use presrs_core::{Frame, Recording};
use presrs_io::atomic::write_atomic;
use presrs_sim::{Dataset, DatasetSpec, SimConfig, TrialOutput};
use serde::Serialize;

use presrs::method::CANDIDATE_FEATURES;

use super::common::{progress_bar, spinner};
use super::eval::{CalibrationJson, calibration_line};
use super::report::SimulationReportData;
use super::simulate::{DatasetKey, check_simulator, read_dataset, write_dataset_with};

/// The paper's Table II: accuracy per tested gait when trained on G2.
const PAPER_TABLE2: [(&str, f64); 4] = [
    ("G1", 0.993),
    ("G2", 0.991),
    ("G3", 0.986),
    ("overall", 0.990),
];
/// The paper's classification time on a 2.67 GHz Core 2 Duo, ns.
const PAPER_CLASSIFY_NS: u64 = 245_000;

/// Reproduce the paper: simulate the hopper on wood, carpet, clay and grass at gaits G1-G3, print
/// Table I (forward velocities), train on G2 (20 images per terrain: 13 + 7) and test on all other images
/// (Table II), repeated with new draws; also train on G1 and G3.
///
/// The simulated data set is written to DIR/dataset (TekScan movies, manifest.csv, truth, config.json and
/// stamp.json, as `presrs simulate --out` writes them), the heavier hopper's to DIR/dataset-load1.30. A
/// later run with the same seed, hops per gait and presrs version reads them back instead of simulating
/// (the results are the same), and says so; on any mismatch or missing or changed file it says why and
/// simulates afresh. `presrs simulate --out DIR/dataset --seed S` makes a data set this reuses.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Data sets: the simulated data set is kept in DIR/dataset (the layout of \
`presrs simulate --out`: recordings/*.asf TekScan movies, manifest.csv, truth/, config.json, and \
stamp.json, written last), the heavier hopper's of the load test in DIR/dataset-load1.30. A later run \
with the same seed, hops per gait and presrs version reads them back instead of simulating (the results \
are the same) and says so; on any mismatch, a missing or changed file, or a simulator that no longer \
makes its first trial, it says why and simulates afresh.

Examples:
  presrs reproduce --out results --seed 1
  presrs reproduce --out results --seed 1 --resimulate
  presrs simulate --out results/dataset --seed 1   # presrs reproduce --out results reuses it
  presrs reproduce --out small --hops-per-gait 10 --per-class 8 --validation 3 --repeats 3"
)]
pub struct ReproduceArgs {
    /// Folder for results.json, results.md, the report and the simulated data sets (dataset/,
    /// dataset-load1.30/).
    #[arg(long, default_value = "results")]
    pub out: PathBuf,
    /// Seed of the simulation and of the training draws.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Repeats of each training draw, at least 1.
    #[arg(long, default_value_t = 10, value_parser = super::usage::positive_count)]
    pub repeats: usize,
    /// Training images drawn per terrain (the paper's 20), of which --validation choose the Parzen
    /// window's sigma; smaller values allow a small --hops-per-gait (at least this many per gait).
    #[arg(long, default_value_t = 20)]
    pub per_class: usize,
    /// Of the --per-class images, how many validate (the paper's 7).
    #[arg(long, default_value_t = 7)]
    pub validation: usize,
    /// Recorded hops per terrain and gait, at least --per-class (default: the simulator's paper-sized
    /// experiment, 80).
    #[arg(long, value_parser = super::usage::positive_count)]
    pub hops_per_gait: Option<usize>,
    /// Skip the HTML report (DIR/report/index.html).
    #[arg(long)]
    pub no_report: bool,
    /// Extra load of the load-independence test, as a fraction of the nominal body mass: the heavier
    /// hopper weighs nominal x (1 + EXTRA_LOAD), so it must be above -1 (a negative value tests a
    /// lighter hopper).
    #[arg(long, default_value_t = 0.3, allow_negative_numbers = true, value_parser = parse_extra_load)]
    pub extra_load: f64,
    /// Skip the comparison of every feature family x classifier (same draws as Table II).
    #[arg(long)]
    pub no_comparison: bool,
    /// Simulate the data sets afresh (and rewrite them) even when DIR holds matching ones.
    #[arg(long)]
    pub resimulate: bool,
}

/// Where a data set came from.
#[derive(Debug, Clone, Serialize)]
struct DatasetOrigin {
    path: PathBuf,
    /// Read back from `path` (its stamp matched) rather than simulated.
    reused: bool,
    /// Why it was simulated (no data set there, a mismatch, a changed file, `--resimulate`).
    #[serde(skip_serializing_if = "Option::is_none")]
    simulated_because: Option<String>,
}

/// Load independence: a model trained at the nominal load tested on images recorded at a higher load,
/// as they are and scaled by nominal / actual load (the paper's "scaling factor").
#[derive(Debug, Serialize)]
struct LoadCheck {
    nominal_load_kg: f64,
    test_load_kg: f64,
    test_images: usize,
    /// Accuracy on the heavier robot's images as recorded.
    accuracy_unscaled: MeanStd,
    /// Accuracy after multiplying every test image by nominal / test load.
    accuracy_scaled: MeanStd,
    /// Accuracy of a model trained with `--normalise-load` (each image divided by its total load) on the
    /// heavier robot's images as recorded: no knowledge of the load.
    accuracy_normalised: MeanStd,
}

/// One feature x classifier combination of the comparison (trained on G2, 20 per terrain, 7 validating).
#[derive(Debug, Serialize)]
struct ComparisonSummary {
    features: String,
    classifier: String,
    /// Over every tested image (mean and spread over repeats); `None` when it could not be trained.
    overall: Option<MeanStd>,
    per_gait: BTreeMap<String, MeanStd>,
    /// Training time of one model, ms.
    train_ms: MeanStd,
    median_classify_ns: u64,
    error: Option<String>,
}

impl ComparisonSummary {
    fn of(row: &ComparisonRow) -> Self {
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
    true_hops: usize,
    found_stances: usize,
    /// True hops whose stance was found with its first and last frame within one frame.
    matched_within_one_frame: usize,
    /// Found mid-stance frames equal to the simulator's.
    same_mid_frame: usize,
}

/// The training draw: images per terrain, and how many of them validate.
#[derive(Debug, Clone, Copy, Serialize)]
struct Draw {
    per_class: usize,
    validation: usize,
}

#[derive(Debug, Serialize)]
struct Results {
    seed: u64,
    repeats: usize,
    /// Training images per terrain and how many of them validate (the paper's 20 and 7).
    draw: Draw,
    presrs_version: &'static str,
    /// Forward velocity per gait and terrain, m/s.
    table1: BTreeMap<String, BTreeMap<String, f64>>,
    table1_paper: BTreeMap<String, BTreeMap<String, f64>>,
    /// Accuracy per tested gait and overall, trained on G2 (means over repeats).
    table2: BTreeMap<String, f64>,
    table2_std: BTreeMap<String, f64>,
    table2_paper: BTreeMap<String, f64>,
    median_classify_ns: u64,
    paper_classify_ns: u64,
    /// Table II's confidences against whether they were right, as `eval --json` gives them.
    table2_calibration: CalibrationJson,
    /// Train gait -> tested gait -> accuracy (means over repeats).
    train_test_matrix: BTreeMap<String, BTreeMap<String, f64>>,
    images_per_gait: BTreeMap<String, usize>,
    segmentation: SegmentationCheck,
    /// Where the data sets came from: `main` and (when measured) `load`.
    datasets: BTreeMap<String, DatasetOrigin>,
    /// `None` when the heavier hopper could not be simulated (the reason is printed).
    load_independence: Option<LoadCheck>,
    /// Every feature family x classifier with Table II's protocol and draws (empty with --no-comparison).
    comparison: Vec<ComparisonSummary>,
    /// Full reports of every training gait.
    evaluations: BTreeMap<String, EvalReport>,
    timings_s: BTreeMap<String, f64>,
}

/// `--extra-load`: a finite fraction above -1 (the heavier hopper's mass stays positive).
fn parse_extra_load(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x > -1.0 => Ok(x),
        _ => Err(format!(
            "expected a fraction of the nominal body mass above -1 (the test hopper weighs nominal x \
             (1 + EXTRA_LOAD)), got {text:?}"
        )),
    }
}

/// The options that must agree with each other, checked before anything is simulated: some of the
/// --per-class images train, and every gait records at least --per-class images per terrain.
fn check_args(args: &ReproduceArgs, config: &SimConfig) -> Result<(), String> {
    if args.validation >= args.per_class {
        return Err(format!(
            "--validation {} must be smaller than --per-class {}: some images must train; give \
             --validation {} or less, or a larger --per-class",
            args.validation,
            args.per_class,
            args.per_class.saturating_sub(1)
        ));
    }
    let hops = args
        .hops_per_gait
        .unwrap_or(config.experiment.hops_per_gait);
    if hops < args.per_class {
        return Err(format!(
            "--hops-per-gait {hops} records {hops} images per terrain and gait, fewer than the \
             --per-class {} training images drawn per terrain from the training gait; give \
             --hops-per-gait {} or more, or a --per-class of at most {hops} with a smaller --validation \
             (now {})",
            args.per_class, args.per_class, args.validation
        ));
    }
    Ok(())
}

pub fn run(args: &ReproduceArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let started = Instant::now();
    let mut timings = BTreeMap::new();
    let sim_config = SimConfig::default();
    if let Err(message) = check_args(args, &sim_config) {
        super::usage::exit_usage("reproduce", message);
    }
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
        out,
    )?;
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
    writeln!(out, "Table I (simulated vs paper)")?;
    writeln!(out, "{}", table.format_with_paper())?;
    out.flush()?;
    let mut table1 = BTreeMap::new();
    let mut table1_paper = BTreeMap::new();
    for (g, gait) in table.gaits.iter().enumerate() {
        for (t, terrain) in table.terrains.iter().enumerate() {
            table1
                .entry(gait.clone())
                .or_insert_with(BTreeMap::new)
                .insert(terrain.clone(), table.velocity_m_per_s[g][t]);
            if let Some(paper) = presrs_sim::VelocityTable::paper_value(gait, terrain) {
                table1_paper
                    .entry(gait.clone())
                    .or_insert_with(BTreeMap::new)
                    .insert(terrain.clone(), paper);
            }
        }
    }

    // 3. Samples: the mid-stance frame of every complete stance the segmentation finds.
    let segment_start = Instant::now();
    let (samples, segmentation) = stance_samples(&dataset.trials)?;
    timings.insert("segment".to_owned(), segment_start.elapsed().as_secs_f64());
    // What the report needs from the data set, then the movies go (hundreds of MB; the heavier hopper's
    // data set below would otherwise be held next to them).
    let report_data = if args.no_report {
        None
    } else {
        Some(SimulationReportData::from_dataset(&dataset)?)
    };
    drop(dataset);
    let mut images_per_gait = BTreeMap::new();
    for sample in &samples {
        *images_per_gait.entry(sample.gait.clone()).or_insert(0) += 1;
    }
    writeln!(
        out,
        "{} stance images ({}); segmentation found {} of {} simulated stances within one frame, {} with the \
         same mid-stance frame",
        samples.len(),
        images_per_gait
            .iter()
            .map(|(g, n)| format!("{g}: {n}"))
            .collect::<Vec<_>>()
            .join(", "),
        segmentation.matched_within_one_frame,
        segmentation.true_hops,
        segmentation.same_mid_frame
    )?;

    // 4. Table II and the train-gait x test-gait matrix.
    let eval_samples: Vec<EvalSample<'_>> = samples
        .iter()
        .map(|s| EvalSample {
            frame: s.frame.view(),
            label: &s.terrain,
            condition: Some(&s.gait),
            group: None,
        })
        .collect();
    let config = TrainConfig::default().check()?;
    let gaits: Vec<String> = images_per_gait.keys().cloned().collect();
    let bar = progress_bar((gaits.len() * args.repeats) as u64, "training");
    let eval_start = Instant::now();
    let mut evaluations = BTreeMap::new();
    for gait in &gaits {
        let protocol = Protocol::TrainCondition {
            condition: Some(gait.clone()),
            per_class: Some(draw.per_class),
            validation: ValidationSize::Count(draw.validation),
        };
        let report = Evaluation {
            samples: &eval_samples,
            protocol: &protocol,
            repeats: args.repeats,
            seed: args.seed,
            progress: &|| bar.inc(1),
        }
        .run(Models::Config(&config))
        .with_context(|| format!("evaluation trained on {gait} failed"))?;
        evaluations.insert(gait.clone(), report);
    }
    bar.finish_and_clear();
    timings.insert("evaluate".to_owned(), eval_start.elapsed().as_secs_f64());
    let main = evaluations
        .get("G2")
        .context("the simulated data set has no gait G2 to train on")?;
    let mut table2: BTreeMap<String, MeanStd> = main.per_condition.clone();
    table2.insert("overall".to_owned(), main.overall);
    writeln!(
        out,
        "\nTable II (trained on G2, {} images per terrain; mean +- std over {} repeats)",
        draw.per_class, args.repeats
    )?;
    writeln!(out, "{:<10} {:>18} {:>8}", "tested", "simulated", "paper")?;
    for (name, paper) in PAPER_TABLE2 {
        if let Some(m) = table2.get(name) {
            writeln!(
                out,
                "{:<10} {:>9.1} % +- {:<4.1} {:>6.1} %",
                name,
                100.0 * m.mean,
                100.0 * m.std,
                100.0 * paper
            )?;
        }
    }
    writeln!(
        out,
        "median classification time {:.2} us per image (paper: {:.0} us on a 2.67 GHz Core 2 Duo)",
        main.median_classify_ns as f64 / 1e3,
        PAPER_CLASSIFY_NS as f64 / 1e3
    )?;
    if let Some(line) = calibration_line(&main.reliability) {
        writeln!(out, "{line}")?;
    }
    let mut matrix = BTreeMap::new();
    writeln!(out, "\nTrain gait x test gait accuracy (%)")?;
    write!(out, "{:<8}", "train")?;
    for gait in &gaits {
        write!(out, " {gait:>7}")?;
    }
    writeln!(out, " {:>8}", "overall")?;
    for (train_gait, report) in &evaluations {
        write!(out, "{train_gait:<8}")?;
        let mut row = BTreeMap::new();
        for gait in &gaits {
            let value = report.per_condition.get(gait).map_or(f64::NAN, |m| m.mean);
            write!(out, " {:>7.1}", 100.0 * value)?;
            row.insert(gait.clone(), value);
        }
        writeln!(out, " {:>8.1}", 100.0 * report.overall.mean)?;
        row.insert("overall".to_owned(), report.overall.mean);
        matrix.insert(train_gait.clone(), row);
    }

    // 5. Load independence.
    let load_start = Instant::now();
    let nominal_kg = sim_config.robot.body_mass_kg;
    let mut heavy_spec = spec.clone();
    heavy_spec.load_kg = Some(nominal_kg * (1.0 + args.extra_load));
    heavy_spec.seed = args.seed.wrapping_add(1_000_003);
    let heavy_dir = args
        .out
        .join(format!("dataset-load{:.2}", 1.0 + args.extra_load));
    let heavy = obtain_dataset(&sim_config, &heavy_spec, &heavy_dir, args.resimulate, out)
        .and_then(|(heavy, origin)| {
            datasets.insert("load".to_owned(), origin);
            Ok(stance_samples(&heavy.trials)?.0)
        });
    let load_check = match heavy {
        Ok(heavy_samples) => {
            let training_pool: Vec<&StanceSample> =
                samples.iter().filter(|s| s.gait == "G2").collect();
            Some(load_independence(
                &training_pool,
                &heavy_samples,
                (nominal_kg, nominal_kg * (1.0 + args.extra_load)),
                &config,
                draw,
                args.repeats,
                args.seed,
            )?)
        }
        Err(err) => {
            // The main tables stand on their own; say why this part is missing instead of failing all.
            writeln!(out, "\nLoad independence: not measured: {err:#}")?;
            None
        }
    };
    timings.insert(
        "load_independence".to_owned(),
        load_start.elapsed().as_secs_f64(),
    );
    if let Some(load_check) = &load_check {
        writeln!(
            out,
            "\nLoad independence (trained on G2 at {:.2} kg, tested on all gaits at {:.2} kg, {} images)",
            load_check.nominal_load_kg, load_check.test_load_kg, load_check.test_images
        )?;
        writeln!(
            out,
            "  as recorded        {:5.1} % +- {:.1}\n  scaled by load     {:5.1} % +- {:.1}  (the paper: \
             the load is known)\n  normalised         {:5.1} % +- {:.1}  (--normalise-load: trained and \
             tested on images divided by their total, the load unknown)",
            100.0 * load_check.accuracy_unscaled.mean,
            100.0 * load_check.accuracy_unscaled.std,
            100.0 * load_check.accuracy_scaled.mean,
            100.0 * load_check.accuracy_scaled.std,
            100.0 * load_check.accuracy_normalised.mean,
            100.0 * load_check.accuracy_normalised.std
        )?;
    }
    out.flush()?;

    // 6. Other methods: every feature family x classifier with Table II's protocol and draws.
    let mut comparison = Vec::new();
    if !args.no_comparison {
        let compare_start = Instant::now();
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
        let bar = progress_bar((configs.len() * args.repeats) as u64, "comparing");
        let rows = Evaluation {
            samples: &eval_samples,
            protocol: &protocol,
            repeats: args.repeats,
            seed: args.seed,
            progress: &|| bar.inc(1),
        }
        .compare(&configs)
        .context("the comparison of the other methods failed")?;
        bar.finish_and_clear();
        timings.insert(
            "comparison".to_owned(),
            compare_start.elapsed().as_secs_f64(),
        );
        writeln!(
            out,
            "\nOther methods (trained on G2, {} images per terrain, the same draws as Table II; the paper's \
             is fft1d + pwe)",
            draw.per_class
        )?;
        super::eval::print_comparison(&rows, out)?;
        comparison = rows.iter().map(ComparisonSummary::of).collect();
    }
    timings.insert("total".to_owned(), started.elapsed().as_secs_f64());

    // 5. Results files.
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
        comparison,
        evaluations,
        timings_s: timings,
    };
    let json_path = args.out.join("results.json");
    write_atomic(&json_path, |w| {
        serde_json::to_writer_pretty(&mut *w, &results).map_err(std::io::Error::from)?;
        writeln!(w)
    })?;
    let report_path = if let Some(report_data) = &report_data {
        let spin = spinner("writing the report");
        let path = super::report::write_simulation_report(
            report_data,
            &sim_config,
            &results.evaluations,
            args.seed,
            &args.out.join("report"),
        )?;
        spin.finish_and_clear();
        Some(path)
    } else {
        None
    };
    let md_path = args.out.join("results.md");
    write_atomic(&md_path, |w| {
        write_markdown(&results, &table.format_with_paper(), w)
    })?;
    writeln!(
        out,
        "\nwrote {} and {}{} ({:.1} s in all)",
        json_path.display(),
        md_path.display(),
        report_path.map_or_else(String::new, |p| format!(" and the report {}", p.display())),
        started.elapsed().as_secs_f64()
    )?;
    Ok(())
}

/// The data set `config` and `spec` describe: read back from `dir` when its stamp matches (and every
/// file is intact), else simulated and written to `dir`. Says which on `out`, and why it simulated.
fn obtain_dataset(
    config: &SimConfig,
    spec: &DatasetSpec,
    dir: &Path,
    resimulate: bool,
    out: &mut dyn Write,
) -> anyhow::Result<(Dataset, DatasetOrigin)> {
    let wanted = DatasetKey::new(config, spec);
    let reason = if resimulate {
        "--resimulate".to_owned()
    } else {
        let spin = spinner(&format!("reading {}", dir.display()));
        let read = read_dataset(dir, &wanted).and_then(|(dataset, stamp)| {
            check_simulator(config, spec, &dataset)?;
            Ok((dataset, stamp))
        });
        spin.finish_and_clear();
        match read {
            Ok((dataset, _)) => {
                writeln!(
                    out,
                    "reusing {} (seed {}, presrs {})",
                    dir.display(),
                    wanted.seed,
                    wanted.presrs_version
                )?;
                out.flush()?;
                let origin = DatasetOrigin {
                    path: dir.to_path_buf(),
                    reused: true,
                    simulated_because: None,
                };
                return Ok((dataset, origin));
            }
            Err(err) => format!("{err:#}"),
        }
    };
    writeln!(
        out,
        "simulating {} (seed {}, {} kg): {reason}",
        dir.display(),
        wanted.seed,
        wanted.load_kg
    )?;
    out.flush()?;
    let bar = progress_bar(0, "simulating");
    let progress = |done: usize, total: usize| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    };
    let (_, dataset) =
        write_dataset_with(config, spec, dir, true, &progress).with_context(|| {
            format!(
                "cannot simulate and write the data set {} (seed {}, {} kg)",
                dir.display(),
                wanted.seed,
                wanted.load_kg
            )
        })?;
    bar.finish_and_clear();
    let dataset = dataset.context("the simulated trials were not kept")?;
    let origin = DatasetOrigin {
        path: dir.to_path_buf(),
        reused: false,
        simulated_because: Some(reason),
    };
    Ok((dataset, origin))
}

/// Trains on `pool` (`draw`; the paper's: 20 per terrain, 7 of them for validation) once per repeat and tests
/// on `heavy`, as recorded and scaled by `nominal_kg / heavy_kg`.
fn load_independence(
    pool: &[&StanceSample],
    heavy: &[StanceSample],
    (nominal_kg, heavy_kg): (f64, f64),
    config: &CheckedTrainConfig,
    draw: Draw,
    repeats: usize,
    seed: u64,
) -> anyhow::Result<LoadCheck> {
    let factor = nominal_kg / heavy_kg;
    let scaled: Vec<Frame> = heavy
        .iter()
        .map(|s| {
            let mut frame = s.frame.clone();
            frame.values_mut().iter_mut().for_each(|v| *v *= factor);
            frame
        })
        .collect();
    let labels: Vec<&str> = pool.iter().map(|s| s.terrain.as_str()).collect();
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
        let images = |indices: &[usize]| -> Vec<LabeledImage<'_>> {
            indices
                .iter()
                .map(|&i| LabeledImage::new(pool[i].frame.view(), labels[i]))
                .collect()
        };
        let (train_images, validation_images) = (images(&split.train), images(&split.validation));
        let model = train(&train_images, &validation_images, config)?;
        let normalised = train(&train_images, &validation_images, &normalised_config)?;
        let mut session = model.session();
        let mut normalised_session = normalised.session();
        let (mut right_raw, mut right_scaled, mut right_normalised) = (0usize, 0usize, 0usize);
        for (sample, scaled_frame) in heavy.iter().zip(&scaled) {
            if session.classify(&sample.frame.view())?.label == sample.terrain {
                right_raw += 1;
            }
            if session.classify(&scaled_frame.view())?.label == sample.terrain {
                right_scaled += 1;
            }
            if normalised_session.classify(&sample.frame.view())?.label == sample.terrain {
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

/// One stance image of the simulated data set.
pub struct StanceSample {
    pub frame: Frame,
    pub terrain: String,
    pub gait: String,
}

/// Segments every trial, takes the mid-stance frame of each complete stance, and checks the stances
/// against the simulator's ground truth.
pub fn stance_samples(
    trials: &[TrialOutput],
) -> anyhow::Result<(Vec<StanceSample>, SegmentationCheck)> {
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
                samples.push(StanceSample {
                    frame: frame.to_frame(),
                    terrain: trial.plan.terrain.clone(),
                    gait: trial.plan.gait.name.clone(),
                });
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
