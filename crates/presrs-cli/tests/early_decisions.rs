//! Early decisions on the command line, with whole-stance models trained on the shared `jiku-walk`
//! movies (one contact each): `train --decide-at` stores the decision points, and a `--decide-at` the
//! model was not trained for is refused by `stream`, `ros2` and `simulate` before any frame or graph,
//! with how to train one; `eval --decide-at` prints the curve and `auto`'s line.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use std::path::{Path, PathBuf};

use common::{presrs, stderr, stdout};

fn shared(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data")
        .join(path)
}

/// A small whole-stance model of every `jiku-walk` movie, with `extra` options.
fn train(dir: &Path, name: &str, extra: &[&str]) -> PathBuf {
    train_output(dir, name, extra).0
}

/// [`train`], with what it printed.
fn train_output(dir: &Path, name: &str, extra: &[&str]) -> (PathBuf, std::process::Output) {
    train_manifest(&shared("real/jiku-walk/manifest.csv"), dir, name, extra)
}

/// [`train_output`] on the stances of `manifest`.
fn train_manifest(
    manifest: &Path,
    dir: &Path,
    name: &str,
    extra: &[&str],
) -> (PathBuf, std::process::Output) {
    let out = dir.join(name);
    let mut args = vec![
        "train",
        "--manifest",
        manifest.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--sample",
        "stance",
        "--one-sample-per-file",
        "--features",
        "rocket",
        "--classifier",
        "lda",
        "--dims",
        "20",
    ];
    args.extend_from_slice(extra);
    let output = presrs(&args);
    assert!(output.status.success(), "{}", stderr(&output));
    (out, output)
}

/// The refusal of `decide_at` by `command` with `model`: an error naming the option and how to train
/// for it, and nothing on stdout.
fn assert_refused(args: &[&str], decide_at: &str) {
    let output = presrs(args);
    assert!(!output.status.success(), "{args:?} ran");
    let err = stderr(&output);
    assert!(
        err.contains(&format!("not trained to decide at {decide_at}")),
        "{args:?}: {err}"
    );
    assert!(
        err.contains("presrs train") && err.contains(&format!("--decide-at {decide_at}")),
        "{args:?}: {err}"
    );
    assert!(
        err.contains("--sample stance"),
        "{args:?}: how to train: {err}"
    );
    assert!(stdout(&output).is_empty(), "{args:?}: {}", stdout(&output));
}

#[test]
fn a_moment_the_model_was_not_trained_for_is_refused_by_every_command_line_face() {
    let dir = tempfile::tempdir().unwrap();
    let whole = train(dir.path(), "whole.json", &[]);
    let (points, output) = train_output(dir.path(), "points.json", &["--decide-at", "8,16,whole"]);
    // Where the time went, on stdout; which point or inner fold runs, as progress.
    let printed = stdout(&output);
    let line = printed
        .lines()
        .find(|line| line.starts_with("decision points: 8, 16 frames"))
        .unwrap_or_else(|| panic!("{printed}"));
    assert!(
        line.contains("trained in ")
            && line.contains("the points' classifiers ")
            && line.contains("classifiers in 3 inner folds"),
        "{line}"
    );
    let progress = stderr(&output);
    assert!(
        progress.contains("decision point 8 frames (1 of 2): training on 120 cut stances")
            && progress.contains("auto's rule: inner fold 1 of 3"),
        "{progress}"
    );
    let stored: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&points).unwrap()).unwrap();
    let cost = &stored["model"]["early"]["cost"];
    assert_eq!(cost["inner_models"].as_u64(), Some(9), "{cost}");
    assert_eq!(cost["rule_stances"], cost["stances"]);
    assert!(cost["points_seconds"].as_f64().unwrap() >= 0.0);
    let frames: Vec<u64> = stored["model"]["early"]["points"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["frames"].as_u64().unwrap())
        .collect();
    assert_eq!(frames, [8, 16]);
    assert!(stored["model"]["early"]["auto"]["threshold"].is_number());
    // jiku-walk's two walkers are too few groups to learn auto's rule by leaving one out: it is
    // learned on stratified splits, and train says what that cannot see.
    assert_eq!(stored["model"]["early"]["auto"]["validated_by"], "split");
    assert!(
        progress.contains("warning: auto's rule for early decisions was learned on training stances held out by three stratified 70/30 splits")
            && progress.contains("train without --decide-at"),
        "{progress}"
    );
    for (model, decide_at) in [(&whole, "8"), (&whole, "auto"), (&points, "12")] {
        let model = model.to_str().unwrap();
        assert_refused(
            &["stream", "--model", model, "--decide-at", decide_at],
            decide_at,
        );
        assert_refused(
            &[
                "ros2",
                "--model",
                model,
                "--input",
                "/foot/pressure",
                "--decide-at",
                decide_at,
            ],
            decide_at,
        );
        assert_refused(
            &[
                "simulate",
                "--track",
                "wood:1",
                "--adaptive",
                model,
                "--decide-at",
                decide_at,
            ],
            decide_at,
        );
    }
    // What the model was trained for starts (stdin closed at once: the stream reads, finds no frame,
    // and ends with its summary line).
    for decide_at in ["8", "auto"] {
        let output = presrs(&[
            "stream",
            "--model",
            points.to_str().unwrap(),
            "--decide-at",
            decide_at,
        ]);
        let err = stderr(&output);
        assert!(!err.contains("not trained"), "{decide_at}: {err}");
        assert!(err.contains("0 frames, 0 stances"), "{decide_at}: {err}");
    }
}

/// `eval --decide-at` on a few `jiku-walk` subjects' movies, leave one subject out: the table of the
/// points (the one-frame model beside each) and `auto`'s line on stdout, and with `--report` the HTML
/// report's section of accuracy against decision time, its figure beside the page.
#[test]
fn eval_decide_at_prints_the_curve_and_reports_it() {
    let dir = tempfile::tempdir().unwrap();
    // Thirty movies of each subject keep the run short.
    let source = std::fs::read_to_string(shared("real/jiku-walk/manifest.csv")).unwrap();
    let mut rows = vec![source.lines().next().unwrap().to_owned()];
    for subject in ["s00", "s01"] {
        rows.extend(
            source
                .lines()
                .filter(|line| line.starts_with(subject))
                .take(30)
                .map(|line| {
                    let path = shared("real/jiku-walk").join(line.split(',').next().unwrap());
                    let rest = line.split_once(',').unwrap().1;
                    format!("{},{rest}", path.display())
                }),
        );
    }
    let manifest = dir.path().join("manifest.csv");
    std::fs::write(&manifest, rows.join("\n") + "\n").unwrap();
    let report = dir.path().join("report");
    let output = presrs(&[
        "eval",
        "--manifest",
        manifest.to_str().unwrap(),
        "--sample",
        "stance",
        "--one-sample-per-file",
        "--leave-one-out",
        "group",
        "--repeats",
        "1",
        "--features",
        "rocket",
        "--classifier",
        "lda",
        "--dims",
        "10",
        "--decide-at",
        // 55: past some stances' lift-off (s00_t00 is 54 frames long).
        "8,16,55",
        "--report",
        report.to_str().unwrap(),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    let table = stdout(&output);
    assert!(
        table.contains("early decisions (60 held-out stances, 2 folds"),
        "{table}"
    );
    assert!(table.contains("one frame %") && table.contains("lift-off"));
    assert!(table.contains("auto: "), "{table}");
    assert!(
        table.contains("decided before lift-off") && table.contains("by mid-stance"),
        "{table}"
    );
    // Each fold's rule with what it gave on its 30 held-out stances: their mean is auto's figure.
    let percent = |text: &str| -> f64 { text.trim().trim_end_matches('%').trim().parse().unwrap() };
    let overall = percent(
        table
            .lines()
            .find_map(|line| line.strip_prefix("auto: "))
            .and_then(|rest| rest.split(" (").next())
            .unwrap_or_else(|| panic!("{table}")),
    );
    let by_fold = table
        .lines()
        .find_map(|line| line.strip_prefix("auto's rule by fold: "))
        .unwrap_or_else(|| panic!("{table}"));
    let folds: Vec<f64> = by_fold
        .split("; ")
        .filter_map(|rule| rule.split_once(" (")?.1.split(", whole").next())
        .map(percent)
        .collect();
    assert_eq!(folds.len(), 2, "{by_fold}");
    assert!(
        ((folds[0] + folds[1]) / 2.0 - overall).abs() < 0.11,
        "{by_fold} against {overall}"
    );
    // The one-frame model at 55 is tested on the stances that reach frame 55 only.
    let late = table
        .lines()
        .find(|line| line.trim_start().starts_with("55 "))
        .unwrap_or_else(|| panic!("no row for 55: {table}"));
    let tested: usize = late
        .split("(n=")
        .nth(1)
        .and_then(|rest| rest.trim_end_matches(')').parse().ok())
        .unwrap_or_else(|| panic!("{late}"));
    assert!(tested > 0 && tested < 60, "{late}");
    let page = std::fs::read_to_string(report.join("index.html")).unwrap();
    assert!(
        page.contains("Early decisions: accuracy against decision time"),
        "no early section"
    );
    assert!(page.contains("8.0 frames") && page.contains("16.0 frames"));
    assert!(page.contains("auto: mean"));
    assert!(report.join("early_decisions.png").is_file());
}

/// With 3 or more groups (here four, each holding every class), auto's rule is learned by leaving
/// groups out, and train warns of nothing about it.
#[test]
fn with_enough_groups_the_rule_is_learned_by_leaving_groups_out() {
    let dir = tempfile::tempdir().unwrap();
    let source = shared("real/jiku-walk/manifest.csv");
    let folder = source.parent().unwrap();
    let text = std::fs::read_to_string(&source).unwrap();
    let mut manifest = String::from("path,label,condition,group\n");
    for (i, line) in text.lines().skip(1).enumerate() {
        let fields: Vec<&str> = line.split(',').collect();
        let path = folder.join(fields[0]);
        manifest.push_str(&format!(
            "{},{},walk,g{}\n",
            path.display(),
            fields[1],
            i % 4
        ));
    }
    let manifest_path = dir.path().join("four_groups.csv");
    std::fs::write(&manifest_path, manifest).unwrap();
    let (out, output) = train_manifest(
        &manifest_path,
        dir.path(),
        "grouped.json",
        &["--decide-at", "8,16,whole"],
    );
    assert!(
        !stderr(&output).contains("auto's rule for early decisions"),
        "{}",
        stderr(&output)
    );
    assert!(
        stdout(&output).contains("held-out training stances (leaving one group out)"),
        "{}",
        stdout(&output)
    );
    let stored: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(stored["model"]["early"]["auto"]["validated_by"], "group");
}
