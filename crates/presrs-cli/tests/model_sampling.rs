//! A model remembers how its samples were taken and the sensor they came from (issues #45 and #43),
//! through the command line: a whole-stance model trained on one-contact trials (`real/jiku-walk`,
//! read in place from the shared data folder) classifies such a trial, streams a walk step by step,
//! and refuses a movie of another sensor; `classify` that classifies nothing fails; profile files are
//! checked, and `ros2` takes `--calibrate`; a series model given a movie says it takes series.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::OnceLock;

use common::{presrs, stderr, stdout, train_one_contact_stance_model};
use serde_json::Value;

fn shared(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data")
        .join(path)
}

/// Runs `presrs` with `args`, `input` on stdin.
fn presrs_with_input(args: &[&str], input: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_presrs"))
        .args(args)
        .stdin(std::fs::File::open(input).unwrap())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .output()
        .unwrap()
}

fn json_lines(text: &str) -> Vec<Value> {
    text.lines()
        .filter_map(|line| serde_json::from_str(line).ok())
        .collect()
}

/// A movie of `frames` frames of `rows x cols`: a load rising and falling.
fn write_movie(path: &Path, frames: usize, (rows, cols): (usize, usize)) {
    let mut values = Vec::with_capacity(frames * rows * cols);
    for t in 0..frames {
        let envelope = 1.0 + ((t as f64 + 0.5) / frames as f64 * std::f64::consts::PI).sin();
        values.extend((0..rows * cols).map(|k| envelope * (5.0 + (k % 7) as f64)));
    }
    let file = std::fs::File::create(path).unwrap();
    presrs_io::npy::write_npy_f64(file, &[frames, rows, cols], &values).unwrap();
}

/// A whole-stance model trained, as a new user would, on the first subject's one-contact trials:
/// `train --sample stance --one-sample-per-file` (MiniRocket + ridge, to be quick). Its folder is
/// kept for the test binary's life.
fn one_contact_model() -> &'static (tempfile::TempDir, PathBuf) {
    static MODEL: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();
    MODEL.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let jiku = shared("real/jiku-walk");
        let text = std::fs::read_to_string(jiku.join("manifest.csv")).unwrap();
        let mut rows = String::from("path,label,group\n");
        for line in text.lines().skip(1).filter(|line| line.starts_with("s00_")) {
            let fields: Vec<&str> = line.split(',').collect();
            let path = jiku.join(fields[0]);
            rows.push_str(&format!("{},{},{}\n", path.display(), fields[1], fields[3]));
        }
        let manifest = dir.path().join("manifest.csv");
        std::fs::write(&manifest, rows).unwrap();
        let model = dir.path().join("model.json");
        train_one_contact_stance_model(&manifest, &model);
        (dir, model)
    })
}

/// `classify` on a trial the model was trained on: one stance classified, without any option (it said
/// "no complete stance phase; nothing classified" and exited 0 before); the model file says how the
/// samples were taken and from which sensor.
#[test]
fn a_one_contact_model_classifies_its_own_trials() {
    let (_, model) = one_contact_model();
    let model = model.to_str().unwrap();
    let trial = shared("real/jiku-walk/s00_t00.npy");
    let out = presrs(&[
        "classify",
        "--model",
        model,
        trial.to_str().unwrap(),
        "--json",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let document: Value = serde_json::from_str(&stdout(&out)).unwrap();
    assert_eq!(
        document["results"].as_array().unwrap().len(),
        1,
        "{document}"
    );
    assert!(!stderr(&out).contains("warning"), "{}", stderr(&out));

    let file: Value = serde_json::from_str(&std::fs::read_to_string(model).unwrap()).unwrap();
    assert_eq!(
        file["model"]["sensor"],
        serde_json::json!({"rows": 63, "cols": 33})
    );
    assert_eq!(file["model"]["sampling"]["one_sample_per_file"], true);
}

/// A run in which no file gives a sample exits 1, after each file's warning, in the table and with
/// `--json` (its document still written).
#[test]
fn classify_that_classifies_nothing_fails() {
    let (dir, model) = one_contact_model();
    let short = dir.path().join("short.npy");
    write_movie(&short, 2, (63, 33));
    for json in [false, true] {
        let mut args = vec![
            "classify",
            "--model",
            model.to_str().unwrap(),
            short.to_str().unwrap(),
        ];
        if json {
            args.push("--json");
        }
        let out = presrs(&args);
        assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
        let log = stderr(&out);
        assert!(
            log.contains("short.npy: 2 frames but no complete stance phase; nothing classified")
                && log.contains("error: nothing classified: the file gave no sample"),
            "{log}"
        );
        if json {
            let document: Value = serde_json::from_str(&stdout(&out)).unwrap();
            assert_eq!(document["results"], serde_json::json!([]));
        }
    }
}

/// A stance model refuses a movie of another sensor in `classify` and `stream` (it classified a
/// 40 x 30 movie with a 63 x 33 model before), and training refuses a data set of two sensors.
#[test]
fn a_stance_model_refuses_another_sensor() {
    let (dir, model) = one_contact_model();
    let model = model.to_str().unwrap();
    let small = dir.path().join("small-sensor.npy");
    write_movie(&small, 60, (40, 30));
    let out = presrs(&["classify", "--model", model, small.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(
        stderr(&out).contains(
            "expected 63x33 frames, the sensor this whole-stance model was trained on, got 40x30"
        ),
        "{}",
        stderr(&out)
    );

    let bag = dir.path().join("small-sensor.mcap");
    let out = presrs(&["convert", small.to_str().unwrap(), bag.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    let out = presrs_with_input(&["stream", "--model", model, "--format", "mcap"], &bag);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let events = json_lines(&stdout(&out));
    let error = events.iter().find(|e| e["event"] == "error").unwrap();
    assert!(
        error["message"]
            .as_str()
            .unwrap()
            .contains("the sensor this whole-stance model was trained on"),
        "{error}"
    );

    let manifest = dir.path().join("mixed.csv");
    let trial = shared("real/jiku-walk/s00_t00.npy");
    std::fs::write(
        &manifest,
        format!(
            "path,label\n{},fast\n{},slow\n",
            trial.display(),
            small.display()
        ),
    )
    .unwrap();
    let out = presrs(&[
        "train",
        "--manifest",
        manifest.to_str().unwrap(),
        "--out",
        dir.path().join("mixed.json").to_str().unwrap(),
        "--sample",
        "stance",
        "--one-sample-per-file",
    ]);
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("small-sensor.npy` has 40x30 frames where `")
            && stderr(&out).contains("has 63x33: a stance model is trained on one sensor"),
        "{}",
        stderr(&out)
    );
}

/// The profile `train` writes for one-contact trials streams a walk of six of them (a swing of zeros
/// between) as six stances, each decided, with no warm-up (it took the walk for one stance before).
#[test]
fn a_walk_of_one_contact_trials_streams_step_by_step() {
    let (dir, model) = one_contact_model();
    let file: Value = serde_json::from_str(&std::fs::read_to_string(model).unwrap()).unwrap();
    assert_eq!(
        file["online"]["segment"]["baseline"], "drifting",
        "{}",
        file["online"]
    );
    let (rows, cols) = (63, 33);
    let mut values = Vec::new();
    let mut frames = 0;
    for k in 0..6 {
        let trial = shared(&format!("real/jiku-walk/s00_t{k:02}.npy"));
        let recording = presrs_io::read_recording(&trial).unwrap();
        values.extend(std::iter::repeat_n(0.0, 12 * rows * cols));
        frames += 12 + recording.frame_count();
        for frame in recording.frames() {
            values.extend_from_slice(frame.values());
        }
    }
    values.extend(std::iter::repeat_n(0.0, 12 * rows * cols));
    frames += 12;
    let walk = dir.path().join("walk.npy");
    let file = std::fs::File::create(&walk).unwrap();
    presrs_io::npy::write_npy_f64(file, &[frames, rows, cols], &values).unwrap();
    let bag = dir.path().join("walk.mcap");
    let out = presrs(&["convert", walk.to_str().unwrap(), bag.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));

    let model = model.to_str().unwrap();
    let out = presrs_with_input(&["stream", "--model", model, "--format", "mcap"], &bag);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(!stderr(&out).contains("warm-up"), "{}", stderr(&out));
    let events = json_lines(&stdout(&out));
    let count = |kind: &str| events.iter().filter(|e| e["event"] == kind).count();
    assert_eq!(count("touchdown"), 6, "{events:?}");
    assert_eq!(count("classification"), 6, "{events:?}");
}

/// `--profile` takes a profile file, checked: a model file is named as one, unknown and missing
/// fields are errors naming the file and the field; `ros2` takes `--calibrate` (it was refused by the
/// parser), read before the node joins the graph.
#[test]
fn profile_files_are_checked_and_ros2_takes_calibrate() {
    let (dir, model) = one_contact_model();
    let model = model.to_str().unwrap();
    let unknown = dir.path().join("unknown.json");
    std::fs::write(&unknown, r#"{"foo": 1}"#).unwrap();
    let missing = dir.path().join("missing.json");
    std::fs::write(&missing, r#"{"gait_table": {}}"#).unwrap();
    let cases = [
        (
            model,
            "is a model file, not an online profile: give it with --model",
        ),
        (
            unknown.to_str().unwrap(),
            "not an online profile: unknown field `foo`",
        ),
        (
            missing.to_str().unwrap(),
            "not an online profile: missing field `params`",
        ),
    ];
    let trial = shared("real/jiku-walk/s00_t00.npy");
    for (profile, says) in cases {
        for face in [
            vec!["stream", "--model", model, "--profile", profile],
            vec![
                "ros2",
                "--model",
                model,
                "--input",
                "pressure",
                "--profile",
                profile,
            ],
        ] {
            let out = presrs_with_input(&face, &trial);
            assert_eq!(out.status.code(), Some(1), "{face:?}: {}", stderr(&out));
            assert!(
                stderr(&out).contains(profile) && stderr(&out).contains(says),
                "{face:?}: {}",
                stderr(&out)
            );
        }
    }
    // `ros2 --calibrate` reads the manifest before joining: a missing one is named.
    let absent = dir.path().join("absent.csv");
    let out = presrs(&[
        "ros2",
        "--model",
        model,
        "--input",
        "pressure",
        "--calibrate",
        absent.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(stderr(&out).contains("absent.csv"), "{}", stderr(&out));
    let out = presrs(&["ros2", "--help"]);
    assert!(
        stdout(&out).contains("--calibrate <MANIFEST>"),
        "{}",
        stdout(&out)
    );
}

/// A series model given a movie says it takes series, in `classify` and `stream`.
#[test]
fn a_series_model_given_a_movie_says_it_takes_series() {
    let dir = tempfile::tempdir().unwrap();
    let mut rows = String::from("path,label,group\n");
    for k in 0..12 {
        let label = if k % 2 == 0 { "a" } else { "b" };
        let speed = if label == "a" { 0.3 } else { 0.9 };
        let values: Vec<f64> = (0..4 * 40)
            .map(|i| (speed * (i % 40) as f64 + (i / 40) as f64 + k as f64 * 0.1).sin())
            .collect();
        let path = dir.path().join(format!("s{k}.npy"));
        presrs_io::npy::write_npy_f64(std::fs::File::create(&path).unwrap(), &[4, 40], &values)
            .unwrap();
        rows.push_str(&format!("{},{label},g{}\n", path.display(), k % 3));
    }
    let manifest = dir.path().join("manifest.csv");
    std::fs::write(&manifest, rows).unwrap();
    let model = dir.path().join("series.json");
    let out = presrs(&[
        "train",
        "--manifest",
        manifest.to_str().unwrap(),
        "--out",
        model.to_str().unwrap(),
        "--sample",
        "series",
        "--features",
        "rocket",
        "--classifier",
        "ridge",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let model = model.to_str().unwrap();
    let movie = dir.path().join("movie.npy");
    write_movie(&movie, 60, (4, 40));
    let out = presrs(&["classify", "--model", model, movie.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("a movie of 60 frames of 4x40, but the model classifies series"),
        "{}",
        stderr(&out)
    );
    let bag = dir.path().join("movie.mcap");
    let other = dir.path().join("other.npy");
    write_movie(&other, 60, (8, 6));
    let out = presrs(&["convert", other.to_str().unwrap(), bag.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    let out = presrs_with_input(&["stream", "--model", model, "--format", "mcap"], &bag);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let events = json_lines(&stdout(&out));
    let error = events.iter().find(|e| e["event"] == "error").unwrap();
    let message = error["message"].as_str().unwrap();
    assert!(
        message.contains("this model classifies series of 4 channels x 40 time steps")
            && message.contains("not the frames of a sensor"),
        "{message}"
    );
}
