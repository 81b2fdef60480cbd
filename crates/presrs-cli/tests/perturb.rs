//! `presrs eval --perturb KIND=LEVEL`: accuracy with faulty test images, next to the clean run.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers outside #[test] functions

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use presrs_core::pipeline::{SYNTHETIC_CLASSES, synthetic_frame};
use presrs_core::{Recording, SensorMeta};
use rand::SeedableRng;

fn presrs(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_presrs"))
        .args(args)
        .stdin(Stdio::null())
        .output()
        .expect("the presrs binary runs")
}

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
