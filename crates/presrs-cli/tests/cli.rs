//! End-to-end tests of the `presrs` binary: a new user's path from files to a model to labels, and the
//! errors a user sees for bad input.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers outside #[test] functions

mod common;
use common::{presrs, stderr, stdout};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use presrs_core::pipeline::{SYNTHETIC_CLASSES, synthetic_frame};
use presrs_core::{Frame, Grid, Recording, SensorMeta};
use rand::SeedableRng;

fn shared(name: &str) -> String {
    format!(
        "{}/../../../shared/data/tekscan/{name}",
        env!("CARGO_MANIFEST_DIR")
    )
}

/// A movie of `stances` stance phases of one class: 14 loaded frames (half-sine load on a synthetic
/// foot print) separated by 10 unloaded frames, at 100 Hz.
fn movie(class: usize, stances: usize, rng: &mut rand_chacha::ChaCha8Rng) -> Recording {
    let grid = Grid::new(44, 44);
    let mut data = Vec::new();
    data.extend(std::iter::repeat_n(0.0, 10 * grid.len()));
    for _ in 0..stances {
        let print = synthetic_frame(class, rng);
        for k in 0..14 {
            let scale = (std::f64::consts::PI * (k as f64 + 0.5) / 14.0).sin();
            data.extend(print.values().iter().map(|v| (v * scale).round()));
        }
        data.extend(std::iter::repeat_n(0.0, 10 * grid.len()));
    }
    Recording::new(grid, Some(0.01), data, None, SensorMeta::default()).unwrap()
}

/// A dataset folder: single-frame PNG, NPY and text files plus TekScan movies, and its manifest.
fn dataset(dir: &Path) -> PathBuf {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(42);
    let mut manifest = String::from("path,label,condition,group,frame,load\n");
    for i in 0..96 {
        let class = i % 4;
        let label = SYNTHETIC_CLASSES[class];
        let frame: Frame = synthetic_frame(class, &mut rng);
        let condition = ["G1", "G2", "G3"][i % 3];
        let name = match i % 3 {
            0 => {
                let name = format!("img{i}.png");
                presrs_io::png::write_frame_png(frame.view(), Some(255.0), &dir.join(&name))
                    .unwrap();
                name
            }
            1 => {
                let name = format!("img{i}.npy");
                let rec = Recording::from_frame(frame, SensorMeta::default()).unwrap();
                presrs_io::npy::write_recording_npy(&rec, &dir.join(&name)).unwrap();
                name
            }
            _ => {
                let name = format!("img{i}.txt");
                let text: String = frame
                    .values()
                    .chunks(44)
                    .map(|row| {
                        row.iter()
                            .map(|v| v.to_string())
                            .collect::<Vec<_>>()
                            .join(" ")
                            + "\n"
                    })
                    .collect();
                std::fs::write(dir.join(&name), text).unwrap();
                name
            }
        };
        manifest.push_str(&format!("{name},{label},{condition},,,\n"));
    }
    for class in 0..4 {
        let name = format!("movie_{}.asf", SYNTHETIC_CLASSES[class]);
        presrs_io::tekscan::write_tekscan_file(&movie(class, 6, &mut rng), &dir.join(&name))
            .unwrap();
        manifest.push_str(&format!(
            "{name},{},G4,trial{class},,\n",
            SYNTHETIC_CLASSES[class]
        ));
    }
    let path = dir.join("manifest.csv");
    std::fs::write(&path, manifest).unwrap();
    path
}

#[test]
fn train_then_classify_files_of_every_format() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = dataset(dir.path());
    let model = dir.path().join("model.json");
    let out = presrs(&[
        "train",
        "--manifest",
        manifest.to_str().unwrap(),
        "--out",
        model.to_str().unwrap(),
        "--per-class",
        "20",
        "--validation",
        "7",
        "--seed",
        "3",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stdout(&out).contains("80 images (52 training + 28 validation)"),
        "{}",
        stdout(&out)
    );
    // without --features/--classifier the method is chosen automatically and the choice is printed
    assert!(stdout(&out).contains("chosen: "), "{}", stdout(&out));
    let saved: serde_json::Value = serde_json::from_slice(&std::fs::read(&model).unwrap()).unwrap();
    assert_eq!(saved["format"], "presrs-model");
    assert_eq!(saved["provenance"]["seed"], 3);
    assert_eq!(saved["provenance"]["train_counts"]["wood"], 13);

    // classify one file of each kind plus a movie (six stances -> six mid-stance samples)
    let files: Vec<String> = ["img0.png", "img1.npy", "img2.txt", "movie_grass.asf"]
        .iter()
        .map(|f| dir.path().join(f).display().to_string())
        .collect();
    let mut args = vec!["classify", "--model", model.to_str().unwrap(), "--json"];
    args.extend(files.iter().map(String::as_str));
    let out = presrs(&args);
    assert!(out.status.success(), "{}", stderr(&out));
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let results = doc["results"].as_array().unwrap();
    assert_eq!(results.len(), 3 + 6);
    let movie_frames: Vec<u64> = results[3..]
        .iter()
        .map(|r| r["frame"].as_u64().unwrap())
        .collect();
    // stance k starts at 10 + 24 k; its mid-stance frame is 6 frames later
    assert_eq!(
        movie_frames,
        (0..6).map(|k| 16 + 24 * k).collect::<Vec<u64>>()
    );
    let right = results[3..]
        .iter()
        .filter(|r| r["label"] == "grass")
        .count();
    assert!(right >= 5, "{results:?}");
    for r in results {
        let p: f64 = r["posteriors"]
            .as_object()
            .unwrap()
            .values()
            .map(|v| v.as_f64().unwrap())
            .sum();
        assert!((p - 1.0).abs() < 1e-9);
    }
}

#[test]
fn eval_reports_the_contract_fields() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = dataset(dir.path());
    let out = presrs(&[
        "eval",
        "--manifest",
        manifest.to_str().unwrap(),
        "--train-condition",
        "G2",
        "--per-class",
        "6",
        "--validation",
        "3",
        "--repeats",
        "2",
        "--dims",
        "20",
        "--json",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let overall = doc["overall_accuracy"].as_f64().unwrap();
    assert!((0.7..=1.0).contains(&overall), "{overall}");
    let per = doc["per_condition"].as_object().unwrap();
    assert_eq!(per.keys().collect::<Vec<_>>(), ["G1", "G2", "G3", "G4"]);
    assert!(doc["median_classify_ns"].as_u64().unwrap() > 0);
    assert_eq!(doc["confusion"]["labels"].as_array().unwrap().len(), 4);

    let out = presrs(&[
        "eval",
        "--manifest",
        manifest.to_str().unwrap(),
        "--leave-one-out",
        "condition",
        "--repeats",
        "1",
        "--dims",
        "10",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stdout(&out).contains("leave one `condition` out"),
        "{}",
        stdout(&out)
    );
}

#[test]
fn inspect_describes_the_shared_tekscan_files() {
    let out = presrs(&["inspect", &shared("FrasP01L.asf"), "--json"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        (doc["rows"].as_u64(), doc["cols"].as_u64()),
        (Some(60), Some(21))
    );
    assert_eq!(doc["frames"], 205);
    assert_eq!(doc["frame_period_s"], 0.032);
    assert_eq!(doc["units"], "KPa");
    let stances = doc["stances"].as_array().unwrap();
    let complete: Vec<_> = stances.iter().filter(|s| s["partial"] == false).collect();
    assert_eq!(complete.len(), 5);
    assert!(
        complete
            .iter()
            .all(|s| (22..=25).contains(&s["len"].as_u64().unwrap()))
    );
    assert_eq!(stances[0]["partial"], true);

    let out = presrs(&["inspect", &shared("example3.asf")]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = stdout(&out);
    assert!(
        text.contains("16 rows x 16 cols") && text.contains("frames         10 at 0.7 s"),
        "{text}"
    );
}

#[test]
fn features_prints_the_paper_vector_and_survives_a_closed_pipe() {
    let out = presrs(&["features", &shared("example3.asf"), "--frame", "3"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = stdout(&out);
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 2);
    // 16 x 16 = 256 values, padded to N = 256: 129 magnitudes, plus the frame column
    assert_eq!(lines[0].split(',').count(), 130);
    assert!(lines[1].starts_with("3,"));

    // `presrs features ... | head -c 20`: the reader goes away; presrs ends quietly
    let mut child = Command::new(env!("CARGO_BIN_EXE_presrs"))
        .args(["features", &shared("FrasP01L.asf"), "--stance-frame", "all"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut pipe = child.stdout.take().unwrap();
    let mut buf = [0u8; 20];
    std::io::Read::read_exact(&mut pipe, &mut buf).unwrap();
    drop(pipe);
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "{:?} {}", out.status, stderr(&out));
    assert!(stderr(&out).is_empty(), "{}", stderr(&out));
}

#[test]
fn bad_input_gets_a_clear_error_and_exit_code() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = dir.path().join("m.csv");
    std::fs::write(&manifest, "path,label,frame\nnope.png,wood,\n").unwrap();
    let model = dir.path().join("model.json");
    let out = presrs(&[
        "train",
        "--manifest",
        manifest.to_str().unwrap(),
        "--out",
        model.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let err = stderr(&out);
    assert!(
        err.contains("m.csv line 2") && err.contains("nope.png"),
        "{err}"
    );
    assert!(!model.exists());

    std::fs::write(&manifest, "path,label,frame\nimg.png,wood,x\n").unwrap();
    let out = presrs(&[
        "train",
        "--manifest",
        manifest.to_str().unwrap(),
        "--out",
        model.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        stderr(&out).contains("line 2: field `frame`"),
        "{}",
        stderr(&out)
    );

    let bad = dir.path().join("bad.asf");
    std::fs::write(
        &bad,
        "DATA_TYPE MOVIE\nROWS 2\nCOLS 3\nASCII_DATA @@\n\nFrame 1\n1,2,3\n4,5\n@@\n",
    )
    .unwrap();
    let out = presrs(&["inspect", bad.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let err = stderr(&out);
    assert!(err.contains("bad.asf line 8"), "{err}");

    let out = presrs(&[
        "classify",
        "--model",
        model.to_str().unwrap(),
        bad.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains("model.json"), "{}", stderr(&out));

    let out = presrs(&["train", "--no-such-option"]);
    assert_eq!(out.status.code(), Some(2));
}
