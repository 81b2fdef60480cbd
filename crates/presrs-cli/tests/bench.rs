//! `presrs bench --export DIR`: the inputs and answers `bench/side_by_side.sh` hands to the Python peer.

#![allow(clippy::expect_used)] // the shared helpers in common/ run the binary outside #[test] functions

mod common;
use common::{presrs, stderr, stdout};

use presrs_io::model_file::load_model;
use presrs_io::npy::read_npy;

/// `presrs bench --synthetic --export DIR --json` with `timing` options; asserts that it succeeds.
fn export_synthetic(dir: &std::path::Path, timing: &[&str]) -> std::process::Output {
    let mut args = vec![
        "bench",
        "--synthetic",
        "--json",
        "--export",
        dir.to_str().expect("a UTF-8 temporary path"),
    ];
    args.extend_from_slice(timing);
    let out = presrs(&args);
    assert!(out.status.success(), "{}", stderr(&out));
    out
}

#[test]
fn export_writes_a_model_images_and_matching_predictions() {
    let dir = tempfile::tempdir().unwrap();
    let export = dir.path().join("inputs");
    let out = export_synthetic(
        &export,
        &["--iterations", "50", "--batch", "16", "--batch-runs", "2"],
    );
    let report: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
    let ns = |key: &str| report[key].as_u64().unwrap();
    assert!(ns("single_image_min_ns") > 0);
    // Order statistics of one sample: non-decreasing.
    let order = [
        "single_image_min_ns",
        "single_image_p25_ns",
        "single_image_median_ns",
        "single_image_p75_ns",
        "single_image_p99_ns",
    ];
    assert!(order.windows(2).all(|w| ns(w[0]) <= ns(w[1])), "{report}");
    // Each stage timed alone; together about one classification (not asserted: timings are noisy).
    for stage in ["features", "pca", "classifier"] {
        assert!(
            report["stages_median_ns"][stage].as_u64().unwrap() > 0,
            "{stage}"
        );
    }
    assert_eq!(
        report["batch_runs_images_per_s"].as_array().unwrap().len(),
        2
    );

    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(export.join("presrs.json")).unwrap())
            .unwrap();
    assert_eq!(doc["format"], "presrs-bench-export");
    assert_eq!(doc["image_shape"], serde_json::json!([64, 44, 44]));
    assert_eq!(doc["cropped_shape"], serde_json::json!([38, 41]));
    assert_eq!(doc["timing"]["batch"], 16);

    // The exported model classifies the exported images as presrs.json says.
    let model = load_model(&export.join("model.json")).unwrap().model;
    let images = read_npy(&export.join("images.npy")).unwrap();
    assert_eq!(images.frame_count(), 64);
    let predictions = doc["predictions"].as_array().unwrap();
    let posteriors = doc["posteriors"].as_array().unwrap();
    let truth = doc["truth"].as_array().unwrap();
    assert_eq!((predictions.len(), truth.len()), (64, 64));
    let mut session = model.session();
    let mut correct = 0;
    for (index, (expected, expected_posteriors)) in predictions.iter().zip(posteriors).enumerate() {
        let frame = images.frame(index).unwrap();
        let prediction = session.classify(&frame).unwrap();
        assert_eq!(prediction.class as u64, expected.as_u64().unwrap());
        assert_eq!(doc["labels"][index], prediction.label);
        for (got, want) in prediction
            .posteriors
            .iter()
            .zip(expected_posteriors.as_array().unwrap())
        {
            assert!((got - want.as_f64().unwrap()).abs() < 1e-12);
        }
        if truth[index] == prediction.label {
            correct += 1;
        }
    }
    assert!(correct >= 60, "{correct} of 64 synthetic images right");

    // Features and reduced vectors, one row per image, as the session computes them.
    let features = read_npy(&export.join("features.npy")).unwrap();
    let reduced = read_npy(&export.join("reduced.npy")).unwrap();
    assert_eq!(
        (
            features.frame_count(),
            features.grid().rows,
            features.grid().cols
        ),
        (1, 64, 1025)
    );
    assert_eq!(
        (
            reduced.frame_count(),
            reduced.grid().rows,
            reduced.grid().cols
        ),
        (1, 64, 51)
    );
    let first = images.frame(0).unwrap();
    let want = session.features(&first).unwrap().to_vec();
    assert_eq!(
        &features.frame(0).unwrap().values()[..1025],
        want.as_slice()
    );
    let want = session.reduce(&first).unwrap().to_vec();
    assert_eq!(&reduced.frame(0).unwrap().values()[..51], want.as_slice());
}

#[test]
fn bench_rejects_zero_counts_as_bad_usage() {
    for option in ["--batch-runs", "--batch", "--iterations"] {
        let out = presrs(&["bench", "--synthetic", option, "0"]);
        assert_eq!(out.status.code(), Some(2), "{option}: {}", stderr(&out));
        assert!(stderr(&out).contains(option), "{}", stderr(&out));
    }
}

#[test]
fn bench_text_keeps_its_label_column() {
    let out = presrs(&[
        "bench",
        "--synthetic",
        "--iterations",
        "10",
        "--batch",
        "4",
        "--batch-runs",
        "1",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = stdout(&out);
    // Every line but the continuation one is a label padded to 27 columns, then its value.
    let width = "batch throughput           ".len();
    for line in text.lines().filter(|l| !l.starts_with("  ")) {
        let (label, value) = line.split_at(width);
        assert!(
            label.ends_with(' ') && !value.starts_with(' '),
            "the value of {line:?} does not start at column {width}:\n{text}"
        );
    }
    assert!(
        text.contains("paper                      245 us per image"),
        "{text}"
    );
}

#[test]
fn bench_times_a_model_on_the_images_of_a_manifest() {
    let dir = tempfile::tempdir().unwrap();
    let export = dir.path().join("inputs");
    export_synthetic(
        &export,
        &["--iterations", "10", "--batch", "4", "--batch-runs", "1"],
    );
    // The exported images as a manifest of single frames.
    let manifest = export.join("manifest.csv");
    let mut rows = String::from("path,label,frame\n");
    for frame in 0..6 {
        rows.push_str(&format!("images.npy,,{frame}\n"));
    }
    std::fs::write(&manifest, rows).unwrap();
    let model = export.join("model.json");
    let out = presrs(&[
        "bench",
        "--model",
        model.to_str().unwrap(),
        "--images",
        manifest.to_str().unwrap(),
        "--iterations",
        "20",
        "--batch",
        "8",
        "--batch-runs",
        "1",
        "--json",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let report: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
    assert_eq!(report["test_images"], 6);
    assert!(
        report["model"]
            .as_str()
            .unwrap()
            .contains("on the images of"),
        "{report}"
    );
    // Images the model cannot take: a clear error naming the sample and the manifest.
    std::fs::write(export.join("small.txt"), "1 2\n3 4\n").unwrap();
    let small = export.join("small.csv");
    std::fs::write(&small, "path,label\nsmall.txt,wood\n").unwrap();
    let out = presrs(&[
        "bench",
        "--model",
        model.to_str().unwrap(),
        "--images",
        small.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        stderr(&out).contains("sample 1 of") && stderr(&out).contains("does not fit"),
        "{}",
        stderr(&out)
    );
    // --images needs the model it is to time.
    let out = presrs(&["bench", "--images", manifest.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("--model"), "{}", stderr(&out));
}
