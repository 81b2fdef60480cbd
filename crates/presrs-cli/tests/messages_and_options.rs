//! What the command line says of options and samples (issue 45, "Messages and options"), on the real
//! one-contact walks of `jiku-walk` (read in place from the shared data folder): a stance length far
//! beyond the data refused before anything is allocated, options that do nothing with the sample kind
//! refused or warned of, options that do nothing with the model named, stance outputs in a stance's own
//! terms, and a sample race that the tie rule decided said so by `train`.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;
use std::path::{Path, PathBuf};

use common::{presrs, stderr, stdout, train_one_contact_stance_model};

fn jiku() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/real/jiku-walk")
}

/// A manifest in `dir` of the `jiku-walk` trials of subject `subject` (`s00`, `s01`), `per_label` of
/// each label (all with `None`).
fn manifest(dir: &Path, subject: &str, per_label: Option<usize>) -> PathBuf {
    let text = std::fs::read_to_string(jiku().join("manifest.csv")).unwrap();
    let mut kept = std::collections::BTreeMap::<String, usize>::new();
    let mut rows = String::from("path,label,condition,group\n");
    for line in text.lines().skip(1) {
        let fields: Vec<&str> = line.split(',').collect();
        if fields[3] != subject {
            continue;
        }
        let count = kept.entry(fields[1].to_owned()).or_default();
        if per_label.is_some_and(|most| *count >= most) {
            continue;
        }
        *count += 1;
        let path = jiku().join(fields[0]);
        rows.push_str(&format!("{},{}\n", path.display(), fields[1..].join(",")));
    }
    let path = dir.join(format!("{subject}.csv"));
    std::fs::write(&path, rows).unwrap();
    path
}

/// A whole-stance model (rocket + ridge) of six `jiku-walk` trials, written in `dir`.
fn stance_model(dir: &Path) -> PathBuf {
    let manifest = manifest(dir, "s00", Some(4));
    let model = dir.join("stance.json");
    train_one_contact_stance_model(&manifest, &model);
    model
}

/// `--stance-length 100000000` asked for 9.6 GB a stance: it is refused before any is allocated, with
/// the longest stance found and what to give, in train and eval alike.
#[test]
fn a_stance_length_far_beyond_the_longest_stance_is_refused_before_allocating() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = manifest(dir.path(), "s00", Some(2));
    let out_model = dir.path().join("m.json");
    let common = [
        "--manifest",
        manifest.to_str().unwrap(),
        "--sample",
        "stance",
        "--one-sample-per-file",
        "--stance-length",
        "100000000",
        "--features",
        "rocket",
        "--classifier",
        "ridge",
    ];
    let train = [
        &["train", "--out", out_model.to_str().unwrap()][..],
        &common,
    ]
    .concat();
    let eval = [&["eval", "--repeats", "1"][..], &common].concat();
    // With `auto`, the whole sample's reading fails the same (the frame does not win by default).
    let raced = [
        "train",
        "--out",
        out_model.to_str().unwrap(),
        "--manifest",
        manifest.to_str().unwrap(),
        "--sample",
        "auto",
        "--one-sample-per-file",
        "--stance-length",
        "100000000",
    ];
    for args in [train, eval, raced.to_vec()] {
        let out = presrs(&args);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            err.contains("--stance-length 100000000 is far longer than the longest stance found (")
                && err.contains("give at most ")
                && err.contains("or leave --stance-length out"),
            "{args:?}: {err}"
        );
        assert!(!err.contains("memory allocation"), "{err}");
    }
    assert!(!out_model.exists());
}

/// `--stance-length` with one-frame samples is refused (as Python refuses `stance_length=`), a
/// `--stance-frame` with whole stances is a warning, and with `--sample auto` both are accepted.
#[test]
fn options_that_do_nothing_with_the_sample_kind_are_refused_or_warned_of() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = manifest(dir.path(), "s00", Some(4));
    let model = dir.path().join("m.json");
    let base = [
        "train",
        "--manifest",
        manifest.to_str().unwrap(),
        "--out",
        model.to_str().unwrap(),
        "--one-sample-per-file",
    ];
    let out = presrs(&[&base[..], &["--sample", "frame", "--stance-length", "50"]].concat());
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains(
            "--stance-length 50 applies to whole-stance samples, not to the frame sample chosen; \
             leave it out, or choose --sample stance"
        ),
        "{err}"
    );
    assert!(err.contains("Usage: presrs train"), "{err}");
    assert!(!model.exists());

    let out = presrs(&[&base[..], &["--sample", "series", "--stance-length", "50"]].concat());
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));

    let whole = [
        "--sample",
        "stance",
        "--stance-frame",
        "peak",
        "--features",
        "rocket",
        "--classifier",
        "ridge",
    ];
    let out = presrs(&[&base[..], &whole].concat());
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains(
            "warning: --stance-frame peak picks one frame of each stance, but a stance sample uses \
             every frame of the stance: it changes nothing here"
        ),
        "{err}"
    );
    // Without it, no such warning.
    let out = presrs(&[&base[..], &whole[..2], &whole[4..]].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(!stderr(&out).contains("--stance-frame"), "{}", stderr(&out));
}

/// A tie in `train --sample auto`'s race kept the frame by rule: train says what the race measured,
/// that the rule decided, and the option that trains the other kind. With `auto` the settings of either
/// kind are accepted without a word.
#[test]
fn train_says_when_the_tie_rule_kept_the_frame() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = manifest(dir.path(), "s01", None);
    let model = dir.path().join("m.json");
    let out = presrs(&[
        "train",
        "--manifest",
        manifest.to_str().unwrap(),
        "--out",
        model.to_str().unwrap(),
        "--sample",
        "auto",
        "--one-sample-per-file",
        "--stance-frame",
        "mid",
    ]);
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("note: a tie in validation goes to one frame"),
        "the race tied: {err}"
    );
    let warning = err
        .lines()
        .find(|line| line.starts_with("warning: the sample race tied in validation (frame "))
        .unwrap_or_else(|| panic!("no tie warning: {err}"));
    assert!(
        warning.contains("the frame sample was kept by rule")
            && warning.contains("stance 100.0 %")
            && warning.contains("train it with --sample stance"),
        "{warning}"
    );
    assert!(!err.contains("--stance-frame"), "{err}");
}

/// A whole-stance model's outputs speak of stances in their own terms: counts of stances, the sample's
/// shape as channels x frames, no principal components for ridge, and no comparison with the paper's
/// per-image time.
#[test]
fn stance_outputs_speak_of_stances() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = manifest(dir.path(), "s00", Some(6));
    let model = dir.path().join("m.json");
    let out = presrs(&[
        "train",
        "--manifest",
        manifest.to_str().unwrap(),
        "--out",
        model.to_str().unwrap(),
        "--sample",
        "stance",
        "--one-sample-per-file",
        "--classifier",
        "ridge",
        "--validate-by",
        "split",
    ]);
    let text = stdout(&out);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(text.contains("rocket + ridge, all features"), "{text}");
    assert!(!text.contains("ridge, 51 dims"), "{text}");
    assert!(text.contains(" on 18 stances ("), "{text}");
    assert!(text.contains("-> 12 channels x "), "{text}");
    assert!(!text.contains(" image"), "{text}");

    let out = presrs(&[
        "eval",
        "--manifest",
        manifest.to_str().unwrap(),
        "--sample",
        "stance",
        "--one-sample-per-file",
        "--features",
        "rocket",
        "--classifier",
        "ridge",
        "--per-class",
        "4",
        "--repeats",
        "1",
    ]);
    let text = stdout(&out);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(text.contains(" validation stances, "), "{text}");
    assert!(text.contains("us per stance"), "{text}");
    assert!(!text.contains("paper: 245 us"), "{text}");
    assert!(!text.contains("image"), "{text}");
}

/// Options that do nothing with a whole-stance model are refused naming themselves (usage errors):
/// `--sample-offset` (with what to give instead) and `--fuse`; `classify --frame` says the model
/// classifies whole stances and what to do instead.
#[test]
fn options_that_do_nothing_with_the_model_name_themselves() {
    let dir = tempfile::tempdir().unwrap();
    let model = stance_model(dir.path());
    let model = model.to_str().unwrap();
    for (args, says) in [
        (
            ["--sample-offset", "4"],
            "--sample-offset 4 picks the frame a one-frame model classifies",
        ),
        (
            ["--fuse", "4,5"],
            "--fuse 4,5 fuses one-frame decisions, but a whole-stance model decides once",
        ),
    ] {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_presrs"))
            .args(["stream", "--model", model])
            .args(args)
            .stdin(std::process::Stdio::null())
            .output()
            .unwrap();
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
        assert!(out.stdout.is_empty(), "nothing streamed: {args:?}");
    }
    let out = presrs(&["stream", "--model", model, "--sample-offset", "4"]);
    assert!(stderr(&out).contains("--decide-at 4"), "{}", stderr(&out));

    let movie = jiku().join("s00_t00.npy");
    let out = presrs(&[
        "classify",
        "--model",
        model,
        "--frame",
        "30",
        movie.to_str().unwrap(),
    ]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("the model classifies whole stances, touchdown to lift-off")
            && err
                .contains("--frame 30 picks one frame: leave --frame out to classify each stance")
            && err.contains("--sample frame"),
        "{err}"
    );
}

/// `inspect` on a clean single step (unloaded before and after one contact) finds its one stance and
/// says nothing is wrong: no hint of a standing preload.
#[test]
fn inspect_takes_a_clean_single_step_for_what_it_is() {
    let dir = tempfile::tempdir().unwrap();
    let step = presrs_io::read_recording(&jiku().join("s00_t00.npy")).unwrap();
    let grid = step.grid();
    let zeros = vec![0.0; 10 * grid.len()];
    let mut values = zeros.clone();
    for index in 0..step.frame_count() {
        values.extend_from_slice(step.frame(index).unwrap().values());
    }
    values.extend_from_slice(&zeros);
    let frames = values.len() / grid.len();
    let path = dir.path().join("step.npy");
    let mut bytes = Vec::new();
    presrs_io::npy::write_npy_f64(&mut bytes, &[frames, grid.rows, grid.cols], &values).unwrap();
    std::fs::write(&path, bytes).unwrap();
    let out = presrs(&["inspect", path.to_str().unwrap()]);
    let text = stdout(&out);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(text.contains("1 found, 1 complete"), "{text}");
    assert!(!text.contains("floor"), "{text}");
    assert!(!text.contains("note "), "{text}");

    // Measuring from the floor finds nothing in a trial that is one contact: the hint names the other
    // modes, not the one in use.
    let trial = jiku().join("s00_t00.npy");
    let out = presrs(&[
        "inspect",
        "--stance-baseline",
        "floor",
        trial.to_str().unwrap(),
    ]);
    let text = stdout(&out);
    assert!(
        text.contains("no stance was found measuring from the local floor")
            && text.contains("try --stance-baseline contact (one contact")
            && !text.contains("try --stance-baseline floor"),
        "{text}"
    );
}
