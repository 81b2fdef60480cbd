//! `presrs reproduce` end to end on a small experiment: the results.json contract, and the data sets it
//! keeps under DIR (DIR/dataset, DIR/dataset-load1.30): reused by a later run with the same seed (with the
//! same results as when simulated), not reused with another seed, and simulated afresh, with the reason
//! said, when a stamp is corrupt or a movie missing.
//!
//! Simulating is slow in a debug build (about 0.1 s per hop), so the experiment is tiny: 4 hops per
//! terrain and gait, 3 training images per terrain (1 validating; 1 left to test), 2 repeats.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;
use common::{presrs, stderr, stdout};

use std::path::Path;

use serde_json::Value;

const HOPS: &str = "4";

/// Runs `presrs reproduce --out DIR --seed SEED` on the small experiment (+ `extra`); returns stdout and
/// the parsed results.json.
fn reproduce(dir: &Path, seed: u64, extra: &[&str]) -> (String, Value) {
    let seed = seed.to_string();
    let mut args = vec!["reproduce", "--out", dir.to_str().unwrap(), "--seed", &seed];
    args.extend([
        "--hops-per-gait",
        HOPS,
        "--per-class",
        "3",
        "--validation",
        "1",
        "--repeats",
        "2",
        "--no-comparison",
        "--no-report",
    ]);
    args.extend(extra);
    let output = presrs(&args);
    assert!(
        output.status.success(),
        "reproduce failed: {}\n{}",
        stderr(&output),
        stdout(&output)
    );
    let text = std::fs::read_to_string(dir.join("results.json")).unwrap();
    (stdout(&output), serde_json::from_str(&text).unwrap())
}

/// The parts of results.json that depend on the data only (not on timing).
fn data_results(results: &Value) -> Value {
    let load = &results["load_independence"];
    assert!(load.is_object(), "load independence measured: {results}");
    serde_json::json!({
        "table1": results["table1"],
        "table2": results["table2"],
        "table2_std": results["table2_std"],
        "train_test_matrix": results["train_test_matrix"],
        "images_per_gait": results["images_per_gait"],
        "segmentation": results["segmentation"],
        "load": [
            load["test_images"],
            load["accuracy_unscaled"],
            load["accuracy_scaled"],
            load["accuracy_normalised"],
        ],
    })
}

fn version() -> &'static str {
    env!("CARGO_PKG_VERSION")
}

fn read_json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn reproduce_reuses_matching_data_sets_and_resimulates_the_others() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("results");
    let data = dir.join("dataset");
    let heavy = dir.join("dataset-load1.30");

    // 1. `presrs simulate --out DIR/dataset` writes a data set reproduce reuses; the heavier hopper's is
    //    simulated (and written) by reproduce.
    let sim = presrs(&[
        "simulate",
        "--out",
        data.to_str().unwrap(),
        "--seed",
        "5",
        "--hops-per-gait",
        HOPS,
    ]);
    assert!(sim.status.success(), "{}", stderr(&sim));
    let (first_out, first) = reproduce(&dir, 5, &[]);
    assert!(
        first_out.contains(&format!(
            "reusing {} (seed 5, presrs {})",
            data.display(),
            version()
        )),
        "{first_out}"
    );
    assert!(
        first_out.contains(&format!(
            "simulating {} (seed 1000008, 3.25 kg): there is no data set there yet",
            heavy.display()
        )),
        "{first_out}"
    );
    // The contract fields.
    let table1 = first["table1"].as_object().unwrap();
    assert_eq!(table1.len(), 3, "three gaits: {first}");
    for row in table1.values() {
        let row = row.as_object().unwrap();
        assert_eq!(row.len(), 4, "four terrains: {row:?}");
        assert!(row.values().all(|v| v.as_f64().unwrap() > 0.0));
    }
    for key in ["G1", "G2", "G3", "overall"] {
        let acc = first["table2"][key].as_f64().unwrap();
        assert!((0.0..=1.0).contains(&acc), "{key}: {acc}");
    }
    assert!(first["median_classify_ns"].as_u64().unwrap() > 0);
    assert_eq!(first["datasets"]["main"]["reused"], true);
    assert_eq!(first["datasets"]["load"]["reused"], false);
    // The heavier data set on disk: the layout of `presrs simulate --out`, and the stamp.
    for file in [
        "manifest.csv",
        "truth/hops.csv",
        "truth/trials.json",
        "config.json",
        "table1.csv",
        "stamp.json",
    ] {
        assert!(heavy.join(file).is_file(), "{file}");
    }
    let movies = std::fs::read_dir(heavy.join("recordings")).unwrap().count();
    assert_eq!(movies, 12, "one movie per terrain and gait");
    let stamp = read_json(&heavy.join("stamp.json"));
    assert_eq!(stamp["made_from"]["seed"], 1_000_008);
    assert_eq!(stamp["made_from"]["hops_per_gait"], 4);
    assert_eq!(stamp["made_from"]["load_kg"], 3.25);
    assert_eq!(stamp["made_from"]["presrs_version"], version());

    // 2. Same seed: both data sets read back, the same results.
    let (second_out, second) = reproduce(&dir, 5, &[]);
    assert!(
        second_out.contains(&format!("reusing {} (seed 5,", data.display())),
        "{second_out}"
    );
    assert!(
        second_out.contains(&format!("reusing {} (seed 1000008,", heavy.display())),
        "{second_out}"
    );
    assert!(!second_out.contains("simulating"), "{second_out}");
    assert_eq!(second["datasets"]["load"]["reused"], true);
    assert_eq!(data_results(&first), data_results(&second));

    // 3. A corrupt stamp and a missing movie: simulated afresh, with the reason; the fresh data sets give
    //    the same results as the reused ones.
    std::fs::write(data.join("stamp.json"), "{\"format\": 1, \"made_fr").unwrap();
    std::fs::remove_file(heavy.join("recordings/clay_G2_000.asf")).unwrap();
    let (broken_out, broken) = reproduce(&dir, 5, &[]);
    assert!(
        broken_out.contains(&format!(
            "simulating {} (seed 5, 2.5 kg): {} is corrupt",
            data.display(),
            data.join("stamp.json").display()
        )),
        "{broken_out}"
    );
    assert!(
        broken_out.contains(&format!(
            "simulating {} (seed 1000008, 3.25 kg): {} is missing",
            heavy.display(),
            heavy.join("recordings/clay_G2_000.asf").display()
        )),
        "{broken_out}"
    );
    assert_eq!(broken["datasets"]["main"]["reused"], false);
    assert_eq!(data_results(&second), data_results(&broken));
    assert!(heavy.join("recordings/clay_G2_000.asf").is_file());
    assert_eq!(read_json(&data.join("stamp.json"))["made_from"]["seed"], 5);

    // 4. Another seed: not reused, and the reason is said.
    let (other_out, other) = reproduce(&dir, 6, &[]);
    assert!(
        other_out.contains(&format!(
            "simulating {} (seed 6, 2.5 kg): it was made with seed 5, not 6",
            data.display()
        )),
        "{other_out}"
    );
    assert!(
        other_out.contains("it was made with seed 1000008, not 1000009"),
        "{other_out}"
    );
    assert_ne!(first["table1"], other["table1"]);

    // 5. --resimulate: simulated although the data sets match, the same results.
    let (again_out, again) = reproduce(&dir, 6, &["--resimulate"]);
    assert!(
        again_out.contains(&format!(
            "simulating {} (seed 6, 2.5 kg): --resimulate",
            data.display()
        )),
        "{again_out}"
    );
    assert!(!again_out.contains("reusing"), "{again_out}");
    assert_eq!(data_results(&other), data_results(&again));
}

#[test]
fn options_that_cannot_work_are_refused_before_simulating() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("r");
    let out_s = out.to_str().unwrap();
    for (args, says) in [
        (&["--hops-per-gait", "0"][..], "--hops-per-gait"),
        // Fewer hops than training images drawn per terrain (the default --per-class 20).
        (&["--hops-per-gait", "3"], "--per-class 20"),
        (
            &[
                "--hops-per-gait",
                "5",
                "--per-class",
                "6",
                "--validation",
                "2",
            ],
            "give --hops-per-gait 6 or more, or a --per-class of at most 5 with a smaller --validation (now 2)",
        ),
        (
            &[
                "--hops-per-gait",
                "4",
                "--per-class",
                "3",
                "--validation",
                "3",
            ],
            "--validation 3 must be smaller than --per-class 3",
        ),
        // The test hopper weighs nominal x (1 + extra load): it must stay above 0.
        (&["--hops-per-gait", "4", "--extra-load=-1"], "--extra-load"),
        (
            &["--hops-per-gait", "4", "--extra-load", "nan"],
            "--extra-load",
        ),
        (&["--hops-per-gait", "4", "--repeats", "0"], "--repeats"),
    ] {
        let mut all = vec!["reproduce", "--out", out_s];
        all.extend(args);
        let output = presrs(&all);
        assert_eq!(
            output.status.code(),
            Some(2),
            "{args:?}: {}",
            stderr(&output)
        );
        assert!(
            stderr(&output).contains(says),
            "{args:?}: {}",
            stderr(&output)
        );
        assert!(!out.join("dataset").exists(), "{args:?} simulated");
    }
}
