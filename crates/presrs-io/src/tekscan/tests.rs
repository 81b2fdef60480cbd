use presrs_core::{FrameInfo, Grid, PressureUnit, SensorMeta};

use super::file::MAX_GAP_WARNINGS;
use super::*;

fn strict(text: &str) -> Result<Parsed, IoError> {
    parse_tekscan(text, "t.asf", &ReadOptions::default())
}

fn lenient(text: &str) -> Result<Parsed, IoError> {
    parse_tekscan(text, "t.asf", &ReadOptions::lenient())
}

/// The error message of a strict parse that must fail.
fn fails(text: &str) -> (Option<usize>, String) {
    match strict(text) {
        Ok(parsed) => panic!("expected an error, read {:?}", parsed.recording),
        Err(err) => (err.line(), err.to_string()),
    }
}

const HEAD_2X3: &str =
    "DATA_TYPE MOVIE\nROWS 2\nCOLS 3\nSTART_FRAME 1\nEND_FRAME 2\nASCII_DATA @@\n\n";

fn movie_2x3() -> String {
    format!("{HEAD_2X3}Frame 1\n1,2,3\n4,5,6\n\nFrame 2\n7,8,9\n10,11,12\n@@\n")
}

#[test]
fn minimal_movie() {
    let parsed = strict(&movie_2x3()).unwrap();
    assert!(parsed.warnings.is_empty(), "{:?}", parsed.warnings);
    let rec = parsed.recording;
    assert_eq!(rec.grid(), Grid::new(2, 3));
    assert_eq!(rec.frame_count(), 2);
    assert_eq!(
        rec.data(),
        (1..=12).map(f64::from).collect::<Vec<_>>().as_slice()
    );
    assert_eq!(rec.frame_period_s(), None);
    assert!(rec.present().is_none());
    assert!(rec.meta.extra.is_empty(), "{:?}", rec.meta.extra);
}

#[test]
fn full_header_typed_and_extra_fields() {
    let text = "DATA_TYPE MOVIE\r\nVERSION Tekscan 7.0\r\nSENSOR_TYPE 5051\r\nROWS 1\r\nCOLS 2\r\n\
        ROW_SPACING 0.05 inches\r\nCOL_SPACING 0.127 cm\r\nSENSEL_AREA 0.0025 in2\r\nNOISE_THRESHOLD 3\r\n\
        SECONDS_PER_FRAME 0.01\r\nSATURATION_PRESSURE 20 PSI \r\nCOMMENTS:\r\nWALK on bricks, take 2\r\n\
        CALIBRATION_POINT_1 75.0001 (Kgs) 4798 (Raw Sum) 240 (Number of Loaded Cells)\r\nUNITS KPa\r\n\
        START_FRAME 7\r\nEND_FRAME 7\r\nASCII_DATA @@\r\n\r\nFrame 7\r\n1.5,2.25\r\n@@\r\n";
    let parsed = strict(text).unwrap();
    assert!(parsed.warnings.is_empty(), "{:?}", parsed.warnings);
    let rec = parsed.recording;
    let meta = &rec.meta;
    assert_eq!(meta.sensor.as_deref(), Some("5051"));
    assert!((meta.row_pitch_mm.unwrap() - 1.27).abs() < 1e-12);
    assert!((meta.col_pitch_mm.unwrap() - 1.27).abs() < 1e-12);
    assert_eq!(meta.units, Some(PressureUnit::KPa));
    assert_eq!(meta.noise_threshold, Some(3.0));
    assert!((meta.full_scale.unwrap() - 137.895_145_863_36).abs() < 1e-6);
    assert_eq!(rec.frame_period_s(), Some(0.01));
    assert_eq!(rec.frame_info()[0].number, 7);
    assert_eq!(rec.data(), &[1.5, 2.25]);
    let extra: Vec<(&str, &str)> = meta
        .extra
        .iter()
        .map(|(k, v)| (k.as_str(), v.as_str()))
        .collect();
    assert_eq!(
        extra,
        vec![
            ("VERSION", "Tekscan 7.0"),
            ("SENSEL_AREA", "0.0025 in2"),
            ("COMMENTS:", ""),
            // The line after `COMMENTS:` is free text even though it starts like a key.
            ("WALK on bricks, take 2", ""),
            (
                "CALIBRATION_POINT_1",
                "75.0001 (Kgs) 4798 (Raw Sum) 240 (Number of Loaded Cells)"
            ),
        ]
    );
}

#[test]
fn a_file_without_units_stays_without_them() {
    let text = "ROWS 1\nCOLS 2\nSATURATION_PRESSURE 255 raw\nASCII_DATA @@\nFrame 1\n3,4\n";
    let rec = strict(text).unwrap().recording;
    assert_eq!(rec.meta.units, None);
    assert_eq!(rec.meta.units_or_raw(), &PressureUnit::Raw);
    // The saturation pressure is read in the assumed raw counts.
    assert_eq!(rec.meta.full_scale, Some(255.0));
    let mut written = Vec::new();
    write_tekscan(&rec, &mut written).unwrap();
    let written = String::from_utf8(written).unwrap();
    assert!(!written.contains("UNITS"), "{written}");
    let again = strict(&written).unwrap().recording;
    assert_eq!(again, rec);
    // A stated raw unit is written back.
    let stated = strict(&text.replace("COLS 2\n", "COLS 2\nUNITS raw\n"))
        .unwrap()
        .recording;
    assert_eq!(stated.meta.units, Some(PressureUnit::Raw));
    let mut written = Vec::new();
    write_tekscan(&stated, &mut written).unwrap();
    assert!(String::from_utf8(written).unwrap().contains("UNITS raw\n"));
}

#[test]
fn comments_that_look_like_keys_stay_text() {
    let text = "ROWS 1\nCOLS 1\nRows 3 were damaged\nUnits are kPa\nCOMMENTS:\nROWS 3 damaged\n\
                COMMENTS:\nCOLS 1\nUNITS KPa\nascii_data was missing once\nASCII_DATA @@\nFrame 1\n3\n";
    let parsed = strict(text).unwrap();
    let rec = parsed.recording;
    assert_eq!(rec.meta.units, Some(PressureUnit::KPa));
    let extra: Vec<(&str, &str)> = rec
        .meta
        .extra
        .iter()
        .map(|(k, v)| (k.as_str(), v.as_str()))
        .collect();
    assert_eq!(
        extra,
        vec![
            ("Rows 3 were damaged", ""),
            ("Units are kPa", ""),
            ("COMMENTS:", ""),
            ("ROWS 3 damaged", ""),
            ("COMMENTS:", ""),
            ("ascii_data was missing once", ""),
        ]
    );
    // `COLS 1` after the second `COMMENTS:` is a plausible key line: a repeat of COLS, not text.
    assert!(parsed.warnings.is_empty(), "{:?}", parsed.warnings);
}

#[test]
fn raw_units_keep_saturation_pressure_verbatim_in_place() {
    let text = "ROWS 1\nCOLS 1\nVERSION x\nSATURATION_PRESSURE 1514.73 KPa\nMAP_VERSION 6.5\nUNITS raw\n\
                ASCII_DATA @@\nFrame 1\n3\n";
    let rec = strict(text).unwrap().recording;
    assert_eq!(rec.meta.full_scale, None);
    assert_eq!(
        rec.meta.extra[1],
        ("SATURATION_PRESSURE".to_owned(), "1514.73 KPa".to_owned())
    );
    assert_eq!(rec.meta.extra[2].0, "MAP_VERSION");
}

#[test]
fn unknown_typed_values_kept_with_warnings() {
    let text = "ROWS 1\nCOLS 1\nROW_SPACING 5 furlongs\nSECONDS_PER_FRAME 0\nNOISE_THRESHOLD low\n\
                SENSOR_TYPE A\nSENSOR_TYPE B\nASCII_DATA @@\n4\n";
    let parsed = strict(text).unwrap();
    let rec = &parsed.recording;
    assert_eq!(rec.meta.row_pitch_mm, None);
    assert_eq!(rec.frame_period_s(), None);
    assert_eq!(rec.meta.noise_threshold, None);
    assert_eq!(rec.meta.sensor.as_deref(), Some("A"));
    assert_eq!(rec.meta.extra.len(), 3);
    assert_eq!(
        rec.meta.extra[0],
        ("ROW_SPACING".into(), "5 furlongs".into())
    );
    assert_eq!(parsed.warnings.len(), 4, "{:?}", parsed.warnings);
    assert!(
        parsed.warnings[0]
            .to_string()
            .starts_with("t.asf line 3: ROW_SPACING"),
        "{:?}",
        parsed.warnings
    );
    assert!(
        parsed.warnings[3].to_string().contains("line 7")
            && parsed.warnings[3].to_string().contains("line 6")
    );
}

#[test]
fn snapshot_without_frame_lines_trailing_commas_and_comma_lines() {
    let text = "DATA_TYPE STATIC\r\nROWS 2\r\nCOLS 3\r\nASCII_DATA @@\r\n,,,\r\n1,2,3,\r\n,,,\r\n4,B,6,\r\n,,,\r\n";
    let rec = strict(text).unwrap().recording;
    assert_eq!(rec.frame_count(), 1);
    assert_eq!(
        rec.frame_info()[0],
        FrameInfo {
            number: 1,
            suffix: None
        }
    );
    assert_eq!(rec.data(), &[1.0, 2.0, 3.0, 4.0, 0.0, 6.0]);
    assert_eq!(
        rec.present(),
        Some(&[true, true, true, true, false, true][..])
    );
    // Several snapshots back to back are cut into frames of ROWS rows, numbered from START_FRAME.
    let text = "ROWS 1\nCOLS 2\nSTART_FRAME 5\nASCII_DATA\n1 2\n3 4\n5 6\n";
    let rec = strict(text).unwrap().recording;
    assert_eq!(rec.frame_count(), 3);
    assert_eq!(rec.frame_info()[2].number, 7);
    assert_eq!(rec.data(), &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
}

#[test]
fn frame_suffix_negative_numbers_and_missing_ascii_data() {
    let text = "ROWS 1\nCOLS 1\nFrame -2, timestamp 728\n0\nframe 3\n1\n";
    let rec = strict(text).unwrap().recording;
    assert_eq!(
        rec.frame_info(),
        &[
            FrameInfo {
                number: -2,
                suffix: Some(", timestamp 728".into())
            },
            FrameInfo {
                number: 3,
                suffix: None
            }
        ]
    );
    // But with ASCII_DATA present, a `Frame ...` comment in the header stays a comment.
    let text = "ROWS 1\nCOLS 1\nFrame 3 was bad\nASCII_DATA @@\nFrame 1\n5\n";
    let rec = strict(text).unwrap().recording;
    assert_eq!(
        rec.meta.extra,
        vec![("Frame 3 was bad".to_owned(), String::new())]
    );
    assert_eq!(rec.data(), &[5.0]);
}

#[test]
fn wrong_column_count_names_line_frame_row_and_cols() {
    let text = format!("{HEAD_2X3}Frame 1\n1,2,3\n4,5,6\nFrame 2\n7,8,9\n10,11\n12,13,14\n@@\n");
    let (line, msg) = fails(&text);
    assert_eq!(line, Some(13));
    assert_eq!(
        msg,
        "t.asf line 13: frame 2 has 2 values in row 2, expected 3 (COLS)"
    );
    let text = format!("{HEAD_2X3}Frame 1\n1,2,3,4\n4,5,6\n");
    assert_eq!(
        fails(&text).1,
        "t.asf line 9: frame 1 has 4 values in row 1, expected 3 (COLS)"
    );
}

#[test]
fn too_many_and_too_few_rows() {
    let text = format!("{HEAD_2X3}Frame 1\n1,2,3\n4,5,6\n7,8,9\nFrame 2\n1,2,3\n4,5,6\n");
    let (line, msg) = fails(&text);
    assert_eq!(line, Some(11));
    assert!(
        msg.contains("frame 1 (from line 8) already has 2 rows (ROWS)"),
        "{msg}"
    );
    let text = format!("{HEAD_2X3}Frame 1\n1,2,3\nFrame 2\n1,2,3\n4,5,6\n@@\n");
    let (line, msg) = fails(&text);
    assert_eq!(line, Some(10));
    assert!(
        msg.contains("frame 1 (from line 8) has 1 rows, expected 2 (ROWS)"),
        "{msg}"
    );
    let text = format!("{HEAD_2X3}Frame 1\n1,2,3\n4,5,6\nFrame 2\n1,2,3\n@@\n");
    let (line, msg) = fails(&text);
    assert_eq!(line, Some(13));
    assert!(
        msg.contains("has 1 rows, expected 2 (ROWS) before the `@@` terminator"),
        "{msg}"
    );
    // A short frame before `@@` is malformed, not truncated: lenient reading does not excuse it.
    assert!(lenient(&text).is_err());
}

#[test]
fn truncated_last_frame_strict_and_lenient() {
    let text = format!("{HEAD_2X3}Frame 1\n1,2,3\n4,5,6\n\nFrame 2\n7,8,9\n");
    let (line, msg) = fails(&text);
    assert_eq!(line, Some(13));
    assert!(
        msg.contains("frame 2 (from line 12) is truncated: the file ends after 1 of 2 rows (ROWS)"),
        "{msg}"
    );
    assert!(msg.contains("leniently"), "{msg}");
    let parsed = lenient(&text).unwrap();
    assert_eq!(parsed.recording.frame_count(), 1);
    assert_eq!(parsed.recording.data(), &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
    assert_eq!(parsed.warnings.len(), 1, "{:?}", parsed.warnings);
    assert!(
        parsed.warnings[0].to_string().contains("frame 2")
            && parsed.warnings[0].to_string().contains("dropped")
    );

    // Cut in the middle of a row (no final newline).
    let text = format!("{HEAD_2X3}Frame 1\n1,2,3\n4,5,6\nFrame 2\n7,8,9\n10,1");
    let (line, msg) = fails(&text);
    assert_eq!(line, Some(13));
    assert!(
        msg.contains("frame 2 is truncated: its row 2 has 2 of 3 values (COLS)"),
        "{msg}"
    );
    let parsed = lenient(&text).unwrap();
    assert_eq!(parsed.recording.frame_count(), 1);
    assert_eq!(parsed.warnings.len(), 1, "{:?}", parsed.warnings);

    // Cut right after a `Frame` line.
    let text = format!("{HEAD_2X3}Frame 1\n1,2,3\n4,5,6\nFrame 2\n");
    assert!(fails(&text).1.contains("ends after 0 of 2 rows"));
    assert_eq!(lenient(&text).unwrap().recording.frame_count(), 1);

    // Only a truncated frame: nothing to return even leniently.
    let text = format!("{HEAD_2X3}Frame 1\n1,2,3\n");
    let msg = lenient(&text).unwrap_err().to_string();
    assert!(msg.contains("only a truncated frame"), "{msg}");
}

#[test]
fn frame_count_against_start_end_frame() {
    // Cut exactly at a frame boundary: END_FRAME reveals it.
    let text = format!("{HEAD_2X3}Frame 1\n1,2,3\n4,5,6\n");
    let (line, msg) = fails(&text);
    assert_eq!(line, Some(4));
    assert!(
        msg.contains("announce 2 frames, the file holds 1") && msg.contains("truncated"),
        "{msg}"
    );
    let parsed = lenient(&text).unwrap();
    assert_eq!(parsed.recording.frame_count(), 1);
    assert_eq!(parsed.warnings.len(), 1);
    // With the terminator the file is complete as written: a warning only.
    let text = format!("{HEAD_2X3}Frame 1\n1,2,3\n4,5,6\n@@\n");
    let parsed = strict(&text).unwrap();
    assert_eq!(parsed.warnings.len(), 1);
    assert!(
        parsed.warnings[0]
            .to_string()
            .contains("keeping the frames found")
    );
    // More frames than announced: a warning.
    let text =
        format!("{HEAD_2X3}Frame 1\n1,2,3\n4,5,6\nFrame 2\n1,2,3\n4,5,6\nFrame 3\n1,2,3\n4,5,6\n");
    let parsed = strict(&text).unwrap();
    assert_eq!(parsed.recording.frame_count(), 3);
    assert_eq!(parsed.warnings.len(), 1);
}

#[test]
fn bad_cells() {
    let cases = [
        (
            "1,x,3",
            "frame 1 row 1 column 2: expected a number or `B` (no sensel), found `x`",
        ),
        (
            "1,NaN,3",
            "frame 1 row 1 column 2: expected a finite number, found `NaN`",
        ),
        (
            "1,2,inf",
            "frame 1 row 1 column 3: expected a finite number, found `inf`",
        ),
        (
            "1,,3",
            "frame 1 row 1 column 2 is empty; expected a number or `B` (no sensel)",
        ),
    ];
    for (row, expected) in cases {
        let text = format!("{HEAD_2X3}Frame 1\n{row}\n4,5,6\n@@\n");
        assert_eq!(fails(&text).1, format!("t.asf line 9: {expected}"));
    }
}

#[test]
fn mask_must_match_across_frames() {
    let text = format!("{HEAD_2X3}Frame 1\nB,2,3\n4,5,6\nFrame 2\nB,2,3\n4,B,6\n");
    let (line, msg) = fails(&text);
    assert_eq!(line, Some(13));
    assert!(
        msg.contains("frame 2 row 2 column 2 is `B` (no sensel) but frame 1 has a value there"),
        "{msg}"
    );
    let text = format!("{HEAD_2X3}Frame 1\nB,2,3\n4,5,6\nFrame 2\n1,2,3\n4,5,6\n");
    let (line, msg) = fails(&text);
    assert_eq!(line, Some(12));
    assert!(
        msg.contains("frame 2 row 1 column 1 holds a value but frame 1 has `B`"),
        "{msg}"
    );
}

#[test]
fn header_errors() {
    let (line, msg) = fails("DATA_TYPE MOVIE\nCOLS 3\nASCII_DATA @@\n1,2,3\n");
    assert_eq!(line, Some(3));
    assert!(msg.contains("no ROWS line"), "{msg}");
    let msg = fails("DATA_TYPE MOVIE\nASCII_DATA @@\n1,2,3\n").1;
    assert!(msg.contains("no ROWS or COLS line"), "{msg}");
    let (line, msg) = fails("ROWS 4.5\nCOLS 3\nASCII_DATA @@\n1,2,3\n");
    assert_eq!(line, Some(1));
    assert!(
        msg.contains("ROWS: expected a positive whole number, found `4.5`"),
        "{msg}"
    );
    assert!(
        fails("ROWS 0\nCOLS 3\nASCII_DATA\n")
            .1
            .contains("found `0`")
    );
    assert!(fails("ROWS\nCOLS 3\nASCII_DATA\n").1.contains("found ``"));
    let (line, msg) = fails("ROWS 2\nCOLS 3\nROWS 3\nASCII_DATA\n");
    assert_eq!(line, Some(3));
    assert!(msg.contains("ROWS 3 contradicts ROWS 2 on line 1"), "{msg}");
    let msg = fails("ROWS 2\nCOLS 3\nSTART_FRAME one\nASCII_DATA\n").1;
    assert!(
        msg.contains("line 3: START_FRAME: expected a whole frame number"),
        "{msg}"
    );
    let (line, msg) = fails("DATA_TYPE MOVIE\nROWS 2\nCOLS 3\n");
    assert_eq!(line, Some(3));
    assert!(msg.contains("expected an `ASCII_DATA` line"), "{msg}");
    let msg = fails("1,2,3\n4,5,6\n").1;
    assert!(msg.contains("ASCII_DATA"), "{msg}");
}

#[test]
fn empty_inputs() {
    for text in ["", "\r\n\n  \n", ",,,\n"] {
        let err = strict(text).unwrap_err();
        assert_eq!(err.line(), None);
        assert!(err.to_string().starts_with("t.asf: empty file"), "{err}");
    }
    let (line, msg) = fails("ROWS 2\nCOLS 2\nASCII_DATA @@\n\n@@\n");
    assert_eq!(line, Some(5));
    assert!(
        msg.contains(
            "expected frame data (2 rows of 2 values) after the header ending on line 3, found none"
        ),
        "{msg}"
    );
}

#[test]
fn huge_header_dimensions_do_not_allocate() {
    // Would be 80 GB if allocated from the header.
    let text = "ROWS 100000\nCOLS 100000\nSTART_FRAME 1\nEND_FRAME 1000000\nASCII_DATA @@\nFrame 1\n1,2,3\n";
    let msg = fails(text).1;
    assert!(
        msg.contains("frame 1 is truncated: its row 1 has 3 of 100000 values"),
        "{msg}"
    );
    let text = "ROWS 100000\nCOLS 100000\nASCII_DATA @@\n";
    assert!(fails(text).1.contains("found none"));
    let text = format!("ROWS {}\nCOLS 4\nASCII_DATA @@\n", usize::MAX);
    assert!(fails(&text).1.contains("too large"));
}

#[test]
fn content_after_terminator_and_mixed_framing() {
    let text = format!("{}junk\n", movie_2x3());
    let (line, msg) = fails(&text);
    assert_eq!(line, Some(16));
    assert!(
        msg.contains("expected nothing after the `@@` terminator on line 15, found `junk`"),
        "{msg}"
    );
    let text = "ROWS 1\nCOLS 1\nASCII_DATA\n5\nFrame 2\n6\n";
    let (line, msg) = fails(text);
    assert_eq!(line, Some(5));
    assert!(
        msg.contains("`Frame` line after frame data that had none"),
        "{msg}"
    );
    let (line, msg) = fails("ROWS 1\nCOLS 1\nASCII_DATA\nFrame x\n5\n");
    assert_eq!(line, Some(4));
    assert!(
        msg.contains("expected a frame number after `Frame`, found `x`"),
        "{msg}"
    );
}

#[test]
fn extreme_start_and_end_frame_do_not_overflow() {
    // END - START + 1 overflows i64: no panic, the (absurd) count is compared in i128.
    let text = "ROWS 1\nCOLS 1\nSTART_FRAME -9000000000000000000\nEND_FRAME 9000000000000000000\n\
        ASCII_DATA @@\nFrame 1\n5\n";
    let (line, msg) = fails(text);
    assert_eq!(line, Some(3));
    assert!(
        msg.contains("announce 18000000000000000001 frames, the file holds 1"),
        "{msg}"
    );
    let parsed = strict(&format!("{text}@@\n")).unwrap();
    assert_eq!(parsed.recording.data(), &[5.0]);
    // Frames without `Frame` lines are numbered from START_FRAME: no room after i64::MAX.
    let text = "ROWS 1\nCOLS 1\nSTART_FRAME 9223372036854775807\nASCII_DATA @@\n5\n6\n";
    let (line, msg) = fails(text);
    assert_eq!(line, Some(6));
    assert!(
        msg.contains(
            "frame 2 of the file cannot be numbered: START_FRAME 9223372036854775807 (line 3) + 1"
        ),
        "{msg}"
    );
    let parsed =
        strict("ROWS 1\nCOLS 1\nSTART_FRAME 9223372036854775807\nASCII_DATA @@\n5\n").unwrap();
    assert_eq!(parsed.recording.frame_info()[0].number, i64::MAX);
    // The same near the bottom: a jump between extreme `Frame` numbers is counted in i128.
    let text = format!(
        "ROWS 1\nCOLS 1\nASCII_DATA @@\nFrame {}\n1\nFrame {}\n2\n",
        i64::MIN,
        i64::MAX
    );
    let parsed = strict(&text).unwrap();
    assert!(
        parsed.warnings[0]
            .to_string()
            .contains("18446744073709551614 frame numbers missing"),
        "{:?}",
        parsed.warnings
    );
}

#[test]
fn repeated_or_decreasing_frame_numbers_are_errors_gaps_are_warnings() {
    let frames = |numbers: &[i64]| {
        let mut text = "ROWS 1\nCOLS 2\nASCII_DATA @@\n".to_owned();
        for n in numbers {
            text.push_str(&format!("Frame {n}\n{n},0\n"));
        }
        text + "@@\n"
    };
    let (line, msg) = fails(&frames(&[1, 2, 2, 3]));
    assert_eq!(line, Some(8));
    assert!(
        msg.contains("frame 2 repeats frame 2 (line 6): expected increasing frame numbers"),
        "{msg}"
    );
    let (line, msg) = fails(&frames(&[1, 2, 3, 1]));
    assert_eq!(line, Some(10));
    assert!(
        msg.contains("frame 1 comes after frame 3 (line 8)"),
        "{msg}"
    );
    assert!(msg.contains("read leniently"), "{msg}");
    // Leniently: kept, with a warning.
    let parsed = lenient(&frames(&[1, 2, 2, 3])).unwrap();
    assert_eq!(parsed.recording.frame_count(), 4);
    assert_eq!(parsed.warnings.len(), 1, "{:?}", parsed.warnings);
    assert!(
        parsed.warnings[0]
            .to_string()
            .starts_with("t.asf line 8: frame 2 repeats frame 2")
    );
    // A jump (49 -> 150): read, with a warning naming the line and the numbers missing.
    let parsed = strict(&frames(&[48, 49, 150, 151])).unwrap();
    assert_eq!(parsed.recording.frame_count(), 4);
    assert_eq!(
        parsed.warnings.render(crate::Face::Cli),
        vec![
            "t.asf line 8: frame 150 follows frame 49: 100 frame numbers missing, so time is \
             not contiguous here"
                .to_owned()
        ]
    );
    let parsed = strict(&frames(&[1, 3])).unwrap();
    assert!(
        parsed.warnings[0]
            .to_string()
            .contains("1 frame number missing"),
        "{:?}",
        parsed.warnings
    );
    // Many jumps: the first few one by one, the rest summed up.
    let numbers: Vec<i64> = (0..20).map(|i| i * 3).collect();
    let parsed = strict(&frames(&numbers)).unwrap();
    assert_eq!(
        parsed.warnings.len(),
        MAX_GAP_WARNINGS + 1,
        "{:?}",
        parsed.warnings
    );
    assert!(
        parsed.warnings[MAX_GAP_WARNINGS].to_string().starts_with(
            "t.asf: 14 more jumps in the frame numbers (from line 16), 28 frame numbers missing"
        ),
        "{:?}",
        parsed.warnings
    );
    // START/END disagreeing with a complete file (`@@`): reported too, also without START_FRAME.
    let text = frames(&[1, 2]).replace("ASCII_DATA", "START_FRAME 1\nEND_FRAME 5000\nASCII_DATA");
    let parsed = strict(&text).unwrap();
    assert_eq!(parsed.warnings.len(), 1, "{:?}", parsed.warnings);
    assert!(
        parsed.warnings[0]
            .to_string()
            .contains("announce 5000 frames, the file holds 2")
    );
    let text = frames(&[1, 2]).replace("ASCII_DATA", "END_FRAME 5000\nASCII_DATA");
    let parsed = strict(&text).unwrap();
    assert_eq!(
        parsed.warnings.render(crate::Face::Cli),
        vec![
            "t.asf line 3: the first frame (1, no START_FRAME) and END_FRAME 5000 announce 5000 \
             frames, the file holds 2; keeping the frames found"
                .to_owned()
        ]
    );
    // Without `@@`, fewer frames than announced means a cut file, as with START_FRAME.
    let (line, msg) = fails(text.trim_end_matches("@@\n"));
    assert_eq!(line, Some(3));
    assert!(msg.contains("looks truncated"), "{msg}");
}

#[test]
fn the_writer_refuses_frame_numbers_that_would_not_read_back() {
    let grid = Grid::new(1, 1);
    let info = |numbers: [i64; 2]| {
        numbers
            .map(|number| FrameInfo {
                number,
                suffix: None,
            })
            .to_vec()
    };
    let rec = |numbers| {
        Recording::with_info(
            grid,
            None,
            vec![1.0, 2.0],
            None,
            info(numbers),
            SensorMeta::default(),
        )
        .unwrap()
    };
    let err = write_tekscan(&rec([3, 3]), &mut Vec::new()).unwrap_err();
    assert!(
        err.to_string().contains("frame numbers must increase"),
        "{err}"
    );
    assert!(write_tekscan(&rec([3, 2]), &mut Vec::new()).is_err());
    let mut out = Vec::new();
    write_tekscan(&rec([3, 7]), &mut out).unwrap();
    let back = strict(std::str::from_utf8(&out).unwrap()).unwrap();
    assert_eq!(back.recording, rec([3, 7]));
}

fn sample_recording() -> Recording {
    let grid = Grid::new(2, 3);
    let meta = SensorMeta {
        sensor: Some("5051".into()),
        row_pitch_mm: Some(1.27),
        col_pitch_mm: Some(0.635),
        units: Some(PressureUnit::KPa),
        full_scale: Some(137.9),
        noise_threshold: Some(3.0),
        extra: vec![
            ("VERSION".into(), "presrs 0.1".into()),
            ("COMMENTS:".into(), String::new()),
            ("walk 3, wood".into(), String::new()),
            ("ROWS".into(), "99".into()),
        ],
    };
    let info = vec![
        FrameInfo {
            number: 10,
            suffix: Some(", timestamp 728".into()),
        },
        FrameInfo {
            number: 11,
            suffix: None,
        },
    ];
    let data = vec![
        0.0, 1.5, -2.0, 1e-7, 255.0, 3.25, 0.1, 0.2, 0.3, 7.0, 8.0, 9.0,
    ];
    Recording::with_info(
        grid,
        Some(0.01),
        data,
        Some(vec![false, true, true, true, true, true]),
        info,
        meta,
    )
    .unwrap()
}

#[test]
fn writer_output_layout() {
    let rec = sample_recording();
    let mut out = Vec::new();
    write_tekscan(&rec, &mut out).unwrap();
    let text = String::from_utf8(out).unwrap();
    let expected = "DATA_TYPE MOVIE\nROWS 2\nCOLS 3\nROW_SPACING 1.27 mm\nCOL_SPACING 0.635 mm\n\
        SENSOR_TYPE 5051\nSECONDS_PER_FRAME 0.01\nUNITS KPa\nNOISE_THRESHOLD 3\n\
        SATURATION_PRESSURE 137.9 KPa\nSTART_FRAME 10\nEND_FRAME 11\nVERSION presrs 0.1\nCOMMENTS:\n\
        walk 3, wood\nASCII_DATA @@\n\nFrame 10, timestamp 728\nB,1.5,-2\n0.0000001,255,3.25\n\n\
        Frame 11\nB,0.2,0.3\n7,8,9\n@@\n";
    assert_eq!(text, expected);
    let back = strict(&text).unwrap();
    assert!(back.warnings.is_empty(), "{:?}", back.warnings);
    let mut want = rec.clone();
    // The stray `ROWS` entry of `extra` is structural and not written.
    want.meta.extra.pop();
    assert_eq!(back.recording, want);
}

#[test]
fn writer_rejects_what_cannot_be_read_back() {
    let grid = Grid::new(1, 2);
    let nan = Recording::new(grid, None, vec![1.0, f64::NAN], None, SensorMeta::default()).unwrap();
    let err = write_tekscan(&nan, &mut Vec::new()).unwrap_err();
    assert!(err.to_string().contains("row 1 column 2 is NaN"), "{err}");
    let empty = Recording::new(grid, None, vec![], None, SensorMeta::default()).unwrap();
    assert!(write_tekscan(&empty, &mut Vec::new()).is_err());
    let bad_suffix = Recording::with_info(
        grid,
        None,
        vec![1.0, 2.0],
        None,
        vec![FrameInfo {
            number: 1,
            suffix: Some("2 x".into()),
        }],
        SensorMeta::default(),
    )
    .unwrap();
    assert!(write_tekscan(&bad_suffix, &mut Vec::new()).is_err());
    let mut newline =
        Recording::new(grid, None, vec![1.0, 2.0], None, SensorMeta::default()).unwrap();
    newline.meta.extra.push(("NOTE".into(), "a\nb".into()));
    assert!(write_tekscan(&newline, &mut Vec::new()).is_err());
    newline.meta.extra[0] = ("ASCII_DATA".into(), String::new());
    assert!(write_tekscan(&newline, &mut Vec::new()).is_err());
}

#[test]
fn file_round_trip_is_atomic_and_exact() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("movie.asf");
    let mut rec = sample_recording();
    rec.meta.extra.pop();
    write_tekscan_file(&rec, &path).unwrap();
    assert_eq!(read_tekscan(&path).unwrap(), rec);
    let err = read_tekscan(&dir.path().join("missing.asf")).unwrap_err();
    assert!(err.to_string().starts_with("cannot read ") && err.to_string().contains("missing.asf"));
}
