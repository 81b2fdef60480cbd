//! MCAP (ROS 2 bags): the fixtures made by the official Python libraries (`fixtures/mcap/make_fixtures.py`)
//! read as the script says they should (`expected.json`), bad inputs give clear errors, and what presrs
//! writes reads back.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};

use presrs_core::{Grid, Recording, SensorMeta};
use presrs_io::mcap::{ImageEncoding, list_topics, parse_mcap, write_recording_mcap};
use presrs_io::{FileKind, IoError, ReadOptions, detect_kind, read_recording_with};
use serde_json::Value;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/mcap")
        .join(name)
}

fn expected() -> serde_json::Map<String, Value> {
    let text = std::fs::read_to_string(fixture("expected.json")).unwrap();
    serde_json::from_str::<Value>(&text)
        .unwrap()
        .as_object()
        .unwrap()
        .clone()
}

fn read(name: &str, topic: Option<&str>) -> Result<presrs_io::Parsed, IoError> {
    let options = ReadOptions {
        topic: topic.map(str::to_owned),
        ..ReadOptions::default()
    };
    read_recording_with(&fixture(name), &options)
}

/// The frames of `expected.json`'s entry as one flat row-major vector, and the grid.
fn expected_frames(entry: &Value) -> (Grid, usize, Vec<f64>) {
    let frames = entry["frames"].as_array().unwrap();
    let rows = frames[0].as_array().unwrap();
    let grid = Grid::new(rows.len(), rows[0].as_array().unwrap().len());
    let mut flat = Vec::new();
    for frame in frames {
        for row in frame.as_array().unwrap() {
            flat.extend(row.as_array().unwrap().iter().map(|v| v.as_f64().unwrap()));
        }
    }
    (grid, frames.len(), flat)
}

#[test]
fn python_made_fixtures_read_as_expected() {
    let all = expected();
    assert!(all.len() >= 7);
    for (key, entry) in &all {
        let (file, topic) = match key.split_once('#') {
            Some((file, topic)) => (file, Some(topic)),
            None => (key.as_str(), None),
        };
        let parsed = read(file, topic).unwrap_or_else(|e| panic!("{key}: {e}"));
        let rec = &parsed.recording;
        let (grid, frames, values) = expected_frames(entry);
        assert_eq!(rec.grid(), grid, "{key}");
        assert_eq!(rec.frame_count(), frames, "{key}");
        assert_eq!(rec.data(), values.as_slice(), "{key}: the values, exactly");
        let period = entry["period_s"].as_f64().unwrap();
        let got = rec.frame_period_s().unwrap();
        assert!(
            (got - period).abs() < 1e-12,
            "{key}: period {got} vs {period}"
        );
        let topic_extra = rec.meta.extra.iter().find(|(k, _)| k == "MCAP_TOPIC");
        assert_eq!(
            topic_extra.map(|(_, v)| v.as_str()),
            entry["topic"].as_str(),
            "{key}"
        );
        // Only the gap fixture has warnings.
        assert_eq!(
            parsed.warnings.is_empty(),
            entry.get("gap_before_message").is_none(),
            "{key}: {:?}",
            parsed.warnings
        );
    }
}

#[test]
fn detected_by_content_and_both_byte_orders_agree() {
    let bytes = std::fs::read(fixture("gap.mcap")).unwrap();
    assert_eq!(
        detect_kind(Path::new("x.dat"), &bytes).unwrap(),
        FileKind::Mcap
    );
    let err = detect_kind(Path::new("x.mcap"), b"hello").unwrap_err();
    assert!(err.to_string().contains("not an MCAP file"), "{err}");
    let le = read("mono16_le_padded.mcap", None).unwrap().recording;
    let be = read("mono16_be_padded.mcap", None).unwrap().recording;
    assert_eq!(le.data(), be.data());
    assert_eq!(le.frame_count(), 12);
}

#[test]
fn gaps_are_reported_with_the_message_index() {
    let parsed = read("gap.mcap", None).unwrap();
    assert_eq!(parsed.warnings.len(), 1, "{:?}", parsed.warnings);
    let warning = &parsed.warnings[0].to_string();
    assert!(warning.contains("gap.mcap"), "{warning}");
    assert!(warning.contains("topic /foot"), "{warning}");
    assert!(
        warning.contains("a gap of 0.040000 s before message 5"),
        "{warning}"
    );
    assert!(warning.contains("about 3 frame(s) missing"), "{warning}");
    assert_eq!(parsed.recording.frame_period_s(), Some(0.01));
}

#[test]
fn topics_are_listed_and_several_need_a_choice() {
    let file = std::fs::File::open(fixture("two_topics.mcap")).unwrap();
    let topics = list_topics(std::io::BufReader::new(file), "two_topics.mcap").unwrap();
    let listed: Vec<(&str, &str, u64)> = topics
        .iter()
        .map(|t| (t.topic.as_str(), t.schema.as_str(), t.messages))
        .collect();
    assert_eq!(
        listed,
        [
            ("/left", "sensor_msgs/msg/Image", 6),
            ("/right", "std_msgs/msg/UInt16MultiArray", 6),
            ("/status", "std_msgs/msg/String", 6),
        ]
    );
    assert_eq!(
        topics.iter().filter(|t| t.has_frames()).count(),
        2,
        "String is not frames"
    );
    let err = read("two_topics.mcap", None).unwrap_err().to_string();
    assert!(err.contains("several topics (/left, /right"), "{err}");
    assert!(err.contains("--topic"), "{err}");
}

#[test]
fn bad_inputs_name_the_topic_and_message() {
    let err = read("bad_encoding.mcap", None).unwrap_err().to_string();
    assert!(
        err.starts_with(&fixture("bad_encoding.mcap").display().to_string()),
        "{err}"
    );
    assert!(err.contains("topic /camera message 0"), "{err}");
    assert!(err.contains("\"rgb8\" is not supported"), "{err}");

    let err = read("size_change.mcap", None).unwrap_err().to_string();
    assert!(err.contains("topic /foot message 3"), "{err}");
    assert!(
        err.contains("a 3x4 frame, the earlier ones are 3x3"),
        "{err}"
    );

    let err = read("two_topics.mcap", Some("/status"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("topic /status holds std_msgs/msg/String messages, not frames"),
        "{err}"
    );

    let err = read("two_topics.mcap", Some("/nope"))
        .unwrap_err()
        .to_string();
    assert!(err.contains("no messages on topic /nope"), "{err}");
    assert!(
        err.contains("/left (sensor_msgs/msg/Image, 6 messages)"),
        "{err}"
    );
}

#[test]
fn truncated_files_are_errors_at_every_length() {
    let bytes = std::fs::read(fixture("mono16_le_padded.mcap")).unwrap();
    // Every cut is an error (never a panic), a short one included; the full file reads.
    for cut in (0..bytes.len()).step_by(7) {
        let result = parse_mcap(&bytes[..cut], "cut.mcap", None);
        let err = result.expect_err(&format!("cut at {cut} bytes read without an error"));
        assert!(err.to_string().starts_with("cut.mcap: "), "{err}");
    }
    assert!(parse_mcap(bytes.as_slice(), "whole.mcap", None).is_ok());
}

#[test]
fn written_bags_read_back() {
    let grid = Grid::new(3, 4);
    // Integer counts: mono16, exact.
    let counts: Vec<f64> = (0..5 * 12).map(|i| f64::from((i * 37) % 1000)).collect();
    let mut rec = Recording::new(grid, Some(0.01), counts, None, SensorMeta::default()).unwrap();
    let mut bytes = Vec::new();
    let encoding = write_recording_mcap(&mut bytes, "out.mcap", &rec, "/presrs/frames").unwrap();
    assert_eq!(encoding, ImageEncoding::Mono16);
    let back = parse_mcap(bytes.as_slice(), "out.mcap", None).unwrap();
    assert_eq!(back.recording.data(), rec.data());
    assert_eq!(back.recording.frame_period_s(), Some(0.01));
    assert!(back.warnings.is_empty(), "{:?}", back.warnings);

    // Values exact in f32 (multiples of 1/64, negative ones too): 32FC1, exact.
    let floats: Vec<f64> = (0..5 * 12)
        .map(|i| f64::from(i * 13 - 200) / 64.0)
        .collect();
    rec = Recording::new(grid, Some(0.02), floats, None, SensorMeta::default()).unwrap();
    bytes.clear();
    let encoding = write_recording_mcap(&mut bytes, "out.mcap", &rec, "/x").unwrap();
    assert_eq!(encoding, ImageEncoding::Float32);
    let back = parse_mcap(bytes.as_slice(), "out.mcap", Some("/x")).unwrap();
    assert_eq!(back.recording.data(), rec.data());
    assert_eq!(back.recording.frame_period_s(), Some(0.02));
}

/// Seeded mutations of every fixture (bytes flipped, runs overwritten with 0xff, cuts): the reader
/// returns, an error or a recording, never a panic, and never more values than the input had bytes.
#[test]
fn mutated_bags_never_panic() {
    let mut state = 0x2400_u64;
    let mut next = move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        state >> 33
    };
    let mut read_ok = 0;
    for entry in std::fs::read_dir(fixture("")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "mcap") {
            continue;
        }
        let original = std::fs::read(&path).unwrap();
        for round in 0..150 {
            let mut bytes = original.clone();
            for _ in 0..1 + next() % 4 {
                let at = (next() as usize) % bytes.len();
                match round % 3 {
                    0 => bytes[at] ^= 1 << (next() % 8),
                    1 => {
                        let end = (at + 1 + next() as usize % 8).min(bytes.len());
                        bytes[at..end].fill(0xff);
                    }
                    _ => bytes.truncate(at.max(8)),
                }
            }
            let result = std::panic::catch_unwind(|| parse_mcap(bytes.as_slice(), "m.mcap", None));
            let parsed =
                result.unwrap_or_else(|_| panic!("{} round {round} panicked", path.display()));
            if let Ok(parsed) = parsed {
                read_ok += 1;
                assert!(parsed.recording.data().len() <= bytes.len() * 8);
            }
        }
    }
    // Some mutations land in padding or unchecked bytes and still read.
    assert!(read_ok > 0);
}

/// A real TekScan export (read in place from `shared/`) through a bag: values, period, unit, pitch and
/// outline (absent sensels) all come back.
#[test]
fn a_real_tekscan_file_keeps_everything_through_a_bag() {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/tekscan/FrasP01L.asf");
    let original = presrs_io::read_recording(&path).unwrap();
    let mut bytes = Vec::new();
    write_recording_mcap(&mut bytes, "f.mcap", &original, "/presrs/frames").unwrap();
    let back = parse_mcap(bytes.as_slice(), "f.mcap", None).unwrap();
    assert!(back.warnings.is_empty(), "{:?}", back.warnings);
    let back = back.recording;
    assert_eq!(back.data(), original.data());
    assert_eq!(back.frame_period_s(), original.frame_period_s());
    assert_eq!(back.present(), original.present());
    assert_eq!(back.meta.units, original.meta.units);
    assert_eq!(back.meta.sensor, original.meta.sensor);
    assert_eq!(back.meta.row_pitch_mm, original.meta.row_pitch_mm);
    assert_eq!(back.meta.col_pitch_mm, original.meta.col_pitch_mm);
    assert!(original.meta.units.is_some() || original.present().is_some());
}

/// Inputs the `parse_mcap` fuzz target flagged (`tests/fuzz_regressions/parse_mcap/`, the first byte
/// picks the topic as in the target): each is an error, not a panic. `header_string_length_1_8_gb`
/// claims a 1.8 GB string in the header record; the `mcap` crate reserves it (virtual memory, never
/// touched) before finding the record short, which libFuzzer's `-malloc_limit_mb` reports.
#[test]
fn fuzz_findings_are_errors() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_regressions/parse_mcap");
    for entry in std::fs::read_dir(dir).unwrap() {
        let bytes = std::fs::read(entry.unwrap().path()).unwrap();
        let rest = &bytes[1..];
        assert!(parse_mcap(rest, "f.mcap", None).is_err());
        assert!(list_topics(rest, "f.mcap").is_err());
    }
}
