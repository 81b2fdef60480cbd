//! The bad-input corpus: small broken files (generated here, in a temporary folder) of every kind the
//! `presrs` binary reads. Each must give exit code 1 and a one-line `error:` naming the file (and the line
//! when there is one), never a panic, and leave no output file behind. Also: an interrupted `simulate`
//! leaves no half-written file under a final name.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers outside #[test] functions

mod common;
use common::presrs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::Duration;

/// Asserts a clean failure: exit code 1, an `error:` line mentioning every needle, no panic.
fn assert_clean_failure(case: &str, out: &Output, needles: &[&str]) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        out.status.code(),
        Some(1),
        "{case}: exit code {:?}, stderr: {err}",
        out.status.code()
    );
    assert!(!err.contains("panicked"), "{case}: panic: {err}");
    assert!(err.starts_with("error: "), "{case}: {err}");
    for needle in needles {
        assert!(
            err.contains(needle),
            "{case}: `{needle}` missing from: {err}"
        );
    }
}

fn npy_bytes(descr: &str, shape: &str, data: &[u8]) -> Vec<u8> {
    let mut header = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    bytes.extend_from_slice(data);
    bytes
}

fn f64s(values: &[f64]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// Deterministic "random" bytes (a linear congruential generator: no dependency, same bytes every run).
fn garbage(len: usize, seed: u64) -> Vec<u8> {
    let mut state = seed;
    (0..len)
        .map(|_| {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 56) as u8
        })
        .collect()
}

fn utf16le_without_text_bom(text: &str) -> Vec<u8> {
    text.encode_utf16().flat_map(u16::to_le_bytes).collect()
}

fn png_header_only() -> Vec<u8> {
    let mut bytes = Vec::new();
    presrs_io::png::write_png_gray8(&mut bytes, presrs_core::Grid::new(4, 4), &[7; 16]).unwrap();
    bytes
}

fn rgb_png() -> Vec<u8> {
    let mut bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut bytes, 2, 2);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().unwrap();
        writer.write_image_data(&[9; 12]).unwrap();
    }
    bytes
}

const TEKSCAN_HEAD: &str = "DATA_TYPE MOVIE\nROWS 2\nCOLS 3\nASCII_DATA @@\n\n";

/// (file name, content, text the error must contain besides the file name).
fn recording_cases() -> Vec<(&'static str, Vec<u8>, &'static str)> {
    let t = |body: &str| format!("{TEKSCAN_HEAD}{body}").into_bytes();
    let png = png_header_only();
    vec![
        // TekScan ASCII.
        ("empty.asf", Vec::new(), "empty file"),
        ("blank.asf", b"\n \n\t\n".to_vec(), "empty file"),
        ("truncated.asf", t("Frame 1\n1,2,3\n4,5"), "line 8"),
        ("no_end.asf", t("Frame 1\n1,2,3\n"), "line"),
        ("wrong_width.asf", t("Frame 1\n1,2,3\n4,5,6,7\n@@\n"), "line 8"),
        ("extra_row.asf", t("Frame 1\n1,2,3\n4,5,6\n7,8,9\n@@\n"), "line 9"),
        ("nan.asf", t("Frame 1\n1,2,3\n4,nan,6\n@@\n"), "line 8"),
        ("inf.asf", t("Frame 1\n1,2,3\n4,5,-inf\n@@\n"), "line 8"),
        ("word.asf", t("Frame 1\n1,2,3\n4,five,6\n@@\n"), "line 8"),
        ("huge_number.asf", t("Frame 1\n1,2,3\n4,1e999,6\n@@\n"), "line 8"),
        (
            "huge_dims.asf",
            b"DATA_TYPE MOVIE\nROWS 99999999999\nCOLS 99999999999\nASCII_DATA @@\n\nFrame 1\n1\n@@\n"
                .to_vec(),
            "too large",
        ),
        (
            "big_dims.asf",
            b"DATA_TYPE MOVIE\nROWS 100000\nCOLS 100000\nASCII_DATA @@\n\nFrame 1\n1,2\n@@\n".to_vec(),
            "line 7",
        ),
        (
            "negative_dims.asf",
            b"DATA_TYPE MOVIE\nROWS -2\nCOLS 3\nASCII_DATA @@\n\nFrame 1\n1,2,3\n@@\n".to_vec(),
            "line 2",
        ),
        (
            "zero_dims.asf",
            b"DATA_TYPE MOVIE\nROWS 0\nCOLS 3\nASCII_DATA @@\n\n@@\n".to_vec(),
            "line 2",
        ),
        ("garbage.asf", garbage(3000, 1), ""),
        // NumPy.
        ("empty.npy", Vec::new(), "not a NumPy file"),
        ("magic_only.npy", b"\x93NUMPY".to_vec(), "header"),
        (
            "truncated.npy",
            npy_bytes("<f8", "(2, 3)", &f64s(&[1.0, 2.0, 3.0])),
            "truncated",
        ),
        (
            "nan.npy",
            npy_bytes("<f8", "(2, 3)", &f64s(&[1.0, 2.0, f64::NAN, 4.0, 5.0, 6.0])),
            "[0, 2] is NaN",
        ),
        (
            "inf.npy",
            npy_bytes(
                "<f8",
                "(1, 2, 2)",
                &f64s(&[1.0, 2.0, 3.0, f64::INFINITY]),
            ),
            "[0, 1, 1] is inf",
        ),
        (
            "strings.npy",
            npy_bytes("<U5", "(2, 3)", &[b'x'; 120]),
            "unsupported dtype",
        ),
        ("object.npy", npy_bytes("|O", "(2, 3)", &[0; 48]), "npy"),
        ("one_d.npy", npy_bytes("<f8", "(6,)", &f64s(&[1.0; 6])), "1-D"),
        (
            "four_d.npy",
            npy_bytes("<f8", "(1, 1, 2, 3)", &f64s(&[1.0; 6])),
            "4-D",
        ),
        ("zero_size.npy", npy_bytes("<f8", "(0, 3)", &[]), "empty"),
        (
            "huge_shape.npy",
            npy_bytes("<f8", "(100000, 100000, 100000)", &[0; 48]),
            "truncated",
        ),
        (
            "overflowing_shape.npy",
            npy_bytes("<f8", "(4294967296, 4294967296, 4)", &[0; 48]),
            "overflow",
        ),
        (
            "negative_shape.npy",
            npy_bytes("<f8", "(-2, 3)", &f64s(&[1.0; 6])),
            "header",
        ),
        ("garbage_header.npy", npy_bytes("<f8", "((", &[]), "header"),
        // PNG.
        ("empty.png", Vec::new(), "not a PNG"),
        ("truncated.png", png[..png.len() - 20].to_vec(), "PNG"),
        ("signature_only.png", png[..8].to_vec(), "PNG"),
        ("rgb.png", rgb_png(), "greyscale"),
        // Text matrices.
        ("empty.txt", Vec::new(), "no data"),
        ("comments.txt", b"# nothing\n#\n".to_vec(), "no data"),
        ("ragged.txt", b"1 2 3\n4 5\n".to_vec(), "line 2"),
        ("nan.txt", b"1 2\n3 NaN\n".to_vec(), "line 2"),
        ("inf.txt", b"1 inf\n".to_vec(), "line 1"),
        ("empty_cell.txt", b"1,,2\n".to_vec(), "line 1"),
        ("binary.txt", garbage(2000, 2), "binary file"),
        ("binary.dat", [b"1 2\n".to_vec(), vec![0, 0, 1, 2]].concat(), "binary file"),
        (
            "utf16_ragged.txt",
            utf16le_without_text_bom("\u{feff}1 2\r\n3\r\n"),
            "line 2",
        ),
    ]
}

#[test]
fn every_bad_recording_gets_a_clear_error_from_inspect() {
    let dir = tempfile::tempdir().unwrap();
    let cases = recording_cases();
    assert!(cases.len() >= 40);
    for (name, bytes, needle) in &cases {
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        let out = presrs(&["inspect", path.to_str().unwrap()]);
        assert_clean_failure(name, &out, &[name, needle]);
        assert!(out.stdout.is_empty(), "{name}: printed a table");
    }
}

#[test]
fn utf16_files_are_read_like_utf8_ones() {
    let dir = tempfile::tempdir().unwrap();
    let text = format!("{TEKSCAN_HEAD}Frame 1\r\n1,2,3\r\n4,5,6\r\n@@\r\n");
    for (name, bytes) in [
        (
            "le_bom.asf",
            utf16le_without_text_bom(&format!("\u{feff}{text}")),
        ),
        ("le.asf", utf16le_without_text_bom(&text)),
        (
            "be_bom.asf",
            format!("\u{feff}{text}")
                .encode_utf16()
                .flat_map(u16::to_be_bytes)
                .collect(),
        ),
        (
            "matrix.txt",
            utf16le_without_text_bom("\u{feff}1 2 3\r\n4 5 6\r\n"),
        ),
    ] {
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        let out = presrs(&["inspect", "--json", path.to_str().unwrap()]);
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert_eq!(out.status.code(), Some(0), "{name}: {stdout}");
        assert!(
            stdout.contains("\"rows\": 2") && stdout.contains("\"cols\": 3"),
            "{name}: {stdout}"
        );
    }
}

#[test]
fn bad_manifests_stop_train_and_eval_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("ok.txt"), "1 2\n3 4\n").unwrap();
    std::fs::write(d.join("nan.txt"), "1 2\n3 nan\n").unwrap();
    std::fs::create_dir(d.join("folder")).unwrap();
    let utf16: Vec<u8> = "\u{feff}path,label\nok.txt,wood\n"
        .encode_utf16()
        .flat_map(u16::to_le_bytes)
        .collect();
    let cases: Vec<(&str, Vec<u8>, &[&str])> = vec![
        ("empty.csv", Vec::new(), &["line 1", "empty manifest"]),
        ("header_only.csv", b"path,label\n".to_vec(), &["no samples"]),
        (
            "no_path.csv",
            b"label\nwood\n".to_vec(),
            &["line 1", "`path`"],
        ),
        (
            "missing_file.csv",
            b"path,label\nnope.txt,wood\n".to_vec(),
            &["line 2", "nope.txt"],
        ),
        (
            "negative_frame.csv",
            b"path,label,frame\nok.txt,wood,-1\n".to_vec(),
            &["line 2", "frame"],
        ),
        (
            "huge_frame.csv",
            b"path,label,frame\nok.txt,wood,99999999999999999999999\n".to_vec(),
            &["line 2", "frame"],
        ),
        (
            "frame_out_of_range.csv",
            b"path,label,frame\nok.txt,wood,5\n".to_vec(),
            &["line 2", "ok.txt"],
        ),
        (
            "negative_load.csv",
            b"path,label,load\nok.txt,wood,-5\n".to_vec(),
            &["line 2", "load"],
        ),
        (
            "nan_load.csv",
            b"path,label,load\nok.txt,wood,nan\n".to_vec(),
            &["line 2", "load"],
        ),
        (
            "long_row.csv",
            b"path,label\nok.txt,wood,x\n".to_vec(),
            &["line 2", "fields"],
        ),
        (
            "empty_label.csv",
            b"path,label\nok.txt,\n".to_vec(),
            &["line 2", "label"],
        ),
        (
            "folder.csv",
            b"path,label\nfolder,wood\n".to_vec(),
            &["line 2", "folder"],
        ),
        (
            "bad_file.csv",
            b"path,label\nnan.txt,wood\n".to_vec(),
            &["line 2", "nan.txt"],
        ),
        ("binary.csv", garbage(500, 3), &["UTF-8"]),
        ("utf16.csv", utf16, &["line 1", "UTF-16"]),
    ];
    let out_path = d.join("model.json");
    for (name, bytes, needles) in &cases {
        let manifest = d.join(name);
        std::fs::write(&manifest, bytes).unwrap();
        let out = presrs(&[
            "train",
            "--manifest",
            manifest.to_str().unwrap(),
            "--out",
            out_path.to_str().unwrap(),
        ]);
        assert_clean_failure(name, &out, &[&[*name][..], needles].concat());
        assert!(!out_path.exists(), "{name}: train wrote a model");
    }
    // eval reads manifests the same way.
    let out = presrs(&[
        "eval",
        "--manifest",
        d.join("missing_file.csv").to_str().unwrap(),
    ]);
    assert_clean_failure("eval", &out, &["missing_file.csv", "line 2"]);
    // No temporary files are left behind either.
    let leftovers: Vec<PathBuf> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

#[test]
fn bad_model_files_stop_classify() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let frame = d.join("ok.txt");
    std::fs::write(&frame, "1 2\n3 4\n").unwrap();
    let (model, _) = presrs_core::testing::bench_fixture(1, 0).unwrap();
    let good = serde_json::to_vec(&presrs_io::model_file::ModelFile::new(
        model,
        presrs_io::model_file::Provenance::default(),
    ))
    .unwrap();
    let mut wrong_version: serde_json::Value = serde_json::from_slice(&good).unwrap();
    wrong_version["format_version"] = serde_json::json!(999);
    let mut bad_dims: serde_json::Value = serde_json::from_slice(&good).unwrap();
    bad_dims["model"]["class_names"] = serde_json::json!(["a", "b", "c", "d", "e", "f", "g"]);
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("empty.json", Vec::new(), "corrupted"),
        (
            "truncated.json",
            good[..good.len() / 2].to_vec(),
            "corrupted",
        ),
        ("null.json", b"null".to_vec(), "not a presrs model"),
        ("array.json", b"[1, 2]".to_vec(), "not a presrs model"),
        // what is wrong in words, not Rust's Debug text (`Some("other")`, `None`)
        (
            "other.json",
            b"{\"format\": \"other\"}".to_vec(),
            "(its format is \"other\", expected \"presrs-model\")",
        ),
        ("no_format.json", b"{}".to_vec(), "(it has no format field)"),
        ("list.json", b"[1, 2]".to_vec(), "(it has no format field)"),
        ("nan.json", b"{\"format\": NaN}".to_vec(), "corrupted"),
        ("garbage.json", garbage(300, 4), "corrupted"),
        (
            "version.json",
            serde_json::to_vec(&wrong_version).unwrap(),
            "999",
        ),
        (
            "class_names.json",
            serde_json::to_vec(&bad_dims).unwrap(),
            "class names",
        ),
        (
            "utf16.json",
            utf16le_without_text_bom("\u{feff}{}"),
            "corrupted",
        ),
    ];
    for (name, bytes, needle) in &cases {
        let path = d.join(name);
        std::fs::write(&path, bytes).unwrap();
        let out = presrs(&[
            "classify",
            "--model",
            path.to_str().unwrap(),
            frame.to_str().unwrap(),
        ]);
        assert_clean_failure(name, &out, &[name, needle]);
    }
}

/// Kills `simulate` as soon as its first recording appears (others are then being written); every file
/// under a final name must be complete: each recording, the manifest (if written) and JSON read strictly.
#[test]
fn interrupted_simulate_leaves_no_half_written_file() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("sim");
    let mut child = Command::new(env!("CARGO_BIN_EXE_presrs"))
        .args([
            "simulate",
            "--out",
            out_dir.to_str().unwrap(),
            "--hops-per-gait",
            "40",
        ])
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let is_final_asf = |p: &PathBuf| {
        let name = p.file_name().unwrap().to_string_lossy();
        name.ends_with(".asf") && !name.starts_with('.')
    };
    let start = std::time::Instant::now();
    while !walk(&out_dir).iter().any(is_final_asf) && start.elapsed() < Duration::from_secs(120) {
        if child.try_wait().unwrap().is_some() {
            break;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    let _ = child.kill();
    let status = child.wait().unwrap();
    assert!(
        !status.success(),
        "simulate finished before it could be interrupted"
    );
    let mut complete = 0;
    for path in walk(&out_dir) {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if name.starts_with('.') && name.ends_with(".tmp") {
            continue; // an unfinished atomic write: not under a final name
        }
        match path.extension().and_then(|e| e.to_str()) {
            Some("asf") => {
                presrs_io::read_recording(&path)
                    .unwrap_or_else(|err| panic!("{} is half written: {err}", path.display()));
                complete += 1;
            }
            Some("csv") if name == "manifest.csv" => {
                presrs_io::manifest::read_manifest(&path).unwrap();
            }
            Some("json") => {
                let text = std::fs::read_to_string(&path).unwrap();
                serde_json::from_str::<serde_json::Value>(&text)
                    .unwrap_or_else(|err| panic!("{} is half written: {err}", path.display()));
            }
            _ => {}
        }
    }
    assert!(complete >= 1, "no recording was written before the kill");
}

fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return out;
    };
    for entry in entries {
        let path = entry.unwrap().path();
        if path.is_dir() {
            out.extend(walk(&path));
        } else {
            out.push(path);
        }
    }
    out
}
