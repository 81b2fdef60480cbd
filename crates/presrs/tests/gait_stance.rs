//! The gait loop (`presrs simulate --track ... --adaptive MODEL`, `presrs::sim::gait::compare_on_track`)
//! with a whole-stance model: a small stance model trained on simulated movies decides on the track
//! (at lift-off, or `decide_at` frames after touchdown), and the gait switches as its table says.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use presrs::core::classifier::ClassifierKind;
use presrs::core::online::DecideAt;
use presrs::core::pipeline::{TrainConfig, train};
use presrs::core::sample::SampleKind;
use presrs::core::stance::ValidSegmentParams;
use presrs::core::stance::summary::SummaryConfig;
use presrs::io::model_file::{ModelFile, Provenance, save_model};
use presrs::sim::gait::{GaitSweep, TrackOptions, compare_on_track};
use presrs::simulator::{DatasetSpec, SimConfig, simulate_dataset};
use presrs::{Dataset, Quiet, SampleOptions};

/// Simulated movies of wood and grass in every gait, a few hops each, written with their manifest.
fn write_movies(dir: &Path, config: &SimConfig) -> PathBuf {
    let spec = DatasetSpec {
        terrains: vec!["wood".into(), "grass".into()],
        hops_per_gait: Some(8),
        ..DatasetSpec::paper(5)
    };
    let data = simulate_dataset(config, &spec).unwrap();
    let mut manifest = String::from("path,label,condition,group\n");
    for trial in &data.trials {
        let name = format!("{}.npy", trial.plan.name());
        presrs::io::npy::write_recording_npy(&trial.recording, &dir.join(&name)).unwrap();
        let (terrain, gait) = (&trial.plan.terrain, &trial.plan.gait.name);
        manifest.push_str(&format!("{name},{terrain},{gait},{}\n", trial.plan.name()));
    }
    let path = dir.join("manifest.csv");
    std::fs::write(&path, manifest).unwrap();
    path
}

/// A whole-stance model (168 MiniRocket features, linear discriminant) of the movies, with the online
/// profile learned from them and the terrain-to-gait table `table`, saved as a model file.
/// With classifiers for the decision points `points` (frames after touchdown).
fn stance_model(manifest: &Path, table: &BTreeMap<String, String>, points: &[usize]) -> PathBuf {
    let options = SampleOptions {
        kind: SampleKind::Stance {
            summary: SummaryConfig::default(),
            length: None,
        },
        decision_points: points.to_vec(),
        ..SampleOptions::default()
    };
    let dataset = Dataset::load(manifest, &options, &Quiet).unwrap();
    assert!(dataset.samples.len() >= 40, "{}", dataset.samples.len());
    let model = common::small_rocket_model(&dataset, ClassifierKind::LDA, 10, dataset.sample);
    let model = common::with_points(model, &dataset);
    let mut profile = presrs::train::manifest_online_profile(
        manifest,
        &SampleOptions::default(),
        &ValidSegmentParams::default(),
    )
    .unwrap();
    profile.gait_table = table.clone();
    let mut file = ModelFile::new(model, Provenance::default());
    file.online = Some(profile);
    let path = manifest.with_file_name(format!("stance-model{points:?}.json"));
    save_model(&path, &file).unwrap();
    path
}

fn track_options(model: &Path, decide_at: Option<DecideAt>) -> TrackOptions {
    TrackOptions {
        seed: 2,
        repeats: 1,
        adaptive: Some(model.to_owned()),
        gait_sweep: GaitSweep(None),
        confirm: 1,
        fixed_gaits: vec!["G2".into()],
        start_gait: Some("G2".into()),
        decide_at,
        novelty: true,
    }
}

#[test]
fn a_whole_stance_model_decides_on_the_track_and_the_gait_follows_its_table() {
    let dir = tempfile::tempdir().unwrap();
    let config = SimConfig::default();
    let manifest = write_movies(dir.path(), &config);
    let table: BTreeMap<String, String> = [("wood", "G1"), ("grass", "G3")]
        .into_iter()
        .map(|(t, g)| (t.to_owned(), g.to_owned()))
        .collect();
    let model = stance_model(&manifest, &table, &[4]);
    for decide_at in [None, Some(DecideAt::Frames(4))] {
        let outcome = compare_on_track(
            &config,
            "wood:2,grass:2",
            &track_options(&model, decide_at),
            &Quiet,
        )
        .unwrap();
        let comparison = &outcome.comparison;
        assert_eq!(comparison.gait_table, table);
        let adaptive = &comparison.policies[0];
        assert_eq!(adaptive.policy, "adaptive");
        let run = &adaptive.runs[0];
        let hops = run.hops.len();
        assert!(
            run.decided * 2 >= hops,
            "{decide_at:?}: {} decisions in {hops} hops",
            run.decided
        );
        // On the whole stance the model is right; on its first frames (a model trained on whole
        // stances, zero-padded) it may well not be, and the gait follows whatever it decided.
        if decide_at.is_none() {
            assert!(
                run.misclassified * 4 <= run.decided,
                "{} of {} decisions wrong",
                run.misclassified,
                run.decided
            );
        }
        // Each decision sets the next hop's gait to its terrain's (confirm 1), unless the hop fell.
        let mut followed = 0;
        for pair in run.hops.windows(2) {
            if let (Some(believed), false) = (&pair[0].believed, pair[0].fell) {
                assert_eq!(pair[1].gait, table[believed], "{decide_at:?}: {:?}", pair);
                followed += 1;
            }
        }
        assert!(followed > 0, "{decide_at:?}");
        assert!(run.switches >= 1, "{decide_at:?}: never switched");
        if decide_at.is_none() {
            // both terrains recognised: both of the table's gaits were run
            assert!(run.gait_hops.contains_key("G1") && run.gait_hops.contains_key("G3"));
        }
    }
}

/// `decide_at` is for whole-stance models: a one-frame model's adaptive run says so, naming the option.
#[test]
fn decide_at_with_a_one_frame_model_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let config = SimConfig::default();
    let manifest = write_movies(dir.path(), &config);
    let dataset = Dataset::load(&manifest, &SampleOptions::default(), &Quiet).unwrap();
    let images = common::labeled_images(&dataset);
    let config_paper = TrainConfig {
        classifier: ClassifierKind::LDA.default_config(),
        ..TrainConfig::default()
    }
    .check()
    .unwrap();
    let model = train(&images, &[], &config_paper).unwrap();
    let path = dir.path().join("frame-model.json");
    save_model(&path, &ModelFile::new(model, Provenance::default())).unwrap();
    let err = compare_on_track(
        &config,
        "wood:1",
        &track_options(&path, Some(DecideAt::Frames(3))),
        &Quiet,
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("--decide-at 3"), "{err}");
    assert!(err.contains("whole-stance models"), "{err}");
}

/// A whole-stance model decides only at the moments it was trained for: the gait loop refuses a
/// `decide_at` (or `auto`) it has no classifier for, saying how to train one.
#[test]
fn decide_at_a_moment_the_model_was_not_trained_for_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let config = SimConfig::default();
    let manifest = write_movies(dir.path(), &config);
    let table: BTreeMap<String, String> = [("wood", "G1"), ("grass", "G3")]
        .into_iter()
        .map(|(t, g)| (t.to_owned(), g.to_owned()))
        .collect();
    let model = stance_model(&manifest, &table, &[]);
    for (decide_at, said) in [
        (DecideAt::Frames(4), "--decide-at 4"),
        (DecideAt::AUTO, "--decide-at auto"),
    ] {
        let err = compare_on_track(
            &config,
            "wood:1",
            &track_options(&model, Some(decide_at)),
            &Quiet,
        )
        .unwrap_err()
        .to_string();
        assert!(err.contains("not trained to decide at"), "{err}");
        assert!(
            err.contains(said) && err.contains("--sample stance"),
            "{err}"
        );
    }
}
