//! What the command line says about stances on real recordings (read in place from the shared data
//! folder): `inspect` names the mode and hints the option to try; loading a data set whose files give
//! no sample says so in one line; training names too few samples of a class as the cause.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn shared(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data")
        .join(path)
}

fn presrs(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_presrs"))
        .args(args)
        .output()
        .unwrap()
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn inspect_names_the_mode_and_hints_the_option_to_try() {
    let movie = shared("real/jiku-walk/s00_t00.npy");
    let out = presrs(&["inspect", movie.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains(
            "stances        1 found, 0 complete, measured from the zero level: the recording is \
             one contact (--stance-baseline contact)"
        ),
        "{stdout}"
    );
    assert!(
        stdout.contains(
            "note           the recording is one contact from its first frame to its last: its \
             stance is partial at both ends and gives no sample without --include-partial \
             (--one-sample-per-file for a data set of such trials)"
        ),
        "{stdout}"
    );

    let walk = shared("tekscan/FrasP01L.asf");
    let out = presrs(&["inspect", walk.to_str().unwrap()]);
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains("stances        6 found, 5 complete, measured from the baseline"),
        "{stdout}"
    );
    assert!(!stdout.contains("note "), "{stdout}");
}

#[test]
fn a_data_set_of_one_contact_movies_is_summarised_in_one_line_and_the_cause_named() {
    let jiku = shared("real/jiku-walk");
    let dir = tempfile::tempdir().unwrap();
    let manifest = dir.path().join("m.csv");
    let mut rows = format!(
        "path,label,frame\n{},slow,20\n",
        jiku.join("s00_t01.npy").display()
    );
    for (file, label) in [
        ("s00_t00.npy", "fast"),
        ("s00_t02.npy", "slow"),
        ("s00_t03.npy", "normal"),
    ] {
        rows.push_str(&format!("{},{label},\n", jiku.join(file).display()));
    }
    std::fs::write(&manifest, rows).unwrap();
    let model = dir.path().join("model.json");
    let out = presrs(&[
        "train",
        "--manifest",
        manifest.to_str().unwrap(),
        "--out",
        model.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    let lines: Vec<&str> = stderr.lines().collect();
    // One warning line for the three files, then the error.
    assert_eq!(lines.len(), 2, "{stderr}");
    assert!(
        lines[0].starts_with("warning: 3 of 4 files gave no sample: ")
            && lines[0].ends_with(
                " ; they are one contact each (loaded from the first frame to the last): try \
                 --one-sample-per-file"
            ),
        "{stderr}"
    );
    assert!(
        lines[1].starts_with(&format!(
            "error: {}: cannot train: too few samples per class: \"fast\" has 0, \"normal\" 0, \
             \"slow\" 1 (at least 3 needed, 1 sample in all); 3 of 4 files gave no sample",
            manifest.display()
        )),
        "{stderr}"
    );
    assert!(!stderr.contains("validation"), "{stderr}");
    assert!(!model.exists());
}

/// `--sample auto` races the sample kinds in `train` (both scores said, the winner stored) and in
/// every fold of `eval`; the commands that take one kind say so and name the kinds instead of treating
/// auto as one of them.
#[test]
fn sample_auto_is_raced_in_train_and_eval_and_refused_elsewhere_with_the_kinds_named() {
    let manifest = shared("real/jiku-walk/manifest.csv");
    let manifest = manifest.to_str().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("m.json");
    let out = presrs(&[
        "train",
        "--manifest",
        manifest,
        "--one-sample-per-file",
        "--sample",
        "auto",
        "--classifier",
        "lda",
        "--features",
        "auto",
        "--per-class",
        "12",
        "--out",
        model.to_str().unwrap(),
    ]);
    let stderr = text(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("note: sample frame: "), "{stderr}");
    assert!(stderr.contains("note: sample stance: "), "{stderr}");
    assert!(stderr.contains(", chosen\n"), "{stderr}");
    let stored = std::fs::read_to_string(&model).unwrap();
    let chosen_stance = stderr
        .lines()
        .any(|l| l.starts_with("note: sample stance") && l.ends_with(", chosen"));
    assert_eq!(
        stored.contains("\"kind\": \"stance\""),
        chosen_stance,
        "{stored:.400}"
    );

    // eval races inside every fold, and says per fold which kind won, both scores and why
    let out = presrs(&[
        "eval",
        "--manifest",
        manifest,
        "--one-sample-per-file",
        "--sample",
        "auto",
        "--classifier",
        "lda",
        "--features",
        "auto",
        "--repeats",
        "1",
    ]);
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert!(out.status.success(), "{stderr}");
    assert!(stdout.contains("overall "), "{stdout}");
    assert!(stdout.contains("folds won of 2: "), "{stdout}");
    let folds: Vec<&str> = stdout
        .lines()
        .filter(|l| l.starts_with("seed 1, s0"))
        .collect();
    assert_eq!(folds.len(), 2, "{stdout}");
    for fold in folds {
        assert!(
            fold.contains(": frame ") && fold.contains(", stance "),
            "{fold}"
        );
    }
    // a command that reads one kind says so and names the kinds
    let movie = shared("real/jiku-walk/s00_t00.npy");
    let out = presrs(&[
        "inspect",
        movie.to_str().unwrap(),
        "--one-sample-per-file",
        "--sample",
        "auto",
    ]);
    let stderr = text(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr
            .contains("--sample auto races one frame against the whole sample (presrs train, eval"),
        "{stderr}"
    );
    assert!(stderr.contains("frame, stance or series"), "{stderr}");
    // the race takes one automatic choice per kind: other options that read one kind are refused
    let out = presrs(&[
        "eval",
        "--manifest",
        manifest,
        "--one-sample-per-file",
        "--sample",
        "auto",
        "--compare",
    ]);
    let stderr = text(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains("--compare, --perturb and --export-draws take one sample kind"),
        "{stderr}"
    );
}
