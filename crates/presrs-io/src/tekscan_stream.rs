//! Incremental reading of a TekScan ASCII movie as it is written (stdin, a pipe, a growing file): one
//! frame at a time, nothing held but the current frame.
//!
//! The header is read up to `ASCII_DATA`; only `ROWS`, `COLS` (required) and `SECONDS_PER_FRAME` are
//! interpreted (the whole-file reader [`crate::tekscan`] keeps everything else; a live stream does not
//! need it). Then frames: a `Frame N` line followed by `ROWS` data lines of `COLS` cells (numbers or `B`
//! for no sensel), or, in files without `Frame` lines, every `ROWS` data lines. `Frame` lines are read
//! as the whole-file reader reads them (`Frame 12, timestamp 728`, `Frame -2`, `Frame +3`; `Frame12` is
//! not a `Frame` line). Blank and comma-only lines are skipped; `@@` ends a recording.
//!
//! **Recordings one after another** (`cat a.asf b.asf | presrs stream`): after `@@`, or where a
//! `DATA_TYPE` line comes instead of the next frame, another header may follow. When its frames have the
//! same size the stream goes on with them; otherwise that is an error and the stream stops
//! ([`TekscanStream::stopped`]): one stream carries frames of one size.
//!
//! **Faults.** Lines are capped in length (a line without end cannot eat memory). Each fault is an error
//! naming the line (and the frame, row and column when there are some), after which the stream can go
//! on ([`TekscanStream::next_frame`] can be called again):
//!
//! * a bad row (wrong cell count, a cell that is not a number or `B`, a line too long or not UTF-8)
//!   drops its frame. With `Frame` lines the reader then skips to the next `Frame` line; without them
//!   it skips the remaining rows of that frame, so that the next frame starts where it should;
//! * a frame with fewer than `ROWS` rows (none at all included) before the next `Frame` line, `@@` or
//!   the end of the input is an error, as in the whole-file reader; the next `Frame` line starts the
//!   next frame;
//! * a malformed `Frame` line (`Frame x`) is an error, and its rows are skipped;
//! * in a stream with `Frame` lines, a data row after a complete frame and before the next `Frame`
//!   line is an error, and the reader skips to the next `Frame` line.
//!
//! A `Frame` line is always taken as the start of a frame, even in a stream that had none so far.
//! Frame numbers are reported as written ([`StreamFrame::number`]); gaps are not checked here.

use std::io::{BufRead, Read};

use presrs_core::Grid;

use crate::error::IoError;
use crate::tekscan::frame_line;
use crate::textutil::{is_blank, parse_cell};

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
    /// Line of its `Frame` line (of its first row without `Frame` lines).
    pub line: usize,
    /// Whether some sensel is `B` (absent): the mask is meaningful.
    pub has_absent: bool,
}

/// The frame [`TekscanStream::next_frame`] is reading.
struct FrameInProgress {
    /// Rows read so far.
    row: usize,
    /// Whether some sensel read so far is absent.
    has_absent: bool,
    /// The frame, once its `Frame` line or first row is read: (number, line).
    current: Option<(i64, usize)>,
}

/// What [`TekscanStream::next_frame`] does after one line.
enum LineOutcome {
    /// Read the next line.
    NextLine,
    /// The line is a data row (or cannot be read as any other line).
    DataRow,
    /// Return this: a complete frame, or `None` at the end of the stream.
    Finished(Option<StreamFrame>),
}

/// What [`TekscanStream::next_line`] read.
enum Line {
    /// The end of the input.
    End,
    /// A line of text, in `self.line`.
    Text,
    /// A line that cannot be read as text (too long, not UTF-8): why. It counts as a line.
    Bad(String),
}

/// Reads a TekScan ASCII movie frame by frame (see the module docs).
#[derive(Debug)]
pub struct TekscanStream<R> {
    reader: R,
    source_name: String,
    line_no: usize,
    line: Vec<u8>,
    header: Option<StreamHeader>,
    /// A `Frame` line read while the frame before it was reported short: (number, line).
    pending_frame: Option<(i64, usize)>,
    /// Frames counted in a stream without `Frame` lines.
    counted: i64,
    /// Whether frames start with `Frame` lines (known from the first `Frame` line or data row).
    framed: Option<bool>,
    /// After a fault in a stream with `Frame` lines: skip data rows until the next `Frame` line.
    resync: bool,
    /// After a fault in a stream without `Frame` lines: rows of the broken frame still to skip.
    skip_rows: usize,
    /// The rest of an over-long line is still to be read and dropped.
    discard_line: bool,
    /// The line in `self.line` is to be read again (the first line of a following recording's header).
    replay_line: bool,
    ended: bool,
    /// The stream stopped on an error it cannot go on from (a following recording of another size).
    stopped: bool,
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
            framed: None,
            resync: false,
            skip_rows: 0,
            discard_line: false,
            replay_line: false,
            ended: false,
            stopped: false,
        }
    }

    /// Whether the stream stopped on an error it cannot go on from: the header of a following
    /// recording was unreadable or gave another frame size. Later calls give `Ok(None)`.
    pub fn stopped(&self) -> bool {
        self.stopped
    }

    pub fn header(&self) -> Option<StreamHeader> {
        self.header
    }

    fn read_error(&self, err: &std::io::Error) -> IoError {
        IoError::format(&self.source_name, format!("cannot read: {err}"))
    }

    /// Reads the next line (without its end) into `self.line`. Capped at `limit` bytes (the rest of a
    /// longer line is dropped before the next line is read); must be UTF-8. An error only when the
    /// input cannot be read.
    fn next_line(&mut self, limit: usize) -> Result<Line, IoError> {
        if std::mem::take(&mut self.replay_line) {
            self.line_no += 1;
            return Ok(Line::Text);
        }
        if self.discard_line {
            self.discard_rest_of_line()?;
        }
        self.line.clear();
        let mut take = Read::take(&mut self.reader, limit as u64 + 1);
        let n = take
            .read_until(b'\n', &mut self.line)
            .map_err(|err| self.read_error(&err))?;
        if n == 0 {
            return Ok(Line::End);
        }
        self.line_no += 1;
        if self.line.len() > limit && self.line.last() != Some(&b'\n') {
            self.discard_line = true;
            return Ok(Line::Bad(format!("line longer than {limit} bytes")));
        }
        while matches!(self.line.last(), Some(b'\n' | b'\r')) {
            self.line.pop();
        }
        if std::str::from_utf8(&self.line).is_err() {
            return Ok(Line::Bad("not UTF-8 / ASCII text".to_owned()));
        }
        Ok(Line::Text)
    }

    /// Reads and drops input up to and including the next line end (or to the end of the input).
    fn discard_rest_of_line(&mut self) -> Result<(), IoError> {
        loop {
            let (used, done) = match self.reader.fill_buf() {
                Ok([]) => (0, true),
                Ok(buf) => match buf.iter().position(|&b| b == b'\n') {
                    Some(at) => (at + 1, true),
                    None => (buf.len(), false),
                },
                Err(err) if err.kind() == std::io::ErrorKind::Interrupted => (0, false),
                Err(err) => return Err(self.read_error(&err)),
            };
            self.reader.consume(used);
            if done {
                break;
            }
        }
        self.discard_line = false;
        Ok(())
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
            let line = match self.next_line(MAX_HEADER_LINE)? {
                Line::Text => std::str::from_utf8(&self.line).unwrap_or(""),
                Line::Bad(message) => return Err(IoError::parse(&name, line_no, message)),
                Line::End => {
                    return Err(IoError::parse(
                        &name,
                        line_no,
                        "the stream ended before `ASCII_DATA` (no TekScan header)",
                    ));
                }
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
    /// reader skips what is left of the broken frame (see the module docs); calling again continues
    /// with the next frame.
    pub fn next_frame(
        &mut self,
        values: &mut Vec<f64>,
        present: &mut Vec<bool>,
    ) -> Result<Option<StreamFrame>, IoError> {
        let header = self.read_header()?;
        if self.ended {
            return Ok(None);
        }
        let limit = header.grid.cols.saturating_mul(64).max(1024);
        values.clear();
        present.clear();
        let mut frame = FrameInProgress {
            row: 0,
            has_absent: false,
            current: self.pending_frame.take(),
        };
        loop {
            let unreadable = match self.next_line(limit)? {
                Line::End => return self.end_of_input(&frame, header.grid.rows),
                Line::Text => None,
                Line::Bad(message) => Some(message),
            };
            if unreadable.is_none() {
                match self.structure_line(header.grid, &mut frame)? {
                    LineOutcome::NextLine => continue,
                    LineOutcome::Finished(done) => return Ok(done),
                    LineOutcome::DataRow => {}
                }
            }
            match self.data_row(unreadable, header.grid, &mut frame, values, present)? {
                LineOutcome::Finished(done) => return Ok(done),
                LineOutcome::NextLine | LineOutcome::DataRow => {}
            }
        }
    }

    /// The input ended: the end of the stream between frames, an error inside one.
    fn end_of_input(
        &mut self,
        frame: &FrameInProgress,
        rows: usize,
    ) -> Result<Option<StreamFrame>, IoError> {
        self.ended = true;
        let Some((number, _)) = frame.current else {
            return Ok(None);
        };
        Err(IoError::parse(
            &self.source_name,
            self.line_no,
            format!(
                "the stream ended inside frame {number} ({} of {rows} rows)",
                frame.row
            ),
        ))
    }

    /// A readable line in `self.line` that may not be a data row: a blank line, the end of a
    /// recording (`@@` or another header), or a `Frame` line. Anything else is a data row.
    fn structure_line(
        &mut self,
        grid: Grid,
        frame: &mut FrameInProgress,
    ) -> Result<LineOutcome, IoError> {
        let rows = grid.rows;
        let line = std::str::from_utf8(&self.line).unwrap_or("").trim();
        if is_blank(line) {
            return Ok(LineOutcome::NextLine);
        }
        let header_next = line.to_ascii_uppercase().starts_with("DATA_TYPE");
        if frame.current.is_none() && (line == "@@" || header_next) {
            // The end of a recording; another may follow.
            if self.next_recording(grid, header_next)? {
                return Ok(LineOutcome::NextLine);
            }
            self.ended = true;
            return Ok(LineOutcome::Finished(None));
        }
        if line == "@@" {
            self.ended = true;
            let Some((number, _)) = frame.current else {
                return Ok(LineOutcome::Finished(None));
            };
            return Err(IoError::parse(
                &self.source_name,
                self.line_no,
                format!("`@@` inside frame {number} ({} of {rows} rows)", frame.row),
            ));
        }
        // Only the number is kept: the rest of the line borrows `self.line`.
        match frame_line(line).map(|parsed| parsed.map(|(number, _)| number)) {
            Some(parsed) => self.frame_start(parsed, rows, frame),
            None => Ok(LineOutcome::DataRow),
        }
    }

    /// A `Frame` line: it starts the next frame, after reporting the frame before it if that is short
    /// (the line is then kept for the next call), or is itself broken (its rows are then skipped).
    fn frame_start(
        &mut self,
        parsed: Result<i64, String>,
        rows: usize,
        frame: &mut FrameInProgress,
    ) -> Result<LineOutcome, IoError> {
        let line_no = self.line_no;
        self.framed = Some(true);
        self.resync = false;
        self.skip_rows = 0;
        let row = frame.row;
        let unfinished = frame
            .current
            .map(|(prev, _)| format!("frame {prev} has {row} rows, expected {rows} (ROWS)"));
        match (parsed, unfinished) {
            (Ok(number), None) => {
                frame.current = Some((number, line_no));
                Ok(LineOutcome::NextLine)
            }
            // The previous frame is short (or empty); this line starts the next one.
            (Ok(number), Some(unfinished)) => {
                self.pending_frame = Some((number, line_no));
                Err(IoError::parse(&self.source_name, line_no, unfinished))
            }
            (Err(message), unfinished) => {
                self.resync = true;
                let message = match unfinished {
                    Some(unfinished) => format!("{message}; and {unfinished}"),
                    None => format!("{message}; its rows are skipped"),
                };
                Err(IoError::parse(&self.source_name, line_no, message))
            }
        }
    }

    /// A data row (or a line that cannot be one, `unreadable` saying why): appended to the frame, the
    /// frame returned when it is complete; skipped while resynchronising after a fault.
    fn data_row(
        &mut self,
        unreadable: Option<String>,
        grid: Grid,
        frame: &mut FrameInProgress,
        values: &mut Vec<f64>,
        present: &mut Vec<bool>,
    ) -> Result<LineOutcome, IoError> {
        let Grid { rows, cols } = grid;
        if self.resync {
            return Ok(LineOutcome::NextLine);
        }
        if self.skip_rows > 0 {
            self.skip_rows -= 1;
            return Ok(LineOutcome::NextLine);
        }
        let line_no = self.line_no;
        let (number, first) = self.frame_of_row(frame, rows)?;
        let row = frame.row;
        let result = match unreadable {
            Some(message) => Err(format!("frame {number} row {}: {message}", row + 1)),
            None => {
                let line = std::str::from_utf8(&self.line).unwrap_or("").trim();
                parse_row(
                    line,
                    number,
                    row,
                    cols,
                    values,
                    present,
                    &mut frame.has_absent,
                )
            }
        };
        if let Err(message) = result {
            if self.framed == Some(true) {
                self.resync = true;
            } else {
                self.skip_rows = rows - row - 1;
            }
            return Err(IoError::parse(&self.source_name, line_no, message));
        }
        frame.row += 1;
        if frame.row < rows {
            return Ok(LineOutcome::NextLine);
        }
        Ok(LineOutcome::Finished(Some(StreamFrame {
            number,
            line: first,
            has_absent: frame.has_absent,
        })))
    }

    /// The frame a data row belongs to: the current one; a new, counted one in a stream without
    /// `Frame` lines; an error (and a resynchronisation) after a complete frame in one with them.
    fn frame_of_row(
        &mut self,
        frame: &mut FrameInProgress,
        rows: usize,
    ) -> Result<(i64, usize), IoError> {
        let line_no = self.line_no;
        match frame.current {
            Some(current) => Ok(current),
            None if self.framed == Some(true) => {
                self.resync = true;
                Err(IoError::parse(
                    &self.source_name,
                    line_no,
                    format!(
                        "a row of data after a complete frame ({rows} rows, ROWS); expected a \
                         `Frame` line or `@@`. Skipping to the next `Frame` line"
                    ),
                ))
            }
            None => {
                self.framed = Some(false);
                self.counted += 1;
                let current = (self.counted, line_no);
                frame.current = Some(current);
                Ok(current)
            }
        }
    }
}

impl<R: BufRead> TekscanStream<R> {
    /// Makes the line in `self.line` the next one read again.
    fn unread_line(&mut self) {
        self.replay_line = true;
        self.line_no -= 1;
    }

    /// After the end of a recording (`@@`, or a header line `again` in `self.line`): false at the end
    /// of the input; true when another recording's header follows with frames of `grid`, whose frames
    /// are then read on; an error, and the stream stopped, when it cannot be read or its frames have
    /// another size.
    fn next_recording(&mut self, grid: Grid, again: bool) -> Result<bool, IoError> {
        if again {
            self.unread_line();
        }
        loop {
            match self.next_line(MAX_HEADER_LINE)? {
                Line::End => return Ok(false),
                Line::Text => {
                    let line = std::str::from_utf8(&self.line).unwrap_or("").trim();
                    if !is_blank(line) && line != "@@" {
                        break;
                    }
                }
                Line::Bad(message) => {
                    self.ended = true;
                    self.stopped = true;
                    let message = format!("after the end of a recording: {message}");
                    return Err(IoError::parse(&self.source_name, self.line_no, message));
                }
            }
        }
        let first = self.header.take();
        let line_no = self.line_no;
        self.unread_line();
        let next = self.read_header();
        self.header = first;
        let message = match next {
            Ok(next) if next.grid == grid => {
                self.framed = None;
                self.counted = 0;
                return Ok(true);
            }
            Ok(next) => format!(
                "another recording follows with {} frames where the first had {grid}: one stream \
                 carries frames of one size (stream each recording on its own)",
                next.grid
            ),
            Err(err) => format!("another recording follows, but its header cannot be read: {err}"),
        };
        self.ended = true;
        self.stopped = true;
        Err(IoError::parse(&self.source_name, line_no, message))
    }
}

/// Appends the cells of data row `row` (0-based) of frame `number` to `values` and `present`; on a bad
/// row, appends nothing and says what is wrong.
fn parse_row(
    line: &str,
    number: i64,
    row: usize,
    cols: usize,
    values: &mut Vec<f64>,
    present: &mut Vec<bool>,
    has_absent: &mut bool,
) -> Result<(), String> {
    let start_len = values.len();
    let mut cell_error = None;
    let mut absent = false;
    let split = for_each_cell(line, |c, cell| {
        if c >= cols {
            return false;
        }
        match parse_cell(cell) {
            Ok(parsed) => absent |= !parsed.push_to(values, present),
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
        (_, Some(message)) => Err(message),
        (Err(at), None) => Err(format!(
            "frame {number} row {} column {} is empty",
            row + 1,
            at + 1
        )),
        (Ok(count), None) if count != cols => Err(format!(
            "frame {number} row {} has {count} values, expected {cols} (COLS)",
            row + 1
        )),
        (Ok(_), None) => Ok(()),
    };
    if result.is_err() {
        values.truncate(start_len);
        present.truncate(start_len);
    } else {
        *has_absent |= absent;
    }
    result
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

    /// Every `next_frame` result until the end: `Ok(number, values)` or `Err(message)`.
    fn drain(text: &str) -> Vec<Result<(i64, Vec<f64>), String>> {
        let mut stream = TekscanStream::new(text.as_bytes(), "s");
        let (mut values, mut present) = (Vec::new(), Vec::new());
        let mut out = Vec::new();
        loop {
            match stream.next_frame(&mut values, &mut present) {
                Ok(Some(frame)) => out.push(Ok((frame.number, values.clone()))),
                Ok(None) => return out,
                Err(err) => out.push(Err(err.to_string())),
            }
            assert!(out.len() < 100, "no end: {out:?}");
        }
    }

    fn frame(number: i64, values: &[f64]) -> Result<(i64, Vec<f64>), String> {
        Ok((number, values.to_vec()))
    }

    const HEAD: &str = "ROWS 2\nCOLS 3\nASCII_DATA @@\n";

    #[test]
    fn without_frame_lines_a_bad_row_drops_only_its_frame() {
        // A bad second row: the frame is dropped and the next one read (it used to skip everything
        // after the error, waiting for a `Frame` line that never comes, and end as if clean).
        let got = drain(&format!(
            "{HEAD}1,2,3\n4,x,6\n7,8,9\n10,11,12\n13,14,15\n16,17,18\n"
        ));
        assert_eq!(
            got,
            vec![
                Err(
                    "s line 5: frame 1 row 2 column 2: `x`: expected a number or `B` (no sensel)"
                        .to_owned()
                ),
                frame(2, &[7.0, 8.0, 9.0, 10.0, 11.0, 12.0]),
                frame(3, &[13.0, 14.0, 15.0, 16.0, 17.0, 18.0]),
            ]
        );
        // A bad first row: the rest of its frame is skipped, so the frames after it stay aligned.
        let got = drain(&format!(
            "{HEAD}1,2,3\n4,5,6\n7,8\n10,11,12\n\n13,14,15\n16,17,18\n@@\n"
        ));
        assert_eq!(got.len(), 3, "{got:?}");
        assert_eq!(got[0], frame(1, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]));
        assert!(
            got[1]
                .as_ref()
                .is_err_and(|e| e == "s line 6: frame 2 row 1 has 2 values, expected 3 (COLS)"),
            "{got:?}"
        );
        assert_eq!(got[2], frame(3, &[13.0, 14.0, 15.0, 16.0, 17.0, 18.0]));
    }

    #[test]
    fn an_over_long_line_is_one_error_and_the_stream_goes_on() {
        let long = "1,".repeat(1000);
        // Without `Frame` lines: the long line is row 2 of frame 1.
        let got = drain(&format!("{HEAD}1,2,3\n{long}\n7,8,9\n10,11,12\n"));
        assert_eq!(
            got,
            vec![
                Err("s line 5: frame 1 row 2: line longer than 1024 bytes".to_owned()),
                frame(2, &[7.0, 8.0, 9.0, 10.0, 11.0, 12.0]),
            ]
        );
        // With `Frame` lines, and a line that is not UTF-8.
        let got = drain(&format!(
            "{HEAD}Frame 1\n1,2,3\n{long}\nFrame 2\n1,\u{fffd}\n0,0,0\nFrame 3\n7,8,9\n10,11,12\n"
        ));
        assert_eq!(got.len(), 3, "{got:?}");
        assert_eq!(
            got[0],
            Err("s line 6: frame 1 row 2: line longer than 1024 bytes".to_owned())
        );
        assert!(
            got[1].as_ref().is_err_and(|e| e.contains("line 8")),
            "{got:?}"
        );
        assert_eq!(got[2], frame(3, &[7.0, 8.0, 9.0, 10.0, 11.0, 12.0]));
        let mut bytes = format!("{HEAD}1,2,3\n").into_bytes();
        bytes.extend_from_slice(b"4,\xff,6\n7,8,9\n1,1,1\n");
        let mut stream = TekscanStream::new(bytes.as_slice(), "s");
        let (mut values, mut present) = (Vec::new(), Vec::new());
        let err = stream.next_frame(&mut values, &mut present).unwrap_err();
        assert_eq!(
            err.to_string(),
            "s line 5: frame 1 row 2: not UTF-8 / ASCII text"
        );
        let f = stream
            .next_frame(&mut values, &mut present)
            .unwrap()
            .unwrap();
        assert_eq!(
            (f.number, values.as_slice()),
            (2, &[7.0, 8.0, 9.0, 1.0, 1.0, 1.0][..])
        );
    }

    #[test]
    fn empty_frames_are_errors_as_in_the_whole_file_reader() {
        let got = drain(&format!("{HEAD}Frame 1\nFrame 2\n1,2,3\n4,5,6\n@@\n"));
        assert_eq!(
            got,
            vec![
                Err("s line 5: frame 1 has 0 rows, expected 2 (ROWS)".to_owned()),
                frame(2, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]),
            ]
        );
        let got = drain(&format!("{HEAD}Frame 1\n1,2,3\n4,5,6\nFrame 2\n@@\n"));
        assert_eq!(
            got[1],
            Err("s line 8: `@@` inside frame 2 (0 of 2 rows)".to_owned())
        );
        let got = drain(&format!("{HEAD}Frame 1\n1,2,3\n4,5,6\nFrame 2\n"));
        assert_eq!(
            got[1],
            Err("s line 7: the stream ended inside frame 2 (0 of 2 rows)".to_owned())
        );
        // The whole-file reader agrees.
        let whole = crate::parse_tekscan(
            &format!("{HEAD}Frame 1\nFrame 2\n1,2,3\n4,5,6\n@@\n"),
            "s",
            &crate::ReadOptions::default(),
        );
        assert!(whole.is_err());
    }

    #[test]
    fn frame_lines_are_read_as_the_whole_file_reader_reads_them() {
        let got = drain(&format!("{HEAD}Frame +12, timestamp 5\n1,2,3\n4,5,6\n"));
        assert_eq!(got, vec![frame(12, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0])]);
        // `Frame12` is not a `Frame` line (nor for the whole-file reader): a bad data row.
        let got = drain(&format!("{HEAD}Frame12\n1,2,3\n"));
        assert!(
            got[0].as_ref().is_err_and(|e| e.contains("`Frame12`")),
            "{got:?}"
        );
        // A malformed number: an error, its rows skipped, the next frame read.
        let got = drain(&format!(
            "{HEAD}Frame x\n1,2,3\n4,5,6\nFrame 2\n1,2,3\n4,5,6\n@@\n"
        ));
        assert_eq!(got.len(), 2, "{got:?}");
        assert!(
            got[0].as_ref().is_err_and(
                |e| e.starts_with("s line 4: expected a frame number after `Frame`, found `x`")
            ),
            "{got:?}"
        );
        assert_eq!(got[1], frame(2, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]));
        // A row too many after a frame: an error, then the next `Frame` line.
        let got = drain(&format!(
            "{HEAD}Frame 1\n1,2,3\n4,5,6\n7,8,9\nFrame 2\n1,2,3\n4,5,6\n"
        ));
        assert_eq!(got.len(), 3, "{got:?}");
        assert!(
            got[1]
                .as_ref()
                .is_err_and(|e| e.starts_with("s line 7: a row of data after a complete frame")),
            "{got:?}"
        );
        assert_eq!(got[2], frame(2, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]));
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

    #[test]
    fn recordings_one_after_another_go_on_when_their_sizes_agree() {
        let second = MOVIE.replace("Frame 1\n0,1,2", "Frame 1\n6,7,8");
        let joined = format!("{MOVIE}{second}");
        let frames = drain(&joined);
        assert_eq!(frames.len(), 4, "{frames:?}");
        assert_eq!(frames[2], frame(1, &[6.0, 7.0, 8.0, 3.0, 4.0, 5.0]));
        // Without the closing `@@` (a header where the next frame would be) too.
        let joined = format!("{}{second}", MOVIE.trim_end_matches("@@\n"));
        assert_eq!(drain(&joined).len(), 4, "{:?}", drain(&joined));
    }

    #[test]
    fn a_recording_of_another_size_after_the_first_is_an_error_and_a_stop() {
        let other = "ROWS 3\nCOLS 3\nASCII_DATA @@\nFrame 1\n1,1,1\n1,1,1\n1,1,1\n@@\n";
        let joined = format!("{MOVIE}{other}");
        let mut stream = TekscanStream::new(joined.as_bytes(), "stdin");
        let (mut values, mut present) = (Vec::new(), Vec::new());
        for _ in 0..2 {
            assert!(
                stream
                    .next_frame(&mut values, &mut present)
                    .unwrap()
                    .is_some()
            );
        }
        let err = stream.next_frame(&mut values, &mut present).unwrap_err();
        let text = err.to_string();
        assert!(
            text.contains("line 15") && text.contains("3x3 frames where the first had 2x3"),
            "{text}"
        );
        assert!(stream.stopped());
        assert_eq!(stream.next_frame(&mut values, &mut present).unwrap(), None);
        // Garbage after `@@` is not silence either.
        let joined = format!("{MOVIE}this is not a header\n");
        let frames = drain(&joined);
        assert_eq!(frames.len(), 3, "{frames:?}");
        let last = frames[2].clone().unwrap_err();
        assert!(last.contains("header cannot be read"), "{last}");
    }
}
