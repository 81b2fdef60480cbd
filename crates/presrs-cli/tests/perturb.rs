//! Sensor faults: `presrs eval --perturb KIND=LEVEL` (accuracy with faulty test images, next to the clean
//! run) and the dead sensels `presrs inspect` reports.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers outside #[test] functions

mod common;
use common::presrs;
use std::path::{Path, PathBuf};

use presrs_core::pipeline::{SYNTHETIC_CLASSES, synthetic_frame};
use presrs_core::{Recording, SensorMeta};
use rand::SeedableRng;

/// 72 single-frame NPY files of the four synthetic classes over three conditions, and their manifest.
fn dataset(dir: &Path) -> PathBuf {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let mut manifest = String::from("path,label,condition\n");
    for i in 0..72 {
        let class = i % 4;
        let name = format!("f{i}.npy");
        let rec = Recording::from_frame(synthetic_frame(class, &mut rng), SensorMeta::default());
        presrs_io::npy::write_recording_npy(&rec, &dir.join(&name)).unwrap();
        let condition = ["G1", "G2", "G3"][(i / 4) % 3];
        manifest.push_str(&format!(
            "{name},{},{condition}\n",
            SYNTHETIC_CLASSES[class]
        ));
    }
    let path = dir.join("manifest.csv");
    std::fs::write(&path, manifest).unwrap();
    path
}

#[test]
fn eval_reports_accuracy_under_each_perturbation() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = dataset(dir.path());
    let out = presrs(&[
        "eval",
        "--manifest",
        manifest.to_str().unwrap(),
        "--train-condition",
        "G2",
        "--validation",
        "3",
        "--repeats",
        "2",
        "--features",
        "fft1d",
        "--classifier",
        "pwe",
        "--perturb",
        "load=1",
        "--perturb",
        "dead=1",
        "--perturb",
        "noise=0.5",
        "--json",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let rows = json["perturbations"].as_array().unwrap();
    let accuracy = |name: &str| {
        rows.iter()
            .find(|r| r["perturbation"] == name)
            .unwrap_or_else(|| panic!("no row {name}: {rows:?}"))["accuracy"]
            .as_f64()
            .unwrap()
    };
    assert_eq!(rows.len(), 4);
    // The clean row is the main result; a factor-1 load is no change at all.
    assert_eq!(accuracy("none"), json["overall_accuracy"].as_f64().unwrap());
    assert_eq!(accuracy("load=1"), accuracy("none"));
    assert!(accuracy("none") > 0.8, "{rows:?}");
    // Every sensel dead: blank images cannot be told apart.
    assert!(accuracy("dead=1") <= 0.5, "{rows:?}");
    assert!(rows.iter().all(|r| r["method"] == "configured"));

    // The table form, and a bad level is a usage error.
    let text = presrs(&[
        "eval",
        "--manifest",
        manifest.to_str().unwrap(),
        "--train-condition",
        "G2",
        "--validation",
        "3",
        "--repeats",
        "1",
        "--features",
        "fft1d",
        "--classifier",
        "pwe",
        "--perturb",
        "shift=1,1",
    ]);
    let stdout = String::from_utf8_lossy(&text.stdout);
    assert!(
        stdout.contains("accuracy with perturbed test images") && stdout.contains("shift=1,1"),
        "{stdout}"
    );
    let bad = presrs(&[
        "eval",
        "--manifest",
        manifest.to_str().unwrap(),
        "--perturb",
        "dead=2",
    ]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("between 0 and 1"));
}

#[test]
fn inspect_reports_dead_sensels() {
    // The real F-Scan insole export: three sensels stay at 0 while the load covers them.
    let real = format!(
        "{}/../../../shared/data/tekscan/FrasP01L.asf",
        env!("CARGO_MANIFEST_DIR")
    );
    let out = presrs(&["inspect", "--json", &real]);
    assert_eq!(out.status.code(), Some(0));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let dead: Vec<(u64, u64)> = json["dead_sensels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| (d["row"].as_u64().unwrap(), d["col"].as_u64().unwrap()))
        .collect();
    assert_eq!(dead, [(16, 9), (17, 7), (37, 1)]);

    // A synthetic movie with one sensel killed inside the foot print, in the table form.
    let dir = tempfile::tempdir().unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let print = synthetic_frame(0, &mut rng);
    let grid = print.grid();
    let (r, c) = (0..grid.len())
        .map(|i| (i / grid.cols, i % grid.cols))
        .max_by(|a, b| {
            let v = |p: &(usize, usize)| print.view().get(p.0, p.1);
            v(a).total_cmp(&v(b))
        })
        .unwrap();
    let mut data = Vec::new();
    for k in 0..6 {
        data.extend(print.values().iter().map(|v| (v * (k + 1) as f64).round()));
        data[k * grid.len() + r * grid.cols + c] = 0.0;
    }
    let rec = Recording::new(grid, Some(0.01), data, None, SensorMeta::default()).unwrap();
    let path = dir.path().join("dead.asf");
    presrs_io::tekscan::write_tekscan_file(&rec, &path).unwrap();
    let out = presrs(&["inspect", path.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains(&format!(
            "dead sensels   1 at row, col (0-based) ({r}, {c})"
        )),
        "{stdout}"
    );
    let clean = dir.path().join("clean.asf");
    let rec = Recording::from_frame(print, SensorMeta::default());
    presrs_io::tekscan::write_tekscan_file(&rec, &clean).unwrap();
    let out = presrs(&["inspect", clean.to_str().unwrap()]);
    assert!(!String::from_utf8_lossy(&out.stdout).contains("dead sensels"));
}
