//! What a new user met on the command line (issue #35): outputs checked before the work, one stance
//! numbering in inspect and plot, negative numbers judged by their option, help texts that name every
//! format read, simulate refusing to replace a data set, classify printing nothing before an error.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers outside #[test] functions

mod common;
use common::{presrs, stderr, stdout, write_image_set};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

fn text(path: &Path) -> &str {
    path.to_str().expect("a UTF-8 temporary path")
}

/// Trains the paper's method on `manifest` into `model` (fast: nothing to choose).
fn train_fixed(manifest: &Path, model: &Path) {
    let out = presrs(&[
        "train",
        "--manifest",
        text(manifest),
        "--out",
        text(model),
        "--features",
        "fft1d",
        "--classifier",
        "pwe",
        "--dims",
        "3",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
}

/// Asserts a failure before any work: exit code 1, stdout empty, one `error:` line on stderr that
/// mentions each of `needles`.
fn assert_refused_at_once(case: &str, out: &Output, needles: &[&str]) {
    let err = stderr(out);
    assert_eq!(out.status.code(), Some(1), "{case}: {err}");
    assert_eq!(stdout(out), "", "{case}: printed before failing");
    assert_eq!(
        err.lines().count(),
        1,
        "{case}: worked before failing:\n{err}"
    );
    assert!(err.starts_with("error: cannot write"), "{case}: {err}");
    for needle in needles {
        assert!(
            err.contains(needle),
            "{case}: `{needle}` missing from {err}"
        );
    }
}

#[test]
fn outputs_that_cannot_be_written_fail_before_the_work() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = write_image_set(dir.path(), (12, 12), 2, 6, 3, 0.0, 3);
    let model = dir.path().join("m.json");
    train_fixed(&manifest, &model);
    let missing = dir.path().join("no/such/dir");
    let file = dir.path().join("taken.txt");
    std::fs::write(&file, "keep me").unwrap();
    let image = dir.path().join("c0_0.npy");
    let (manifest, model, image) = (text(&manifest), text(&model), text(&image));
    let in_missing = |name: &str| missing.join(name).display().to_string();
    let (json, mcap, png) = (
        in_missing("m.json"),
        in_missing("x.mcap"),
        in_missing("x.png"),
    );
    let file_text = text(&file);
    let cases: Vec<(&str, Vec<&str>, &str)> = vec![
        // The automatic choice would run first (and print its table) before the fix.
        (
            "train",
            vec!["train", "--manifest", manifest, "--out", &json],
            "does not exist",
        ),
        (
            "report",
            vec!["report", "--manifest", manifest, "--out", file_text],
            "it is a file",
        ),
        (
            "eval --report",
            vec!["eval", "--manifest", manifest, "--report", file_text],
            "it is a file",
        ),
        (
            "eval --export-draws",
            vec!["eval", "--manifest", manifest, "--export-draws", file_text],
            "it is a file",
        ),
        ("convert", vec!["convert", image, &mcap], "does not exist"),
        ("plot", vec!["plot", image, "--out", &png], "does not exist"),
        (
            "classify --mcap",
            vec!["classify", "--model", model, image, "--mcap", &mcap],
            "does not exist",
        ),
        (
            "stream --record",
            vec!["stream", "--model", model, "--record", &mcap],
            "does not exist",
        ),
        (
            "simulate",
            vec!["simulate", "--out", file_text],
            "it is a file",
        ),
        (
            "simulate --track --json",
            vec!["simulate", "--track", "wood:1", "--json", &json],
            "does not exist",
        ),
        (
            "reproduce",
            vec!["reproduce", "--out", file_text],
            "it is a file",
        ),
        (
            "bench --export",
            vec!["bench", "--synthetic", "--export", file_text],
            "it is a file",
        ),
    ];
    for (case, args, reason) in cases {
        let out = presrs(&args);
        let named = if reason == "does not exist" {
            missing.display().to_string()
        } else {
            file.display().to_string()
        };
        assert_refused_at_once(case, &out, &[reason, &named]);
    }
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "keep me");
    assert!(!missing.exists());
    // A folder where a file goes.
    let out = presrs(&["plot", image, "--out", text(dir.path())]);
    assert_refused_at_once("plot into a folder", &out, &["it is a folder"]);
}

/// A movie of `frames` 10x10 frames as .npy: the foot loaded over `stances` (start, len) spans, with a
/// load that rises and falls, a texture, and nothing between.
fn write_movie(path: &Path, frames: usize, stances: &[(usize, usize)]) {
    let (rows, cols) = (10, 10);
    let mut data = vec![0.0; frames * rows * cols];
    for &(start, len) in stances {
        for t in start..start + len {
            // A partial stance at the start is cut at its heaviest, so it still falls within the movie.
            let phase = (t + 1 - start) as f64 / (len + 1) as f64;
            let load = 50.0 + 100.0 * (std::f64::consts::PI * phase).sin();
            for k in 0..rows * cols {
                data[t * rows * cols + k] = load * (1.0 + 0.3 * ((k * 7 + t) % 5) as f64 / 5.0);
            }
        }
    }
    let file = std::fs::File::create(path).unwrap();
    presrs_io::npy::write_npy_f64(file, &[frames, rows, cols], &data).unwrap();
}

#[test]
fn plot_numbers_stances_as_inspect_does() {
    let dir = tempfile::tempdir().unwrap();
    let movie = dir.path().join("walk.npy");
    // The first stance is cut by the start of the recording: partial, yet inspect's #0.
    write_movie(&movie, 100, &[(0, 12), (30, 20), (70, 20)]);
    let out = presrs(&["inspect", text(&movie), "--json"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let stances = report["stances"].as_array().unwrap();
    assert_eq!(stances.len(), 3, "{report}");
    assert_eq!(stances[0]["partial"], true, "{report}");
    for (n, stance) in stances.iter().enumerate() {
        let png = dir.path().join(format!("stance{n}.png"));
        let out = presrs(&[
            "plot",
            text(&movie),
            "--stance",
            &n.to_string(),
            "--out",
            text(&png),
        ]);
        assert!(out.status.success(), "{}", stderr(&out));
        let frame = stance["sample_frame"].as_u64().unwrap();
        assert_eq!(
            stdout(&out).trim(),
            format!("wrote {} (frame {frame})", png.display()),
            "plot --stance {n} draws inspect's stance {n}"
        );
    }
    let out = presrs(&["plot", text(&movie), "--stance", "3", "--out", "x.png"]);
    assert!(
        stderr(&out).contains("--stance 3 but 3 stance phase(s) were found"),
        "{}",
        stderr(&out)
    );
}

/// The options of `presrs SUB` that take a value, read from its help.
fn value_options(sub: &str) -> Vec<String> {
    let help = stdout(&presrs(&[sub, "--help"]));
    help.lines()
        .filter_map(|line| {
            let line = line.trim_start();
            let line = line.split_once(", ").map_or(line, |(_, rest)| rest);
            let (flag, rest) = line.split_once(' ')?;
            (flag.starts_with("--") && rest.starts_with('<')).then(|| flag.to_owned())
        })
        .collect()
}

const SUBCOMMANDS: [&str; 15] = [
    "simulate",
    "inspect",
    "features",
    "train",
    "classify",
    "eval",
    "reproduce",
    "bench",
    "stream",
    "replay",
    "view",
    "plot",
    "report",
    "convert",
    "ros2",
];

#[test]
fn a_negative_number_reaches_the_option_s_own_check() {
    let out = presrs(&["plot", "x.asf", "--frame-period", "-0.01", "--out", "x.png"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("expected a positive number of seconds, got \"-0.01\""),
        "{}",
        stderr(&out)
    );
    let dir = tempfile::tempdir().unwrap();
    let mut checked = 0;
    for sub in SUBCOMMANDS {
        for option in value_options(sub) {
            // The trailing unknown flag stops every parse that accepts the value: nothing runs.
            let out = Command::new(env!("CARGO_BIN_EXE_presrs"))
                .args([sub, option.as_str(), "-0.01", "--not-an-option"])
                .current_dir(dir.path())
                .stdin(Stdio::null())
                .output()
                .unwrap();
            let err = stderr(&out);
            assert!(
                !err.contains("unexpected argument '-0"),
                "{sub} {option} -0.01: {err}"
            );
            checked += 1;
        }
    }
    assert!(checked > 100, "only {checked} options found in the helps");
}

#[test]
fn every_reader_of_recordings_says_it_reads_mcap() {
    for sub in SUBCOMMANDS {
        let help = stdout(&presrs(&[sub, "--help"]));
        let flat = help.split_whitespace().collect::<Vec<_>>().join(" ");
        if flat.contains("text matrix") {
            assert!(
                flat.contains("MCAP"),
                "{sub} lists formats without MCAP:\n{help}"
            );
        }
    }
}

#[test]
fn simulate_replaces_a_data_set_only_with_force() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("sim");
    let args = |force: bool| {
        let mut args = vec![
            "simulate",
            "--out",
            text(&out_dir),
            "--terrains",
            "wood",
            "--gaits",
            "G2",
            "--hops-per-gait",
            "1",
        ];
        if force {
            args.push("--force");
        }
        args
    };
    let first = presrs(&args(false));
    assert!(first.status.success(), "{}", stderr(&first));
    let manifest: PathBuf = out_dir.join("manifest.csv");
    let mut edited = std::fs::read_to_string(&manifest).unwrap();
    edited.push_str("# my own line\n");
    std::fs::write(&manifest, &edited).unwrap();

    let again = presrs(&args(false));
    assert_eq!(again.status.code(), Some(1));
    let err = stderr(&again);
    assert!(
        err.contains("already holds a data set") && err.contains("--force to replace it"),
        "{err}"
    );
    assert_eq!(std::fs::read_to_string(&manifest).unwrap(), edited);

    let forced = presrs(&args(true));
    assert!(forced.status.success(), "{}", stderr(&forced));
    assert!(
        !std::fs::read_to_string(&manifest)
            .unwrap()
            .contains("my own line")
    );
}

#[test]
fn classify_prints_no_table_header_before_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = write_image_set(dir.path(), (12, 12), 2, 6, 3, 0.0, 3);
    let model = dir.path().join("m.json");
    train_fixed(&manifest, &model);
    let image = dir.path().join("c0_0.npy");
    let out = presrs(&[
        "classify",
        "--model",
        text(&model),
        text(&image),
        "--frame",
        "99999",
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(stdout(&out), "", "nothing but the error");
    assert!(stderr(&out).contains("99999"), "{}", stderr(&out));
    // A good frame still gets its header.
    let out = presrs(&["classify", "--model", text(&model), text(&image)]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stdout(&out).starts_with("file"), "{}", stdout(&out));
}

/// Trials cut to one foot contact each (as `jiku-walk`): the report with `--one-sample-per-file` says
/// what it sampled, marks those samples on the load curves, names the classifier's own
/// hyper-parameters, and says why the fault sweep's clean accuracy differs from the evaluation's.
#[test]
fn a_report_with_one_sample_per_file_says_what_it_did() {
    let dir = tempfile::tempdir().unwrap();
    let mut manifest = String::from("path,label,condition,group\n");
    for class in 0..3 {
        for trial in 0..9 {
            let name = format!("t{class}_{trial}.npy");
            let frames = 30 + 3 * trial;
            let (rows, cols) = (10, 8);
            let data: Vec<f64> = (0..frames * rows * cols)
                .map(|k| {
                    let (t, cell) = (k / (rows * cols), k % (rows * cols));
                    let load =
                        40.0 + 100.0 * (std::f64::consts::PI * t as f64 / frames as f64).sin();
                    let stripe = ((cell / cols) as f64 * (0.3 + 0.4 * class as f64)).sin();
                    load * (1.5 + stripe + 0.1 * ((cell * 7 + trial) % 3) as f64)
                })
                .collect();
            let file = std::fs::File::create(dir.path().join(&name)).unwrap();
            presrs_io::npy::write_npy_f64(file, &[frames, rows, cols], &data).unwrap();
            manifest.push_str(&format!("{name},c{class},walk,s{}\n", trial % 3));
        }
    }
    std::fs::write(dir.path().join("manifest.csv"), manifest).unwrap();
    let out_dir = dir.path().join("report");
    let out = presrs(&[
        "report",
        "--manifest",
        text(&dir.path().join("manifest.csv")),
        "--out",
        text(&out_dir),
        "--one-sample-per-file",
        "--frame-period",
        "0.01",
        "--features",
        "fft1d",
        "--classifier",
        "mle",
        "--dims",
        "3",
        "--per-class",
        "6",
        "--validation",
        "2",
        "--repeats",
        "2",
        "--fault-repeats",
        "1",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let html = std::fs::read_to_string(out_dir.join("index.html")).unwrap();
    assert!(
        html.contains("mid frame(s) of the whole recording (one contact per file) of 27 movie(s)"),
        "{html}"
    );
    assert!(!html.contains("complete stance"), "{html}");
    assert!(!html.contains("σ = —"), "{html}");
    assert!(html.contains("classifier mle ("), "{html}");
    assert!(
        html.contains("(mid, red dots)"),
        "the samples are marked: {html}"
    );
    assert!(
        html.contains("averages these 1 repeat(s), where the evaluation above averages 2"),
        "{html}"
    );
}

/// A model file given to `inspect` is described (what it classifies and how, in text or JSON); given
/// where a recording is read (`classify`'s files), it is named as a model file, not parsed as a text
/// matrix ("expected a number, found `{`").
#[test]
fn inspect_describes_a_model_file_and_readers_name_one() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = write_image_set(dir.path(), (12, 12), 2, 6, 3, 0.0, 3);
    let model = dir.path().join("m.json");
    train_fixed(&manifest, &model);
    let out = presrs(&["inspect", text(&model)]);
    assert!(out.status.success(), "{}", stderr(&out));
    let description = stdout(&out);
    assert!(description.starts_with("pwe classifier"), "{description}");
    assert!(description.contains("fft1d"), "{description}");
    let out = presrs(&["inspect", "--json", text(&model)]);
    assert!(out.status.success(), "{}", stderr(&out));
    let json: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
    assert_eq!(json["model_file"], text(&model));
    assert!(
        json["description"][0]
            .as_str()
            .unwrap()
            .starts_with("pwe classifier")
    );
    let out = presrs(&["classify", "--model", text(&model), text(&model)]);
    assert_eq!(out.status.code(), Some(1));
    let err = stderr(&out);
    assert!(
        err.contains("m.json: a presrs model file, not a recording") && err.contains("inspect"),
        "{err}"
    );
    assert!(!err.contains("expected a number"), "{err}");
}
