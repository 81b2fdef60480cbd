//! The header: `KEY value` lines up to `ASCII_DATA` (see the module documentation of
//! [`crate::tekscan`]), read one line at a time by both the stream and the whole-file reader.

use std::collections::HashMap;

use presrs_core::{Grid, PressureUnit, SensorMeta};

use super::lines::{clip, frame_line, is_ascii_data};
use crate::error::IoError;
use crate::message::Warnings;
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
#[derive(Clone, Debug)]
pub(super) struct Header {
    pub(super) grid: Grid,
    pub(super) period: Option<f64>,
    pub(super) meta: SensorMeta,
    pub(super) start_frame: Option<(usize, i64)>,
    pub(super) end_frame: Option<(usize, i64)>,
    /// Line number of the `ASCII_DATA` line (or of the `Frame` line that ended the header).
    pub(super) end_line: usize,
}

/// Where the header ends.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum HeaderEnd {
    /// On an `ASCII_DATA` line: the data starts on the next line.
    AsciiData,
    /// On a `Frame N` line (a file without `ASCII_DATA`): the data starts on this line.
    FrameLine,
}

/// Where the header reader is: a small state machine over the lines up to `ASCII_DATA`.
#[derive(Clone, Copy, PartialEq)]
enum State {
    /// Reading `KEY value` lines.
    Keys,
    /// On the line right after a bare `KEY:` label such as `COMMENTS:`: free text, unless it is a
    /// plausible known key line (`ROWS 44`).
    AfterLabel,
}

/// Reads the header one line at a time ([`Self::line`]), then [`Self::finish`] gives what it says.
pub(super) struct HeaderReader<'a> {
    file: &'a str,
    warnings: &'a mut Warnings,
    state: State,
    meta: SensorMeta,
    rows: Option<usize>,
    cols: Option<usize>,
    period: Option<f64>,
    start_frame: Option<(usize, i64)>,
    end_frame: Option<(usize, i64)>,
    /// (value, position in `extra` where it belongs if it stays verbatim): whether it becomes
    /// `full_scale` depends on `UNITS`, which may come later.
    saturation: Option<(String, usize)>,
    /// The line of each known key's first occurrence.
    seen: HashMap<String, usize>,
    /// A `Frame N` line ends the header only in files without an `ASCII_DATA` line (so that a comment
    /// such as `Frame 3 was bad` in a normal header is kept as text); only a reader of the whole
    /// file knows that in advance.
    frame_line_ends: bool,
}

/// The input ended without an `ASCII_DATA` line (nor a `Frame N` line in a file without one); its
/// last line is `last_line`.
pub(super) fn no_ascii_data(file: &str, last_line: usize) -> IoError {
    IoError::parse(
        file,
        last_line.max(1),
        "the input ended before `ASCII_DATA`: expected an `ASCII_DATA` line ending the TekScan \
         header (is this a TekScan ASCII export?)",
    )
}

impl<'a> HeaderReader<'a> {
    /// A reader for the header of `file`; `frame_line_ends`: a `Frame N` line ends the header (the
    /// file has no `ASCII_DATA` line).
    pub(super) fn new(file: &'a str, frame_line_ends: bool, warnings: &'a mut Warnings) -> Self {
        Self {
            file,
            warnings,
            state: State::Keys,
            meta: SensorMeta::default(),
            rows: None,
            cols: None,
            period: None,
            start_frame: None,
            end_frame: None,
            saturation: None,
            seen: HashMap::new(),
            frame_line_ends,
        }
    }

    /// Reads line `line_no`; `Some(end)` when the header ends there (then call [`Self::finish`]).
    pub(super) fn line(&mut self, line_no: usize, raw: &str) -> Result<Option<HeaderEnd>, IoError> {
        let line = raw.trim();
        let token = line.split_whitespace().next().unwrap_or("");
        self.state = if is_blank(line) {
            State::Keys // a label's text is the line right after it, not the next non-blank one
        } else if is_ascii_data(token) {
            return Ok(Some(HeaderEnd::AsciiData));
        } else if self.frame_line_ends && frame_line(line).is_some() {
            return Ok(Some(HeaderEnd::FrameLine));
        } else {
            self.key_line(self.state, line_no, line, token)?
        };
        Ok(None)
    }

    /// A non-blank line starting with `token`: free text, another key, a repeated known key or a
    /// known key's first occurrence.
    fn key_line(
        &mut self,
        state: State,
        line_no: usize,
        line: &str,
        token: &str,
    ) -> Result<State, IoError> {
        let key = token.trim_end_matches(':');
        let value = line[token.len()..].trim();
        let after_label = state == State::AfterLabel;
        let key_like = looks_like_key(token);
        // After a `COMMENTS:` label, a known key counts only if its value makes sense for it.
        let known =
            key_like && KNOWN_KEYS.contains(&key) && (!after_label || plausible_value(key, value));
        if !known && (after_label || !key_like) {
            return Ok(self.free_text(line));
        }
        if !known {
            self.other_key(token, value);
        } else if let Some(&first) = self.seen.get(key) {
            self.repeated_key(key, value, line_no, first)?;
        } else {
            self.seen.insert(key.to_owned(), line_no);
            self.typed_key(key, token, value, line_no)?;
        }
        Ok(if token.ends_with(':') && value.is_empty() {
            State::AfterLabel
        } else {
            State::Keys
        })
    }

    /// A line that is not a `KEY value` line: kept whole, with an empty value.
    fn free_text(&mut self, line: &str) -> State {
        self.meta.extra.push((line.to_owned(), String::new()));
        State::Keys
    }

    /// A key this module does not interpret: kept verbatim, in file order.
    fn other_key(&mut self, token: &str, value: &str) {
        self.meta.extra.push((token.to_owned(), value.to_owned()));
    }

    /// A known key already seen on line `first`: ignored with a warning, except that a ROWS or COLS
    /// contradicting the first is an error (which grid would be right?).
    fn repeated_key(
        &mut self,
        key: &str,
        value: &str,
        line_no: usize,
        first: usize,
    ) -> Result<(), IoError> {
        let previous = match key {
            "ROWS" => self.rows,
            "COLS" => self.cols,
            _ => {
                let file = self.file;
                self.warnings.push(format!(
                    "{file} line {line_no}: repeated {key} ignored, keeping the value of line {first}"
                ));
                return Ok(());
            }
        };
        let now = parse_dim(key, value, self.file, line_no)?;
        if previous != Some(now) {
            return Err(IoError::parse(
                self.file,
                line_no,
                format!(
                    "{key} {now} contradicts {key} {} on line {first}",
                    previous.unwrap_or(0)
                ),
            ));
        }
        Ok(())
    }

    /// The first occurrence of a known key: structural keys are checked, the others fill the header.
    fn typed_key(
        &mut self,
        key: &str,
        token: &str,
        value: &str,
        line_no: usize,
    ) -> Result<(), IoError> {
        let file = self.file;
        match key {
            "DATA_TYPE" => {}
            "ROWS" => self.rows = Some(parse_dim(key, value, file, line_no)?),
            "COLS" => self.cols = Some(parse_dim(key, value, file, line_no)?),
            "START_FRAME" => {
                self.start_frame = Some((line_no, parse_frame_number(key, value, file, line_no)?));
            }
            "END_FRAME" => {
                self.end_frame = Some((line_no, parse_frame_number(key, value, file, line_no)?));
            }
            "SENSOR_TYPE" => self.meta.sensor = (!value.is_empty()).then(|| value.to_owned()),
            "UNITS" => self.meta.units = Some(PressureUnit::parse(value)),
            "SATURATION_PRESSURE" => {
                self.saturation = Some((value.to_owned(), self.meta.extra.len()));
            }
            "ROW_SPACING" | "COL_SPACING" | "SECONDS_PER_FRAME" | "NOISE_THRESHOLD" => {
                self.measure(key, token, value, line_no);
            }
            _ => self.meta.extra.push((token.to_owned(), value.to_owned())),
        }
        Ok(())
    }

    /// A spacing, the frame period or the noise threshold: a value not understood is kept verbatim
    /// with a warning rather than failing the file.
    fn measure(&mut self, key: &str, token: &str, value: &str, line_no: usize) {
        const LENGTH: &str = "expected a positive length with a unit (mm, cm or inches)";
        let number = value.parse::<f64>().ok().filter(|n| n.is_finite());
        let (slot, parsed, expected) = match key {
            "ROW_SPACING" => (&mut self.meta.row_pitch_mm, parse_length_mm(value), LENGTH),
            "COL_SPACING" => (&mut self.meta.col_pitch_mm, parse_length_mm(value), LENGTH),
            "SECONDS_PER_FRAME" => (
                &mut self.period,
                number.filter(|&p| p > 0.0),
                "expected a positive number of seconds; the frame period is unknown",
            ),
            _ => (&mut self.meta.noise_threshold, number, "expected a number"),
        };
        match parsed {
            Some(parsed) => *slot = Some(parsed),
            None => {
                let file = self.file;
                self.warnings.push(format!(
                    "{file} line {line_no}: {token} `{value}` not understood ({expected}); kept verbatim"
                ));
                self.meta.extra.push((token.to_owned(), value.to_owned()));
            }
        }
    }

    /// The header ended on line `end_line` (`ended_by` says how): ROWS and COLS must have been given,
    /// and SATURATION_PRESSURE can now be read in the final UNITS.
    pub(super) fn finish(mut self, end_line: usize, ended_by: &str) -> Result<Header, IoError> {
        let grid = self.grid(end_line, ended_by)?;
        self.place_saturation();
        Ok(Header {
            grid,
            period: self.period,
            meta: self.meta,
            start_frame: self.start_frame,
            end_frame: self.end_frame,
            end_line,
        })
    }

    /// `ROWS x COLS`, both required (the error names the ones missing), the product within `usize`.
    fn grid(&self, end_line: usize, ended_by: &str) -> Result<Grid, IoError> {
        let (rows, cols) = match (self.rows, self.cols) {
            (Some(r), Some(c)) => (r, c),
            (r, c) => {
                let missing: Vec<&str> = [("ROWS", r.is_none()), ("COLS", c.is_none())]
                    .into_iter()
                    .filter_map(|(k, missing)| missing.then_some(k))
                    .collect();
                return Err(IoError::parse(
                    self.file,
                    end_line,
                    format!(
                        "the header has no {} line; expected `ROWS <n>` and `COLS <n>` before the data \
                         (`{}` before `ROWS` and `COLS`: the frame size is unknown)",
                        missing.join(" or "),
                        clip(ended_by)
                    ),
                ));
            }
        };
        if rows.checked_mul(cols).is_none() {
            return Err(IoError::parse(
                self.file,
                end_line,
                format!("ROWS {rows} x COLS {cols} is too large"),
            ));
        }
        Ok(Grid::new(rows, cols))
    }

    /// SATURATION_PRESSURE as `full_scale`, or verbatim at its place in `extra` when it is not
    /// expressible in the recording's units (e.g. kPa for a raw export).
    fn place_saturation(&mut self) {
        let Some((value, at)) = self.saturation.take() else {
            return;
        };
        match saturation_in_units(&value, self.meta.units_or_raw()) {
            Some(full_scale) => self.meta.full_scale = Some(full_scale),
            None => self.meta.extra.insert(
                at.min(self.meta.extra.len()),
                ("SATURATION_PRESSURE".to_owned(), value),
            ),
        }
    }
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
