//! The writer: a recording as a TekScan ASCII movie that reads back equal.

use std::io::{BufWriter, Write};
use std::path::Path;

use presrs_core::Recording;

use super::lines::is_ascii_data;
use crate::error::IoError;
use crate::textutil::{push_int, push_number};

/// Writes a recording as a TekScan ASCII movie (LF line endings).
///
/// The header holds `DATA_TYPE MOVIE`, `ROWS`, `COLS`, `ROW_SPACING`/`COL_SPACING` in mm, `SENSOR_TYPE`,
/// `SECONDS_PER_FRAME`, `UNITS` (when `meta.units` states one), `NOISE_THRESHOLD`,
/// `SATURATION_PRESSURE` (from `full_scale`), `START_FRAME`/`END_FRAME` (the first and last frame numbers), then the entries of `meta.extra` that are
/// not already written, then `ASCII_DATA @@`. Absent sensels are written `B`; numbers are written so that
/// they read back bit-exactly. Reading the output with [`parse_tekscan`](super::parse_tekscan) gives back an equal recording.
///
/// Fails (`InvalidInput`) without writing anything when the recording cannot be represented: no frames,
/// non-finite values, frame numbers that do not increase, or header text / frame suffixes with line
/// breaks or that would be read back as something else.
pub fn write_tekscan<W: Write + ?Sized>(recording: &Recording, w: &mut W) -> std::io::Result<()> {
    validate_for_tekscan(recording)?;
    let mut out = BufWriter::with_capacity(1 << 16, w);
    let meta = &recording.meta;
    let grid = recording.grid();
    let info = recording.frame_info();
    let mut written: Vec<&str> = vec![
        "DATA_TYPE",
        "ROWS",
        "COLS",
        "START_FRAME",
        "END_FRAME",
        "ASCII_DATA",
    ];
    let mut buf: Vec<u8> = Vec::with_capacity(256);

    buf.extend_from_slice(b"DATA_TYPE MOVIE\n");
    header_number(&mut buf, "ROWS", grid.rows as f64, "");
    header_number(&mut buf, "COLS", grid.cols as f64, "");
    if let Some(mm) = meta.row_pitch_mm {
        header_number(&mut buf, "ROW_SPACING", mm, " mm");
        written.push("ROW_SPACING");
    }
    if let Some(mm) = meta.col_pitch_mm {
        header_number(&mut buf, "COL_SPACING", mm, " mm");
        written.push("COL_SPACING");
    }
    if let Some(sensor) = &meta.sensor {
        buf.extend_from_slice(b"SENSOR_TYPE ");
        buf.extend_from_slice(sensor.as_bytes());
        buf.push(b'\n');
        written.push("SENSOR_TYPE");
    }
    if let Some(period) = recording.frame_period_s() {
        header_number(&mut buf, "SECONDS_PER_FRAME", period, "");
        written.push("SECONDS_PER_FRAME");
    }
    // A source that stated no unit is written without one too (read back, it is the same recording).
    if let Some(units) = &meta.units {
        buf.extend_from_slice(b"UNITS ");
        buf.extend_from_slice(units.as_tekscan().as_bytes());
        buf.push(b'\n');
        written.push("UNITS");
    }
    if let Some(noise) = meta.noise_threshold {
        header_number(&mut buf, "NOISE_THRESHOLD", noise, "");
        written.push("NOISE_THRESHOLD");
    }
    if let Some(full_scale) = meta.full_scale {
        let unit = format!(" {}", meta.units_or_raw().as_tekscan());
        header_number(&mut buf, "SATURATION_PRESSURE", full_scale, &unit);
        written.push("SATURATION_PRESSURE");
    }
    let first = info.first().map_or(1, |i| i.number);
    let last = info.last().map_or(1, |i| i.number);
    buf.extend_from_slice(b"START_FRAME ");
    push_int(&mut buf, first);
    buf.extend_from_slice(b"\nEND_FRAME ");
    push_int(&mut buf, last);
    buf.push(b'\n');
    for (key, value) in &meta.extra {
        let skip = !key.contains(char::is_whitespace)
            && written.iter().any(|&w| w == key.trim_end_matches(':'));
        if skip {
            continue;
        }
        buf.extend_from_slice(key.as_bytes());
        if !value.is_empty() {
            buf.push(b' ');
            buf.extend_from_slice(value.as_bytes());
        }
        buf.push(b'\n');
    }
    buf.extend_from_slice(b"ASCII_DATA @@\n");
    out.write_all(&buf)?;

    let present = recording.present();
    for (frame, frame_info) in recording.frames().zip(info) {
        buf.clear();
        buf.extend_from_slice(b"\nFrame ");
        push_int(&mut buf, frame_info.number);
        if let Some(suffix) = &frame_info.suffix {
            buf.extend_from_slice(suffix.as_bytes());
        }
        buf.push(b'\n');
        for (r, row) in frame.values().chunks_exact(grid.cols).enumerate() {
            for (c, &value) in row.iter().enumerate() {
                if c > 0 {
                    buf.push(b',');
                }
                if present.is_some_and(|mask| !mask[r * grid.cols + c]) {
                    buf.push(b'B');
                } else {
                    push_number(&mut buf, value);
                }
            }
            buf.push(b'\n');
        }
        out.write_all(&buf)?;
    }
    out.write_all(b"@@\n")?;
    out.flush()
}

/// Writes a recording as a TekScan ASCII movie file, atomically (see [`crate::atomic`]).
pub fn write_tekscan_file(recording: &Recording, path: &Path) -> Result<(), IoError> {
    crate::atomic::write_atomic(path, |w| write_tekscan(recording, w))
}

fn header_number(buf: &mut Vec<u8>, key: &str, value: f64, unit: &str) {
    buf.extend_from_slice(key.as_bytes());
    buf.push(b' ');
    push_number(buf, value);
    buf.extend_from_slice(unit.as_bytes());
    buf.push(b'\n');
}

fn invalid(message: String) -> std::io::Error {
    std::io::Error::new(std::io::ErrorKind::InvalidInput, message)
}

fn validate_for_tekscan(recording: &Recording) -> std::io::Result<()> {
    if recording.frame_count() == 0 {
        return Err(invalid(
            "a TekScan file holds at least one frame; the recording has none".to_owned(),
        ));
    }
    let grid = recording.grid();
    if let Some(at) = recording.data().iter().position(|v| !v.is_finite()) {
        let (frame, cell) = (at / grid.len(), at % grid.len());
        return Err(invalid(format!(
            "frame {} (0-based) row {} column {} is {}; TekScan files hold finite numbers only",
            frame,
            cell / grid.cols + 1,
            cell % grid.cols + 1,
            recording.data()[at]
        )));
    }
    let meta = &recording.meta;
    for (what, value) in [
        ("ROW_SPACING", meta.row_pitch_mm),
        ("COL_SPACING", meta.col_pitch_mm),
    ] {
        if let Some(v) = value
            && !(v.is_finite() && v > 0.0)
        {
            return Err(invalid(format!(
                "{what} must be a positive length, got {v} mm"
            )));
        }
    }
    for (what, value) in [
        ("NOISE_THRESHOLD", meta.noise_threshold),
        ("SATURATION_PRESSURE", meta.full_scale),
    ] {
        if let Some(v) = value
            && !v.is_finite()
        {
            return Err(invalid(format!("{what} must be a finite number, got {v}")));
        }
    }
    let single_line = |what: &str, text: &str| {
        if text.contains(['\n', '\r']) {
            Err(invalid(format!("{what} {text:?} holds a line break")))
        } else {
            Ok(())
        }
    };
    if let Some(sensor) = &meta.sensor {
        single_line("SENSOR_TYPE", sensor)?;
    }
    if let Some(units) = &meta.units {
        single_line("UNITS", units.as_tekscan())?;
    }
    for (key, value) in &meta.extra {
        single_line("header key", key)?;
        single_line("header value", value)?;
        let token = key.split_whitespace().next().unwrap_or("");
        if token.is_empty() || key.starts_with(char::is_whitespace) {
            return Err(invalid(format!(
                "header key {key:?} must start with a non-blank character"
            )));
        }
        if is_ascii_data(token) {
            return Err(invalid(format!(
                "header entry {key:?} would end the header early"
            )));
        }
    }
    for pair in recording.frame_info().windows(2) {
        if pair[1].number <= pair[0].number {
            return Err(invalid(format!(
                "frame number {} follows frame number {}; frame numbers must increase (the reader \
                 rejects a file whose time repeats or runs backwards)",
                pair[1].number, pair[0].number
            )));
        }
    }
    for info in recording.frame_info() {
        if let Some(suffix) = &info.suffix {
            single_line("frame suffix", suffix)?;
            if suffix.starts_with(|c: char| c.is_ascii_digit()) || suffix.trim_end() != suffix {
                return Err(invalid(format!(
                    "frame {} suffix {suffix:?} would not read back (it must not start with a digit or end with a space)",
                    info.number
                )));
            }
        }
    }
    Ok(())
}
