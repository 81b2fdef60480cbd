//! Whole-stance and series samples on inputs at their edges (issue #33's list), end to end through the
//! library as `presrs train`, `eval` and `classify` use it, on tiny files written to a temporary folder:
//! - stances shorter than a MiniRocket kernel (9 frames): padded with zeros, they train, evaluate and
//!   classify; so does a 3-frame stance at classification (2 frames are no stance: a warning);
//! - a stance longer than the model's length at classification: its first frames, with a warning;
//! - a one-frame stance (a one-frame file) and NaN in a movie: errors naming the file;
//! - a series with one channel: univariate MiniRocket.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};

use presrs::classify::{ClassifyOptions, classify_file};
use presrs::core::classifier::ClassifierKind;
use presrs::core::features::FeatureKind;
use presrs::core::pipeline::TrainedModel;
use presrs::core::sample::SampleKind;
use presrs::core::stance::summary::SummaryConfig;
use presrs::eval::{EvalOptions, EvalSetup, Holdout};
use presrs::io::npy::write_npy_f64;
use presrs::train::{TrainOptions, train};
use presrs::{ClassifierChoice, Dataset, FeatureChoice, Method, Quiet, SampleOptions};

const ROWS: usize = 8;
const COLS: usize = 6;

/// A movie of `frames` frames of 8 x 6: a load rising and falling over the stance; class `b` loads
/// the top half twice as much. `seed` varies the texture.
fn movie(frames: usize, label: &str, seed: usize) -> Vec<f64> {
    let mut values = Vec::with_capacity(frames * ROWS * COLS);
    for t in 0..frames {
        let envelope = 1.0 + ((t as f64 + 0.5) / frames as f64 * std::f64::consts::PI).sin();
        for r in 0..ROWS {
            for c in 0..COLS {
                let texture = 5.0 + ((seed * 7 + r * 3 + c * 5 + t) % 11) as f64 * 0.1;
                let heavy = if label == "b" && r < ROWS / 2 {
                    2.0
                } else {
                    1.0
                };
                values.push(envelope * texture * heavy);
            }
        }
    }
    values
}

fn write_movie(dir: &Path, name: &str, values: &[f64]) -> PathBuf {
    let path = dir.join(name);
    let frames = values.len() / (ROWS * COLS);
    write_npy_f64(
        std::fs::File::create(&path).unwrap(),
        &[frames, ROWS, COLS],
        values,
    )
    .unwrap();
    path
}

/// A manifest of movies, two groups, two classes, `per_class` movies each, of `frames(k)` frames.
fn movie_manifest(dir: &Path, per_class: usize, frames: impl Fn(usize) -> usize) -> PathBuf {
    let mut text = String::from("path,label,group\n");
    for group in ["g0", "g1"] {
        for label in ["a", "b"] {
            for k in 0..per_class {
                let name = format!("{group}_{label}{k}.npy");
                let seed = k + if group == "g1" { 10 } else { 0 };
                write_movie(dir, &name, &movie(frames(k), label, seed));
                text.push_str(&format!("{name},{label},{group}\n"));
            }
        }
    }
    let manifest = dir.join("manifest.csv");
    std::fs::write(&manifest, text).unwrap();
    manifest
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

fn train_on(dataset: &Dataset) -> TrainedModel {
    let options = TrainOptions {
        method: rocket_ridge(),
        ..TrainOptions::default()
    };
    train(dataset, &options).unwrap().model
}

fn classify(model: &TrainedModel, path: &Path, samples: &SampleOptions) -> presrs::Result<String> {
    let options = ClassifyOptions {
        frame: None,
        samples: samples.clone(),
    };
    let mut session = model.session();
    let result = classify_file(model, &mut session, path, &options, &mut Default::default())?;
    let warnings = result.warnings.render(presrs::Face::Cli).join("\n");
    let frames: Vec<String> = result
        .frames
        .iter()
        .map(|f| {
            let warning = f
                .warning
                .as_ref()
                .map(|w| w.render(presrs::Face::Cli))
                .unwrap_or_default();
            format!("{} {} {warning}", f.frame, f.label)
        })
        .collect();
    Ok(format!("{warnings}{}", frames.join("\n")))
}

/// Every stance shorter than a kernel (3 to 6 frames): the samples keep the longest stance's length,
/// MiniRocket pads them to 9, and train, eval and classify all work; at classification a 2-frame stance
/// is padded to the model's length and a 40-frame one cut to it, with a warning.
#[test]
fn stances_shorter_than_a_kernel_train_evaluate_and_classify() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = movie_manifest(dir.path(), 4, |k| 3 + k);
    let options = stance_options();
    let dataset = Dataset::load(&manifest, &options, &Quiet).unwrap();
    assert_eq!(dataset.samples.len(), 16);
    assert!(
        dataset.samples.iter().all(|s| s.frame.grid().cols == 6),
        "laid into the longest stance"
    );
    let model = train_on(&dataset);
    assert_eq!(
        model.sample(),
        SampleKind::Stance {
            summary: SummaryConfig::default(),
            length: Some(6),
        }
    );
    // Read back from its file, as `classify` does.
    let model: TrainedModel =
        serde_json::from_str(&serde_json::to_string(&model).unwrap()).unwrap();

    let eval = EvalOptions {
        holdout: Holdout::LeaveOneOut("group".into()),
        repeats: 1,
        method: rocket_ridge(),
        ..EvalOptions::default()
    };
    let outcome = EvalSetup::new(&dataset, &eval)
        .unwrap()
        .evaluate(&Quiet)
        .unwrap();
    let tested: u64 = outcome.report.confusion.counts.iter().flatten().sum();
    assert_eq!(tested, 16);
    assert!(
        outcome.report.overall.mean >= 0.75,
        "{}",
        outcome.report.overall.mean
    );

    let three = write_movie(dir.path(), "three.npy", &movie(3, "b", 3));
    let said = classify(&model, &three, &options).unwrap();
    assert_eq!(said, "0 b ", "a 3-frame stance, padded");
    // Fewer frames than a stance has at least (3, the segmentation's `min_stance_frames`) are no
    // stance: nothing is classified, and the file says why.
    let two = write_movie(dir.path(), "two.npy", &movie(2, "b", 3));
    let said = classify(&model, &two, &options).unwrap();
    assert!(
        said.ends_with(
            "two.npy: 2 frames but no complete stance phase; nothing classified (it is shorter \
             than a stance of at least 3 frames)"
        ),
        "{said}"
    );
    // In a data set, it gives no sample, and the warning says why.
    let with_two = dir.path().join("with_two.csv");
    let text = std::fs::read_to_string(&manifest).unwrap() + "two.npy,b,g0\n";
    std::fs::write(&with_two, text).unwrap();
    let loaded = Dataset::load(&with_two, &options, &Quiet).unwrap();
    assert_eq!(loaded.samples.len(), 16);
    let warnings = loaded.warnings.render(presrs::Face::Cli).join("\n");
    assert!(
        warnings.contains(
            "1 of 17 files gave no sample: two.npy ; each is shorter than a stance (at least 3 frames)"
        ),
        "{warnings}"
    );
    let long = write_movie(dir.path(), "long.npy", &movie(40, "a", 3));
    let said = classify(&model, &long, &options).unwrap();
    assert!(
        said.contains("the stance has 40 frames, more than the model's 6: its first 6 were used"),
        "{said}"
    );
}

/// A stance of one frame (a one-frame file) and NaN in a movie are errors that name the file, in
/// training (and so eval, which loads the same way) and in classification.
#[test]
fn a_one_frame_stance_and_nan_in_a_movie_are_errors_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = movie_manifest(dir.path(), 3, |k| 12 + k);
    let options = stance_options();
    let model = train_on(&Dataset::load(&manifest, &options, &Quiet).unwrap());

    let one = write_movie(dir.path(), "one.npy", &movie(1, "a", 0));
    let mut nan_values = movie(14, "a", 0);
    nan_values[5 * ROWS * COLS + 2 * COLS + 2] = f64::NAN;
    let nan = write_movie(dir.path(), "nan.npy", &nan_values);
    for (file, says) in [
        ("one.npy", "is one frame, not a movie"),
        ("nan.npy", "element [5, 2, 2] is NaN"),
    ] {
        let bad = dir.path().join(format!("bad_{file}.csv"));
        std::fs::write(
            &bad,
            format!("path,label,group\n{file},a,g0\ng0_b0.npy,b,g0\ng1_a0.npy,a,g1\n"),
        )
        .unwrap();
        let err = Dataset::load(&bad, &options, &Quiet)
            .unwrap_err()
            .to_string();
        assert!(err.contains("line 2"), "{err}");
        assert!(err.contains(file) && err.contains(says), "{err}");
    }
    let err = classify(&model, &one, &options).unwrap_err().to_string();
    assert!(
        err.contains("one.npy") && err.contains("takes movies, not one frame"),
        "{err}"
    );
    let err = classify(&model, &nan, &options).unwrap_err().to_string();
    assert!(err.contains("nan.npy") && err.contains("NaN"), "{err}");
}

/// A series of one channel (a 1 x 30 array) is univariate MiniRocket: it trains, evaluates and
/// classifies; an array of another shape is an error naming the file and both shapes.
#[test]
fn a_one_channel_series_is_univariate_minirocket() {
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::from("path,label,group\n");
    for group in ["g0", "g1"] {
        for (label, frequency) in [("a", 1.0), ("b", 2.5)] {
            for k in 0..5 {
                let name = format!("{group}_{label}{k}.npy");
                let phase = k as f64 * 0.7 + if group == "g1" { 0.3 } else { 0.0 };
                let values: Vec<f64> = (0..30)
                    .map(|t| (t as f64 * 0.2 * frequency + phase).sin())
                    .collect();
                let file = std::fs::File::create(dir.path().join(&name)).unwrap();
                write_npy_f64(file, &[1, 30], &values).unwrap();
                text.push_str(&format!("{name},{label},{group}\n"));
            }
        }
    }
    let manifest = dir.path().join("series.csv");
    std::fs::write(&manifest, text).unwrap();
    let options = SampleOptions {
        kind: SampleKind::Series {
            time_in_rows: false,
        },
        ..SampleOptions::default()
    };
    let dataset = Dataset::load(&manifest, &options, &Quiet).unwrap();
    assert!(
        dataset
            .samples
            .iter()
            .all(|s| s.frame.grid() == presrs::core::Grid::new(1, 30))
    );
    let model = train_on(&dataset);
    let eval = EvalOptions {
        holdout: Holdout::LeaveOneOut("group".into()),
        repeats: 1,
        method: rocket_ridge(),
        ..EvalOptions::default()
    };
    let outcome = EvalSetup::new(&dataset, &eval)
        .unwrap()
        .evaluate(&Quiet)
        .unwrap();
    assert!(
        outcome.report.overall.mean >= 0.9,
        "{}",
        outcome.report.overall.mean
    );
    let said = classify(&model, &dir.path().join("g1_b3.npy"), &options).unwrap();
    assert_eq!(said, "0 b ");
    let column = dir.path().join("column.npy");
    write_npy_f64(
        std::fs::File::create(&column).unwrap(),
        &[30, 1],
        &[0.5; 30],
    )
    .unwrap();
    let err = classify(&model, &column, &options).unwrap_err().to_string();
    assert!(
        err.contains("column.npy") && err.contains("expected 1x30") && err.contains("got 30x1"),
        "{err}"
    );
}
