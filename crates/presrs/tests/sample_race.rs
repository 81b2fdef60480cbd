//! `--sample auto` (`presrs::train::sample_race`): one frame against the whole stance, chosen by validation.
//!
//! Movies whose classes differ only in how fast the foot loads (the same plateau, so the same
//! mid-stance frame) can only be told apart from the whole stance: the race must choose it, and say
//! that one frame validated near chance. A fixed method cannot race (no validation scores).

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;

use presrs::core::classifier::ClassifierKind;
use presrs::core::{Grid, Recording, SensorMeta};
use presrs::eval::race::{RaceReadings, evaluate_racing_samples, race_lines};
use presrs::eval::{EvalOptions, EvalSetup, Holdout};
use presrs::method::{ClassifierChoice, FeatureChoice};
use presrs::train::TrainOptions;
use presrs::train::sample_race::{WholeSample, train_racing_samples};
use presrs::{Method, Quiet, SampleKind, SampleOptions};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A 40-frame movie of 6 x 4: unloaded, a stance from frame 5 to 34 whose load rises over `rise`
/// frames to a plateau (the same for every class) and falls over 4, unloaded again; a little noise.
fn movie(rise: usize, rng: &mut ChaCha8Rng) -> Recording {
    let grid = Grid::new(6, 4);
    let mut data = Vec::new();
    for f in 0..40usize {
        let t = f as f64 - 5.0;
        let level = if !(0.0..30.0).contains(&t) {
            0.0
        } else if t < rise as f64 {
            (t + 1.0) / rise as f64
        } else if t >= 26.0 {
            (30.0 - t) / 4.0
        } else {
            1.0
        };
        data.extend((0..grid.len()).map(|i| {
            let shape = 1.0 + (i % 4) as f64;
            (100.0 * level * shape + rng.random_range(0.0..2.0)).max(0.0)
        }));
    }
    Recording::new(grid, Some(0.01), data, None, SensorMeta::default()).unwrap()
}

fn write_set(dir: &Path) -> std::path::PathBuf {
    write_set_with(dir, None)
}

/// The set, each movie in one of four groups (`g0`..`g3`, both classes in each); the movies of group
/// `other` (if given) with the classes' loading swapped, and another noise.
fn write_set_with(dir: &Path, other: Option<&str>) -> std::path::PathBuf {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut other_rng = ChaCha8Rng::seed_from_u64(99);
    let mut manifest = String::from("path,label,group\n");
    for (label, rise) in [("soft", 12), ("hard", 2)] {
        for i in 0..14 {
            let name = format!("{label}_{i:02}.npy");
            let group = format!("g{}", i % 4);
            // (the usual generator draws every movie, so the other groups' movies stay the same)
            let mut recording = movie(rise, &mut rng);
            if other == Some(group.as_str()) {
                recording = movie(14 - rise, &mut other_rng);
            }
            presrs::io::npy::write_recording_npy(&recording, &dir.join(&name)).unwrap();
            manifest.push_str(&format!("{name},{label},{group}\n"));
        }
    }
    let path = dir.join("manifest.csv");
    std::fs::write(&path, manifest).unwrap();
    path
}

fn options(method: Method) -> TrainOptions {
    TrainOptions {
        method,
        ..TrainOptions::default()
    }
}

/// The automatic choice of features with one fast classifier, and no time budget (the choice does
/// not depend on the machine's speed).
fn lda_auto() -> Method {
    Method {
        classifier: ClassifierChoice::Kind(ClassifierKind::LDA),
        features: FeatureChoice::Auto,
        budget: None,
        dims: Some(5),
        ..Method::default()
    }
}

#[test]
fn the_whole_stance_wins_when_only_the_loading_tells_the_classes_apart() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = write_set(dir.path());
    let raced = train_racing_samples(
        &manifest,
        &SampleOptions::default(),
        WholeSample::default(),
        &options(lda_auto()),
        &Quiet,
    )
    .unwrap();
    let race = &raced.race;
    assert_eq!(race.entries.len(), 2);
    assert_eq!(race.entries[0].kind, SampleKind::Frame);
    assert!(matches!(race.entries[1].kind, SampleKind::Stance { .. }));
    assert_eq!(race.entries[0].samples, 28);
    assert_eq!(race.entries[1].samples, 28);
    let (frame, _) = race.entries[0].outcome.clone().unwrap();
    let (stance, method) = race.entries[1].outcome.clone().unwrap();
    assert!(stance >= 0.9, "stance {stance} ({method})");
    assert!(frame < stance, "frame {frame}, stance {stance}");
    assert_eq!(race.chosen, 1);
    assert!(matches!(
        raced.training.model.sample(),
        SampleKind::Stance { .. }
    ));
    assert!(matches!(raced.dataset.sample, SampleKind::Stance { .. }));
    let lines = race.lines();
    assert!(lines[1].ends_with(", chosen"), "{lines:?}");
    assert!(
        lines[2].contains("stance sample validates best"),
        "{lines:?}"
    );
}

#[test]
fn a_fixed_method_cannot_race_and_says_why() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = write_set(dir.path());
    let err = train_racing_samples(
        &manifest,
        &SampleOptions::default(),
        WholeSample::default(),
        &options(Method::paper()),
        &Quiet,
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("--sample auto"), "{err}");
    assert!(err.contains("frame, stance or series"), "{err}");
}

fn eval_options(method: Method) -> EvalOptions {
    EvalOptions {
        holdout: Holdout::LeaveOneOut("group".to_owned()),
        per_class: None,
        repeats: 1,
        seed: 3,
        method,
        ..EvalOptions::default()
    }
}

fn readings(manifest: &Path, sample: SampleOptions) -> presrs::Result<RaceReadings> {
    RaceReadings::load(manifest, &sample, WholeSample::default(), &Quiet)
}

/// `eval --sample auto`: every fold races on its own training data; the whole stance wins each, and
/// the winners' test is exactly the evaluation of the stance reading alone (the same draws and seeds).
#[test]
fn eval_races_in_every_fold_and_tests_each_winner_in_its_own_sample() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = write_set_with(dir.path(), None);
    let readings = readings(&manifest, SampleOptions::default()).unwrap();
    assert_eq!(readings.frames.sample, SampleKind::Frame);
    assert!(matches!(readings.whole.sample, SampleKind::Stance { .. }));
    let options = eval_options(lda_auto());
    let raced = evaluate_racing_samples(&readings, &options, &Quiet).unwrap();
    let outcome = &raced.outcome;
    let races = &outcome.sample_races;
    assert_eq!(races.len(), 4);
    for (k, race) in races.iter().enumerate() {
        assert_eq!(race.held_out.as_deref(), Some(format!("g{k}").as_str()));
        let [frame, stance] = &race.race.entries[..] else {
            panic!("{race:?}")
        };
        assert_eq!(frame.kind, SampleKind::Frame);
        // the fold's training + validation units: the three other groups (g0 and g1 have 8 movies,
        // g2 and g3 6)
        assert_eq!(stance.samples, if k < 2 { 20 } else { 22 });
        assert_eq!(frame.samples, stance.samples);
        let (frame, stance) = (
            frame.outcome.clone().unwrap().0,
            stance.outcome.clone().unwrap().0,
        );
        assert!(stance > frame, "{}", race.line());
        assert!(matches!(race.race.chosen_kind(), SampleKind::Stance { .. }));
    }
    assert_eq!(outcome.selections.len(), 4);
    let alone = EvalSetup::new(&readings.whole, &options)
        .unwrap()
        .evaluate(&Quiet)
        .unwrap();
    assert_eq!(outcome.report.confusion, alone.report.confusion);
    assert_eq!(outcome.report.overall, alone.report.overall);
    assert!(
        outcome.report.overall.mean >= 0.9,
        "{:?}",
        outcome.report.overall
    );
    let lines = race_lines(races);
    assert!(lines[0].ends_with("folds won of 4: stance 4"), "{lines:?}");
    assert!(
        lines[1].starts_with("seed 3, g0 held out: frame ")
            && lines[1].contains("; the stance sample validates best inside the training data"),
        "{lines:?}"
    );
    let json = serde_json::to_value(presrs::eval::document::EvalJson::of(
        outcome,
        &raced.never_trained,
    ))
    .unwrap();
    let first = &json["sample_races"][0];
    assert_eq!(first["held_out"], "g0");
    assert_eq!(first["chosen"], "stance");
    assert_eq!(first["entries"][0]["sample"], "frame");
    assert!(first["entries"][1]["validation_accuracy"].as_f64().unwrap() > 0.5);
}

/// A fold's race reads its training data only: swapping the held-out group's loading between the
/// classes changes nothing in that fold's race (it changes the folds that train on them).
#[test]
fn the_held_out_units_never_inform_a_folds_race() {
    let (one, two) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let plain = write_set_with(one.path(), None);
    let changed = write_set_with(two.path(), Some("g2"));
    let options = eval_options(lda_auto());
    let races = |manifest: &Path| {
        let readings = readings(manifest, SampleOptions::default()).unwrap();
        evaluate_racing_samples(&readings, &options, &Quiet)
            .unwrap()
            .outcome
            .sample_races
    };
    let (plain, changed) = (races(&plain), races(&changed));
    let scores = |race: &presrs::train::sample_race::FoldRace| {
        race.race
            .entries
            .iter()
            .map(|e| e.outcome.clone())
            .collect::<Vec<_>>()
    };
    assert_eq!(plain[2].held_out.as_deref(), Some("g2"));
    assert_eq!(scores(&plain[2]), scores(&changed[2]));
    assert!(
        (0..4).any(|k| k != 2 && scores(&plain[k]) != scores(&changed[k])),
        "the other folds train on g2's movies"
    );
}

/// Both readings must be the same units: every frame of each stance against one whole stance is
/// refused, naming the counts; a fixed method has no validation score to race on.
#[test]
fn readings_of_other_units_and_fixed_methods_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = write_set_with(dir.path(), None);
    let every_frame = SampleOptions {
        sample: presrs::core::stance::SampleFrame::All,
        ..SampleOptions::default()
    };
    let err = readings(&manifest, every_frame).unwrap_err().to_string();
    assert!(err.contains("cannot race the sample kinds"), "{err}");
    assert!(err.contains("as its stance sample 28"), "{err}");
    let readings = readings(&manifest, SampleOptions::default()).unwrap();
    let err = evaluate_racing_samples(&readings, &eval_options(Method::paper()), &Quiet)
        .unwrap_err()
        .to_string();
    assert!(err.contains("--sample auto"), "{err}");
}

/// `report --sample auto`: the report's evaluation is the race in every fold, and its notes say each
/// fold's race; a given model (one kind) is refused.
#[test]
fn the_report_races_in_every_fold_and_says_so() {
    use presrs::report::{ReportOptions, report_racing_samples};
    let dir = tempfile::tempdir().unwrap();
    let manifest = write_set_with(dir.path(), None);
    let readings = readings(&manifest, SampleOptions::default()).unwrap();
    let options = ReportOptions {
        leave_one_out: Some("group".to_owned()),
        per_class: 10,
        validation: presrs::core::split::ValidationSize::Fraction(0.35),
        repeats: 1,
        fault_repeats: 0,
        method: lda_auto(),
        ..ReportOptions::default()
    };
    let out = dir.path().join("report");
    let summary = report_racing_samples(&readings, &options, &out, &Quiet).unwrap();
    let (name, report) = summary.evaluation.unwrap();
    assert_eq!(name, "leave one group out");
    assert!(report.overall.mean >= 0.8, "{:?}", report.overall);
    let html = std::fs::read_to_string(&summary.index).unwrap();
    assert!(
        html.contains("The sample kinds raced: sample race"),
        "{html:.2000}"
    );
    assert!(html.contains("g3 held out: frame "), "{html:.2000}");
    let with_model = ReportOptions {
        model: Some(dir.path().join("model.json")),
        ..options
    };
    let err = report_racing_samples(&readings, &with_model, &dir.path().join("r2"), &Quiet)
        .unwrap_err()
        .to_string();
    assert!(err.contains("--sample auto"), "{err}");
}
