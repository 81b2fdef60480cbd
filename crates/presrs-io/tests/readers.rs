//! Reading the real TekScan exports in `shared/data/tekscan/` (in place), write/read round trips, and
//! format detection by content and extension.

// Strategy helpers outside `#[test]` functions unwrap too.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};

use presrs_core::{FrameInfo, Grid, PressureUnit, Recording, SensorMeta};
use presrs_io::tekscan::{parse_tekscan, read_tekscan_with, write_tekscan, write_tekscan_file};
use presrs_io::{FileKind, ReadOptions, detect_kind, read_recording, read_recording_with};
use proptest::prelude::*;

fn shared(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/tekscan")
        .join(name)
}

fn extra<'a>(rec: &'a Recording, key: &str) -> Option<&'a str> {
    rec.meta
        .extra
        .iter()
        .find(|(k, _)| k == key)
        .map(|(_, v)| v.as_str())
}

#[test]
fn frasp01l_f_scan_insole() {
    let parsed = read_tekscan_with(&shared("FrasP01L.asf"), &ReadOptions::default()).unwrap();
    assert!(parsed.warnings.is_empty(), "{:?}", parsed.warnings);
    let rec = parsed.recording;
    assert_eq!(rec.grid(), Grid::new(60, 21));
    assert_eq!(rec.frame_count(), 205);
    assert_eq!(rec.frame_period_s(), Some(0.032));
    assert_eq!(rec.meta.units, Some(PressureUnit::KPa));
    assert_eq!(rec.meta.row_pitch_mm, Some(5.08));
    assert_eq!(rec.meta.col_pitch_mm, Some(5.08));
    assert_eq!(rec.meta.sensor.as_deref(), Some("FSCAN"));
    assert_eq!(rec.meta.noise_threshold, Some(3.0));
    assert_eq!(rec.meta.full_scale, Some(1514.73));
    // `B` cells: outside the insole outline, the same in every frame.
    let mask = rec.present().expect("FrasP01L has B cells");
    assert_eq!(mask.iter().filter(|&&here| !here).count(), 305);
    let first = rec.frame(0).unwrap();
    assert!(!first.is_present(0, 0) && !first.is_present(0, 8) && first.is_present(0, 9));
    assert!(!first.is_present(21, 20) && first.is_present(20, 20));
    // Values looked up in the file (rows/columns 0-based here).
    assert_eq!(first.get(20, 5), 18.0); // line 51: 0,0,0,0,0,18,...
    assert_eq!(first.get(25, 3), 107.0); // line 56: 0,0,71,107,...
    assert_eq!(first.total(), 32767.0);
    let frame9 = rec.frame(8).unwrap();
    assert_eq!(frame9.get(22, 10), 380.0); // line 550, the largest value of the file's heaviest frame
    assert_eq!(frame9.get(22, 7), 309.0);
    assert_eq!(rec.frame(100).unwrap().total(), 3980.0);
    assert_eq!(
        rec.frame_info()[204],
        FrameInfo {
            number: 205,
            suffix: None
        }
    );
    // Unknown header fields kept in order, comments as free text.
    let keys: Vec<&str> = rec.meta.extra.iter().map(|(k, _)| k.as_str()).collect();
    assert_eq!(
        keys,
        [
            "VERSION",
            "HARDWARE",
            "MAP_VERSION",
            "HW_TYPE",
            "FILENAME",
            "SENSEL_AREA",
            "MICRO_SECOND",
            "TIME",
            "CALIBRATION_POINT_1",
            "CALIBRATION_MODE_1",
            "CALIBRATION_INFO",
            "SENSITIVITY",
            "COMMENTS:",
            "overground walk p10",
            "MIRROR_ROW",
            "MIRROR_COL"
        ]
    );
    assert_eq!(
        extra(&rec, "TIME"),
        Some("Thursday, 16 February 2017 11:26:22 a.m.")
    );
    assert_eq!(
        extra(&rec, "CALIBRATION_POINT_1"),
        Some("75.0001 (Kgs) 4798 (Raw Sum) 240 (Number of Loaded Cells)")
    );
    assert_eq!(extra(&rec, "overground walk p10"), Some(""));
}

#[test]
fn example3_capacitive_array() {
    let rec = read_recording(&shared("example3.asf")).unwrap();
    assert_eq!(rec.grid(), Grid::new(16, 16));
    assert_eq!(rec.frame_count(), 10);
    assert_eq!(rec.frame_period_s(), Some(0.7));
    // No UNITS line: not stated, taken as raw counts.
    assert_eq!(rec.meta.units, None);
    assert_eq!(rec.meta.units_or_raw(), &PressureUnit::Raw);
    assert_eq!(rec.meta.row_pitch_mm, None);
    assert_eq!(rec.meta.sensor, None);
    assert_eq!(rec.meta.noise_threshold, Some(0.0));
    assert!(rec.present().is_none());
    assert_eq!(
        rec.meta.extra,
        vec![("VERSION".to_owned(), "NRI Capacitive 1.0-A".to_owned())]
    );
    let stamps: Vec<&str> = rec
        .frame_info()
        .iter()
        .map(|i| i.suffix.as_deref().unwrap())
        .collect();
    assert_eq!(stamps[0], ", timestamp 728");
    assert_eq!(stamps[6], ", timestamp 5840");
    assert_eq!(stamps[9], ", timestamp 8064");
    assert_eq!(rec.frame_info()[9].number, 10);
    let first = rec.frame(0).unwrap();
    assert_eq!(first.get(3, 5), 116.0); // 0,0,12,0,0,116,...
    assert_eq!(first.get(6, 8), 255.0);
    assert_eq!(first.get(7, 15), 164.0);
    assert_eq!(rec.frame(2).unwrap().total(), 9383.0);
    assert!(rec.data().iter().all(|&v| (0.0..=255.0).contains(&v)));
}

#[test]
fn real_files_round_trip_through_the_writer() {
    for name in ["FrasP01L.asf", "example3.asf"] {
        let rec = read_recording(&shared(name)).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(name);
        write_tekscan_file(&rec, &path).unwrap();
        let parsed = read_tekscan_with(&path, &ReadOptions::default()).unwrap();
        assert!(parsed.warnings.is_empty(), "{name}: {:?}", parsed.warnings);
        assert_eq!(parsed.recording, rec, "{name}");
    }
}

#[test]
fn a_cut_real_file_is_an_error_and_leniently_drops_the_frame() {
    let text = std::fs::read_to_string(shared("FrasP01L.asf")).unwrap();
    // Cut in the middle of frame 205 (line 12679 is `Frame 205`).
    let cut: String = text.split_inclusive('\n').take(12700).collect();
    let err = parse_tekscan(&cut, "FrasP01L.asf", &ReadOptions::default()).unwrap_err();
    assert_eq!(err.line(), Some(12700));
    assert!(
        err.to_string()
            .contains("FrasP01L.asf line 12700: frame 205 (from line 12679) is truncated: the file ends after 21 of 60 rows"),
        "{err}"
    );
    let parsed = parse_tekscan(&cut, "FrasP01L.asf", &ReadOptions::lenient()).unwrap();
    assert_eq!(parsed.recording.frame_count(), 204);
    assert_eq!(parsed.warnings.len(), 1, "{:?}", parsed.warnings);
}

#[test]
fn simulated_44x44_movie_of_2000_frames() {
    let grid = Grid::new(44, 44);
    let frames = 2000;
    let data: Vec<f64> = (0..frames * grid.len())
        .map(|i| ((i * 7919) % 256) as f64)
        .collect();
    let meta = SensorMeta {
        sensor: Some("5051".into()),
        row_pitch_mm: Some(1.27),
        col_pitch_mm: Some(1.27),
        ..SensorMeta::default()
    };
    let rec = Recording::new(grid, Some(0.01), data, None, meta).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sim.asf");
    let start = std::time::Instant::now();
    write_tekscan_file(&rec, &path).unwrap();
    let written = start.elapsed();
    let back = read_recording(&path).unwrap();
    let read = start.elapsed() - written;
    assert_eq!(back, rec);
    eprintln!("44x44x{frames}: write {written:?}, read {read:?}");
}

#[test]
fn real_greyscale_png_textures() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/textures");
    for name in ["grass.png", "gravel.png", "brick.png"] {
        let rec = read_recording(&dir.join(name)).unwrap();
        assert_eq!(rec.grid(), Grid::new(512, 512), "{name}");
        assert_eq!(rec.frame_count(), 1);
        let values = rec.data();
        assert!(
            values
                .iter()
                .all(|&v| v.fract() == 0.0 && (0.0..=255.0).contains(&v)),
            "{name}"
        );
        // A photograph: many distinct grey levels, not a constant image.
        let mut seen = [false; 256];
        for &v in values {
            seen[v as usize] = true;
        }
        assert!(seen.iter().filter(|&&s| s).count() > 50, "{name}");
    }
}

#[test]
fn detection_by_content_and_extension() {
    let dir = tempfile::tempdir().unwrap();
    let at = |name: &str| dir.path().join(name);
    // A NumPy file named .txt, a PNG named .dat: content wins.
    let npy = at("array.txt");
    let mut bytes = Vec::new();
    presrs_io::npy::write_npy_f64(&mut bytes, &[2, 2], &[1.0, 2.0, 3.0, 4.0]).unwrap();
    std::fs::write(&npy, &bytes).unwrap();
    assert_eq!(detect_kind(&npy, &bytes).unwrap(), FileKind::Npy);
    assert_eq!(read_recording(&npy).unwrap().data(), &[1.0, 2.0, 3.0, 4.0]);
    let png = at("image.dat");
    presrs_io::png::write_png_gray8_file(&png, Grid::new(1, 2), &[3, 4]).unwrap();
    assert_eq!(read_recording(&png).unwrap().data(), &[3.0, 4.0]);
    // A TekScan export named .csv, and one named .txt.
    for name in ["export.csv", "export.txt"] {
        let path = at(name);
        std::fs::write(
            &path,
            "DATA_TYPE MOVIE\nROWS 1\nCOLS 2\nASCII_DATA @@\nFrame 1\n5,6\n",
        )
        .unwrap();
        let rec = read_recording(&path).unwrap();
        assert_eq!(rec.data(), &[5.0, 6.0], "{name}");
    }
    // Plain matrices in .csv and .txt.
    for name in ["matrix.csv", "matrix.txt", "matrix"] {
        let path = at(name);
        std::fs::write(&path, "1,2\n3,4\n").unwrap();
        assert_eq!(
            read_recording(&path).unwrap().grid(),
            Grid::new(2, 2),
            "{name}"
        );
    }
    // Names that lie about binary formats.
    let fake = at("fake.npy");
    std::fs::write(&fake, "1 2\n").unwrap();
    let msg = read_recording(&fake).unwrap_err().to_string();
    assert!(
        msg.contains("fake.npy") && msg.contains("not a NumPy file"),
        "{msg}"
    );
    let fake = at("fake.png");
    std::fs::write(&fake, "1 2\n").unwrap();
    assert!(
        read_recording(&fake)
            .unwrap_err()
            .to_string()
            .contains("not a PNG")
    );
    // An .asf without a TekScan header gets TekScan's message.
    let asf = at("plain.asf");
    std::fs::write(&asf, "1 2\n3 4\n").unwrap();
    let msg = read_recording(&asf).unwrap_err().to_string();
    assert!(msg.contains("ASCII_DATA"), "{msg}");
    // Unknown binary data.
    let bin = at("blob.bin");
    std::fs::write(&bin, [0u8, 1, 2, 3, 0, 0]).unwrap();
    assert!(
        read_recording(&bin)
            .unwrap_err()
            .to_string()
            .contains("binary file")
    );
    // Missing file.
    let msg = read_recording(&at("nope.asf")).unwrap_err().to_string();
    assert!(
        msg.starts_with("cannot read") && msg.contains("nope.asf"),
        "{msg}"
    );
    // Lenient reading through the dispatcher.
    let cut = at("cut.asf");
    std::fs::write(
        &cut,
        "ROWS 2\nCOLS 1\nASCII_DATA @@\nFrame 1\n1\n2\nFrame 2\n3\n",
    )
    .unwrap();
    assert!(read_recording(&cut).is_err());
    let parsed = read_recording_with(&cut, &ReadOptions::lenient()).unwrap();
    assert_eq!(parsed.recording.frame_count(), 1);
    assert_eq!(parsed.warnings.len(), 1);
}

// ----------------------------------------------------------------------------------------------------------
// Property test: write -> read gives back exactly the same recording.

const RESERVED: &[&str] = &[
    "DATA_TYPE",
    "ROWS",
    "COLS",
    "SENSOR_TYPE",
    "ROW_SPACING",
    "COL_SPACING",
    "UNITS",
    "NOISE_THRESHOLD",
    "SECONDS_PER_FRAME",
    "SATURATION_PRESSURE",
    "START_FRAME",
    "END_FRAME",
    "ASCII_DATA",
];

fn not_reserved(entry: &(String, String)) -> bool {
    let token = entry.0.split_whitespace().next().unwrap_or("");
    !RESERVED
        .iter()
        .any(|k| k.eq_ignore_ascii_case(token.trim_end_matches(':')))
}

fn value_strategy() -> impl Strategy<Value = f64> {
    prop_oneof![
        (-1000i32..100_000).prop_map(f64::from),
        (0u8..=255).prop_map(f64::from),
        (-1_000_000i64..1_000_000).prop_map(|n| n as f64 / 1000.0),
        prop::num::f64::NORMAL | prop::num::f64::SUBNORMAL | prop::num::f64::ZERO,
    ]
}

fn extra_strategy() -> impl Strategy<Value = Vec<(String, String)>> {
    let keyed = (
        "[A-Z][A-Z0-9_]{0,12}",
        prop_oneof![Just(String::new()), "[!-~]([ -~]{0,20}[!-~])?"],
    );
    // Free text: not starting with an upper-case letter, not ending with `:`.
    let free = "[a-z(][ -~]{0,20}[!-9;-~]".prop_map(|text| (text, String::new()));
    prop::collection::vec(prop_oneof![3 => keyed, 1 => free], 0..6)
        .prop_map(|entries| entries.into_iter().filter(not_reserved).collect())
}

fn unit_strategy() -> impl Strategy<Value = Option<PressureUnit>> {
    prop::option::of(prop_oneof![
        Just(PressureUnit::Raw),
        Just(PressureUnit::KPa),
        Just(PressureUnit::MPa),
        Just(PressureUnit::Psi),
        Just(PressureUnit::Other("N/cm2".into())),
    ])
}

fn meta_strategy() -> impl Strategy<Value = SensorMeta> {
    (
        prop::option::of("[!-~]([ -~]{0,10}[!-~])?"),
        prop::option::of(1e-3..1e3f64),
        prop::option::of(1e-3..1e3f64),
        unit_strategy(),
        prop::option::of(1e-3..1e6f64),
        prop::option::of(prop_oneof![(0u8..20).prop_map(f64::from), -1e3..1e3f64]),
        extra_strategy(),
    )
        .prop_map(
            |(sensor, row_pitch_mm, col_pitch_mm, units, full_scale, noise_threshold, extra)| {
                SensorMeta {
                    sensor,
                    row_pitch_mm,
                    col_pitch_mm,
                    units,
                    full_scale,
                    noise_threshold,
                    extra,
                }
            },
        )
}

fn recording_strategy() -> impl Strategy<Value = Recording> {
    (1usize..20, 1usize..20, 1usize..5)
        .prop_flat_map(|(rows, cols, frames)| {
            let len = rows * cols;
            (
                Just(Grid::new(rows, cols)),
                prop::collection::vec(value_strategy(), len * frames),
                prop::option::of(prop::collection::vec(prop::bool::weighted(0.8), len)),
                -100i64..100_000,
                prop::collection::vec(
                    (
                        // Steps between frame numbers: increasing, with gaps.
                        1i64..1000,
                        prop::option::of("[,;:a-zA-Z]|[,;: a-zA-Z][ -~]{0,15}[!-~]"),
                    ),
                    frames,
                ),
                prop::option::of(1e-4..10.0f64),
                meta_strategy(),
            )
        })
        .prop_map(|(grid, data, mask, first, info, period, meta)| {
            let mut number = first;
            let info = info
                .into_iter()
                .enumerate()
                .map(|(i, (step, suffix))| {
                    if i > 0 {
                        number += step;
                    }
                    FrameInfo { number, suffix }
                })
                .collect();
            Recording::with_info(grid, period, data, mask, info, meta).unwrap()
        })
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 96,
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn tekscan_write_read_round_trip(rec in recording_strategy()) {
        let mut bytes = Vec::new();
        write_tekscan(&rec, &mut bytes).unwrap();
        let text = String::from_utf8(bytes).unwrap();
        let parsed = parse_tekscan(&text, "prop.asf", &ReadOptions::default())
            .unwrap_or_else(|err| panic!("{err}\n{text}"));
        // Non-consecutive frame numbers give a START/END warning and a warning of each jump (or a
        // summary of them); nothing else may be reported.
        for warning in parsed.warnings.render(presrs_io::Face::Cli) {
            prop_assert!(
                warning.contains("START_FRAME") || warning.contains("time is not contiguous"),
                "{}",
                warning
            );
        }
        let back = parsed.recording;
        prop_assert_eq!(&back, &rec);
        // Bit-exact, including the sign of zero.
        let bits = |r: &Recording| r.data().iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        prop_assert_eq!(bits(&back), bits(&rec));
    }
}
