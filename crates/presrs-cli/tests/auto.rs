//! Drawing and validating on small or grouped data sets: `--per-class` capped with one warning, the
//! automatic choice validated by group (or, when that hides a class from training, by splits, with a
//! warning), and the protocol `eval` takes when none is given.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;
use common::{presrs, stderr, stdout};

/// A `--per-class` larger than a class (or a held-out fold) can give is capped, with one warning line,
/// in train and eval alike; a size every class can give warns nothing.
#[test]
fn per_class_beyond_the_data_is_capped_with_one_warning() {
    let dir = tempfile::tempdir().unwrap();
    // 3 classes x 8 images in 4 groups: 8 per class in all, 6 with a group held out.
    let manifest = common::write_image_set(dir.path(), (20, 24), 3, 8, 4, 0.0, 9);
    let manifest = manifest.to_str().unwrap();
    let model = dir.path().join("m.json");
    let fixed = ["--features", "fft1d", "--classifier", "lda", "--dims", "4"];
    let train = presrs(
        &[
            &[
                "train",
                "--manifest",
                manifest,
                "--per-class",
                "20",
                "--out",
                model.to_str().unwrap(),
            ][..],
            &fixed[..],
        ]
        .concat(),
    );
    assert!(train.status.success(), "{}", stderr(&train));
    let err = stderr(&train);
    let lines: Vec<&str> = err.lines().filter(|l| l.contains("--per-class")).collect();
    assert_eq!(lines.len(), 1, "{err}");
    assert!(lines[0].contains("--per-class 20: capped"), "{err}");
    assert!(lines[0].contains("fewest: 8 of class"), "{err}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&model).unwrap()).unwrap();
    let counts = &json["provenance"]["train_counts"];
    let validation = &json["provenance"]["validation_counts"];
    for class in ["t0", "t1", "t2"] {
        let all = counts[class].as_u64().unwrap() + validation[class].as_u64().unwrap();
        assert_eq!(all, 8, "{json}");
    }

    let eval = |per_class: &str| {
        presrs(
            &[
                &[
                    "eval",
                    "--manifest",
                    manifest,
                    "--leave-one-out",
                    "group",
                    "--per-class",
                    per_class,
                    "--repeats",
                    "1",
                ][..],
                &fixed[..],
            ]
            .concat(),
        )
    };
    let capped = eval("7");
    assert!(capped.status.success(), "{}", stderr(&capped));
    let err = stderr(&capped);
    let lines: Vec<&str> = err.lines().filter(|l| l.contains("--per-class")).collect();
    assert_eq!(lines.len(), 1, "{err}");
    assert!(lines[0].contains("--per-class 7: capped"), "{err}");
    assert!(lines[0].contains("held out"), "{err}");
    assert!(stdout(&capped).contains("overall"), "{}", stdout(&capped));
    let enough = eval("6");
    assert!(enough.status.success(), "{}", stderr(&enough));
    assert!(
        !stderr(&enough).contains("--per-class"),
        "{}",
        stderr(&enough)
    );
}

/// The internal estimate of `train`, validated by the given way; (estimate in %, the words).
fn train_estimate(manifest: &str, out: &std::path::Path, extra: &[&str]) -> (f64, String) {
    let train = presrs(
        &[
            &[
                "train",
                "--manifest",
                manifest,
                "--out",
                out.to_str().unwrap(),
                "--features",
                "fft2d_polar",
                "--dims",
                "6",
            ][..],
            extra,
        ]
        .concat(),
    );
    assert!(train.status.success(), "{}", stderr(&train));
    let text = stdout(&train);
    let line = text
        .lines()
        .find(|l| l.starts_with("internal estimate: "))
        .unwrap_or_else(|| panic!("{text}"));
    let percent: f64 = line["internal estimate: ".len()..]
        .split_whitespace()
        .next()
        .unwrap()
        .parse()
        .unwrap();
    let how = line.split(", validated by ").nth(1).unwrap().to_owned();
    (percent, how)
}

/// On data whose groups differ (each group's images scaled and shifted its own way), the automatic
/// choice validates by group by default: its internal estimate is leave-one-group-out, lower than what
/// stratified splits (which mix the groups) claim; `eval` reports it next to the test result.
#[test]
fn the_automatic_choice_validates_by_group_and_eval_reports_its_estimate() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = common::write_image_set(dir.path(), (16, 16), 3, 24, 4, 1.3, 21);
    let manifest = manifest.to_str().unwrap();
    let model = dir.path().join("m.json");
    let (by_group, how) = train_estimate(manifest, &model, &[]);
    assert!(
        how.starts_with("leave one group out inside the training data (g0, g1, g2, g3)"),
        "{how}"
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&model).unwrap()).unwrap();
    let selection = &json["model"]["selection"];
    let chosen = selection["chosen"].as_u64().unwrap() as usize;
    let scores = selection["scores"][chosen]["per_fold"].clone();
    assert!(scores["g3"].is_number(), "{scores}");
    let (by_split, how) = train_estimate(manifest, &model, &["--validate-by", "split"]);
    assert!(how.starts_with("three stratified"), "{how}");
    assert!(
        by_split > by_group,
        "splits mix the groups and claim more: {by_split} vs {by_group}"
    );
    // One condition only: validating by condition is refused, saying why.
    let refused = presrs(&[
        "train",
        "--manifest",
        manifest,
        "--out",
        model.to_str().unwrap(),
        "--validate-by",
        "condition",
    ]);
    assert!(!refused.status.success());
    assert!(
        stderr(&refused).contains("validating by condition needs at least two conditions"),
        "{}",
        stderr(&refused)
    );

    let eval = |json: bool| {
        let mut args = vec![
            "eval",
            "--manifest",
            manifest,
            "--leave-one-out",
            "group",
            "--repeats",
            "1",
            "--features",
            "fft2d_polar",
            "--dims",
            "6",
        ];
        if json {
            args.push("--json");
        }
        presrs(&args)
    };
    let out = eval(true);
    assert!(out.status.success(), "{}", stderr(&out));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let internal = &json["internal_estimate"];
    assert_eq!(internal["models"], 4, "{internal}");
    assert!(
        internal["validated_by"]
            .as_str()
            .unwrap()
            .starts_with("leave one group out"),
        "{internal}"
    );
    assert!(
        internal["accuracy"]["mean"].as_f64().unwrap() > 0.0,
        "{internal}"
    );
    let out = eval(false);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stdout(&out).contains("internal estimate (validation inside the training data): "),
        "{}",
        stdout(&out)
    );
}

/// With stderr not a terminal (a log), a long run writes `progress: ...` lines (every
/// PRESRS_PROGRESS_SECONDS, 5 s by default), in train and eval; stdout is untouched.
#[test]
fn progress_lines_go_to_stderr_when_it_is_not_a_terminal() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = common::write_image_set(dir.path(), (16, 16), 3, 12, 3, 0.5, 2);
    let manifest = manifest.to_str().unwrap();
    let model = dir.path().join("m.json");
    let run = |args: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_presrs"))
            .args(args)
            .env("PRESRS_PROGRESS_SECONDS", "0.001")
            .stdin(std::process::Stdio::null())
            .output()
            .unwrap()
    };
    let train = run(&[
        "train",
        "--manifest",
        manifest,
        "--out",
        model.to_str().unwrap(),
        "--dims",
        "5",
    ]);
    assert!(train.status.success(), "{}", stderr(&train));
    assert!(
        stderr(&train).contains("progress: training: "),
        "{}",
        stderr(&train)
    );
    assert!(!stdout(&train).contains("progress:"));
    let eval = run(&[
        "eval",
        "--manifest",
        manifest,
        "--leave-one-out",
        "group",
        "--repeats",
        "2",
        "--dims",
        "5",
    ]);
    assert!(eval.status.success(), "{}", stderr(&eval));
    let err = stderr(&eval);
    assert!(
        err.lines()
            .any(|l| l.starts_with("progress: ") && l.contains("/6 (")),
        "{err}"
    );
}

/// `eval --export-draws` writes the images as evaluated and the folds the evaluation used: each test set
/// is one held-out group, the drawn sets hold `--per-class` images per class from the other groups, the
/// counts agree with the evaluation's own, and the same seed gives the same draws.
#[test]
fn eval_exports_its_images_and_draws() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = common::write_image_set(dir.path(), (20, 24), 3, 8, 4, 0.0, 9);
    let manifest = manifest.to_str().unwrap();
    let run = |out: &std::path::Path| {
        let output = presrs(&[
            "eval",
            "--manifest",
            manifest,
            "--leave-one-out",
            "group",
            "--per-class",
            "5",
            "--repeats",
            "2",
            "--features",
            "fft1d",
            "--classifier",
            "lda",
            "--dims",
            "4",
            "--json",
            "--export-draws",
            out.to_str().unwrap(),
        ]);
        assert!(output.status.success(), "{}", stderr(&output));
        let report: serde_json::Value = serde_json::from_str(&stdout(&output)).unwrap();
        let draws: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("draws.json")).unwrap())
                .unwrap();
        (report, draws)
    };
    let (report, draws) = run(&dir.path().join("export"));
    assert_eq!(draws["format"], "presrs-eval-draws");
    let labels: Vec<&str> = draws["labels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l.as_str().unwrap())
        .collect();
    let groups: Vec<&str> = draws["groups"]
        .as_array()
        .unwrap()
        .iter()
        .map(|g| g.as_str().unwrap())
        .collect();
    assert_eq!(labels.len(), 24);
    // the manifest's rows, in order
    let rows: Vec<String> = std::fs::read_to_string(manifest)
        .unwrap()
        .lines()
        .skip(1)
        .map(str::to_owned)
        .collect();
    for (k, row) in rows.iter().enumerate() {
        let fields: Vec<&str> = row.split(',').collect();
        assert_eq!((fields[1], fields[3]), (labels[k], groups[k]), "row {k}");
    }
    let npy = std::fs::read(dir.path().join("export/images.npy")).unwrap();
    let recording = presrs_io::npy::parse_npy_with(&npy, "images.npy", None)
        .unwrap()
        .0;
    assert_eq!(recording.frame_count(), 24);
    let list = draws["draws"].as_array().unwrap();
    assert_eq!(list.len(), 2 * 4, "2 repeats x 4 groups");
    let indices = |draw: &serde_json::Value, key: &str| -> Vec<usize> {
        draw[key]
            .as_array()
            .unwrap()
            .iter()
            .map(|i| i.as_u64().unwrap() as usize)
            .collect()
    };
    for draw in list {
        let held_out = draw["held_out"].as_str().unwrap();
        let test = indices(draw, "test");
        let expected: Vec<usize> = (0..24).filter(|&i| groups[i] == held_out).collect();
        assert_eq!(test, expected);
        let mut drawn = indices(draw, "train");
        drawn.extend(indices(draw, "validation"));
        for class in ["t0", "t1", "t2"] {
            let n = drawn.iter().filter(|&&i| labels[i] == class).count();
            assert_eq!(n, 5, "{draw}");
        }
        assert!(drawn.iter().all(|&i| groups[i] != held_out));
    }
    for (repeat, result) in report["report"]["repeats"]
        .as_array()
        .unwrap()
        .iter()
        .enumerate()
    {
        let of = |key: &str| -> u64 {
            list.iter()
                .filter(|d| d["repeat"] == repeat)
                .map(|d| d[key].as_array().unwrap().len() as u64)
                .sum()
        };
        assert_eq!(of("train"), result["n_train"].as_u64().unwrap());
        assert_eq!(of("validation"), result["n_validation"].as_u64().unwrap());
        assert_eq!(of("test"), result["n_test"].as_u64().unwrap());
    }
    let (_, again) = run(&dir.path().join("again"));
    assert_eq!(again["draws"], draws["draws"]);
}

/// Simulated trials of `presrs --help`'s example: one trial (group) per terrain and gait.
fn simulated(dir: &std::path::Path) -> String {
    let sim = dir.join("sim");
    let out = presrs(&[
        "simulate",
        "--out",
        sim.to_str().unwrap(),
        "--seed",
        "7",
        "--hops-per-gait",
        "6",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    sim.join("manifest.csv").to_str().unwrap().to_owned()
}

/// Issue #35: trained on one gait, every terrain is one group, so leaving a group out leaves its
/// terrain out of training and every candidate scored 0 %, silently. The choice now falls back to
/// stratified splits and says so in one warning line, in train and eval alike; the table says whether
/// the choice is the paper's method and why the model keeps fewer components than it names.
#[test]
fn a_validation_that_hides_a_class_from_training_is_replaced_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = simulated(dir.path());
    let model = dir.path().join("m.json");
    let train = presrs(&[
        "train",
        "--manifest",
        &manifest,
        "--train-condition",
        "G2",
        "--out",
        model.to_str().unwrap(),
    ]);
    assert!(train.status.success(), "{}", stderr(&train));
    let (err, text) = (stderr(&train), stdout(&train));
    let warned: Vec<&str> = err
        .lines()
        .filter(|l| l.contains("instead of leaving one group out"))
        .collect();
    assert_eq!(warned.len(), 1, "{err}");
    assert!(
        warned[0].starts_with(
            "warning: the automatic choice validated its candidates by three \
             stratified 70/30 splits"
        ) && warned[0].contains("leaves no training image of class")
            && warned[0].contains("--validate-by split"),
        "{err}"
    );
    assert!(
        text.starts_with("automatic choice (three stratified 70/30 splits"),
        "{text}"
    );
    let (percent, _) = estimate_of(&text);
    assert!(percent > 50.0, "{text}");
    // The paper's method is named only when chosen; otherwise its score is given beside the choice.
    let chosen = text.lines().find(|l| l.starts_with("chosen: ")).unwrap();
    assert!(!chosen.contains("--features"), "{chosen}");
    assert_eq!(
        chosen.contains("(the paper's method)"),
        chosen.starts_with("chosen: fft1d + pwe, 51 dims"),
        "{chosen}"
    );
    // 16 training images keep at most 15 components, whatever the candidate asked for.
    let summary = text.lines().find(|l| l.contains("PCA ")).unwrap();
    assert!(summary.contains("PCA 15 components"), "{text}");
    assert!(
        text.contains("the model keeps 15 of the ")
            && text.contains("at most one fewer than its 16 training images"),
        "{text}"
    );

    let eval = presrs(&[
        "eval",
        "--manifest",
        &manifest,
        "--train-condition",
        "G2",
        "--repeats",
        "1",
        "--budget",
        "0",
        "--classifier",
        "lda",
        "--features",
        "fft1d",
    ]);
    assert!(eval.status.success(), "{}", stderr(&eval));
    // (a fixed method makes no choice, so no warning)
    assert!(!stderr(&eval).contains("instead of"), "{}", stderr(&eval));
    let eval = presrs(&[
        "eval",
        "--manifest",
        &manifest,
        "--train-condition",
        "G2",
        "--repeats",
        "1",
        "--budget",
        "0.000001",
    ]);
    assert!(eval.status.success(), "{}", stderr(&eval));
    let err = stderr(&eval);
    assert_eq!(
        err.lines()
            .filter(|l| l.contains("instead of leaving one group out"))
            .count(),
        1,
        "{err}"
    );
}

/// (internal estimate in %, the validation's words) from `train`'s output.
fn estimate_of(text: &str) -> (f64, String) {
    let line = text
        .lines()
        .find(|l| l.starts_with("internal estimate: "))
        .unwrap_or_else(|| panic!("{text}"));
    let percent: f64 = line["internal estimate: ".len()..]
        .split_whitespace()
        .next()
        .unwrap()
        .parse()
        .unwrap();
    (
        percent,
        line.split(", validated by ").nth(1).unwrap().to_owned(),
    )
}

/// Candidates a budget cuts say the budget in force, and the warning names their classifiers
/// (issue #35).
#[test]
fn a_cut_search_names_the_budget_and_every_candidate_it_left_out() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = simulated(dir.path());
    let model = dir.path().join("m.json");
    let train = presrs(&[
        "train",
        "--manifest",
        &manifest,
        "--train-condition",
        "G2",
        "--budget",
        "0.000001",
        "--out",
        model.to_str().unwrap(),
    ]);
    assert!(train.status.success(), "{}", stderr(&train));
    let (err, text) = (stderr(&train), stdout(&train));
    assert!(
        text.contains("glcm + svm, 51 dims")
            && text.contains("not tried: the time budget of 0.000001 s was spent"),
        "{text}"
    );
    assert!(err.contains("glcm with pwe, mle, lda, svm, knn"), "{err}");
}

/// `eval` decides its protocol before any training (issue #35: one condition and no protocol trained
/// for 37 s, then found nothing to test on): leave one group out where there are groups, as `report`
/// does; without groups, an error that names the options, at once. Its counts say they are per fold.
#[test]
fn eval_without_a_protocol_holds_out_groups_or_says_what_to_give() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = common::write_image_set(dir.path(), (16, 16), 3, 8, 4, 0.0, 5);
    let fixed = [
        "--features",
        "fft1d",
        "--classifier",
        "lda",
        "--dims",
        "4",
        "--repeats",
        "1",
    ];
    let eval = |manifest: &std::path::Path| {
        presrs(
            &[
                &["eval", "--manifest", manifest.to_str().unwrap()][..],
                &fixed[..],
            ]
            .concat(),
        )
    };
    let grouped = eval(&manifest);
    assert!(grouped.status.success(), "{}", stderr(&grouped));
    let text = stdout(&grouped);
    assert!(text.starts_with("leave one `group` out"), "{text}");
    assert!(
        text.contains("per repeat: 4 folds, per fold (on average) ")
            && text.contains("24 tested in all (summed over the folds: "),
        "{text}"
    );
    let plain = dir.path().join("plain.csv");
    let rows: Vec<String> = std::fs::read_to_string(&manifest)
        .unwrap()
        .lines()
        .map(|l| l.rsplit_once(',').unwrap().0.to_owned())
        .collect();
    std::fs::write(&plain, rows.join("\n")).unwrap();
    let refused = eval(&plain);
    assert!(!refused.status.success());
    let err = stderr(&refused);
    assert!(
        err.contains("no image would be left to test on")
            && err.contains("--leave-one-out group")
            && err.contains("--train-condition")
            && err.contains("--per-class"),
        "{err}"
    );
    // A per-class draw without a protocol is the random draw it always was.
    let drawn = presrs(
        &[
            &[
                "eval",
                "--manifest",
                plain.to_str().unwrap(),
                "--per-class",
                "5",
            ][..],
            &fixed[..],
        ]
        .concat(),
    );
    assert!(drawn.status.success(), "{}", stderr(&drawn));
    assert!(
        stdout(&drawn).contains("per repeat: 9 training + 6 validation images, 9 tested"),
        "{}",
        stdout(&drawn)
    );
}

/// `train` and `eval` end with the run's peak memory and that peak per sample (`memory` in `eval
/// --json`), say where the automatic choice's time went (the scoring the budget bounds, training the
/// winner after it; `cost` in each selection), and name each stage on stderr as it begins.
#[test]
fn train_and_eval_state_their_peak_memory_per_sample_and_their_stages() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = common::write_image_set(dir.path(), (16, 16), 3, 12, 3, 0.5, 2);
    let manifest = manifest.to_str().unwrap();
    let model = dir.path().join("m.json");
    let train = presrs(&[
        "train",
        "--manifest",
        manifest,
        "--out",
        model.to_str().unwrap(),
        "--dims",
        "5",
    ]);
    assert!(train.status.success(), "{}", stderr(&train));
    let out = stdout(&train);
    let last = out.lines().last().unwrap();
    assert!(last.starts_with("peak memory "), "{out}");
    assert!(last.ends_with("per sample over 36 samples"), "{last}");
    let time = out.lines().find(|l| l.starts_with("time: ")).unwrap();
    assert!(time.contains("scored on all 36 samples"), "{time}");
    assert!(time.contains("within the budget of 60 s"), "{time}");
    assert!(
        time.contains("training the winner on all 36 samples"),
        "{time}"
    );
    let err = stderr(&train);
    for stage in [
        "progress: scoring ",
        "progress: features: fft1d",
        "progress: training the winner, ",
    ] {
        assert!(err.contains(stage), "{stage}: {err}");
    }
    let eval = presrs(&[
        "eval",
        "--manifest",
        manifest,
        "--leave-one-out",
        "group",
        "--repeats",
        "1",
        "--dims",
        "5",
        "--json",
    ]);
    assert!(eval.status.success(), "{}", stderr(&eval));
    let json: serde_json::Value = serde_json::from_slice(&eval.stdout).unwrap();
    let memory = &json["memory"];
    let peak = memory["peak_bytes"].as_u64().unwrap();
    assert!(peak > 1 << 20, "{memory}");
    assert_eq!(memory["samples"], 36, "{memory}");
    assert_eq!(memory["bytes_per_sample"].as_u64().unwrap(), peak / 36);
    let cost = &json["selections"][0]["cost"];
    assert_eq!(cost["scored_on"], cost["samples"], "{cost}");
    assert!(cost["final_fit_seconds"].as_f64().unwrap() > 0.0, "{cost}");
    assert_eq!(cost["budget_seconds"], 60.0, "{cost}");
}

/// On a small whole-stance set the race's ridges read four MiniRocket draws side by side: `train`'s
/// summary and `inspect` name them, and the model file stores the four fitted draws.
#[test]
fn the_race_s_ridges_read_four_draws_on_a_small_set() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/real/jiku-walk/manifest.csv");
    let model = dir.path().join("m.json");
    let train = presrs(&[
        "train",
        "--manifest",
        manifest.to_str().unwrap(),
        "--sample",
        "stance",
        "--one-sample-per-file",
        "--classifier",
        "ridge_raw",
        "--out",
        model.to_str().unwrap(),
    ]);
    assert!(train.status.success(), "{}", stderr(&train));
    assert!(stdout(&train).contains(", 4 draws)"), "{}", stdout(&train));
    let inspect = presrs(&["inspect", model.to_str().unwrap()]);
    assert!(inspect.status.success(), "{}", stderr(&inspect));
    assert!(
        stdout(&inspect).contains(", 4 draws)"),
        "{}",
        stdout(&inspect)
    );
    let stored: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&model).unwrap()).unwrap();
    let features = &stored["model"]["features"];
    assert_eq!(features["draws"], 4, "{features}");
    assert_eq!(
        features["fitted"]["more_draws"].as_array().unwrap().len(),
        3
    );
}
