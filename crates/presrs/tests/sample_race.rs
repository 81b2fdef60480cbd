//! `--sample auto` (`presrs::sample_race`): one frame against the whole stance, chosen by validation.
//!
//! Movies whose classes differ only in how fast the foot loads (the same plateau, so the same
//! mid-stance frame) can only be told apart from the whole stance: the race must choose it, and say
//! that one frame validated near chance. A fixed method cannot race (no validation scores).

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;

use presrs::core::classifier::ClassifierKind;
use presrs::core::{Grid, Recording, SensorMeta};
use presrs::method::{ClassifierChoice, FeatureChoice};
use presrs::sample_race::{WholeSample, train_racing_samples};
use presrs::train::TrainOptions;
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
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut manifest = String::from("path,label\n");
    for (label, rise) in [("soft", 12), ("hard", 2)] {
        for i in 0..14 {
            let name = format!("{label}_{i:02}.npy");
            presrs::io::npy::write_recording_npy(&movie(rise, &mut rng), &dir.join(&name)).unwrap();
            manifest.push_str(&format!("{name},{label}\n"));
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
