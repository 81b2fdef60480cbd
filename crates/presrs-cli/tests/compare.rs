//! `presrs eval --compare` and `--features auto --classifier auto` on a small simulated data set.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;
use common::presrs;

#[test]
fn compare_prints_every_combination_and_auto_records_its_choice() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    let sim = presrs(&[
        "simulate",
        "--out",
        out,
        "--seed",
        "3",
        "--hops-per-gait",
        "12",
        "--terrains",
        "wood,grass,clay",
        "--gaits",
        "G1,G2",
    ]);
    assert!(
        sim.status.success(),
        "{}",
        String::from_utf8_lossy(&sim.stderr)
    );
    let manifest = format!("{out}/manifest.csv");
    let common = [
        "--manifest",
        manifest.as_str(),
        "--train-condition",
        "G2",
        "--per-class",
        "10",
        "--validation",
        "4",
        "--repeats",
        "1",
        "--dims",
        "10",
    ];
    let compare = presrs(&[&["eval", "--compare", "--json"][..], &common[..]].concat());
    assert!(
        compare.status.success(),
        "{}",
        String::from_utf8_lossy(&compare.stderr)
    );
    let text = String::from_utf8_lossy(&compare.stdout);
    // user-facing shapes, no serialised Rust enums
    assert!(
        !text.contains("\"Ok\"") && !text.contains("\"Err\"") && !text.contains("\"Count\""),
        "{text}"
    );
    let json: serde_json::Value = serde_json::from_slice(&compare.stdout).unwrap();
    let rows = json["comparison"].as_array().unwrap();
    assert_eq!(rows.len(), 5 * 5, "every feature x classifier combination");
    let mut best = 0.0_f64;
    for row in rows {
        let report = &row["report"];
        assert!(report.is_object(), "{row}");
        assert!(row.get("error").is_none(), "{row}");
        let overall = row["overall_accuracy"].as_f64().unwrap();
        assert_eq!(report["overall"]["mean"].as_f64().unwrap(), overall);
        assert!(
            overall > 0.5,
            "{} + {}: {overall}",
            row["features"],
            row["classifier"]
        );
        assert!(row["per_condition"]["G1"].is_number());
        assert!(report["per_condition"]["G1"]["mean"].is_number());
        assert_eq!(report["protocol"]["validation"], 4);
        best = best.max(overall);
    }
    // the contract's fields, of the best combination (no --features/--classifier given)
    assert_eq!(
        json["summary_of"]["reason"], "best",
        "{}",
        json["summary_of"]
    );
    assert_eq!(json["overall_accuracy"].as_f64().unwrap(), best);
    assert!(json["per_condition"]["G1"].is_number());
    assert!(json["median_classify_ns"].as_u64().unwrap() > 0);
    assert!(json["confusion"]["labels"].is_array());

    // with both given, the configured combination's
    let configured = presrs(
        &[
            &[
                "eval",
                "--compare",
                "--json",
                "--features",
                "fft2d",
                "--classifier",
                "lda",
            ][..],
            &common[..],
        ]
        .concat(),
    );
    assert!(configured.status.success());
    let configured: serde_json::Value = serde_json::from_slice(&configured.stdout).unwrap();
    assert_eq!(
        configured["summary_of"],
        serde_json::json!({"features": "fft2d", "classifier": "lda", "reason": "configured"})
    );
    let row = rows
        .iter()
        .find(|r| r["features"] == "fft2d" && r["classifier"] == "lda")
        .unwrap();
    assert_eq!(configured["overall_accuracy"], row["overall_accuracy"]);
    let table = presrs(&[&["eval", "--compare"][..], &common[..]].concat());
    let text = String::from_utf8_lossy(&table.stdout);
    assert!(
        text.contains("fft2d_polar+glcm") && text.contains("svm"),
        "{text}"
    );

    // auto is the default: the cheap feature families (fft1d, fft2d, fft2d_polar) x every classifier,
    // then each after the square root and log1p intensity transforms x every classifier, then the texture
    // families (glcm, fft2d_polar+glcm), also under each transform, x every classifier; --dims given: no
    // refinement of the dims
    let auto = presrs(&[&["eval", "--json"][..], &common[..]].concat());
    assert!(
        auto.status.success(),
        "{}",
        String::from_utf8_lossy(&auto.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&auto.stdout).unwrap();
    let selection = &json["selections"][0];
    let scores = selection["scores"].as_array().unwrap();
    assert_eq!(scores.len(), 75);
    assert!(selection["chosen"].as_u64().unwrap() < 75);
    let texture = |s: &serde_json::Value| s["features"].as_str().unwrap().contains("glcm");
    assert!(scores[45..].iter().all(texture), "texture families last");
    assert!(!scores[..45].iter().any(texture));
    assert!(scores.iter().all(|s| s.get("skipped").is_none()));

    // a budget spent at once: only the first feature group (the paper's features) is scored, the rest
    // is marked skipped, and a warning says so and what to do
    let cut = presrs(&[&["eval", "--json", "--budget", "0.000001"][..], &common[..]].concat());
    assert!(
        cut.status.success(),
        "{}",
        String::from_utf8_lossy(&cut.stderr)
    );
    let stderr = String::from_utf8_lossy(&cut.stderr);
    assert!(
        stderr.contains("the automatic choice was cut short (the time budget of")
            && stderr.contains("70 of 75 candidates not tried")
            && stderr.contains("--budget 0 for no limit"),
        "{stderr}"
    );
    let json: serde_json::Value = serde_json::from_slice(&cut.stdout).unwrap();
    // the JSON carries the warnings stderr printed, for a script that reads stdout alone
    let warnings = json["warnings"].as_array().unwrap();
    assert!(
        warnings.iter().any(|w| w
            .as_str()
            .unwrap()
            .contains("the automatic choice was cut short")),
        "{warnings:?}"
    );
    assert!(json.get("warnings").is_some() && auto_has_no_cut(&auto.stdout));
    let scores = json["selections"][0]["scores"].as_array().unwrap();
    let skipped: Vec<bool> = scores.iter().map(|s| s["skipped"] == true).collect();
    assert_eq!(skipped, [vec![false; 5], vec![true; 70]].concat());
    let bad = presrs(&[&["eval", "--budget=-1"][..], &common[..]].concat());
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("0 or more"));

    let model = format!("{out}/auto.model.json");
    let train = presrs(&[
        "train",
        "--manifest",
        manifest.as_str(),
        "--out",
        model.as_str(),
        "--per-class",
        "10",
        "--dims",
        "10",
        "--features",
        "auto",
        "--classifier",
        "auto",
        "--full-search",
    ]);
    assert!(
        train.status.success(),
        "{}",
        String::from_utf8_lossy(&train.stderr)
    );
    let text = String::from_utf8_lossy(&train.stdout);
    // The simulator's groups are its recordings (6 here): validated by group, merged whole into 5 folds.
    assert!(
        text.contains("5 folds of whole groups inside the training data")
            && text.contains("6 groups"),
        "{text}"
    );
    // --full-search tries the texture families too, and the choice is printed
    assert!(text.contains("fft2d_polar+glcm"), "{text}");
    assert!(text.contains("chosen: "), "{text}");
    let saved = std::fs::read_to_string(&model).unwrap();
    assert!(
        saved.contains("\"selection\""),
        "the choice is recorded in the model"
    );
}

/// Images larger than the polar form's 64 x 64 padding (60 x 75, like a real fingertip array): every
/// combination of `--compare` runs, the transform grown to fit instead of aborting.
#[test]
fn compare_runs_on_images_larger_than_the_default_padding() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = common::write_image_set(dir.path(), (60, 75), 3, 8, 1, 0.0, 5);
    let out = presrs(&[
        "eval",
        "--compare",
        "--json",
        "--manifest",
        manifest.to_str().unwrap(),
        "--per-class",
        "5",
        "--validation",
        "2",
        "--repeats",
        "1",
        "--dims",
        "5",
    ]);
    assert!(out.status.success(), "{}", common::stderr(&out));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let rows = json["comparison"].as_array().unwrap();
    assert_eq!(rows.len(), 5 * 5, "every feature x classifier combination");
    for row in rows {
        assert!(row.get("error").is_none(), "{row}");
    }
    let polar = rows
        .iter()
        .find(|row| row["features"] == "fft2d_polar" && row["classifier"] == "lda")
        .expect("the polar row");
    assert!(polar["overall_accuracy"].as_f64().unwrap() > 0.5, "{polar}");
}

/// Whether an eval document's warnings (absent when there are none) say nothing of a cut budget.
fn auto_has_no_cut(stdout: &[u8]) -> bool {
    let json: serde_json::Value = serde_json::from_slice(stdout).unwrap();
    json.get("warnings")
        .is_none_or(|warnings| !warnings.to_string().contains("cut short"))
}
