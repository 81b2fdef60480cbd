//! Incremental reading of a TekScan ASCII movie as it is written (stdin, a pipe, a growing file): one
//! frame at a time, nothing held but the current frame.
//!
//! The header is read up to `ASCII_DATA`; only `ROWS`, `COLS` (required) and `SECONDS_PER_FRAME` are
//! interpreted (the whole-file reader [`crate::tekscan`] keeps everything else; a live stream does not
//! need it). Then frames: a `Frame N` line followed by `ROWS` data lines of `COLS` cells (numbers or `B`
//! for no sensel), or, in files without `Frame` lines, every `ROWS` data lines. Blank and comma-only lines
//! are skipped; `@@` ends the stream.
//!
//! **Faults.** Lines are capped in length (a line without end cannot eat memory). A bad row (wrong cell
//! count, a cell that is not a number or `B`) is an error naming the line, frame, row and column; the
//! reader then skips to the next `Frame` line, so the stream can go on ([`TekscanStream::next_frame`]
//! can be called again). The end of the input inside a frame is an error too.

use std::io::{BufRead, Read};

use presrs_core::Grid;

use crate::error::IoError;
use crate::textutil::{Cell, is_blank, parse_cell};

/// Longest header line accepted, bytes.
const MAX_HEADER_LINE: usize = 64 * 1024;
/// Header lines accepted before `ASCII_DATA`.
const MAX_HEADER_LINES: usize = 10_000;
/// Largest grid accepted (sensels).
pub const MAX_STREAM_SENSELS: usize = 1 << 20;

/// What the header says.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StreamHeader {
    pub grid: Grid,
    pub period_s: Option<f64>,
}

/// A frame read by [`TekscanStream::next_frame`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StreamFrame {
    /// The number on its `Frame` line (or counted from 1 without `Frame` lines).
    pub number: i64,
    /// Line of its first row.
    pub line: usize,
    /// Whether some sensel is `B` (absent): the mask is meaningful.
    pub has_absent: bool,
}

/// Reads a TekScan ASCII movie frame by frame (see the module docs).
#[derive(Debug)]
pub struct TekscanStream<R> {
    reader: R,
    source_name: String,
    line_no: usize,
    line: Vec<u8>,
    header: Option<StreamHeader>,
    pending_frame: Option<(i64, usize)>,
    counted: i64,
    resync: bool,
    ended: bool,
}

impl<R: BufRead> TekscanStream<R> {
    pub fn new(reader: R, source_name: &str) -> Self {
        Self {
            reader,
            source_name: source_name.to_owned(),
            line_no: 0,
            line: Vec::new(),
            header: None,
            pending_frame: None,
            counted: 0,
            resync: false,
            ended: false,
        }
    }

    pub fn header(&self) -> Option<StreamHeader> {
        self.header
    }

    /// Reads the next line (without its end) into `self.line`; false at the end of the input. Capped at
    /// `limit` bytes; must be UTF-8.
    fn next_line(&mut self, limit: usize) -> Result<bool, IoError> {
        self.line.clear();
        let mut take = Read::take(&mut self.reader, limit as u64 + 1);
        let n = take
            .read_until(b'\n', &mut self.line)
            .map_err(|err| IoError::format(&self.source_name, format!("cannot read: {err}")))?;
        if n == 0 {
            return Ok(false);
        }
        self.line_no += 1;
        if self.line.len() > limit && self.line.last() != Some(&b'\n') {
            return Err(IoError::parse(
                &self.source_name,
                self.line_no,
                format!("line longer than {limit} bytes"),
            ));
        }
        while matches!(self.line.last(), Some(b'\n' | b'\r')) {
            self.line.pop();
        }
        if std::str::from_utf8(&self.line).is_err() {
            return Err(IoError::parse(
                &self.source_name,
                self.line_no,
                "not UTF-8 / ASCII text",
            ));
        }
        Ok(true)
    }

    /// Reads the header (up to `ASCII_DATA`). Called by [`Self::next_frame`] if needed.
    pub fn read_header(&mut self) -> Result<StreamHeader, IoError> {
        if let Some(header) = self.header {
            return Ok(header);
        }
        let (mut rows, mut cols, mut period) = (None, None, None);
        let name = self.source_name.clone();
        for _ in 0..MAX_HEADER_LINES {
            let line_no = self.line_no + 1;
            let line = if self.next_line(MAX_HEADER_LINE)? {
                std::str::from_utf8(&self.line).unwrap_or("")
            } else {
                return Err(IoError::parse(
                    &name,
                    line_no,
                    "the stream ended before `ASCII_DATA` (no TekScan header)",
                ));
            };
            let mut tokens = line.split_whitespace();
            let key = tokens
                .next()
                .unwrap_or("")
                .trim_end_matches(':')
                .to_ascii_uppercase();
            let value = tokens.next().unwrap_or("");
            let dim = |what: &str| -> Result<usize, IoError> {
                value
                    .parse::<usize>()
                    .ok()
                    .filter(|&v| v > 0)
                    .ok_or_else(|| {
                        IoError::parse(
                            &name,
                            line_no,
                            format!("{what} must be a positive integer, found `{value}`"),
                        )
                    })
            };
            match key.as_str() {
                "ROWS" => rows = Some(dim("ROWS")?),
                "COLS" => cols = Some(dim("COLS")?),
                "SECONDS_PER_FRAME" => {
                    period = value
                        .parse::<f64>()
                        .ok()
                        .filter(|p| p.is_finite() && *p > 0.0);
                }
                "ASCII_DATA" => {
                    let (Some(rows), Some(cols)) = (rows, cols) else {
                        return Err(IoError::parse(
                            &name,
                            line_no,
                            "`ASCII_DATA` before `ROWS` and `COLS`: the frame size is unknown",
                        ));
                    };
                    if rows.saturating_mul(cols) > MAX_STREAM_SENSELS {
                        return Err(IoError::parse(
                            &name,
                            line_no,
                            format!(
                                "{rows}x{cols} frames exceed the limit of {MAX_STREAM_SENSELS} sensels"
                            ),
                        ));
                    }
                    let header = StreamHeader {
                        grid: Grid::new(rows, cols),
                        period_s: period,
                    };
                    self.header = Some(header);
                    return Ok(header);
                }
                _ => {}
            }
        }
        Err(IoError::parse(
            &name,
            self.line_no,
            format!("no `ASCII_DATA` line within the first {MAX_HEADER_LINES} lines"),
        ))
    }

    /// Reads the next frame into `values` and `present` (resized to the grid, allocations reused).
    /// `Ok(None)` at the end of the stream (`@@` or end of input between frames). After an error the
    /// reader skips to the next `Frame` line; calling again continues from there.
    pub fn next_frame(
        &mut self,
        values: &mut Vec<f64>,
        present: &mut Vec<bool>,
    ) -> Result<Option<StreamFrame>, IoError> {
        let header = self.read_header()?;
        if self.ended {
            return Ok(None);
        }
        let Grid { rows, cols } = header.grid;
        let limit = cols.saturating_mul(64).max(1024);
        let name = self.source_name.clone();
        values.clear();
        present.clear();
        let mut has_absent = false;
        let mut row = 0;
        let mut current = self.pending_frame.take();
        loop {
            if !self.next_line(limit)? {
                self.ended = true;
                if row == 0 {
                    return Ok(None);
                }
                let (number, _) = current.unwrap_or((self.counted, 0));
                return Err(IoError::parse(
                    &name,
                    self.line_no,
                    format!("the stream ended inside frame {number} ({row} of {rows} rows)"),
                ));
            }
            let line = std::str::from_utf8(&self.line).unwrap_or("").trim();
            if is_blank(line) {
                continue;
            }
            if line == "@@" {
                self.ended = true;
                if row == 0 {
                    return Ok(None);
                }
                return Err(IoError::parse(
                    &name,
                    self.line_no,
                    format!("`@@` inside a frame ({row} of {rows} rows)"),
                ));
            }
            if let Some(number) = frame_number(line) {
                self.resync = false;
                let line_no = self.line_no;
                if row > 0 {
                    // The previous frame was short; this line starts the next one.
                    self.pending_frame = Some((number, line_no));
                    let (prev, _) = current.unwrap_or((self.counted, 0));
                    return Err(IoError::parse(
                        &name,
                        line_no,
                        format!("frame {prev} has {row} rows, expected {rows} (ROWS)"),
                    ));
                }
                current = Some((number, line_no));
                continue;
            }
            if self.resync {
                continue;
            }
            // A data row. Lines borrowed from self.line: parse it now.
            let line_no = self.line_no;
            if row == 0 && current.is_none() {
                self.counted += 1;
                current = Some((self.counted, line_no));
            }
            let number = current.map_or(self.counted, |c| c.0);
            let bad = |message: String| IoError::parse(&name, line_no, message);
            let start_len = values.len();
            let mut cell_error = None;
            let split = for_each_cell(line, |c, cell| {
                if c >= cols {
                    return false;
                }
                match parse_cell(cell) {
                    Ok(Cell::Value(v)) => {
                        values.push(v);
                        present.push(true);
                    }
                    Ok(Cell::Absent) => {
                        values.push(0.0);
                        present.push(false);
                        has_absent = true;
                    }
                    Err(err) => {
                        cell_error = Some(format!(
                            "frame {number} row {} column {}: `{cell}`: {}",
                            row + 1,
                            c + 1,
                            err.expected(true)
                        ));
                        return false;
                    }
                }
                true
            });
            let result = match (split, cell_error) {
                (_, Some(message)) => Err(bad(message)),
                (Err(at), None) => Err(bad(format!(
                    "frame {number} row {} column {} is empty",
                    row + 1,
                    at + 1
                ))),
                (Ok(count), None) if count != cols => Err(bad(format!(
                    "frame {number} row {} has {count} values, expected {cols} (COLS)",
                    row + 1
                ))),
                (Ok(_), None) => Ok(()),
            };
            if let Err(err) = result {
                values.truncate(start_len);
                present.truncate(start_len);
                self.resync = true;
                return Err(err);
            }
            row += 1;
            if row == rows {
                let (number, first) = current.unwrap_or((self.counted, line_no));
                return Ok(Some(StreamFrame {
                    number,
                    line: first,
                    has_absent,
                }));
            }
        }
    }
}

/// Calls `visit(index, cell)` for each cell of a data line, split as [`crate::textutil`] splits them
/// (commas and whitespace separate cells, trailing commas allowed) until `visit` returns false. Returns
/// the number of cells (counting on past a stop), or `Err(k)` when cell `k` is empty between two commas.
fn for_each_cell(line: &str, mut visit: impl FnMut(usize, &str) -> bool) -> Result<usize, usize> {
    let line = line.trim();
    let mut count = 0;
    let mut go = true;
    let mut cell = |c: &str, count: &mut usize| {
        if go {
            go = visit(*count, c);
        }
        *count += 1;
    };
    if !line.contains(',') {
        for c in line.split_whitespace() {
            cell(c, &mut count);
        }
        return Ok(count);
    }
    let line = line.trim_end_matches(|c: char| c == ',' || c.is_whitespace());
    for piece in line.split(',') {
        let piece = piece.trim();
        if piece.is_empty() {
            return Err(count);
        }
        for c in piece.split_whitespace() {
            cell(c, &mut count);
        }
    }
    Ok(count)
}

/// `Frame 12...` -> 12.
fn frame_number(line: &str) -> Option<i64> {
    let head = line.get(..5)?;
    if !head.eq_ignore_ascii_case("frame") {
        return None;
    }
    let rest = line[5..].trim_start();
    let end = rest
        .char_indices()
        .find(|&(i, c)| !(c.is_ascii_digit() || (i == 0 && c == '-')))
        .map_or(rest.len(), |(i, _)| i);
    rest[..end].parse().ok()
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    const MOVIE: &str = "DATA_TYPE MOVIE\nROWS 2\nCOLS 3\nSECONDS_PER_FRAME 0.01\nASCII_DATA @@\n\n\
        Frame 1\n0,1,2\n3,4,5\n\nFrame 2\nB,1,2\n3,4,5\n@@\n";

    #[test]
    fn reads_frames_one_by_one() {
        let mut stream = TekscanStream::new(MOVIE.as_bytes(), "stdin");
        let (mut values, mut present) = (Vec::new(), Vec::new());
        let f = stream
            .next_frame(&mut values, &mut present)
            .unwrap()
            .unwrap();
        assert_eq!((f.number, f.has_absent), (1, false));
        assert_eq!(values, [0.0, 1.0, 2.0, 3.0, 4.0, 5.0]);
        assert_eq!(
            stream.header().unwrap(),
            StreamHeader {
                grid: Grid::new(2, 3),
                period_s: Some(0.01)
            }
        );
        let f = stream
            .next_frame(&mut values, &mut present)
            .unwrap()
            .unwrap();
        assert_eq!((f.number, f.has_absent), (2, true));
        assert!(!present[0]);
        assert!(
            stream
                .next_frame(&mut values, &mut present)
                .unwrap()
                .is_none()
        );
    }

    #[test]
    fn bad_rows_are_errors_and_the_stream_resyncs() {
        let text = "ROWS 2\nCOLS 3\nASCII_DATA @@\nFrame 1\n0,1\n3,4,5\nFrame 2\n0,1,x\n0,0,0\n\
            Frame 3\n1,1,1\n1,1,1\nFrame 4\n1,1,1\n";
        let mut stream = TekscanStream::new(text.as_bytes(), "stdin");
        let (mut values, mut present) = (Vec::new(), Vec::new());
        let err = stream.next_frame(&mut values, &mut present).unwrap_err();
        assert!(
            err.to_string()
                .contains("line 5: frame 1 row 1 has 2 values, expected 3"),
            "{err}"
        );
        let err = stream.next_frame(&mut values, &mut present).unwrap_err();
        assert!(
            err.to_string().contains("frame 2 row 1 column 3: `x`"),
            "{err}"
        );
        let f = stream
            .next_frame(&mut values, &mut present)
            .unwrap()
            .unwrap();
        assert_eq!(f.number, 3);
        let err = stream.next_frame(&mut values, &mut present).unwrap_err();
        assert!(
            err.to_string()
                .contains("ended inside frame 4 (1 of 2 rows)"),
            "{err}"
        );
        assert!(
            stream
                .next_frame(&mut values, &mut present)
                .unwrap()
                .is_none()
        );
    }

    #[test]
    fn header_faults() {
        let (mut values, mut present) = (Vec::new(), Vec::new());
        let err = TekscanStream::new("ROWS 2\nASCII_DATA\n".as_bytes(), "s")
            .next_frame(&mut values, &mut present)
            .unwrap_err();
        assert!(
            err.to_string().contains("before `ROWS` and `COLS`"),
            "{err}"
        );
        let err = TekscanStream::new("ROWS 2\n".as_bytes(), "s")
            .next_frame(&mut values, &mut present)
            .unwrap_err();
        assert!(
            err.to_string().contains("ended before `ASCII_DATA`"),
            "{err}"
        );
        let long = format!("ROWS 2\nCOLS 2\nASCII_DATA\n{}\n", "1,".repeat(5000));
        let err = TekscanStream::new(long.as_bytes(), "s")
            .next_frame(&mut values, &mut present)
            .unwrap_err();
        assert!(err.to_string().contains("longer than"), "{err}");
    }
}
