//! Drawing and validating on small or grouped data sets: `--per-class` capped with one warning, and the
//! automatic choice validated by group.

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
