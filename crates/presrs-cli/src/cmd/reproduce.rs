//! `presrs reproduce`: the paper's experiment end to end on the built-in simulator (Tables I and II).

use std::collections::BTreeMap;
use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use presrs_core::evaluation::{EvalReport, EvalSample, MeanStd, Protocol, evaluate};
use presrs_core::pipeline::TrainConfig;
use presrs_core::split::ValidationSize;
use presrs_core::stance::{ValidSegmentParams, segment_recording};
use presrs_core::{Frame, Recording};
use presrs_io::atomic::write_atomic;
use presrs_sim::{DatasetSpec, SimConfig, TrialOutput, simulate_dataset};
use serde::Serialize;

use super::common::{progress_bar, spinner};

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
#[derive(Debug, clap::Args)]
#[command(after_help = "Example:\n  presrs reproduce --out results --seed 1")]
pub struct ReproduceArgs {
    /// Folder for results.json and results.md.
    #[arg(long, default_value = "results")]
    pub out: PathBuf,
    /// Seed of the simulation and of the training draws.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Repeats of each training draw.
    #[arg(long, default_value_t = 10)]
    pub repeats: usize,
    /// Recorded hops per terrain and gait (default: the simulator's paper-sized experiment).
    #[arg(long)]
    pub hops_per_gait: Option<usize>,
}

#[derive(Debug, Serialize)]
struct SegmentationCheck {
    /// Hops the simulator recorded (with a stance frame) and stances the segmentation found.
    true_hops: usize,
    found_stances: usize,
    /// True hops whose stance was found with its first and last frame within one frame.
    matched_within_one_frame: usize,
    /// Found mid-stance frames equal to the simulator's.
    same_mid_frame: usize,
}

#[derive(Debug, Serialize)]
struct Results {
    seed: u64,
    repeats: usize,
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
    /// Train gait -> tested gait -> accuracy (means over repeats).
    train_test_matrix: BTreeMap<String, BTreeMap<String, f64>>,
    images_per_gait: BTreeMap<String, usize>,
    segmentation: SegmentationCheck,
    /// Full reports of every training gait.
    evaluations: BTreeMap<String, EvalReport>,
    timings_s: BTreeMap<String, f64>,
}

pub fn run(args: &ReproduceArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let started = Instant::now();
    let mut timings = BTreeMap::new();
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create the output folder {}", args.out.display()))?;

    // 1. The data set.
    let mut spec = DatasetSpec::paper(args.seed);
    spec.hops_per_gait = args.hops_per_gait;
    let spin = spinner("simulating the hopper");
    let dataset =
        simulate_dataset(&SimConfig::default(), &spec).context("the simulation failed")?;
    spin.finish_and_clear();
    timings.insert("simulate".to_owned(), started.elapsed().as_secs_f64());

    // 2. Table I.
    let table = dataset.velocity_table();
    writeln!(out, "Table I (simulated vs paper)")?;
    writeln!(out, "{}", table.format_with_paper())?;
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
            per_class: Some(20),
            validation: ValidationSize::Count(7),
        };
        let report = evaluate(
            &eval_samples,
            &protocol,
            &config,
            args.repeats,
            args.seed,
            &|| bar.inc(1),
        )
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
        "\nTable II (trained on G2, 20 images per terrain; mean +- std over {} repeats)",
        args.repeats
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
    timings.insert("total".to_owned(), started.elapsed().as_secs_f64());

    // 5. Results files.
    let results = Results {
        seed: args.seed,
        repeats: args.repeats,
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
        train_test_matrix: matrix,
        images_per_gait,
        segmentation,
        evaluations,
        timings_s: timings,
    };
    let json_path = args.out.join("results.json");
    write_atomic(&json_path, |w| {
        serde_json::to_writer_pretty(&mut *w, &results).map_err(std::io::Error::from)?;
        writeln!(w)
    })?;
    let md_path = args.out.join("results.md");
    write_atomic(&md_path, |w| {
        write_markdown(&results, &table.format_with_paper(), w)
    })?;
    writeln!(
        out,
        "\nwrote {} and {} ({:.1} s in all)",
        json_path.display(),
        md_path.display(),
        started.elapsed().as_secs_f64()
    )?;
    Ok(())
}

/// One stance image of the simulated data set.
struct StanceSample {
    frame: Frame,
    terrain: String,
    gait: String,
}

/// Segments every trial, takes the mid-stance frame of each complete stance, and checks the stances
/// against the simulator's ground truth.
fn stance_samples(
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
    writeln!(w, "## Table II: classification accuracy, trained on G2\n")?;
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
    let s = &results.segmentation;
    writeln!(
        w,
        "\nSegmentation against the simulator's truth: {} of {} stances within one frame ({} found), {} \
         with the same mid-stance frame.",
        s.matched_within_one_frame, s.true_hops, s.found_stances, s.same_mid_frame
    )
}
