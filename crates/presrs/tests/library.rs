//! The library alone, as the Python package and robot programs use it: a real data set (objects on a
//! high-resolution pressure array, recorded by others) read from its manifest, trained on, evaluated
//! leaving one group out, and classified; and what the library says when the data do not fit.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};

use presrs::eval::{EvalOptions, EvalSetup, Holdout};
use presrs::train::{TrainOptions, train};
use presrs::{Dataset, Error, Method, Quiet, Recorder, SampleOptions};

fn tais22() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/real/tais22/manifest.csv")
}

#[test]
fn a_real_data_set_trains_evaluates_and_classifies_through_the_library() {
    let dataset = Dataset::load(&tais22(), &SampleOptions::default(), &Quiet).unwrap();
    assert_eq!(dataset.samples.len(), 1100);
    assert!(dataset.warnings.is_empty(), "{:?}", dataset.warnings);
    assert_eq!(dataset.grid(), presrs::core::Grid::new(28, 50));

    // Leave one group (block of images) out, the paper's method, 20 images per object.
    let options = EvalOptions {
        holdout: Holdout::LeaveOneOut("group".into()),
        per_class: Some(20),
        repeats: 1,
        method: Method::paper(),
        ..EvalOptions::default()
    };
    let setup = EvalSetup::new(&dataset, &options).unwrap();
    assert_eq!(setup.folds(), 5);
    assert!(setup.never_trained.is_empty());
    let progress = Recorder::default();
    let outcome = setup.evaluate(&progress).unwrap();
    let report = &outcome.report;
    assert_eq!(report.confusion.labels.len(), 22);
    // Every image is tested once (each in its held-out fold); chance is 1 in 22.
    let tested: u64 = report.confusion.counts.iter().flatten().sum();
    assert_eq!(tested, 1100);
    assert!(report.overall.mean > 0.5, "{}", report.overall.mean);
    // One step per trained model, announced beforehand.
    let log = progress.log();
    assert_eq!(log.tasks, vec![("training".to_owned(), Some(5))]);
    assert_eq!(log.steps, 5);

    // Train on blocks b0-b3, classify an image of b4.
    let train_options = TrainOptions {
        per_class: Some(20),
        method: Method::paper(),
        ..TrainOptions::default()
    };
    let training = train(&dataset, &train_options).unwrap();
    assert_eq!(training.model.class_names().len(), 22);
    assert_eq!(training.n_train() + training.n_validation(), 440);
    let file = training.model_file(&dataset, &train_options, true, None);
    assert_eq!(
        file.provenance.manifest_sha256.as_deref(),
        Some(dataset.manifest.sha256.as_str())
    );
    let mut session = training.model.session();
    let sample = &dataset.samples[7];
    let prediction = session.classify(&sample.frame.view()).unwrap();
    assert!(
        training
            .model
            .class_names()
            .iter()
            .any(|c| c == prediction.label)
    );
    assert!((0.0..=1.0).contains(&prediction.confidence));
}

#[test]
fn data_that_do_not_fit_are_errors_that_say_where_and_what_to_try() {
    let dir = tempfile::tempdir().unwrap();
    let first = tais22().with_file_name("img/adhesive_01.npy");
    let manifest = dir.path().join("m.csv");
    std::fs::write(
        &manifest,
        format!(
            "path,label,condition\n{0},a,c1\n{0},,c1\n{0},b,c2\n",
            first.display()
        ),
    )
    .unwrap();
    let dataset = Dataset::load(&manifest, &SampleOptions::default(), &Quiet).unwrap();

    let err = train(&dataset, &TrainOptions::default()).unwrap_err();
    assert_eq!(
        err.to_string(),
        format!(
            "{} line 3: field `label` is empty; training needs a label for every sample",
            manifest.display()
        )
    );
    let options = TrainOptions {
        condition: Some("c3".into()),
        ..TrainOptions::default()
    };
    let err = train(&dataset, &options).unwrap_err();
    assert!(matches!(err, Error::Data(_)));
    assert!(
        err.to_string()
            .ends_with("no sample has condition \"c3\" (conditions present: c1, c2)"),
        "{err}"
    );
    let eval = EvalOptions {
        holdout: Holdout::LeaveOneOut("subject".into()),
        ..EvalOptions::default()
    };
    let err = EvalSetup::new(&dataset, &eval).unwrap_err();
    assert!(
        err.to_string()
            .contains("--leave-one-out subject: the manifest has no such column (columns: path, label, condition)"),
        "{err}"
    );

    std::fs::write(&manifest, "path,label\n").unwrap();
    let err = Dataset::load(&manifest, &SampleOptions::default(), &Quiet).unwrap_err();
    assert_eq!(
        err.to_string(),
        format!(
            "{}: the manifest lists no samples (only a header)",
            manifest.display()
        )
    );
}

/// A manifest of one-contact movies (real plantar-pressure trials, `jiku-walk`), of which only one
/// row gives a sample (it names its frame): training and evaluation say that classes have too few
/// samples, with their counts and why the files gave none (and the option to try), before anything
/// about the validation set.
#[test]
fn too_few_samples_of_a_class_is_named_before_the_validation_set() {
    let jiku = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/real/jiku-walk");
    let dir = tempfile::tempdir().unwrap();
    let manifest = dir.path().join("m.csv");
    let mut text = String::from("path,label,frame\n");
    text.push_str(&format!("{},slow,20\n", jiku.join("s00_t01.npy").display()));
    for (file, label) in [
        ("s00_t00.npy", "fast"),
        ("s00_t02.npy", "slow"),
        ("s00_t03.npy", "normal"),
        ("s00_t04.npy", "fast"),
        ("s00_t05.npy", "normal"),
    ] {
        text.push_str(&format!("{},{label},\n", jiku.join(file).display()));
    }
    std::fs::write(&manifest, text).unwrap();
    let dataset = Dataset::load(&manifest, &SampleOptions::default(), &Quiet).unwrap();
    assert_eq!(dataset.samples.len(), 1);

    let err = train(&dataset, &TrainOptions::default()).unwrap_err();
    let message = err.to_string();
    assert!(matches!(err, Error::Data(_)), "{message}");
    assert!(
        message.contains(
            "cannot train: too few samples per class: \"fast\" has 0, \"normal\" 0, \"slow\" 1 \
             (at least 3 needed, 1 sample in all); 5 of 6 files gave no sample: "
        ),
        "{message}"
    );
    assert!(message.ends_with("try --one-sample-per-file"), "{message}");
    assert!(!message.contains("validation"), "{message}");

    let err = EvalSetup::new(&dataset, &EvalOptions::default()).unwrap_err();
    let message = err.to_string();
    assert!(
        message.contains("cannot evaluate: too few samples per class: \"fast\" has 0"),
        "{message}"
    );
    assert!(message.ends_with("try --one-sample-per-file"), "{message}");

    // Asked for 2 per class with one sample per file: every movie gives one, and "slow" (2 of them)
    // has enough; the others have 2 too.
    let one_each = SampleOptions {
        one_sample_per_file: true,
        ..SampleOptions::default()
    };
    let dataset = Dataset::load(&manifest, &one_each, &Quiet).unwrap();
    assert_eq!(dataset.samples.len(), 6);
    assert!(dataset.too_few_samples(None, 2).is_none());
    assert_eq!(
        dataset.too_few_samples(None, 3).unwrap().to_string(),
        "too few samples per class: \"fast\" has 2, \"normal\" 2, \"slow\" 2 (at least 3 needed, 6 \
         samples in all)"
    );
}
