//! TekScan ASCII movies and snapshots (`.asf`, sometimes `.csv`): reader, stream reader and writer.
//!
//! One parser reads both a live stream and a whole file: [`TekscanStream`] (`stream.rs`) reads a
//! text one frame at a time, with the header read line by line (`header.rs`), rows parsed by
//! `rows.rs` and lines by `line_reader.rs`; [`parse_tekscan`] (`file.rs`) drives it over a file's text,
//! stopping at the first fault, and collects its frames into a [`Recording`] with the checks only a
//! whole file allows (frame numbers, truncation, the announced frame count). A fault in the frames is
//! one type (`fault.rs`) worded for either reader; the stream's module docs list what a stream and a
//! file treat differently.
//!
//! See `docs/tekscan-ascii.md` for the format. What this module does where the format notes are
//! silent:
//!
//! * **Header.** Lines up to `ASCII_DATA` (found by search) are `KEY value` lines; the key is the first
//!   token, an upper-case identifier as TekScan writes them, with a trailing `:` ignored (`ROWS: 44`
//!   works). A line whose first token is not an upper-case identifier (`overground walk p10`, `Rows 3 were
//!   damaged`), and the line right after a bare `KEY:` line such as `COMMENTS:` (unless it is a plausible
//!   known key line such as `ROWS 44`), is free text: it is kept in [`SensorMeta::extra`](presrs_core::SensorMeta::extra) as the whole line
//!   with an empty value. Blank lines in the header are skipped. If the file has no `ASCII_DATA` line but
//!   a `Frame N` line follows the header, the header ends there.
//! * **Typed keys.** `ROWS`/`COLS` (required, positive integers) give the grid; `SENSOR_TYPE`,
//!   `ROW_SPACING`/`COL_SPACING` (converted to mm from `mm`/`millimeters`/`cm`/`inches`/...), `UNITS`,
//!   `NOISE_THRESHOLD`, `SECONDS_PER_FRAME` and `SATURATION_PRESSURE` (as `full_scale`, when its unit is
//!   `UNITS` or convertible to it) fill [`SensorMeta`](presrs_core::SensorMeta) and the frame period. A typed value that cannot be
//!   understood (`ROW_SPACING 5 furlongs`, `SECONDS_PER_FRAME 0`) is kept verbatim in `extra` and
//!   reported as a warning; nothing is lost. `DATA_TYPE`, `START_FRAME`, `END_FRAME` and `ASCII_DATA` are
//!   structural: they are checked but not kept (the writer derives them). Every other key is kept verbatim,
//!   in file order, in `extra`. A repeated typed key keeps the first value (a conflicting repeated
//!   `ROWS`/`COLS` is an error) and is reported as a warning.
//! * **Frames.** Frame numbers and `Frame` line suffixes are kept as written in [`FrameInfo`](presrs_core::FrameInfo). Files
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

mod fault;
mod file;
mod header;
mod line_reader;
mod lines;
mod rows;
mod stream;
#[cfg(test)]
mod tests;
mod write;

use std::path::Path;

use presrs_core::Recording;

use crate::error::{IoError, display_name};
use crate::textutil::{decode_text, numbered_lines};
use crate::{Parsed, ReadOptions};

pub use self::stream::{MAX_STREAM_SENSELS, StreamFrame, StreamHeader, TekscanStream};
pub use self::write::{write_tekscan, write_tekscan_file};

/// The result of parsing a TekScan file: the recording and any warnings (see [`Parsed`]).
pub type ParsedTekscan = Parsed;

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
    file::parse_file(text, source_name, options)
}
