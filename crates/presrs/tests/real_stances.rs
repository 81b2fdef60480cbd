//! Stance segmentation on real recordings that nobody on this project made, read in place from the
//! shared data folder, through the library as `presrs inspect` and the data-set loader use it:
//! - `tekscan/FrasP01L.asf` (F-Scan insole, overground walking): five complete stances;
//! - every `real/jiku-walk/` movie (plantar pressure, one foot contact from the first frame to the
//!   last): exactly one stance, partial at both ends, and one sample each with one sample per file.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};

use presrs::core::stance::BaselineMode;
use presrs::inspect::inspect;
use presrs::{Dataset, Quiet, SampleOptions};

fn shared(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data")
        .join(path)
}

fn jiku_movies() -> Vec<PathBuf> {
    let mut movies: Vec<PathBuf> = std::fs::read_dir(shared("real/jiku-walk"))
        .unwrap()
        .map(|entry| entry.unwrap().path())
        .filter(|path| path.extension().is_some_and(|ext| ext == "npy"))
        .collect();
    movies.sort();
    movies
}

#[test]
fn the_walking_f_scan_file_has_five_complete_stances() {
    let report = inspect(&shared("tekscan/FrasP01L.asf"), &SampleOptions::default()).unwrap();
    assert_eq!(report.stance_mode, BaselineMode::Drifting);
    let complete: Vec<(usize, usize)> = report
        .stances
        .iter()
        .filter(|s| !s.partial)
        .map(|s| (s.start, s.len))
        .collect();
    assert_eq!(complete.len(), 5, "{complete:?}");
    // ~23-frame stances at 31.25 Hz.
    assert!(
        complete.iter().all(|&(_, len)| (20..=26).contains(&len)),
        "{complete:?}"
    );
}

#[test]
fn every_jiku_walk_movie_is_exactly_one_stance() {
    let movies = jiku_movies();
    assert_eq!(movies.len(), 120);
    let one_each = SampleOptions {
        one_sample_per_file: true,
        ..SampleOptions::default()
    };
    for movie in &movies {
        let report = inspect(movie, &SampleOptions::default()).unwrap();
        assert_eq!(report.stances.len(), 1, "{}", movie.display());
        let stance = &report.stances[0];
        assert_eq!(
            (stance.start, stance.len),
            (0, report.frames),
            "{}",
            movie.display()
        );
        assert!(stance.partial);
        assert_eq!(
            report.stance_mode,
            BaselineMode::Contact,
            "{}",
            movie.display()
        );
        assert!(
            report
                .stance_notes
                .iter()
                .any(|n| n.contains("--one-sample-per-file")),
            "{}: {:?}",
            movie.display(),
            report.stance_notes
        );
        let report = inspect(movie, &one_each).unwrap();
        assert_eq!(report.stances.len(), 1);
        assert_eq!(
            report.stances[0].sample_frame,
            Some((report.frames - 1) / 2)
        );
    }
}

#[test]
fn the_jiku_walk_data_set_gives_one_sample_a_file_when_asked_and_says_why_not_otherwise() {
    let manifest = shared("real/jiku-walk/manifest.csv");
    let one_each = SampleOptions {
        one_sample_per_file: true,
        ..SampleOptions::default()
    };
    let dataset = Dataset::load(&manifest, &one_each, &Quiet).unwrap();
    assert_eq!(dataset.samples.len(), 120);
    let err = Dataset::load(&manifest, &SampleOptions::default(), &Quiet).unwrap_err();
    let message = err.to_string();
    assert!(
        message.contains("the manifest gives no samples: 120 of 120 files gave no sample: "),
        "{message}"
    );
    assert!(message.ends_with("try --one-sample-per-file"), "{message}");
}
