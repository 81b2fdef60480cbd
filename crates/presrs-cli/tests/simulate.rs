//! `presrs simulate` end to end: files written, read back by the TekScan reader, manifest, determinism.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;
use std::process::Command;

fn simulate(out: &Path, extra: &[&str]) -> String {
    let output = Command::new(env!("CARGO_BIN_EXE_presrs"))
        .args(["simulate", "--out"])
        .arg(out)
        .args(extra)
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "simulate failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    String::from_utf8(output.stdout).unwrap()
}

#[test]
fn movies_read_back_with_stances_where_the_truth_says() {
    let dir = tempfile::tempdir().unwrap();
    let args = [
        "--seed",
        "4",
        "--hops-per-gait",
        "3",
        "--terrains",
        "wood,grass",
        "--gaits",
        "G1,G3",
    ];
    let stdout = simulate(dir.path(), &args);
    assert!(stdout.contains("Forward velocity"), "{stdout}");

    let manifest = std::fs::read_to_string(dir.path().join("manifest.csv")).unwrap();
    let mut lines = manifest.lines();
    assert_eq!(lines.next(), Some("path,label,condition,group,frame,load"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 4, "one movie per terrain and gait");
    for row in &rows {
        let rec = presrs_io::read_recording(&dir.path().join(row[0])).unwrap();
        assert_eq!((rec.grid().rows, rec.grid().cols), (44, 44));
        assert_eq!(rec.frame_period_s(), Some(0.01));
        assert_eq!(rec.meta.sensor.as_deref(), Some("5051"));
        assert!(
            rec.data()
                .iter()
                .all(|&v| (0.0..=255.0).contains(&v) && v.fract() == 0.0)
        );
        assert!(["wood", "grass"].contains(&row[1]));
        assert!(["G1", "G3"].contains(&row[2]));
        assert_eq!(row[5], "2.5");
    }

    // Stance frames from the truth carry load; the frames just outside them are flight (empty).
    let hops = std::fs::read_to_string(dir.path().join("truth/hops.csv")).unwrap();
    let mut lines = hops.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let mut checked = 0;
    for line in lines {
        let cells: Vec<&str> = line.split(',').collect();
        let rec = presrs_io::read_recording(&dir.path().join(cells[col("path")])).unwrap();
        let totals = rec.total_per_frame();
        let first: usize = cells[col("first_stance_frame")].parse().unwrap();
        let last: usize = cells[col("last_stance_frame")].parse().unwrap();
        let mid: usize = cells[col("mid_stance_frame")].parse().unwrap();
        assert!(first < mid && mid < last);
        assert!(
            totals[mid] > 1000.0,
            "mid-stance frame {mid} is loaded: {}",
            totals[mid]
        );
        if first > 0 {
            assert!(totals[first - 1] < totals[mid] * 0.01);
        }
        if last + 1 < totals.len() {
            assert!(totals[last + 1] < totals[mid] * 0.01);
        }
        checked += 1;
    }
    assert_eq!(checked, 12);
}

#[test]
fn same_seed_same_bytes() {
    let a = tempfile::tempdir().unwrap();
    let b = tempfile::tempdir().unwrap();
    let args = [
        "--seed",
        "9",
        "--hops-per-gait",
        "2",
        "--terrains",
        "carpet,clay",
        "--gaits",
        "G2",
    ];
    simulate(a.path(), &args);
    simulate(b.path(), &args);
    for file in [
        "manifest.csv",
        "truth/hops.csv",
        "truth/trials.json",
        "recordings/carpet_G2_000.asf",
        "recordings/clay_G2_000.asf",
    ] {
        let x = std::fs::read(a.path().join(file)).unwrap();
        let y = std::fs::read(b.path().join(file)).unwrap();
        assert!(x == y, "{file} differs between runs with the same seed");
    }
}

#[test]
fn print_config_and_overrides_and_image_terrain() {
    let output = Command::new(env!("CARGO_BIN_EXE_presrs"))
        .args(["simulate", "--print-config"])
        .output()
        .unwrap();
    assert!(output.status.success());
    let text = String::from_utf8(output.stdout).unwrap();
    assert!(text.contains("\"realism\"") && text.contains("\"touchdown_gain\""));

    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("cfg.json");
    std::fs::write(
        &cfg,
        r#"{"experiment": {"hops_per_trial": 2}, "realism": {"sensor_noise_counts": 0}}"#,
    )
    .unwrap();
    let texture =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/textures/grass.png");
    let mut args = vec![
        "--config".to_owned(),
        cfg.display().to_string(),
        "--hops-per-gait".into(),
        "3".into(),
        "--gaits".into(),
        "G2".into(),
        "--load".into(),
        "3".into(),
    ];
    let with_image = texture.exists();
    if with_image {
        args.extend(["--terrains".into(), "wood,photo".into()]);
        args.extend([
            "--terrain-image".into(),
            format!("photo={}", texture.display()),
        ]);
    } else {
        args.extend(["--terrains".into(), "wood".into()]);
    }
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    simulate(&dir.path().join("out"), &args);
    let manifest = std::fs::read_to_string(dir.path().join("out/manifest.csv")).unwrap();
    // 3 hops with 2 per trial: two movies per terrain; load column is the mass.
    assert_eq!(
        manifest
            .lines()
            .filter(|l| l.starts_with("recordings/wood_G2_"))
            .count(),
        2
    );
    assert!(manifest.lines().skip(1).all(|l| l.ends_with(",3")));
    if with_image {
        assert!(manifest.contains("recordings/photo_G2_000.asf,photo,G2"));
    }

    // Bad usage is an error with a readable message.
    let output = Command::new(env!("CARGO_BIN_EXE_presrs"))
        .args(["simulate", "--out"])
        .arg(dir.path().join("bad"))
        .args(["--terrains", "sand"])
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&output.stderr).contains("unknown terrain"));
}

/// `presrs simulate --out DIR ARGS`, expected to be refused as bad usage (exit 2) before writing
/// anything; returns stderr.
fn refused(args: &[&str]) -> String {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let output = Command::new(env!("CARGO_BIN_EXE_presrs"))
        .args(["simulate", "--out"])
        .arg(&out)
        .args(args)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert_eq!(output.status.code(), Some(2), "{args:?}: {stderr}");
    assert!(!out.exists(), "{args:?} wrote {}", out.display());
    stderr
}

#[test]
fn terrains_and_gaits_are_named_once_and_images_not_after_built_ins() {
    let texture = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/textures/grass.png")
        .display()
        .to_string();
    let err = refused(&["--terrains", "wood,clay,wood", "--hops-per-gait", "1"]);
    assert!(err.contains("--terrains lists wood twice"), "{err}");
    let err = refused(&["--gaits", "G2,G2", "--hops-per-gait", "1"]);
    assert!(err.contains("--gaits lists G2 twice"), "{err}");
    // An image called like a built-in (the built-in would be simulated), with or without --terrains.
    let image = format!("wood={texture}");
    let err = refused(&["--terrain-image", &image, "--hops-per-gait", "1"]);
    assert!(err.contains("wood is a built-in terrain"), "{err}");
    let err = refused(&["--terrains", "clay", "--terrain-image", &image]);
    assert!(err.contains("wood is a built-in terrain"), "{err}");
    // Two images of one name; an image left out of --terrains.
    let a = format!("photo={texture}");
    let err = refused(&["--terrain-image", &a, "--terrain-image", &a]);
    assert!(err.contains("gives the name photo to two images"), "{err}");
    let err = refused(&["--terrains", "clay", "--terrain-image", &a]);
    assert!(
        err.contains("--terrain-image photo is not among --terrains"),
        "{err}"
    );
    let err = refused(&["--gaits", "G9"]);
    assert!(err.contains("--gaits G9: unknown gait"), "{err}");
}

#[test]
fn bad_option_values_are_bad_usage() {
    for (args, says) in [
        (&["--hops-per-gait", "0"][..], "--hops-per-gait"),
        (&["--load", "0"], "--load"),
        (&["--load", "nan"], "--load"),
        (&["--terrain-image", "foo"], "NAME=PNG"),
        (&["--track", "foo"], "TERRAIN:METRES"),
        (&["--track", "mud:3"], "unknown terrain \"mud\""),
        (&["--track", "wood:1", "--repeats", "0"], "--repeats"),
        (&["--track", "wood:1", "--start-gait", "G2"], "--adaptive"),
        (&["--track", "wood:1", "--terrains", "wood"], "--terrains"),
        (
            &["--track", "wood:1", "--terrain-image", "x=y.png"],
            "--terrain-image",
        ),
        (
            &["--track", "wood:1", "--fixed-gait", "G9"],
            "--fixed-gait G9",
        ),
        // Judged before the model is even read.
        (
            &[
                "--track",
                "wood:1",
                "--adaptive",
                "no-such-model.json",
                "--start-gait",
                "G9",
            ],
            "--start-gait G9: unknown gait",
        ),
    ] {
        let err = refused(args);
        assert!(err.contains(says), "{args:?}: {err}");
    }
}
