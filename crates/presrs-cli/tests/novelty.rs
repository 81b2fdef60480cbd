//! Unknown terrain end to end on the command line: a model trained on several recordings per terrain
//! calls a terrain it never saw `unknown` and a new recording of a known one by its name; a model whose
//! terrains each come from one recording gets no novelty score, and `train` says why.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;
use std::process::{Command, Output};

fn presrs(args: &[&str], dir: &Path) -> Output {
    let output = Command::new(env!("CARGO_BIN_EXE_presrs"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "presrs {args:?} failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    output
}

fn simulate(dir: &Path, out: &str, terrains: &str, gaits: &str, hops: &str, seed: &str) {
    presrs(
        &[
            "simulate",
            "--out",
            out,
            "--terrains",
            terrains,
            "--gaits",
            gaits,
            "--hops-per-gait",
            hops,
            "--seed",
            seed,
        ],
        dir,
    );
}

/// `classify --json`'s (file, label) of every stance of `files` (`extra` options before them).
fn labels(dir: &Path, model: &str, extra: &[&str], files: &[&str]) -> Vec<(String, String)> {
    let mut args = vec!["classify", "--model", model, "--json"];
    args.extend(extra);
    args.extend(files);
    let out: serde_json::Value = serde_json::from_slice(&presrs(&args, dir).stdout).unwrap();
    out["results"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| {
            let file = v["file"].as_str().unwrap().to_owned();
            (file, v["label"].as_str().unwrap().to_owned())
        })
        .collect()
}

#[test]
fn several_recordings_per_terrain_give_unknown_for_a_terrain_never_seen_and_one_each_gives_none() {
    let dir = tempfile::tempdir().unwrap();
    let dir = dir.path();
    simulate(dir, "two", "wood,clay,grass", "G1,G2", "6", "3");
    simulate(dir, "one", "wood,clay,grass", "G2", "8", "3");
    simulate(dir, "new", "carpet,wood", "G2", "5", "9");
    let train = |manifest: &str, model: &str, extra: &[&str]| {
        let mut args = vec![
            "train",
            "--manifest",
            manifest,
            "--features",
            "fft1d",
            "--classifier",
            "pwe",
            "--out",
            model,
        ];
        args.extend(extra);
        String::from_utf8(presrs(&args, dir).stderr).unwrap()
    };
    let files = [
        "new/recordings/carpet_G2_000.asf",
        "new/recordings/wood_G2_000.asf",
    ];

    // Two recordings (gaits) per terrain: the threshold is learned by holding recordings out.
    let said = train("two/manifest.csv", "two.json", &[]);
    assert!(!said.contains("no novelty score"), "{said}");
    assert!(
        said.contains("progress: fitting the novelty score on 36 samples"),
        "{said}"
    );
    let decided = labels(dir, "two.json", &[], &files);
    let share = |file: &str, label: &str| {
        let of_file: Vec<_> = decided.iter().filter(|(f, _)| f.ends_with(file)).collect();
        of_file.iter().filter(|(_, l)| l == label).count() as f64 / of_file.len() as f64
    };
    assert!(share("carpet_G2_000.asf", "unknown") >= 0.8, "{decided:?}");
    assert!(share("wood_G2_000.asf", "wood") >= 0.6, "{decided:?}");

    // `--novelty off`: the same model decides among its classes only, and `train` fits no score.
    let decided = labels(dir, "two.json", &["--novelty", "off"], &files);
    assert!(decided.iter().all(|(_, l)| l != "unknown"), "{decided:?}");
    let decided = labels(dir, "two.json", &["--novelty=on"], &files);
    assert!(decided.iter().any(|(_, l)| l == "unknown"), "{decided:?}");
    let said = train("two/manifest.csv", "off.json", &["--novelty", "off"]);
    assert!(!said.contains("fitting the novelty score"), "{said}");
    let decided = labels(dir, "off.json", &[], &files);
    assert!(decided.iter().all(|(_, l)| l != "unknown"), "{decided:?}");

    // One recording per terrain: nothing tells a new recording from a new terrain, so no score.
    let said = train("one/manifest.csv", "one.json", &[]);
    assert!(
        said.contains("no novelty score") && said.contains("no class is recorded in two groups"),
        "{said}"
    );
    let decided = labels(dir, "one.json", &[], &files);
    assert!(decided.iter().all(|(_, l)| l != "unknown"), "{decided:?}");
}
