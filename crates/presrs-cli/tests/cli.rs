//! End-to-end tests of the `presrs` binary: a new user's path from files to a model to labels, and the
//! errors a user sees for bad input.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers outside #[test] functions

mod common;
use common::{presrs, stderr, stdout};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use presrs_core::testing::{SYNTHETIC_CLASSES, synthetic_frame};
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
    // How far the confidences can be trusted: the summary agrees with the full tally.
    let calibration = &doc["calibration"];
    let tally = &doc["report"]["reliability"];
    let bins = tally["bins"].as_array().unwrap();
    assert_eq!(bins.len(), 10);
    let count: u64 = bins.iter().map(|b| b["count"].as_u64().unwrap()).sum();
    let right: u64 = bins.iter().map(|b| b["right"].as_u64().unwrap()).sum();
    let confusion_total: u64 = doc["confusion"]["counts"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|row| row.as_array().unwrap().iter().map(|c| c.as_u64().unwrap()))
        .sum();
    assert_eq!(count, confusion_total);
    let sum: f64 = bins
        .iter()
        .map(|b| b["confidence_sum"].as_f64().unwrap())
        .sum();
    let mean = calibration["mean_confidence"].as_f64().unwrap();
    assert!((mean - sum / count as f64).abs() < 1e-9, "{calibration}");
    assert!((0.25..=1.0).contains(&mean), "{calibration}");
    let ece = calibration["expected_calibration_error"].as_f64().unwrap();
    let naive_ece: f64 = bins
        .iter()
        .map(|b| {
            (b["right"].as_u64().unwrap() as f64 - b["confidence_sum"].as_f64().unwrap()).abs()
        })
        .sum::<f64>()
        / count as f64;
    assert!(
        (ece - naive_ece).abs() < 1e-9 && (0.0..=1.0).contains(&ece),
        "{calibration}"
    );
    assert!(right as f64 / count as f64 >= 0.7);

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

    // The movies only: each trial is one terrain, so holding a trial out holds its label out too.
    let text = std::fs::read_to_string(&manifest).unwrap();
    let movies: String = text
        .lines()
        .filter(|line| line.starts_with("path,") || line.contains(",G4,"))
        .map(|line| format!("{line}\n"))
        .collect();
    let movies_manifest = dir.path().join("movies.csv");
    std::fs::write(&movies_manifest, movies).unwrap();
    let out = presrs(&[
        "eval",
        "--manifest",
        movies_manifest.to_str().unwrap(),
        "--leave-one-out",
        "group",
        "--classifier",
        "mle",
        "--repeats",
        "1",
        "--dims",
        "5",
        "--json",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(
        err.contains(&format!(
            "with group trial0 held out, its test images labelled {} cannot be recognised",
            SYNTHETIC_CLASSES[0]
        )),
        "{err}"
    );
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let never = doc["labels_never_trained"].as_object().unwrap();
    assert_eq!(never.len(), 4, "{never:?}");
    assert_eq!(never["trial2"], serde_json::json!([SYNTHETIC_CLASSES[2]]));
    assert_eq!(doc["overall_accuracy"], 0.0);
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
    assert_eq!(doc["units_stated"], true);
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
    // example3.asf has no UNITS line: raw counts, said to be assumed.
    assert!(
        text.contains("units          raw (assumed: the file states no unit)"),
        "{text}"
    );
    let out = presrs(&["inspect", &shared("example3.asf"), "--json"]);
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        (&doc["units"], &doc["units_stated"]),
        (&"raw".into(), &false.into())
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
fn a_closed_stderr_does_not_turn_messages_into_a_panic() {
    // `presrs ... 2>&1 | head -1` where the reader has gone: the error message (a missing file) goes
    // nowhere, and the exit code stays that of the run (1), not a panic's 101.
    let mut child = Command::new(env!("CARGO_BIN_EXE_presrs"))
        .args(["inspect", "/nonexistent/presrs-test.asf"])
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stderr.take());
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(1), "{status:?}");
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

/// Trains the paper's method quickly on `dataset` (fft1d + pwe, 10 per class, 10 components).
fn quick_model(dir: &Path, manifest: &Path) -> PathBuf {
    let model = dir.join("quick.model.json");
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
        "--per-class",
        "10",
        "--validation",
        "3",
        "--dims",
        "10",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    model
}

#[test]
fn classify_reports_a_bad_file_at_the_end_and_classifies_the_others() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = dataset(dir.path());
    let model = quick_model(dir.path(), &manifest);
    let file = |name: &str| dir.path().join(name).display().to_string();
    let (png, missing, movie) = (
        file("img0.png"),
        file("missing.png"),
        file("movie_grass.asf"),
    );
    let base = ["classify", "--model", model.to_str().unwrap()];

    // table: every readable file is classified, the missing one (second) is reported, exit 1
    let out = presrs(&[&base[..], &[png.as_str(), missing.as_str(), movie.as_str()]].concat());
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let text = stdout(&out);
    assert_eq!(text.lines().count(), 1 + 1 + 6, "{text}");
    assert!(
        text.contains("img0.png") && text.contains("movie_grass.asf"),
        "{text}"
    );
    let err = stderr(&out);
    assert!(err.contains("missing.png"), "{err}");
    assert!(
        err.lines()
            .last()
            .unwrap()
            .contains("1 of 3 file(s) could not be classified"),
        "{err}"
    );

    // --json: the document is still written, with the failure under `errors`
    let out = presrs(
        &[
            &base[..],
            &["--json", png.as_str(), missing.as_str(), movie.as_str()],
        ]
        .concat(),
    );
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(doc["results"].as_array().unwrap().len(), 1 + 6);
    let errors = doc["errors"].as_array().unwrap();
    assert_eq!(errors.len(), 1);
    assert_eq!(errors[0]["file"], missing.as_str());
    assert!(errors[0]["error"].as_str().unwrap().contains("missing.png"));
}

#[test]
fn classify_warns_when_the_frame_is_no_foot_contact() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = dataset(dir.path());
    let model = quick_model(dir.path(), &manifest);
    let movie = dir.path().join("movie_grass.asf").display().to_string();
    let base = ["classify", "--model", model.to_str().unwrap(), "--json"];

    // frames 0-9 are unloaded (before the first stance), 16 is the first mid-stance frame
    let out = presrs(&[&base[..], &[movie.as_str(), "--frame", "5"]].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let warning = doc["results"][0]["warning"].as_str().unwrap();
    assert!(
        warning.contains("frame 5 lies outside every stance phase")
            && warning.contains("total load 0"),
        "{warning}"
    );
    assert!(stderr(&out).contains("warning: "), "{}", stderr(&out));

    let out = presrs(&[&base[..], &[movie.as_str(), "--frame", "16"]].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(doc["results"][0].get("warning").is_none(), "{doc}");
    assert!(!stderr(&out).contains("warning"), "{}", stderr(&out));

    // an image without load
    let empty = dir.path().join("empty.txt");
    let row = vec!["0"; 44].join(" ") + "\n";
    std::fs::write(&empty, row.repeat(44)).unwrap();
    let out = presrs(&[&base[..], &[empty.to_str().unwrap()]].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(
        doc["results"][0]["warning"]
            .as_str()
            .unwrap()
            .contains("carries no load"),
        "{doc}"
    );
}

#[test]
fn bad_option_values_are_usage_errors_that_list_the_choices() {
    let usage = |args: &[&str], needles: &[&str]| {
        let out = presrs(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        for needle in needles {
            assert!(
                stderr(&out).contains(needle),
                "{args:?}: {needle}: {}",
                stderr(&out)
            );
        }
    };
    let train = ["train", "--manifest", "m.csv", "--out", "model.json"];
    let eval = ["eval", "--manifest", "m.csv"];
    usage(
        &[&train[..], &["--dims", "0"]].concat(),
        &["--dims", "at least 1"],
    );
    usage(
        &[&train[..], &["--per-class", "0"]].concat(),
        &["at least 1"],
    );
    usage(
        &[&eval[..], &["--per-class", "0"]].concat(),
        &["at least 1"],
    );
    usage(
        &[&eval[..], &["--repeats", "0"]].concat(),
        &["--repeats", "at least 1"],
    );
    usage(
        &[&eval[..], &["--leave-one-out", "label"]].concat(),
        &["cannot hold out `label`"],
    );
    usage(
        &[&train[..], &["--classifier", "foo"]].concat(),
        &["known: auto, pwe, mle, lda, svm, knn"],
    );
    usage(
        &[&train[..], &["--features", "fft1d+foo"]].concat(),
        &["\"foo\"", "known: auto, fft1d, fft2d, fft2d_polar, glcm"],
    );
    usage(
        &[&train[..], &["--crop", "foo"]].concat(),
        &["expected auto, none, paper"],
    );
    usage(&["features", "x.asf", "--crop", ""], &["the crop is empty"]);
    usage(
        &["features", "x.asf", "--crop", "  "],
        &["the crop is empty"],
    );
    usage(
        &["features", "x.asf", "--features", "auto"],
        &["name the families"],
    );
}

#[test]
fn train_says_when_dims_is_capped_and_what_pwe_needs_to_train() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = dataset(dir.path());
    let model = dir.path().join("m.json");
    let train = [
        "train",
        "--manifest",
        manifest.to_str().unwrap(),
        "--out",
        model.to_str().unwrap(),
        "--features",
        "fft1d",
        "--classifier",
        "pwe",
        "--per-class",
        "10",
    ];
    let out = presrs(&[&train[..], &["--validation", "3", "--dims", "100000"]].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    // 4 classes x 7 training images = 28: at most 27 components
    assert!(
        stderr(&out).contains("warning: --dims 100000: kept 27 principal components")
            && stdout(&out).contains("PCA 27 components"),
        "{}\n{}",
        stderr(&out),
        stdout(&out)
    );
    // without --dims, the default is lowered quietly
    let out = presrs(&[&train[..], &["--validation", "3"]].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(!stderr(&out).contains("--dims"), "{}", stderr(&out));

    std::fs::remove_file(&model).unwrap();
    let out = presrs(&[&train[..], &["--validation", "0"]].concat());
    assert_eq!(out.status.code(), Some(1));
    let err = stderr(&out);
    assert!(
        err.contains("--validation 0 leaves no validation images")
            && err.contains("pwe")
            && !err.contains("fixed sigma"),
        "{err}"
    );
    assert!(!model.exists());
    // The automatic choice tries pwe too: refused before any candidate is scored.
    let mut auto = train.to_vec();
    auto[8] = "auto";
    let out = presrs(&[&auto[..], &["--validation", "0"]].concat());
    assert_eq!(out.status.code(), Some(1));
    let err = stderr(&out);
    assert!(
        err.contains("--validation 0 leaves no validation images")
            && err.contains("automatic choice tries the Parzen window"),
        "{err}"
    );
    assert!(!model.exists());
}

#[test]
fn features_takes_every_family_train_takes() {
    let file = shared("example3.asf");
    let count = |features: &str| {
        let out = presrs(&["features", &file, "--frame", "3", "--features", features]);
        assert!(out.status.success(), "{features}: {}", stderr(&out));
        let text = stdout(&out);
        let header = text.lines().next().unwrap().to_owned();
        header.split(',').count() - 1
    };
    let (fft1d, glcm) = (count("fft1d"), count("glcm"));
    assert_eq!(fft1d, 129);
    assert!(count("fft2d") > 0 && count("fft2d_polar") > 0 && glcm > 0);
    assert_eq!(count("fft1d+glcm"), fft1d + glcm);
    let help = stdout(&presrs(&["features", "--help"]));
    for name in ["fft2d_polar", "glcm", "fft1d+glcm"] {
        assert!(help.contains(name), "{name}: {help}");
    }
}

#[test]
fn eval_json_has_no_rust_enum_tags() {
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
        "2",
        "--repeats",
        "1",
        "--dims",
        "10",
        "--features",
        "fft1d",
        "--classifier",
        "pwe",
        "--json",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let protocol = &doc["report"]["protocol"];
    assert_eq!(protocol["validation"], 2, "{protocol}");
    // the document reads back, and so does the tagged form earlier versions wrote
    let read: presrs_core::evaluation::Protocol = serde_json::from_value(protocol.clone()).unwrap();
    let mut old = protocol.clone();
    old["validation"] = serde_json::json!({"Count": 2});
    let read_old: presrs_core::evaluation::Protocol = serde_json::from_value(old).unwrap();
    assert_eq!(read, read_old);
    let fraction: presrs_core::split::ValidationSize =
        serde_json::from_value(serde_json::json!(0.35)).unwrap();
    assert_eq!(fraction, presrs_core::split::ValidationSize::Fraction(0.35));
    let old_fraction: presrs_core::split::ValidationSize =
        serde_json::from_value(serde_json::json!({"Fraction": 0.35})).unwrap();
    assert_eq!(old_fraction, fraction);
}

#[test]
fn inspect_and_frame_errors_read_well_on_a_single_float_image() {
    let dir = tempfile::tempdir().unwrap();
    let image = dir.path().join("one.txt");
    let row = (0..20)
        .map(|c| format!("{:.7}", 1.0 + c as f64 / 3.0))
        .collect::<Vec<_>>()
        .join(" ")
        + "\n";
    std::fs::write(&image, row.repeat(12)).unwrap();
    let file = image.to_str().unwrap();
    let out = presrs(&["inspect", file]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = stdout(&out);
    assert!(
        text.contains("frames         1 (frame period unknown)"),
        "{text}"
    );
    // the sum of 240 values with 7 decimals, printed to one decimal
    let load = text
        .lines()
        .find(|l| l.starts_with("total load"))
        .unwrap()
        .split_whitespace()
        .nth(2)
        .unwrap();
    assert_eq!(load.split('.').nth(1).map(str::len), Some(1), "{text}");
    let out = presrs(&["features", file, "--frame", "3"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        stderr(&out).contains("--frame 3 is past the end (1 frame, frame 0)"),
        "{}",
        stderr(&out)
    );
}

/// Runs presrs with `stdin` (a file) or none, its stdout closed before it writes anything, as in
/// `presrs ... | head -0`.
fn with_closed_stdout(args: &[&str], stdin: Option<&Path>) -> std::process::Output {
    let input = match stdin {
        Some(path) => Stdio::from(std::fs::File::open(path).unwrap()),
        None => Stdio::null(),
    };
    let mut child = Command::new(env!("CARGO_BIN_EXE_presrs"))
        .args(args)
        .stdin(input)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    child.wait_with_output().unwrap()
}

#[test]
fn every_writing_command_ends_quietly_on_a_closed_pipe() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = dataset(dir.path());
    let model = quick_model(dir.path(), &manifest);
    let model = model.to_str().unwrap();
    let movie = dir.path().join("movie_grass.asf");
    let movie_name = movie.display().to_string();
    let fras = shared("FrasP01L.asf");
    let runs: Vec<(Vec<&str>, Option<&Path>)> = vec![
        (vec!["inspect", &fras], None),
        (vec!["inspect", &fras, "--json"], None),
        (vec!["features", &fras, "--stance-frame", "all"], None),
        (vec!["classify", "--model", model, &movie_name], None),
        (
            vec!["classify", "--model", model, &movie_name, "--json"],
            None,
        ),
        (vec!["stream", "--model", model], Some(movie.as_path())),
    ];
    for (args, stdin) in runs {
        let out = with_closed_stdout(&args, stdin);
        let code = out.status.code();
        assert!(
            matches!(code, Some(0 | 141)),
            "{args:?}: {code:?} {}",
            stderr(&out)
        );
        assert!(
            !stderr(&out).contains("error:"),
            "{args:?}: {}",
            stderr(&out)
        );
    }
}

#[test]
fn a_time_last_npy_is_named_and_read_with_axes() {
    // rows x cols x frames = 20 x 10 x 90: read frames-first it would be 20 frames of 10 x 90.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("walk.npy");
    let data: Vec<f64> = (0..20 * 10 * 90).map(|i| f64::from(i % 7)).collect();
    let file = std::fs::File::create(&path).unwrap();
    presrs_io::npy::write_npy_f64(file, &[20, 10, 90], &data).unwrap();
    let name = path.to_str().unwrap();
    let out = presrs(&["inspect", name, "--json"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(doc["frames"], 20);
    let warnings = doc["warnings"].to_string();
    assert!(warnings.contains("--axes rows,cols,frames"), "{warnings}");
    let out = presrs(&["inspect", name, "--json", "--axes", "rows,cols,frames"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        (&doc["frames"], &doc["rows"], &doc["cols"]),
        (&90.into(), &20.into(), &10.into())
    );
    assert!(!doc["warnings"].to_string().contains("--axes"));
    let out = presrs(&["inspect", name, "--axes", "rows,cols"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
}

#[test]
fn inspect_gives_the_load_in_the_recordings_unit_and_in_newtons() {
    // kPa with a 5.08 mm pitch: the sum in kPa, and the force in newtons as plot --movie draws it.
    let out = presrs(&["inspect", &shared("FrasP01L.asf")]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = stdout(&out);
    let line = |start: &str| {
        text.lines()
            .find(|l| l.starts_with(start))
            .unwrap_or_else(|| panic!("no {start:?} in {text}"))
            .to_owned()
    };
    assert!(
        line("total load")
            .to_lowercase()
            .contains("kpa summed over sensels"),
        "{text}"
    );
    assert!(line("total force").ends_with("N (pressure x sensel area, as plot --movie draws it)"));
    let out = presrs(&["inspect", &shared("FrasP01L.asf"), "--json"]);
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let (load, force) = (
        doc["load_max"].as_f64().unwrap(),
        doc["force_max_n"].as_f64().unwrap(),
    );
    assert!(
        (force - load * 5.08 * 5.08 * 1e-3).abs() < 1e-6 * force,
        "{load} {force}"
    );
    // Raw counts, no pitch: the sum in raw counts and no force.
    let out = presrs(&["inspect", &shared("example3.asf")]);
    let text = stdout(&out);
    assert!(text.contains("raw counts summed over sensels"), "{text}");
    assert!(!text.contains("total force"), "{text}");
}

#[test]
fn the_classify_table_stays_aligned_with_long_paths() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = dataset(dir.path());
    let model = quick_model(dir.path(), &manifest);
    let deep = dir
        .path()
        .join("a-rather-long-folder-name-for-the-recordings/of/one/session");
    std::fs::create_dir_all(&deep).unwrap();
    let long = deep.join("movie_grass.asf");
    std::fs::copy(dir.path().join("movie_grass.asf"), &long).unwrap();
    let short = dir.path().join("img0.png");
    let out = presrs(&[
        "classify",
        "--model",
        model.to_str().unwrap(),
        short.to_str().unwrap(),
        long.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = stdout(&out);
    // Every row's columns are where the header's are: the frame number ends under "frame", the label
    // starts under "label".
    let header = text.lines().next().unwrap();
    let frame_end = header.find("frame").unwrap() + "frame".len();
    let label_at = header.find("label").unwrap();
    assert_eq!(text.lines().count(), 1 + 1 + 6, "{text}");
    for line in text.lines().skip(1) {
        let bytes = line.as_bytes();
        assert!(bytes[frame_end - 1].is_ascii_digit(), "{text}");
        assert_eq!(&line[frame_end..label_at], "  ", "{text}");
        assert_ne!(bytes[label_at], b' ', "{text}");
    }
}

#[test]
fn the_feature_csv_header_names_what_each_column_is() {
    let file = shared("example3.asf");
    let header = |features: &str| {
        let out = presrs(&["features", &file, "--frame", "3", "--features", features]);
        assert!(out.status.success(), "{}", stderr(&out));
        stdout(&out).lines().next().unwrap().to_owned()
    };
    let fft1d = header("fft1d");
    assert!(fft1d.starts_with("frame,fft1d_bin0,fft1d_bin1,"), "{fft1d}");
    assert!(fft1d.ends_with(",fft1d_bin128"), "{fft1d}");
    let both = header("fft2d_polar+glcm");
    assert!(both.starts_with("frame,fft2d_polar_ring0,"), "{both}");
    assert!(both.contains(",fft2d_polar_wedge0,"), "{both}");
    assert!(both.ends_with(",glcm_entropy_d5"), "{both}");
    assert!(header("fft2d").starts_with("frame,fft2d_r0_c0,fft2d_r0_c1,"));
}

#[test]
fn a_report_on_a_users_images_speaks_of_that_data() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = dataset(dir.path());
    let model = quick_model(dir.path(), &manifest);
    // The single images alone, without conditions.
    let text = std::fs::read_to_string(&manifest).unwrap();
    let mut images = String::from("path,label\n");
    for line in text.lines().skip(1).filter(|l| l.starts_with("img")) {
        let fields: Vec<&str> = line.split(',').collect();
        images.push_str(&format!("{},{}\n", fields[0], fields[1]));
    }
    let manifest = dir.path().join("images.csv");
    std::fs::write(&manifest, images).unwrap();
    let out_dir = dir.path().join("report");
    let out = presrs(&[
        "report",
        "--manifest",
        manifest.to_str().unwrap(),
        "--model",
        model.to_str().unwrap(),
        "--fault-repeats",
        "0",
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let html = std::fs::read_to_string(out_dir.join("index.html")).unwrap();
    assert!(html.contains("96 single image(s)"), "what the data are");
    for wrong in [
        "stance of a movie",
        "Fig. 5",
        "Fig. 6",
        "the paper's",
        "Margins {",
        "Window {",
        "<th>overall</th>",
    ] {
        assert!(
            !html.contains(wrong),
            "{wrong:?} in the report on a user's images"
        );
    }
    // One tested condition: one accuracy column.
    assert!(html.contains("<th>evaluation</th><th>all</th></tr>"));
}
