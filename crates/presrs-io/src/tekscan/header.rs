//! The header: `KEY value` lines up to `ASCII_DATA` (see the module documentation of
//! [`crate::tekscan`]).

use std::collections::HashMap;

use presrs_core::{Grid, PressureUnit, SensorMeta};

use super::lines::{frame_line, is_ascii_data};
use crate::error::IoError;
use crate::textutil::is_blank;

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

/// What the header says.
pub(super) struct Header {
    pub(super) grid: Grid,
    pub(super) period: Option<f64>,
    pub(super) meta: SensorMeta,
    pub(super) start_frame: Option<(usize, i64)>,
    pub(super) end_frame: Option<(usize, i64)>,
    /// Index into the file's lines of the first data line.
    pub(super) data_start: usize,
    /// Line number of the `ASCII_DATA` line (or of the last header line).
    pub(super) end_line: usize,
}

pub(super) fn parse_header(
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
