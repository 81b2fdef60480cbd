//! `presrs train --gait-table` and `presrs simulate --track --adaptive` end to end.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::process::Command;

fn presrs(args: &[&str]) -> String {
    let output = Command::new(env!("CARGO_BIN_EXE_presrs"))
        .args(args)
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "presrs {args:?} failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    String::from_utf8(output.stdout).unwrap()
}

#[test]
fn a_trained_model_carries_its_gait_table_and_runs_a_track_against_the_fixed_gaits() {
    let dir = tempfile::tempdir().unwrap();
    let sim = dir.path().join("sim");
    let sim = sim.to_str().unwrap();
    presrs(&[
        "simulate",
        "--out",
        sim,
        "--seed",
        "3",
        "--hops-per-gait",
        "8",
        "--gaits",
        "G2,G3",
    ]);
    let model = dir.path().join("m.json");
    let model = model.to_str().unwrap();
    let manifest = format!("{sim}/manifest.csv");
    let stdout = presrs(&[
        "train",
        "--manifest",
        &manifest,
        "--out",
        model,
        "--per-class",
        "12",
        "--validation",
        "4",
        "--gait-table",
        "wood=G3,clay=G2@0.50,carpet=G3,grass=G3",
    ]);
    assert!(
        stdout.contains("gait table carpet=G3,clay=G2@0.50"),
        "{stdout}"
    );
    let file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(model).unwrap()).unwrap();
    assert_eq!(file["online"]["gait_table"]["clay"], "G2@0.50");
    assert!(file["online"]["calibration"].is_object());

    let json = dir.path().join("track.json");
    let stdout = presrs(&[
        "simulate",
        "--track",
        "wood:1.5,clay:1.5",
        "--adaptive",
        model,
        "--repeats",
        "2",
        "--start-gait",
        "G1",
        "--json",
        json.to_str().unwrap(),
    ]);
    for needle in [
        "adaptive",
        "fixed G1",
        "fixed G2",
        "fixed G3",
        "fixed G2@0.50",
        "misclassified",
    ] {
        assert!(stdout.contains(needle), "{needle}: {stdout}");
    }
    assert!(stdout.contains("adaptation helps") || stdout.contains("adaptation does NOT help"));
    let cmp: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let policies = cmp["policies"].as_array().unwrap();
    // The configured gaits and the table's variant, each fixed.
    assert_eq!(policies.len(), 5);
    let adaptive = &policies[0];
    assert_eq!(adaptive["policy"], "adaptive");
    for run in adaptive["runs"].as_array().unwrap() {
        assert_eq!(run["finished"], true);
        let hops = run["hops"].as_array().unwrap();
        // It starts in G1 and, once it has classified a stance, follows the table; a stance the
        // novelty score puts far from every trained terrain is `unknown`, which the table does not
        // name, so the next hop keeps the gait it has.
        assert_eq!(hops[0]["gait"], "G1");
        assert!(run["switches"].as_u64().unwrap() >= 1, "{run}");
        assert!(run["decided"].as_u64().unwrap() as usize >= hops.len() / 2);
        for pair in hops.windows(2) {
            if let Some(believed) = pair[0]["believed"].as_str() {
                let want = match believed {
                    "clay" => "G2@0.50",
                    "unknown" => pair[0]["gait"].as_str().unwrap(),
                    _ => "G3",
                };
                assert_eq!(pair[1]["gait"], want, "{pair:?}");
            }
        }
    }
    // The fixed runs never classify.
    assert_eq!(policies[1]["runs"][0]["decided"], 0);
}

#[test]
fn a_bad_track_is_refused() {
    let output = Command::new(env!("CARGO_BIN_EXE_presrs"))
        .args(["simulate", "--track", "wood:abc"])
        .output()
        .unwrap();
    assert!(!output.status.success());
    assert!(String::from_utf8_lossy(&output.stderr).contains("wood:abc"));
}
