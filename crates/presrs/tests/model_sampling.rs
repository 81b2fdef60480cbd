//! A model remembers how its samples were taken (issue #45) and the sensor they came from (issue #43):
//! trained on one-contact trials (`real/jiku-walk`, read in place from the shared data folder), it
//! classifies such a trial whole without being told, its online profile finds the steps of a walk,
//! and a movie of another sensor, a data set of mixed sensors and a movie given to a series model are
//! clear errors.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};

use presrs::classify::{ClassifyOptions, classify_file};
use presrs::core::classifier::ClassifierKind;
use presrs::core::features::FeatureKind;
use presrs::core::online::{OnlineClassifier, OnlineEvent};
use presrs::core::pipeline::TrainedModel;
use presrs::core::sample::SampleKind;
use presrs::core::stance::BaselineMode;
use presrs::core::stance::summary::SummaryConfig;
use presrs::core::{FrameView, Grid};
use presrs::io::npy::write_npy_f64;
use presrs::train::profile::{
    GaitTableSim, ProfileChoice, ProfileRequest, TrainRequest, train_model_file,
};
use presrs::train::sample_race::WholeSample;
use presrs::train::{TrainOptions, train};
use presrs::{ClassifierChoice, Dataset, FeatureChoice, Method, Quiet, SampleOptions};

fn shared(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data")
        .join(path)
}

fn stance_options() -> SampleOptions {
    SampleOptions {
        one_sample_per_file: true,
        kind: SampleKind::Stance {
            summary: SummaryConfig::default(),
            length: None,
        },
        ..SampleOptions::default()
    }
}

fn rocket_ridge() -> Method {
    Method {
        features: FeatureChoice::Kinds(vec![FeatureKind::ROCKET]),
        classifier: ClassifierChoice::Kind(ClassifierKind::RIDGE),
        ..Method::default()
    }
}

/// A manifest of the first subject's trials of `real/jiku-walk` (absolute paths), plus `extra` rows.
fn jiku_manifest(dir: &Path, extra: &str) -> PathBuf {
    let jiku = shared("real/jiku-walk");
    let text = std::fs::read_to_string(jiku.join("manifest.csv")).unwrap();
    let mut rows = String::from("path,label,group\n");
    for line in text.lines().skip(1).filter(|line| line.starts_with("s00_")) {
        let fields: Vec<&str> = line.split(',').collect();
        let path = jiku.join(fields[0]);
        rows.push_str(&format!("{},{},{}\n", path.display(), fields[1], fields[3]));
    }
    rows.push_str(extra);
    let manifest = dir.join("manifest.csv");
    std::fs::write(&manifest, rows).unwrap();
    manifest
}

/// `presrs train --sample stance --one-sample-per-file` as the command line asks it: the model file.
fn train_one_contact(manifest: &Path) -> presrs::train::profile::TrainedFile {
    let request = TrainRequest {
        manifest,
        sample: presrs::dataset::SampleChoice::Kind(stance_options().kind),
        samples: stance_options(),
        whole: WholeSample::default(),
        train: TrainOptions {
            method: rocket_ridge(),
            ..TrainOptions::default()
        },
        profile: ProfileRequest {
            choice: ProfileChoice::WhenMovies,
            gait_table: None,
            sim: GaitTableSim {
                config: None,
                seed: 1,
                sweep: presrs::sim::gait::GaitSweep(None),
            },
        },
        command: None,
        decide_at: presrs::train::early::DecisionPoints::Whole,
    };
    train_model_file(&request, &Quiet, &mut |_, _| {}).unwrap()
}

/// A movie of `frames` frames of `grid`: a load rising and falling.
fn write_movie(path: &Path, frames: usize, grid: Grid) {
    let mut values = Vec::with_capacity(frames * grid.len());
    for t in 0..frames {
        let envelope = 1.0 + ((t as f64 + 0.5) / frames as f64 * std::f64::consts::PI).sin();
        values.extend((0..grid.len()).map(|k| envelope * (5.0 + (k % 7) as f64)));
    }
    let file = std::fs::File::create(path).unwrap();
    write_npy_f64(file, &[frames, grid.rows, grid.cols], &values).unwrap();
}

/// Trained on one-contact trials, the model says how its samples were taken and from which sensor;
/// `classify` takes a trial it was trained on whole without being told (it found "no complete stance
/// phase" before); the online profile written by default finds each step of a walk made of six
/// trials; a movie of another sensor is refused offline and online; an older file without these
/// fields loads and takes any sensor as before.
#[test]
fn a_one_contact_model_classifies_its_trials_streams_a_walk_and_refuses_another_sensor() {
    let dir = tempfile::tempdir().unwrap();
    let trained = train_one_contact(&jiku_manifest(dir.path(), ""));
    let model = &trained.file.model;
    assert_eq!(model.sensor(), Some(Grid::new(63, 33)));
    let sampling = model
        .sampling()
        .expect("the model says how its samples were taken");
    assert!(sampling.one_sample_per_file);

    // classify, with no option given: the trial is one sample, as in training.
    let trial = shared("real/jiku-walk/s00_t00.npy");
    let mut session = model.session();
    let options = ClassifyOptions::default();
    let result = classify_file(
        model,
        &mut session,
        &trial,
        &options,
        &mut Default::default(),
    )
    .unwrap();
    assert_eq!(result.frames.len(), 1, "{:?}", result.warnings);
    assert!(result.warnings.is_empty(), "{:?}", result.warnings);

    // The profile written by default streams steps: a drifting baseline, calibrated on the contacts.
    let profile = trained.file.online.as_ref().expect("a profile by default");
    assert_eq!(profile.segment.params().baseline, BaselineMode::Drifting);
    let calibration = profile.calibration.expect("calibrated on the trials");
    assert!(calibration.load_range > 1000.0, "{calibration:?}");
    assert!(profile.typical_stance_frames.is_some());
    let trials: Vec<_> = (0..6)
        .map(|k| {
            let path = shared(&format!("real/jiku-walk/s00_t{k:02}.npy"));
            presrs::io::read_recording(&path).unwrap()
        })
        .collect();
    let grid = trials[0].grid();
    let swing = vec![0.0; grid.len()];
    let mut walk: Vec<Vec<f64>> = Vec::new();
    for trial in &trials {
        walk.extend((0..12).map(|_| swing.clone()));
        walk.extend(trial.frames().map(|frame| frame.values().to_vec()));
    }
    walk.extend((0..12).map(|_| swing.clone()));
    let mut online = OnlineClassifier::new(
        model,
        &profile.segment,
        &profile.params,
        profile.calibration,
    )
    .unwrap();
    let mut decisions = 0;
    for values in &walk {
        let step = online
            .push(&FrameView::new(grid, values, None).unwrap())
            .unwrap();
        decisions += step
            .events
            .iter()
            .filter(|event| matches!(event, OnlineEvent::Decision(_)))
            .count();
    }
    assert_eq!(online.stats().stances, 6, "{:?}", online.stats());
    assert_eq!(decisions, 6);

    // Another sensor: a clear error offline and online.
    let small = dir.path().join("small.npy");
    write_movie(&small, 60, Grid::new(40, 30));
    let err = classify_file(
        model,
        &mut session,
        &small,
        &options,
        &mut Default::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("small.npy")
            && err.contains("expected 63x33 frames, the sensor this whole-stance model was trained on, got 40x30"),
        "{err}"
    );
    let mut online = OnlineClassifier::new(
        model,
        &profile.segment,
        &profile.params,
        profile.calibration,
    )
    .unwrap();
    let zeros = vec![0.0; 40 * 30];
    let err = online
        .push(&FrameView::new(Grid::new(40, 30), &zeros, None).unwrap())
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.contains("the sensor this whole-stance model was trained on"),
        "{err}"
    );

    // A file written before the sensor and the sampling were stored loads, and takes any grid.
    let mut value = serde_json::to_value(model).unwrap();
    let fields = value.as_object_mut().unwrap();
    assert!(fields.remove("sensor").is_some() && fields.remove("sampling").is_some());
    let old: TrainedModel = serde_json::from_value(value).unwrap();
    assert_eq!((old.sensor(), old.sampling()), (None, None));
    assert!(old.check_sensor(Grid::new(40, 30)).is_ok());
}

/// A data set of stances from two sensors is refused, naming both files and grids.
#[test]
fn a_stance_data_set_of_two_sensors_is_refused_naming_both() {
    let dir = tempfile::tempdir().unwrap();
    let small = dir.path().join("small.npy");
    write_movie(&small, 60, Grid::new(40, 30));
    let manifest = jiku_manifest(dir.path(), &format!("{},fast,s00\n", small.display()));
    let err = Dataset::load(&manifest, &stance_options(), &Quiet)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("small.npy` has 40x30 frames where `")
            && err.contains(
                "s00_t00.npy` (line 2) has 63x33: a stance model is trained on one sensor"
            ),
        "{err}"
    );
}

/// A series model takes one 2-D array of its channels x time: given a movie, `classify` says that the
/// model classifies series; given a series of another length, it says which it takes.
#[test]
fn a_series_model_says_it_takes_series() {
    let dir = tempfile::tempdir().unwrap();
    let mut rows = String::from("path,label,group\n");
    for k in 0..12 {
        let label = if k % 2 == 0 { "a" } else { "b" };
        let path = dir.path().join(format!("s{k}.npy"));
        let values: Vec<f64> = (0..4 * 40)
            .map(|i| {
                let (channel, t) = ((i / 40) as f64, (i % 40) as f64);
                let speed = if label == "a" { 0.3 } else { 0.9 };
                (speed * t + channel + k as f64 * 0.1).sin()
            })
            .collect();
        write_npy_f64(std::fs::File::create(&path).unwrap(), &[4, 40], &values).unwrap();
        rows.push_str(&format!("{},{label},g{}\n", path.display(), k % 3));
    }
    let manifest = dir.path().join("manifest.csv");
    std::fs::write(&manifest, rows).unwrap();
    let options = SampleOptions {
        kind: SampleKind::Series {
            time_in_rows: false,
        },
        ..SampleOptions::default()
    };
    let dataset = Dataset::load(&manifest, &options, &Quiet).unwrap();
    assert_eq!(dataset.sensor, Some(Grid::new(4, 40)));
    let train_options = TrainOptions {
        method: rocket_ridge(),
        ..TrainOptions::default()
    };
    let model = train(&dataset, &train_options).unwrap().model;
    assert_eq!(model.sensor(), Some(Grid::new(4, 40)));

    let movie = dir.path().join("movie.npy");
    write_movie(&movie, 30, Grid::new(8, 6));
    let mut session = model.session();
    let options = ClassifyOptions::default();
    let err = classify_file(
        &model,
        &mut session,
        &movie,
        &options,
        &mut Default::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("movie.npy: a movie of 30 frames of 8x6, but the model classifies series")
            && err.contains("4 channels x 40 time steps"),
        "{err}"
    );
    let short = dir.path().join("short.npy");
    write_npy_f64(
        std::fs::File::create(&short).unwrap(),
        &[4, 30],
        &[0.5; 120],
    )
    .unwrap();
    let err = classify_file(
        &model,
        &mut session,
        &short,
        &options,
        &mut Default::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains(
            "expected 4x40 (4 channels x 40 time steps), the series this model was trained on, got 4x30"
        ),
        "{err}"
    );
}
