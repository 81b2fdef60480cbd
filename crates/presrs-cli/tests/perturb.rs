//! Sensor faults: `presrs eval --perturb KIND=LEVEL` (accuracy with faulty test images, next to the clean
//! run) and the dead sensels `presrs inspect` reports.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers outside #[test] functions

mod common;
use common::presrs;
use std::path::{Path, PathBuf};

use presrs_core::testing::{SYNTHETIC_CLASSES, synthetic_frame};
use presrs_core::{Recording, SensorMeta};
use rand::SeedableRng;

/// 72 single-frame NPY files of the four synthetic classes over three conditions, and their manifest.
fn dataset(dir: &Path) -> PathBuf {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let mut manifest = String::from("path,label,condition\n");
    for i in 0..72 {
        let class = i % 4;
        let name = format!("f{i}.npy");
        let rec =
            Recording::from_frame(synthetic_frame(class, &mut rng), SensorMeta::default()).unwrap();
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
        "--perturb",
        "load=1e308",
        "--json",
        "--report",
        dir.path().join("report").to_str().unwrap(),
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
    assert_eq!(rows.len(), 5);
    // Loads pushed past f64's range cannot be classified: each test image counts as wrong, and the
    // row says how many there were; every other row classified all of its images.
    let unclassified = |name: &str| {
        rows.iter().find(|r| r["perturbation"] == name).unwrap()["unclassified"]
            .as_u64()
            .unwrap()
    };
    assert!(unclassified("load=1e308") > 0, "{rows:?}");
    assert_eq!(accuracy("load=1e308"), 0.0, "{rows:?}");
    for name in ["none", "load=1", "dead=1", "noise=0.5"] {
        assert_eq!(unclassified(name), 0, "{name}: {rows:?}");
    }
    // The clean row is the main result; a factor-1 load is no change at all.
    assert_eq!(accuracy("none"), json["overall_accuracy"].as_f64().unwrap());
    assert_eq!(accuracy("load=1"), accuracy("none"));
    assert!(accuracy("none") > 0.8, "{rows:?}");
    // Every sensel dead: blank images cannot be told apart.
    assert!(accuracy("dead=1") <= 0.5, "{rows:?}");
    assert!(rows.iter().all(|r| r["method"] == "configured"));
    // The report charts accuracy against fault level, with the same numbers.
    let html = std::fs::read_to_string(dir.path().join("report/index.html")).unwrap();
    assert!(dir.path().join("report/fault_sweep.png").is_file());
    let row = html.split("<tr><td>noise=0.5</td>").nth(1).unwrap();
    let noise = rows
        .iter()
        .find(|r| r["perturbation"] == "noise=0.5")
        .unwrap();
    let expected = format!(
        "<td>{:.1} % ± {:.1}</td>",
        100.0 * noise["accuracy"].as_f64().unwrap(),
        100.0 * noise["accuracy_std"].as_f64().unwrap()
    );
    assert!(row.starts_with(&expected), "{expected}");

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
        "--perturb",
        "load=1e308",
    ]);
    let stdout = String::from_utf8_lossy(&text.stdout);
    assert!(
        stdout.contains("accuracy with perturbed test images") && stdout.contains("shift=1,1"),
        "{stdout}"
    );
    assert!(
        stdout.contains("load=1e308: ")
            && stdout.contains("could not be classified by this pipeline"),
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

/// With an automatic part, the rows named `paper` are the paper's method (fft1d + pwe) even when the
/// other part is fixed: here the features are automatic and the classifier mle, and the paper rows
/// equal the rows of an explicit fft1d + pwe run with the same draws (they were fft1d + mle's).
#[test]
fn the_paper_rows_next_to_an_automatic_choice_are_the_paper_method() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = dataset(dir.path());
    let rows = |pipeline: &[&str], method: &str| {
        let mut args = vec![
            "eval",
            "--manifest",
            manifest.to_str().unwrap(),
            "--train-condition",
            "G2",
            "--validation",
            "3",
            "--repeats",
            "2",
            "--dims",
            "10",
            "--perturb",
            "dead=0.1",
            "--perturb",
            "rotate=10",
            "--json",
        ];
        args.extend_from_slice(pipeline);
        let out = presrs(&args);
        assert_eq!(
            out.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        json["perturbations"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|r| r["method"] == method)
            .map(|r| (r["perturbation"].clone(), r["accuracy"].clone()))
            .collect::<Vec<_>>()
    };
    let paper = rows(&["--classifier", "mle"], "paper");
    let explicit = rows(
        &["--features", "fft1d", "--classifier", "pwe"],
        "configured",
    );
    assert_eq!(paper.len(), 3);
    assert_eq!(paper, explicit);
}

/// The real F-Scan insole export (60 x 21, 205 frames, absent sensels outside the insole).
fn real_file() -> PathBuf {
    PathBuf::from(format!(
        "{}/../../../shared/data/tekscan/FrasP01L.asf",
        env!("CARGO_MANIFEST_DIR")
    ))
}

fn dead_of(json: &serde_json::Value) -> Vec<(u64, u64)> {
    json["dead_sensels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| (d["row"].as_u64().unwrap(), d["col"].as_u64().unwrap()))
        .collect()
}

#[test]
fn inspect_reports_dead_sensels() {
    // The real file has none: its silent sensels sit on the insole's outline or in the arch, where
    // their neighbours read zero too in all but a frame or two.
    let real = real_file();
    let out = presrs(&["inspect", "--json", real.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(dead_of(&json), []);

    // The same file with its most loaded sensel killed in every frame: found, and filled on reading.
    let rec = presrs_io::read_recording(&real).unwrap();
    let grid = rec.grid();
    let (r, c) = most_loaded(&rec);
    let mut data = rec.data().to_vec();
    for frame in data.chunks_exact_mut(grid.len()) {
        frame[r * grid.cols + c] = 0.0;
    }
    let killed = Recording::with_info(
        grid,
        rec.frame_period_s(),
        data,
        rec.present().map(<[bool]>::to_vec),
        rec.frame_info().to_vec(),
        rec.meta.clone(),
    )
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("killed.asf");
    presrs_io::tekscan::write_tekscan_file(&killed, &path).unwrap();
    let out = presrs(&["inspect", "--json", path.to_str().unwrap()]);
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(dead_of(&json), [(r as u64, c as u64)]);
    assert_eq!(json["dead_sensels_filled"], true);
    let out = presrs(&[
        "inspect",
        "--json",
        "--keep-dead-sensels",
        path.to_str().unwrap(),
    ]);
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["dead_sensels_filled"], false);

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
    assert!(stdout.contains("filled from their neighbours"), "{stdout}");
    // One image of it: reported, but not filled.
    let single = dir.path().join("single.asf");
    let rec = presrs_io::read_recording(&path).unwrap();
    let one =
        Recording::from_frame(rec.frame(5).unwrap().to_frame(), SensorMeta::default()).unwrap();
    presrs_io::tekscan::write_tekscan_file(&one, &single).unwrap();
    let out = presrs(&["inspect", single.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("not filled: 1 frame(s)"), "{stdout}");
    let clean = dir.path().join("clean.asf");
    let rec = Recording::from_frame(print, SensorMeta::default()).unwrap();
    presrs_io::tekscan::write_tekscan_file(&rec, &clean).unwrap();
    let out = presrs(&["inspect", clean.to_str().unwrap()]);
    assert!(!String::from_utf8_lossy(&out.stdout).contains("dead sensels"));
}

/// The present sensel with the largest total load over a recording (row, column).
fn most_loaded(rec: &Recording) -> (usize, usize) {
    let grid = rec.grid();
    let mut sums = vec![0.0; grid.len()];
    for frame in rec.data().chunks_exact(grid.len()) {
        for (s, v) in sums.iter_mut().zip(frame) {
            *s += v;
        }
    }
    let i = (0..grid.len())
        .max_by(|&a, &b| sums[a].total_cmp(&sums[b]))
        .unwrap();
    (i / grid.cols, i % grid.cols)
}

/// The feature vector `presrs features` prints for frame `frame` of `file`, and its stderr.
fn features_of(file: &Path, frame: usize, extra: &[&str]) -> (Vec<f64>, String) {
    let frame = frame.to_string();
    let mut args = vec![
        "features",
        file.to_str().unwrap(),
        "--frame",
        &frame,
        "--features",
        "fft1d",
    ];
    args.extend_from_slice(extra);
    let out = presrs(&args);
    assert_eq!(out.status.code(), Some(0), "{}", common::stderr(&out));
    let values = common::stdout(&out)
        .lines()
        .last()
        .unwrap()
        .split(',')
        .filter_map(|v| v.trim().parse::<f64>().ok())
        .collect();
    (values, common::stderr(&out))
}

#[test]
fn a_dead_sensel_in_a_movie_is_filled_before_classifying() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = dataset(dir.path());
    let model = dir.path().join("model.json");
    let out = presrs(&[
        "train",
        "--manifest",
        manifest.to_str().unwrap(),
        "--out",
        model.to_str().unwrap(),
        "--features",
        "fft1d",
        "--classifier",
        "pwe",
        "--validation",
        "3",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", common::stderr(&out));
    // Single images: nothing to fill, no note; the model records that correction was on.
    assert!(!common::stderr(&out).contains("dead sensel"));
    let saved: serde_json::Value = serde_json::from_slice(&std::fs::read(&model).unwrap()).unwrap();
    assert_eq!(
        saved["provenance"]["dead_sensels"],
        serde_json::json!({"corrected": true, "sensels": 0, "recordings": 0})
    );

    // A 6-frame movie of one "wood" print, and the same with its most loaded sensel dead.
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(99);
    let print = synthetic_frame(3, &mut rng);
    let grid = print.grid();
    let movie = |dead: Option<(usize, usize)>| {
        let mut data = Vec::new();
        for _ in 0..6 {
            let mut frame = print.values().to_vec();
            if let Some((r, c)) = dead {
                frame[r * grid.cols + c] = 0.0;
            }
            data.extend(frame);
        }
        Recording::new(grid, Some(0.01), data, None, SensorMeta::default()).unwrap()
    };
    let clean_rec = movie(None);
    let (r, c) = most_loaded(&clean_rec);
    let clean = dir.path().join("clean.npy");
    let faulty = dir.path().join("faulty.npy");
    presrs_io::npy::write_recording_npy(&clean_rec, &clean).unwrap();
    presrs_io::npy::write_recording_npy(&movie(Some((r, c))), &faulty).unwrap();

    let out = presrs(&[
        "classify",
        "--model",
        model.to_str().unwrap(),
        "--frame",
        "3",
        "--json",
        clean.to_str().unwrap(),
        faulty.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", common::stderr(&out));
    assert!(
        common::stderr(&out).contains("note: filled 1 dead sensel in 1 recording"),
        "{}",
        common::stderr(&out)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let results = json["results"].as_array().unwrap();
    assert_eq!(results[0]["label"], SYNTHETIC_CLASSES[3]);
    assert_eq!(results[1]["label"], SYNTHETIC_CLASSES[3]);

    // What the classifier sees: the filled sensel brings the features back near the clean ones.
    let (reference, _) = features_of(&clean, 3, &[]);
    let (filled, note) = features_of(&faulty, 3, &[]);
    let (kept, kept_note) = features_of(&faulty, 3, &["--keep-dead-sensels"]);
    assert!(note.contains("filled 1 dead sensel"), "{note}");
    assert!(!kept_note.contains("dead sensel"), "{kept_note}");
    let distance = |a: &[f64], b: &[f64]| {
        assert_eq!(a.len(), b.len());
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    let (d_filled, d_kept) = (distance(&filled, &reference), distance(&kept, &reference));
    assert!(d_filled < 0.25 * d_kept, "{d_filled} vs {d_kept}");
}
