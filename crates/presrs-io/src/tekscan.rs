//! TekScan ASCII movies and snapshots (`.asf`, sometimes `.csv`): reader and writer.
//!
//! See `docs/tekscan-ascii.md` for the format. What this module does where the format notes are
//! silent:
//!
//! * **Header.** Lines up to `ASCII_DATA` (found by search) are `KEY value` lines; the key is the first
//!   token, an upper-case identifier as TekScan writes them, with a trailing `:` ignored (`ROWS: 44`
//!   works). A line whose first token is not an upper-case identifier (`overground walk p10`, `Rows 3 were
//!   damaged`), and the line right after a bare `KEY:` line such as `COMMENTS:` (unless it is a plausible
//!   known key line such as `ROWS 44`), is free text: it is kept in [`SensorMeta::extra`] as the whole line
//!   with an empty value. Blank lines in the header are skipped. If the file has no `ASCII_DATA` line but
//!   a `Frame N` line follows the header, the header ends there.
//! * **Typed keys.** `ROWS`/`COLS` (required, positive integers) give the grid; `SENSOR_TYPE`,
//!   `ROW_SPACING`/`COL_SPACING` (converted to mm from `mm`/`millimeters`/`cm`/`inches`/...), `UNITS`,
//!   `NOISE_THRESHOLD`, `SECONDS_PER_FRAME` and `SATURATION_PRESSURE` (as `full_scale`, when its unit is
//!   `UNITS` or convertible to it) fill [`SensorMeta`] and the frame period. A typed value that cannot be
//!   understood (`ROW_SPACING 5 furlongs`, `SECONDS_PER_FRAME 0`) is kept verbatim in `extra` and
//!   reported as a warning; nothing is lost. `DATA_TYPE`, `START_FRAME`, `END_FRAME` and `ASCII_DATA` are
//!   structural: they are checked but not kept (the writer derives them). Every other key is kept verbatim,
//!   in file order, in `extra`. A repeated typed key keeps the first value (a conflicting repeated
//!   `ROWS`/`COLS` is an error) and is reported as a warning.
//! * **Frames.** Frame numbers and `Frame` line suffixes are kept as written in [`FrameInfo`]. Files
//!   without `Frame` lines (snapshots) are cut into frames of `ROWS` rows, numbered from `START_FRAME`
//!   (default 1). Blank and comma-only lines are skipped anywhere; `@@` ends the data and must be followed
//!   only by blank lines. `B` cells must be at the same positions in every frame.
//! * **Frame numbers.** `Frame` numbers must increase: a repeated number or one that goes back (time
//!   repeating or running backwards) is an error (a warning when reading leniently, the frames kept). A
//!   jump (`Frame 49` then `Frame 150`) means frames are missing and time is not contiguous there: it is
//!   reported as a warning naming the line. Numbers too large to count on from `START_FRAME` in a file
//!   without `Frame` lines are an error.
//! * **Frame count.** `START_FRAME`/`END_FRAME` announce `END - START + 1` frames (without `START_FRAME`,
//!   START is the first frame's number). Fewer frames in a file
//!   without the `@@` terminator means the file was cut at a frame boundary: an error (a warning when
//!   reading leniently). Any other disagreement (more frames, or fewer before an `@@`) is a warning: the
//!   frames in the file are the truth.
//! * **Truncation.** A last frame with missing rows, or whose last line has fewer than `COLS` values, at
//!   the end of the file is an error; with [`ReadOptions::lenient`] it is dropped and reported as a warning.
//!   A short frame anywhere else (before another `Frame` line or `@@`) is always an error.
//! * **Memory.** Nothing is allocated from the header's `ROWS x COLS` alone: the data grows as rows are
//!   read, and reservations are capped by the size of the input.

use std::collections::HashMap;
use std::io::{BufWriter, Write};
use std::path::Path;

use presrs_core::{FrameInfo, Grid, PressureUnit, Recording, SensorMeta};

use crate::error::{IoError, display_name};
use crate::textutil::{
    Cell, decode_text, is_blank, numbered_lines, parse_cell, push_int, push_number, split_cells,
};
use crate::{Parsed, ReadOptions};

/// The result of parsing a TekScan file: the recording and any warnings (see [`Parsed`]).
pub type ParsedTekscan = Parsed;

/// Header keys this module interprets (everything else goes to [`SensorMeta::extra`] untouched).
const KNOWN_KEYS: &[&str] = &[
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

/// Reads a TekScan ASCII file strictly (any problem is an error; warnings are discarded).
pub fn read_tekscan(path: &Path) -> Result<Recording, IoError> {
    Ok(read_tekscan_with(path, &ReadOptions::default())?.recording)
}

/// Reads a TekScan ASCII file with options, returning the warnings too.
pub fn read_tekscan_with(path: &Path, options: &ReadOptions) -> Result<ParsedTekscan, IoError> {
    let bytes = std::fs::read(path).map_err(|source| IoError::io("read", path, source))?;
    parse_tekscan(&decode_text(&bytes), &display_name(path), options)
}

/// Whether `text` looks like a TekScan ASCII export: a `KEY value` header with `ASCII_DATA` or
/// `DATA_TYPE` among its first lines. Used to recognise `.csv`/`.txt` files that are TekScan exports.
pub fn looks_like_tekscan(text: &str) -> bool {
    numbered_lines(text).into_iter().take(200).any(|(_, line)| {
        let token = line.split_whitespace().next().unwrap_or("");
        let key = token.trim_end_matches(':');
        key == "ASCII_DATA" || key == "DATA_TYPE"
    })
}

/// Parses the text of a TekScan ASCII file. `source_name` names the file in error messages.
pub fn parse_tekscan(
    text: &str,
    source_name: &str,
    options: &ReadOptions,
) -> Result<ParsedTekscan, IoError> {
    let lines = numbered_lines(text);
    if lines.iter().all(|(_, line)| is_blank(line)) {
        return Err(IoError::format(
            source_name,
            "empty file: expected a TekScan ASCII header (`DATA_TYPE MOVIE`, `ROWS`, `COLS`, ..., \
             `ASCII_DATA`) followed by frames",
        ));
    }
    let mut warnings = Vec::new();
    let header = parse_header(&lines, source_name, &mut warnings)?;
    let data_lines = &lines[header.data_start..];
    let body = parse_frames(
        &header,
        data_lines,
        text.len(),
        source_name,
        options,
        &mut warnings,
    )?;
    check_frame_count(&header, &body, source_name, options, &mut warnings)?;
    let recording = Recording::with_info(
        header.grid,
        header.period,
        body.data,
        body.mask,
        body.info,
        header.meta,
    )
    .map_err(|source| IoError::Model {
        file: source_name.to_owned(),
        source,
    })?;
    Ok(Parsed {
        recording,
        warnings,
    })
}

/// What the header says.
struct Header {
    grid: Grid,
    period: Option<f64>,
    meta: SensorMeta,
    start_frame: Option<(usize, i64)>,
    end_frame: Option<(usize, i64)>,
    /// Index into the file's lines of the first data line.
    data_start: usize,
    /// Line number of the `ASCII_DATA` line (or of the last header line).
    end_line: usize,
}

fn parse_header(
    lines: &[(usize, &str)],
    file: &str,
    warnings: &mut Vec<String>,
) -> Result<Header, IoError> {
    let mut meta = SensorMeta::default();
    let mut rows: Option<(usize, usize)> = None;
    let mut cols: Option<(usize, usize)> = None;
    let mut period = None;
    let mut start_frame = None;
    let mut end_frame = None;
    // (value, position in `extra` where it belongs if it stays verbatim)
    let mut saturation: Option<(String, usize)> = None;
    let mut seen: HashMap<String, usize> = HashMap::new();
    let mut after_label = false;
    let mut end = None;
    // A `Frame N` line ends the header only in files without an `ASCII_DATA` line (so that a comment such
    // as `Frame 3 was bad` in a normal header is kept as text).
    let has_ascii_data = lines
        .iter()
        .any(|(_, line)| is_ascii_data(line.split_whitespace().next().unwrap_or("")));

    for (index, &(line_no, raw)) in lines.iter().enumerate() {
        let line = raw.trim();
        if is_blank(line) {
            after_label = false;
            continue;
        }
        let token = line.split_whitespace().next().unwrap_or("");
        let key = token.trim_end_matches(':').to_owned();
        if is_ascii_data(token) {
            end = Some((index + 1, line_no));
            break;
        }
        if !has_ascii_data && frame_line(line).is_some() {
            end = Some((index, line_no));
            break;
        }
        let value = line[token.len()..].trim();
        let key_like = looks_like_key(token);
        // After a `COMMENTS:` label, a known key counts only if its value makes sense for it.
        let known = key_like
            && KNOWN_KEYS.contains(&key.as_str())
            && (!after_label || plausible_value(&key, value));
        if !known && (after_label || !key_like) {
            meta.extra.push((line.to_owned(), String::new()));
            after_label = false;
            continue;
        }
        after_label = token.ends_with(':') && value.is_empty();
        if !known {
            meta.extra.push((token.to_owned(), value.to_owned()));
            continue;
        }
        if let Some(first) = seen.get(&key) {
            let same_dims = match key.as_str() {
                "ROWS" | "COLS" => {
                    let previous = if key == "ROWS" { rows } else { cols };
                    let now = parse_dim(&key, value, file, line_no)?;
                    if previous.map(|(_, n)| n) != Some(now) {
                        return Err(IoError::parse(
                            file,
                            line_no,
                            format!(
                                "{key} {now} contradicts {key} {} on line {first}",
                                previous.map_or(0, |(_, n)| n)
                            ),
                        ));
                    }
                    true
                }
                _ => false,
            };
            if !same_dims {
                warnings.push(format!(
                    "{file} line {line_no}: repeated {key} ignored, keeping the value of line {first}"
                ));
            }
            continue;
        }
        seen.insert(key.clone(), line_no);
        match key.as_str() {
            "DATA_TYPE" => {}
            "ROWS" => rows = Some((line_no, parse_dim(&key, value, file, line_no)?)),
            "COLS" => cols = Some((line_no, parse_dim(&key, value, file, line_no)?)),
            "START_FRAME" => {
                start_frame = Some((line_no, parse_frame_number(&key, value, file, line_no)?))
            }
            "END_FRAME" => {
                end_frame = Some((line_no, parse_frame_number(&key, value, file, line_no)?))
            }
            "SENSOR_TYPE" => meta.sensor = (!value.is_empty()).then(|| value.to_owned()),
            "UNITS" => meta.units = Some(PressureUnit::parse(value)),
            "ROW_SPACING" | "COL_SPACING" => match parse_length_mm(value) {
                Some(mm) if key == "ROW_SPACING" => meta.row_pitch_mm = Some(mm),
                Some(mm) => meta.col_pitch_mm = Some(mm),
                None => keep_verbatim(
                    &mut meta,
                    warnings,
                    file,
                    line_no,
                    token,
                    value,
                    "expected a positive length with a unit (mm, cm or inches)",
                ),
            },
            "SECONDS_PER_FRAME" => match value.parse::<f64>() {
                Ok(p) if p.is_finite() && p > 0.0 => period = Some(p),
                _ => keep_verbatim(
                    &mut meta,
                    warnings,
                    file,
                    line_no,
                    token,
                    value,
                    "expected a positive number of seconds; the frame period is unknown",
                ),
            },
            "NOISE_THRESHOLD" => match value.parse::<f64>() {
                Ok(n) if n.is_finite() => meta.noise_threshold = Some(n),
                _ => keep_verbatim(
                    &mut meta,
                    warnings,
                    file,
                    line_no,
                    token,
                    value,
                    "expected a number",
                ),
            },
            "SATURATION_PRESSURE" => {
                saturation = Some((value.to_owned(), meta.extra.len()));
            }
            _ => meta.extra.push((token.to_owned(), value.to_owned())),
        }
    }

    let last_line = lines.last().map_or(1, |&(n, _)| n);
    let Some((data_start, end_line)) = end else {
        return Err(IoError::parse(
            file,
            last_line,
            "expected an `ASCII_DATA` line ending the TekScan header, found the end of the file \
             (is this a TekScan ASCII export?)",
        ));
    };
    let (rows, cols) = match (rows, cols) {
        (Some((_, r)), Some((_, c))) => (r, c),
        (r, c) => {
            let missing: Vec<&str> = [("ROWS", r.is_none()), ("COLS", c.is_none())]
                .into_iter()
                .filter_map(|(k, missing)| missing.then_some(k))
                .collect();
            return Err(IoError::parse(
                file,
                end_line,
                format!(
                    "the header has no {} line; expected `ROWS <n>` and `COLS <n>` before the data",
                    missing.join(" or ")
                ),
            ));
        }
    };
    if rows.checked_mul(cols).is_none() {
        return Err(IoError::parse(
            file,
            end_line,
            format!("ROWS {rows} x COLS {cols} is too large"),
        ));
    }
    if let Some((value, at)) = saturation {
        match saturation_in_units(&value, meta.units_or_raw()) {
            Some(full_scale) => meta.full_scale = Some(full_scale),
            None => {
                // Not expressible in the recording's units (e.g. kPa for a raw export): keep it verbatim.
                meta.extra.insert(
                    at.min(meta.extra.len()),
                    ("SATURATION_PRESSURE".to_owned(), value),
                );
            }
        }
    }
    Ok(Header {
        grid: Grid::new(rows, cols),
        period,
        meta,
        start_frame,
        end_frame,
        data_start,
        end_line,
    })
}

/// `ASCII_DATA` (or `ASCII_DATA:`), the key that ends the header.
fn is_ascii_data(token: &str) -> bool {
    token.trim_end_matches(':') == "ASCII_DATA"
}

/// Whether `value` parses for the keys whose malformed values are errors.
fn plausible_value(key: &str, value: &str) -> bool {
    match key {
        "ROWS" | "COLS" => value.parse::<usize>().is_ok_and(|n| n > 0),
        "START_FRAME" | "END_FRAME" => value.parse::<i64>().is_ok(),
        _ => true,
    }
}

/// An upper-case identifier such as `ROWS`, `CALIBRATION_POINT_1` or `COMMENTS:`.
fn looks_like_key(token: &str) -> bool {
    let key = token.strip_suffix(':').unwrap_or(token);
    let mut chars = key.chars();
    chars.next().is_some_and(|c| c.is_ascii_uppercase())
        && chars.all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_')
}

fn keep_verbatim(
    meta: &mut SensorMeta,
    warnings: &mut Vec<String>,
    file: &str,
    line_no: usize,
    token: &str,
    value: &str,
    expected: &str,
) {
    warnings.push(format!(
        "{file} line {line_no}: {token} `{value}` not understood ({expected}); kept verbatim"
    ));
    meta.extra.push((token.to_owned(), value.to_owned()));
}

fn parse_dim(key: &str, value: &str, file: &str, line_no: usize) -> Result<usize, IoError> {
    match value.parse::<usize>() {
        Ok(n) if n > 0 => Ok(n),
        _ => Err(IoError::parse(
            file,
            line_no,
            format!("{key}: expected a positive whole number, found `{value}`"),
        )),
    }
}

fn parse_frame_number(key: &str, value: &str, file: &str, line_no: usize) -> Result<i64, IoError> {
    value.parse::<i64>().map_err(|_| {
        IoError::parse(
            file,
            line_no,
            format!("{key}: expected a whole frame number, found `{value}`"),
        )
    })
}

/// `5.08 mm`, `0.025 inches`, `0.5 cm` -> millimetres.
fn parse_length_mm(value: &str) -> Option<f64> {
    let mut parts = value.split_whitespace();
    let number: f64 = parts.next()?.parse().ok()?;
    let unit = parts.next()?.to_ascii_lowercase();
    if parts.next().is_some() || !(number.is_finite() && number > 0.0) {
        return None;
    }
    let factor = match unit.as_str() {
        "mm" | "millimeter" | "millimeters" | "millimetre" | "millimetres" => 1.0,
        "cm" | "centimeter" | "centimeters" | "centimetre" | "centimetres" => 10.0,
        "in" | "inch" | "inches" | "\"" => 25.4,
        "m" | "meter" | "meters" | "metre" | "metres" => 1000.0,
        _ => return None,
    };
    Some(number * factor)
}

/// `1514.73 KPa` in the recording's `units`, when the unit is the same or both are pressure units.
fn saturation_in_units(value: &str, units: &PressureUnit) -> Option<f64> {
    let mut parts = value.split_whitespace();
    let number: f64 = parts.next()?.parse().ok()?;
    let unit = PressureUnit::parse(&parts.collect::<Vec<_>>().join(" "));
    if !number.is_finite() || value.split_whitespace().count() < 2 {
        return None;
    }
    if &unit == units {
        return Some(number);
    }
    Some(number * unit.kpa_per_unit()? / units.kpa_per_unit()?)
}

/// `Frame 12, timestamp 728` -> `(12, Some(", timestamp 728"))`; `None` if the line is not a frame line.
/// `Some(Err(..))` if it starts with `Frame ` but the number is malformed. Shared with the stream reader
/// ([`crate::tekscan_stream`]) so that both read `Frame` lines alike.
pub(crate) fn frame_line(line: &str) -> Option<Result<(i64, Option<&str>), String>> {
    let head = line.get(..5)?;
    if !head.eq_ignore_ascii_case("frame") {
        return None;
    }
    let rest = &line[5..];
    if !rest.starts_with(|c: char| c.is_whitespace()) {
        return None;
    }
    let rest = rest.trim_start();
    let digits_end = rest
        .char_indices()
        .find(|&(i, c)| !(c.is_ascii_digit() || (i == 0 && (c == '-' || c == '+'))))
        .map_or(rest.len(), |(i, _)| i);
    let number = &rest[..digits_end];
    let suffix = &rest[digits_end..];
    Some(
        number
            .parse::<i64>()
            .map(|n| (n, (!suffix.is_empty()).then_some(suffix)))
            .map_err(|_| format!("expected a frame number after `Frame`, found `{}`", rest)),
    )
}

/// The frames read.
struct Body {
    data: Vec<f64>,
    mask: Option<Vec<bool>>,
    info: Vec<FrameInfo>,
    /// Line of the `@@` terminator, when present.
    terminator: Option<usize>,
    /// A truncated last frame was dropped (lenient reading).
    dropped_truncated: bool,
}

/// The frame being read.
struct Current {
    number: i64,
    suffix: Option<String>,
    first_line: usize,
    rows_done: usize,
}

fn parse_frames(
    header: &Header,
    lines: &[(usize, &str)],
    input_len: usize,
    file: &str,
    options: &ReadOptions,
    warnings: &mut Vec<String>,
) -> Result<Body, IoError> {
    let Grid { rows, cols } = header.grid;
    let grid_len = header.grid.len();
    // Reserve for the announced frames, but never more than the input could hold (>= 2 bytes per value).
    // In i128: `END_FRAME - START_FRAME + 1` overflows i64 for extreme (crafted) values.
    let announced = match (header.start_frame, header.end_frame) {
        (Some((_, s)), Some((_, e))) if e >= s => {
            usize::try_from(i128::from(e) - i128::from(s) + 1).unwrap_or(usize::MAX)
        }
        _ => 1,
    };
    let cap = announced.saturating_mul(grid_len).min(input_len / 2 + 1);
    let mut data: Vec<f64> = Vec::with_capacity(cap);
    let mut mask: Vec<bool> = Vec::new();
    let mut any_absent = false;
    let mut info: Vec<FrameInfo> = Vec::new();
    let mut framed: Option<bool> = None;
    let mut current: Option<Current> = None;
    let mut terminator: Option<usize> = None;
    let mut dropped_truncated = false;
    let mut cells: Vec<&str> = Vec::new();
    // Jumps in the frame numbers: (line, previous number, number, numbers missing).
    let mut gaps: Vec<(usize, i64, i64, i128)> = Vec::new();
    // Frames without `Frame` lines are numbered from START_FRAME; a crafted START_FRAME near i64::MAX
    // leaves no room for the next number.
    let next_snapshot_number = |info: &Vec<FrameInfo>, line_no: usize| {
        let start = header.start_frame.map_or(1, |(_, s)| s);
        i64::try_from(info.len())
            .ok()
            .and_then(|n| start.checked_add(n))
            .ok_or_else(|| {
                let from = header
                    .start_frame
                    .map_or_else(String::new, |(at, _)| format!(" (line {at})"));
                IoError::parse(
                    file,
                    line_no,
                    format!(
                        "frame {} of the file cannot be numbered: START_FRAME {start}{from} + {} is \
                         beyond the largest frame number ({})",
                        info.len() + 1,
                        info.len(),
                        i64::MAX
                    ),
                )
            })
    };
    let last_nonblank = lines
        .iter()
        .rposition(|(_, line)| !is_blank(line))
        .unwrap_or(0);

    for (index, &(line_no, raw)) in lines.iter().enumerate() {
        let line = raw.trim();
        if is_blank(line) {
            continue;
        }
        if let Some(at) = terminator {
            return Err(IoError::parse(
                file,
                line_no,
                format!(
                    "expected nothing after the `@@` terminator on line {at}, found `{}`",
                    clip(line)
                ),
            ));
        }
        if line == "@@" {
            if let Some(cur) = &current
                && cur.rows_done < rows
            {
                return Err(IoError::parse(
                    file,
                    line_no,
                    format!(
                        "frame {} (from line {}) has {} rows, expected {rows} (ROWS) before the `@@` terminator",
                        cur.number, cur.first_line, cur.rows_done
                    ),
                ));
            }
            terminator = Some(line_no);
            continue;
        }
        if let Some(parsed) = frame_line(line) {
            let (number, suffix) =
                parsed.map_err(|message| IoError::parse(file, line_no, message))?;
            if framed == Some(false) {
                return Err(IoError::parse(
                    file,
                    line_no,
                    "found a `Frame` line after frame data that had none; expected every frame to \
                     start with a `Frame N` line, or none to",
                ));
            }
            framed = Some(true);
            if let Some(cur) = &current
                && cur.rows_done < rows
            {
                return Err(IoError::parse(
                    file,
                    line_no,
                    format!(
                        "frame {} (from line {}) has {} rows, expected {rows} (ROWS), before the next `Frame` line",
                        cur.number, cur.first_line, cur.rows_done
                    ),
                ));
            }
            // `current` is now the complete frame before this one.
            if let Some(prev) = &current {
                let step = i128::from(number) - i128::from(prev.number);
                if step <= 0 {
                    let message = format!(
                        "frame {number} {} frame {} (line {}): expected increasing frame numbers \
                         (time runs backwards or repeats here)",
                        if step == 0 { "repeats" } else { "comes after" },
                        prev.number,
                        prev.first_line
                    );
                    if !options.lenient {
                        return Err(IoError::parse(
                            file,
                            line_no,
                            format!("{message}; read leniently to keep the frames anyway"),
                        ));
                    }
                    warnings.push(format!("{file} line {line_no}: {message}; frames kept"));
                } else if step > 1 {
                    gaps.push((line_no, prev.number, number, step - 1));
                }
            }
            current = Some(Current {
                number,
                suffix: suffix.map(str::to_owned),
                first_line: line_no,
                rows_done: 0,
            });
            continue;
        }

        // A data row.
        if framed.is_none() {
            framed = Some(false);
        }
        let need_new = match &current {
            Some(cur) if cur.rows_done < rows => false,
            Some(cur) if framed == Some(true) => {
                return Err(IoError::parse(
                    file,
                    line_no,
                    format!(
                        "frame {} (from line {}) already has {rows} rows (ROWS); expected a `Frame` line \
                         or the `@@` terminator, found another row of data",
                        cur.number, cur.first_line
                    ),
                ));
            }
            _ => true,
        };
        if need_new {
            current = Some(Current {
                number: next_snapshot_number(&info, line_no)?,
                suffix: None,
                first_line: line_no,
                rows_done: 0,
            });
        }
        let Some(cur) = current.as_mut() else {
            continue;
        };
        let row = cur.rows_done;
        split_cells(line, &mut cells).map_err(|at| {
            IoError::parse(
                file,
                line_no,
                format!(
                    "frame {} row {} column {} is empty; expected a number or `B` (no sensel)",
                    cur.number,
                    row + 1,
                    at + 1
                ),
            )
        })?;
        if cells.len() != cols {
            if index == last_nonblank && cells.len() < cols && terminator.is_none() {
                let message = format!(
                    "frame {} is truncated: its row {} has {} of {cols} values (COLS) at the end of the file",
                    cur.number,
                    row + 1,
                    cells.len()
                );
                if options.lenient {
                    warnings.push(format!("{file} line {line_no}: {message}; frame dropped"));
                    data.truncate(info.len() * grid_len);
                    if info.is_empty() {
                        mask.clear();
                    }
                    current = None;
                    dropped_truncated = true;
                    break;
                }
                return Err(IoError::parse(
                    file,
                    line_no,
                    format!("{message} (read leniently to drop it)"),
                ));
            }
            return Err(IoError::parse(
                file,
                line_no,
                format!(
                    "frame {} has {} values in row {}, expected {cols} (COLS)",
                    cur.number,
                    cells.len(),
                    row + 1
                ),
            ));
        }
        let first_frame = info.is_empty();
        for (col, cell) in cells.iter().enumerate() {
            let parsed = parse_cell(cell).map_err(|err| {
                IoError::parse(
                    file,
                    line_no,
                    format!(
                        "frame {} row {} column {}: {}, found `{}`",
                        cur.number,
                        row + 1,
                        col + 1,
                        err.expected(true),
                        clip(cell)
                    ),
                )
            })?;
            let present = matches!(parsed, Cell::Value(_));
            if first_frame {
                mask.push(present);
                any_absent |= !present;
            } else if mask[row * cols + col] != present {
                let first = info[0].number;
                let message = if present {
                    format!(
                        "frame {} row {} column {} holds a value but frame {first} has `B` (no sensel) there; \
                         expected the same sensel outline in every frame",
                        cur.number,
                        row + 1,
                        col + 1
                    )
                } else {
                    format!(
                        "frame {} row {} column {} is `B` (no sensel) but frame {first} has a value there; \
                         expected the same sensel outline in every frame",
                        cur.number,
                        row + 1,
                        col + 1
                    )
                };
                return Err(IoError::parse(file, line_no, message));
            }
            data.push(parsed.value());
        }
        cur.rows_done += 1;
        if cur.rows_done == rows {
            info.push(FrameInfo {
                number: cur.number,
                suffix: cur.suffix.take(),
            });
        }
    }

    if let Some(cur) = &current
        && cur.rows_done < rows
    {
        let last_line = lines.last().map_or(header.end_line, |&(n, _)| n);
        let message = format!(
            "frame {} (from line {}) is truncated: the file ends after {} of {rows} rows (ROWS)",
            cur.number, cur.first_line, cur.rows_done
        );
        if options.lenient {
            warnings.push(format!("{file} line {last_line}: {message}; frame dropped"));
            data.truncate(info.len() * grid_len);
            dropped_truncated = true;
        } else {
            return Err(IoError::parse(
                file,
                last_line,
                format!("{message} (read leniently to drop it)"),
            ));
        }
    }
    report_gaps(&gaps, file, warnings);
    if info.is_empty() {
        let line_no = lines.last().map_or(header.end_line, |&(n, _)| n);
        return Err(IoError::parse(
            file,
            line_no,
            format!(
                "expected frame data ({rows} rows of {cols} values) after the header ending on line {}, found {}",
                header.end_line,
                if dropped_truncated {
                    "only a truncated frame"
                } else {
                    "none"
                }
            ),
        ));
    }
    Ok(Body {
        data,
        mask: any_absent.then_some(mask),
        info,
        terminator,
        dropped_truncated,
    })
}

/// Gap warnings given one by one; more are summed up in one warning.
const MAX_GAP_WARNINGS: usize = 5;

/// Warns of jumps in the frame numbers (`Frame 49` then `Frame 150`): frames are missing there, so time
/// is not contiguous across the jump.
fn report_gaps(gaps: &[(usize, i64, i64, i128)], file: &str, warnings: &mut Vec<String>) {
    for &(line_no, prev, number, missing) in gaps.iter().take(MAX_GAP_WARNINGS) {
        warnings.push(format!(
            "{file} line {line_no}: frame {number} follows frame {prev}: {missing} frame number{} \
             missing, so time is not contiguous here",
            if missing == 1 { "" } else { "s" }
        ));
    }
    if gaps.len() > MAX_GAP_WARNINGS {
        let more = &gaps[MAX_GAP_WARNINGS..];
        let missing: i128 = more.iter().map(|g| g.3).sum();
        warnings.push(format!(
            "{file}: {} more jumps in the frame numbers (from line {}), {missing} frame numbers missing \
             in them, so time is not contiguous there either",
            more.len(),
            more[0].0
        ));
    }
}

fn check_frame_count(
    header: &Header,
    body: &Body,
    file: &str,
    options: &ReadOptions,
    warnings: &mut Vec<String>,
) -> Result<(), IoError> {
    let Some((end_line, end)) = header.end_frame else {
        return Ok(());
    };
    // Without START_FRAME, the count runs from the first frame's number.
    let (start_line, start, start_text) = match (header.start_frame, body.info.first()) {
        (Some((line, start)), _) => (line, start, format!("START_FRAME {start}")),
        (None, Some(first)) => (
            end_line,
            first.number,
            format!("the first frame ({}, no START_FRAME)", first.number),
        ),
        (None, None) => return Ok(()),
    };
    let announced = i128::from(end) - i128::from(start) + 1;
    let found = body.info.len() as i128 + i128::from(body.dropped_truncated);
    if announced == found {
        return Ok(());
    }
    if announced <= 0 {
        warnings.push(format!(
            "{file} line {start_line}: END_FRAME {end} is before {start_text}; keeping the frames found"
        ));
        return Ok(());
    }
    let message = format!(
        "{start_text} and END_FRAME {end} announce {announced} frames, the file holds {found}"
    );
    if found < announced && body.terminator.is_none() && !body.dropped_truncated {
        if options.lenient {
            warnings.push(format!(
                "{file} line {start_line}: {message} and has no `@@` terminator: it was probably cut short"
            ));
            return Ok(());
        }
        return Err(IoError::parse(
            file,
            start_line,
            format!(
                "{message} and has no `@@` terminator: the file looks truncated (read leniently to accept it)"
            ),
        ));
    }
    warnings.push(format!(
        "{file} line {start_line}: {message}; keeping the frames found"
    ));
    Ok(())
}

/// A cell or line shortened for an error message.
fn clip(text: &str) -> String {
    const MAX: usize = 40;
    if text.chars().count() <= MAX {
        text.to_owned()
    } else {
        let head: String = text.chars().take(MAX).collect();
        format!("{head}...")
    }
}

// ---------------------------------------------------------------------------------------------------------
// Writer

/// Writes a recording as a TekScan ASCII movie (LF line endings).
///
/// The header holds `DATA_TYPE MOVIE`, `ROWS`, `COLS`, `ROW_SPACING`/`COL_SPACING` in mm, `SENSOR_TYPE`,
/// `SECONDS_PER_FRAME`, `UNITS` (when `meta.units` states one), `NOISE_THRESHOLD`,
/// `SATURATION_PRESSURE` (from `full_scale`), `START_FRAME`/`END_FRAME` (the first and last frame numbers), then the entries of `meta.extra` that are
/// not already written, then `ASCII_DATA @@`. Absent sensels are written `B`; numbers are written so that
/// they read back bit-exactly. Reading the output with [`parse_tekscan`] gives back an equal recording.
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

#[cfg(test)]
mod tests {
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
            parsed.warnings[0].starts_with("t.asf line 3: ROW_SPACING"),
            "{:?}",
            parsed.warnings
        );
        assert!(parsed.warnings[3].contains("line 7") && parsed.warnings[3].contains("line 6"));
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
        let text =
            format!("{HEAD_2X3}Frame 1\n1,2,3\n4,5,6\nFrame 2\n7,8,9\n10,11\n12,13,14\n@@\n");
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
            msg.contains(
                "frame 2 (from line 12) is truncated: the file ends after 1 of 2 rows (ROWS)"
            ),
            "{msg}"
        );
        assert!(msg.contains("leniently"), "{msg}");
        let parsed = lenient(&text).unwrap();
        assert_eq!(parsed.recording.frame_count(), 1);
        assert_eq!(parsed.recording.data(), &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        assert_eq!(parsed.warnings.len(), 1, "{:?}", parsed.warnings);
        assert!(parsed.warnings[0].contains("frame 2") && parsed.warnings[0].contains("dropped"));

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
        assert!(parsed.warnings[0].contains("keeping the frames found"));
        // More frames than announced: a warning.
        let text = format!(
            "{HEAD_2X3}Frame 1\n1,2,3\n4,5,6\nFrame 2\n1,2,3\n4,5,6\nFrame 3\n1,2,3\n4,5,6\n"
        );
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
        assert!(msg.contains("expected frame data (2 rows of 2 values) after the header ending on line 3, found none"), "{msg}");
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
            msg.contains("frame 2 of the file cannot be numbered: START_FRAME 9223372036854775807 (line 3) + 1"),
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
            parsed.warnings[0].contains("18446744073709551614 frame numbers missing"),
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
        assert!(parsed.warnings[0].starts_with("t.asf line 8: frame 2 repeats frame 2"));
        // A jump (49 -> 150): read, with a warning naming the line and the numbers missing.
        let parsed = strict(&frames(&[48, 49, 150, 151])).unwrap();
        assert_eq!(parsed.recording.frame_count(), 4);
        assert_eq!(
            parsed.warnings,
            vec![
                "t.asf line 8: frame 150 follows frame 49: 100 frame numbers missing, so time is \
                 not contiguous here"
                    .to_owned()
            ]
        );
        let parsed = strict(&frames(&[1, 3])).unwrap();
        assert!(
            parsed.warnings[0].contains("1 frame number missing"),
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
            parsed.warnings[MAX_GAP_WARNINGS].starts_with(
                "t.asf: 14 more jumps in the frame numbers (from line 16), 28 frame numbers missing"
            ),
            "{:?}",
            parsed.warnings
        );
        // START/END disagreeing with a complete file (`@@`): reported too, also without START_FRAME.
        let text =
            frames(&[1, 2]).replace("ASCII_DATA", "START_FRAME 1\nEND_FRAME 5000\nASCII_DATA");
        let parsed = strict(&text).unwrap();
        assert_eq!(parsed.warnings.len(), 1, "{:?}", parsed.warnings);
        assert!(parsed.warnings[0].contains("announce 5000 frames, the file holds 2"));
        let text = frames(&[1, 2]).replace("ASCII_DATA", "END_FRAME 5000\nASCII_DATA");
        let parsed = strict(&text).unwrap();
        assert_eq!(
            parsed.warnings,
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
        let nan =
            Recording::new(grid, None, vec![1.0, f64::NAN], None, SensorMeta::default()).unwrap();
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
        assert!(
            err.to_string().starts_with("cannot read ") && err.to_string().contains("missing.asf")
        );
    }
}
