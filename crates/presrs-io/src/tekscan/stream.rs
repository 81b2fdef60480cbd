//! Incremental reading of a TekScan ASCII text, one frame at a time, nothing held but the current
//! frame. This is the one frame parser: `presrs stream` uses it on stdin, a pipe or a growing file,
//! and the whole-file reader ([`crate::tekscan`]) drives it over a file's text.
//!
//! The header is read by the whole-file reader's rules (see [`crate::tekscan`]) up to `ASCII_DATA`; a
//! stream keeps [`StreamHeader`] of it. Then frames: a `Frame N` line followed by `ROWS` data lines of
//! `COLS` cells (numbers or `B` for no sensel), or, in texts without `Frame` lines, every `ROWS` data
//! lines, numbered from `START_FRAME` (default 1). `Frame 12, timestamp 728`, `Frame -2` and `Frame +3`
//! are `Frame` lines; `Frame12` is not. Blank and comma-only lines are skipped; `@@` ends a recording.
//! Lines break at `\n`, `\r\n` or a lone `\r`.
//!
//! **A stream and a file** differ in what can be known and what a fault costs:
//!
//! * a stream caps its lines in length (header lines at 64 KiB, data lines at 64 bytes a cell and at
//!   least 1 KiB), its header at 10,000 lines and its frames at [`MAX_STREAM_SENSELS`] (a line without
//!   end cannot eat memory); a file, already in memory, has no caps;
//! * a stream goes on after a fault (below); the whole-file reader stops at the first;
//! * in a stream, recordings may follow one another (below); in a file, only blank lines may follow
//!   `@@`;
//! * in a file, every frame starts with a `Frame` line or none does, and every frame has the first
//!   frame's outline (its `B` cells); in a stream, a `Frame` line always starts a frame, even after
//!   frames without, and each frame says whether it has absent sensels ([`StreamFrame::has_absent`]);
//! * a file without an `ASCII_DATA` line ends its header at the first `Frame` line; a stream, which
//!   cannot look ahead, needs `ASCII_DATA`;
//! * a row with several faults is reported by its first bad cell in a stream, by its cell count in a
//!   file (a last row cut inside a number reads as truncated), and the messages of a few faults are
//!   worded differently (see `fault.rs`).
//!
//! **Recordings one after another** (`cat a.asf b.asf | presrs stream`): after `@@`, or where a
//! `DATA_TYPE` line comes instead of the next frame, another header may follow. When its frames have the
//! same size the stream goes on with them; otherwise that is an error and the stream stops
//! ([`TekscanStream::stopped`]): one stream carries frames of one size.
//!
//! **Faults.** Each fault is an error naming the line (and the frame, row and column when there are
//! some), after which the stream can go on ([`TekscanStream::next_frame`] can be called again):
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
//! Frame numbers are reported as written ([`StreamFrame::number`]); their order and gaps are checked
//! by the whole-file reader only.

use std::io::BufRead;

use presrs_core::Grid;

use super::fault::{Fault, FaultKind, FrameAt, Reading};
use super::header::{Header, HeaderEnd, HeaderReader, no_ascii_data};
use super::line_reader::{Line, LineReader};
use super::lines::frame_line;
use super::rows::{Precedence, parse_row};
use crate::error::IoError;
use crate::message::Warnings;
use crate::textutil::is_blank;

/// Longest header line a stream accepts, bytes.
const MAX_HEADER_LINE: usize = 64 * 1024;
/// Header lines a stream accepts before `ASCII_DATA`.
const MAX_HEADER_LINES: usize = 10_000;
/// Largest grid a stream accepts (sensels).
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
    /// The number on its `Frame` line (or counted from `START_FRAME`, default 1, without `Frame` lines).
    pub number: i64,
    /// Line of its `Frame` line (of its first row without `Frame` lines).
    pub line: usize,
    /// Whether some sensel is `B` (absent): the mask is meaningful.
    pub has_absent: bool,
}

/// Where a frame started: its `Frame` line, or its first row.
#[derive(Clone, Debug)]
struct Started {
    number: i64,
    line: usize,
    framed: bool,
    /// The rest of its `Frame` line after the number (`, timestamp 728`).
    suffix: Option<String>,
}

/// The frame [`TekscanStream::next_frame`] is reading.
struct FrameInProgress {
    /// Rows read so far.
    row: usize,
    /// Whether some sensel read so far is absent.
    has_absent: bool,
    /// The frame, once its `Frame` line or first row is read.
    current: Option<Started>,
}

impl FrameInProgress {
    fn at(&self) -> Option<FrameAt> {
        self.current.as_ref().map(|started| FrameAt {
            number: started.number,
            line: started.line,
            framed: started.framed,
            rows_done: self.row,
        })
    }
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

/// Why [`TekscanStream::read_frame`] gave no frame: an error (the input, the header), or a fault in
/// the frames, which each reader words (and the whole-file reader may excuse) its own way.
pub(super) enum Stop {
    Error(IoError),
    Fault(Fault),
}

/// Reads a TekScan ASCII text frame by frame (see the module docs).
#[derive(Debug)]
pub struct TekscanStream<R> {
    lines: LineReader<R>,
    source_name: String,
    reading: Reading,
    /// A file without `ASCII_DATA`: its header ends at the first `Frame` line.
    frame_line_ends: bool,
    header: Option<StreamHeader>,
    /// The whole header of the first recording, until the whole-file reader takes it.
    details: Option<Header>,
    /// The header's warnings (kept when reading a file).
    warnings: Warnings,
    /// The current recording's START_FRAME (its line and value): frames without `Frame` lines are
    /// numbered from it.
    start_frame: Option<(usize, i64)>,
    /// A `Frame` line read while the frame before it was reported short.
    pending_frame: Option<Started>,
    /// Frames started in the current recording without `Frame` lines.
    counted: usize,
    /// Whether frames start with `Frame` lines (known from the first `Frame` line or data row).
    framed: Option<bool>,
    /// The last complete frame with a `Frame` line: its number and that line.
    last_framed: Option<(i64, usize)>,
    /// Reading a file: the first complete frame's number and outline (presence of each sensel).
    outline: Option<(i64, Vec<bool>)>,
    /// The `Frame` line suffix of the last frame returned.
    suffix: Option<String>,
    /// Reading a file: the line of the `@@` that ended it.
    terminator: Option<usize>,
    /// After a fault in a stream with `Frame` lines: skip data rows until the next `Frame` line.
    resync: bool,
    /// After a fault in a stream without `Frame` lines: rows of the broken frame still to skip.
    skip_rows: usize,
    ended: bool,
    /// The stream stopped on an error it cannot go on from (a following recording of another size).
    stopped: bool,
}

impl<R: BufRead> TekscanStream<R> {
    /// A stream (see the module docs); `source_name` names it in errors.
    pub fn new(reader: R, source_name: &str) -> Self {
        Self::reading(reader, source_name, Reading::Stream, false)
    }

    /// A whole file's text (see the module docs); `has_ascii_data`: the file has an `ASCII_DATA` line.
    pub(super) fn of_file(reader: R, source_name: &str, has_ascii_data: bool) -> Self {
        Self::reading(reader, source_name, Reading::File, !has_ascii_data)
    }

    fn reading(reader: R, source_name: &str, reading: Reading, frame_line_ends: bool) -> Self {
        Self {
            lines: LineReader::new(reader),
            source_name: source_name.to_owned(),
            reading,
            frame_line_ends,
            header: None,
            details: None,
            warnings: Warnings::new(),
            start_frame: None,
            pending_frame: None,
            counted: 0,
            framed: None,
            last_framed: None,
            outline: None,
            suffix: None,
            terminator: None,
            resync: false,
            skip_rows: 0,
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

    /// The whole header and its warnings, once read (for the whole-file reader).
    pub(super) fn take_header(&mut self) -> Option<(Header, Warnings)> {
        let header = self.details.take()?;
        Some((header, std::mem::take(&mut self.warnings)))
    }

    /// The rest of the last frame's `Frame` line after its number (`, timestamp 728`).
    pub(super) fn take_suffix(&mut self) -> Option<String> {
        self.suffix.take()
    }

    /// The line of the `@@` that ended a file, once read.
    pub(super) fn terminator(&self) -> Option<usize> {
        self.terminator
    }

    fn read_error(&self, err: &std::io::Error) -> IoError {
        IoError::format(&self.source_name, format!("cannot read: {err}"))
    }

    /// `limit` for a stream; a file has no caps.
    fn cap(&self, limit: usize) -> usize {
        match self.reading {
            Reading::Stream => limit,
            Reading::File => usize::MAX,
        }
    }

    /// Reads the header (up to `ASCII_DATA`). Called by [`Self::next_frame`] if needed.
    pub fn read_header(&mut self) -> Result<StreamHeader, IoError> {
        if let Some(header) = self.header {
            return Ok(header);
        }
        let details = self.parse_header()?;
        let header = StreamHeader {
            grid: details.grid,
            period_s: details.period,
        };
        self.start_frame = details.start_frame;
        self.details = Some(details);
        self.header = Some(header);
        Ok(header)
    }

    /// Reads a header from the next line on, within a stream's limits.
    fn parse_header(&mut self) -> Result<Header, IoError> {
        let name = self.source_name.clone();
        let (line_limit, max_lines) = (self.cap(MAX_HEADER_LINE), self.cap(MAX_HEADER_LINES));
        let mut warnings = Warnings::new();
        let mut reader = HeaderReader::new(&name, self.frame_line_ends, &mut warnings);
        let mut read = 0;
        let (end, end_line) = loop {
            if read == max_lines {
                return Err(IoError::parse(
                    &name,
                    self.lines.line_no(),
                    format!("no `ASCII_DATA` line within the first {MAX_HEADER_LINES} lines"),
                ));
            }
            read += 1;
            let line_no = self.lines.line_no() + 1;
            match self.lines.next(line_limit) {
                Ok(Line::Text) => {}
                Ok(Line::Bad(message)) => return Err(IoError::parse(&name, line_no, message)),
                Ok(Line::End) => return Err(no_ascii_data(&name, self.lines.line_no())),
                Err(err) => return Err(self.read_error(&err)),
            }
            if let Some(end) = reader.line(line_no, self.lines.text())? {
                break (end, line_no);
            }
        };
        let ended_by = match end {
            HeaderEnd::AsciiData => "ASCII_DATA".to_owned(),
            HeaderEnd::FrameLine => {
                // The `Frame` line is the first line of the data.
                let line = self.lines.text().trim().to_owned();
                self.lines.unread();
                line
            }
        };
        let header = reader.finish(end_line, &ended_by)?;
        let Grid { rows, cols } = header.grid;
        match self.reading {
            Reading::Stream if rows.saturating_mul(cols) > MAX_STREAM_SENSELS => {
                return Err(IoError::parse(
                    &name,
                    end_line,
                    format!(
                        "{rows}x{cols} frames exceed the limit of {MAX_STREAM_SENSELS} sensels"
                    ),
                ));
            }
            Reading::Stream => {}
            Reading::File => self.warnings.extend(warnings),
        }
        Ok(header)
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
        self.read_frame(values, present).map_err(|stop| match stop {
            Stop::Error(err) => err,
            Stop::Fault(fault) => fault.into_error(&self.source_name, self.reading),
        })
    }

    /// [`Self::next_frame`], with a fault in the frames kept typed.
    pub(super) fn read_frame(
        &mut self,
        values: &mut Vec<f64>,
        present: &mut Vec<bool>,
    ) -> Result<Option<StreamFrame>, Stop> {
        let header = self.read_header().map_err(Stop::Error)?;
        if self.ended {
            return Ok(None);
        }
        let limit = self.cap(header.grid.cols.saturating_mul(64).max(1024));
        values.clear();
        present.clear();
        let mut frame = FrameInProgress {
            row: 0,
            has_absent: false,
            current: self.pending_frame.take(),
        };
        loop {
            let unreadable = match self.lines.next(limit) {
                Ok(Line::End) => return self.end_of_input(&frame, header.grid.rows),
                Ok(Line::Text) => None,
                Ok(Line::Bad(message)) => Some(message),
                Err(err) => return Err(Stop::Error(self.read_error(&err))),
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

    /// A fault on the line just read.
    fn fault(&self, frame: Option<FrameAt>, kind: FaultKind) -> Stop {
        Stop::Fault(Fault {
            line: self.lines.line_no(),
            frame,
            kind,
        })
    }

    /// The input ended: the end of the stream between frames, a fault inside one.
    fn end_of_input(
        &mut self,
        frame: &FrameInProgress,
        rows: usize,
    ) -> Result<Option<StreamFrame>, Stop> {
        self.ended = true;
        match frame.at() {
            None => Ok(None),
            Some(at) => Err(self.fault(Some(at), FaultKind::EndedInsideFrame { rows })),
        }
    }

    /// A readable line that may not be a data row: a blank line, the end of a recording (`@@` or
    /// another header), or a `Frame` line. Anything else is a data row.
    fn structure_line(
        &mut self,
        grid: Grid,
        frame: &mut FrameInProgress,
    ) -> Result<LineOutcome, Stop> {
        let line = self.lines.text().trim();
        if is_blank(line) {
            return Ok(LineOutcome::NextLine);
        }
        if let Some(at) = self.terminator {
            let found = line.to_owned();
            return Err(self.fault(None, FaultKind::AfterTerminator { at, found }));
        }
        let terminator = line == "@@";
        let header_next = self.reading == Reading::Stream
            && line
                .get(..9)
                .is_some_and(|head| head.eq_ignore_ascii_case("DATA_TYPE"));
        // Only owned parts are kept: the line borrows the reader.
        let parsed = frame_line(line).map(|parsed| parsed.map(|(n, s)| (n, s.map(str::to_owned))));
        if frame.current.is_none() && (terminator || header_next) {
            if self.reading == Reading::File {
                self.terminator = Some(self.lines.line_no());
                return Ok(LineOutcome::NextLine);
            }
            // The end of a recording; another may follow.
            if self.next_recording(grid, header_next)? {
                return Ok(LineOutcome::NextLine);
            }
            self.ended = true;
            return Ok(LineOutcome::Finished(None));
        }
        if terminator {
            self.ended = true;
            let rows = grid.rows;
            return Err(self.fault(frame.at(), FaultKind::ShortBeforeTerminator { rows }));
        }
        match parsed {
            Some(parsed) => self.frame_start(parsed, grid.rows, frame),
            None => Ok(LineOutcome::DataRow),
        }
    }

    /// A `Frame` line: it starts the next frame, after reporting the frame before it if that is short
    /// (the line is then kept for the next call), or is itself broken (its rows are then skipped).
    fn frame_start(
        &mut self,
        parsed: Result<(i64, Option<String>), String>,
        rows: usize,
        frame: &mut FrameInProgress,
    ) -> Result<LineOutcome, Stop> {
        let (number, suffix) = match parsed {
            Ok(parsed) => parsed,
            Err(message) => {
                self.framed = Some(true);
                self.resync = true;
                self.skip_rows = 0;
                let kind = FaultKind::BadFrameLine { message, rows };
                return Err(self.fault(frame.at(), kind));
            }
        };
        if self.reading == Reading::File && self.framed == Some(false) {
            return Err(self.fault(frame.at(), FaultKind::FrameLineAfterSnapshots));
        }
        self.framed = Some(true);
        self.resync = false;
        self.skip_rows = 0;
        let started = Started {
            number,
            line: self.lines.line_no(),
            framed: true,
            suffix,
        };
        if frame.current.is_some() {
            // The frame before is short (or empty); this line starts the next one.
            self.pending_frame = Some(started);
            return Err(self.fault(frame.at(), FaultKind::ShortBeforeFrameLine { rows }));
        }
        frame.current = Some(started);
        Ok(LineOutcome::NextLine)
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
    ) -> Result<LineOutcome, Stop> {
        let Grid { rows, cols } = grid;
        if self.resync {
            return Ok(LineOutcome::NextLine);
        }
        if self.skip_rows > 0 {
            self.skip_rows -= 1;
            return Ok(LineOutcome::NextLine);
        }
        self.frame_of_row(frame, rows)?;
        let row = frame.row;
        let result = match unreadable {
            Some(why) => Err(FaultKind::Unreadable { row, why }),
            None => {
                let outline = self.outline.as_ref().map(|(first, mask)| {
                    let at = (row * cols).min(mask.len());
                    (*first, &mask[at..(at + cols).min(mask.len())])
                });
                let precedence = match self.reading {
                    Reading::File => Precedence::CountFirst,
                    Reading::Stream => Precedence::CellsFirst,
                };
                parse_row(
                    self.lines.text(),
                    cols,
                    values,
                    present,
                    outline,
                    precedence,
                )
                .map_err(|fault| FaultKind::Row { row, fault })
            }
        };
        match result {
            Ok(absent) => frame.has_absent |= absent,
            Err(kind) => {
                if self.framed == Some(true) {
                    self.resync = true;
                } else {
                    self.skip_rows = rows - row - 1;
                }
                return Err(self.fault(frame.at(), kind));
            }
        }
        frame.row += 1;
        if frame.row < rows {
            return Ok(LineOutcome::NextLine);
        }
        Ok(LineOutcome::Finished(self.complete(frame, present)))
    }

    /// The frame is complete: remembered as the last one (and as the outline of a file).
    fn complete(&mut self, frame: &mut FrameInProgress, present: &[bool]) -> Option<StreamFrame> {
        let started = frame.current.take()?;
        if started.framed {
            self.last_framed = Some((started.number, started.line));
        }
        if self.reading == Reading::File && self.outline.is_none() {
            self.outline = Some((started.number, present.to_vec()));
        }
        self.suffix = started.suffix;
        Some(StreamFrame {
            number: started.number,
            line: started.line,
            has_absent: frame.has_absent,
        })
    }

    /// Makes sure the data row has a frame: the current one; a new, counted one in a stream without
    /// `Frame` lines; a fault (and a resynchronisation) after a complete frame in one with them.
    fn frame_of_row(&mut self, frame: &mut FrameInProgress, rows: usize) -> Result<(), Stop> {
        if frame.current.is_some() {
            return Ok(());
        }
        if self.framed == Some(true) {
            self.resync = true;
            let (number, first_line) = self.last_framed.unwrap_or_default();
            let kind = FaultKind::RowAfterFrame {
                number,
                first_line,
                rows,
            };
            return Err(self.fault(None, kind));
        }
        self.framed = Some(false);
        let number = match self.snapshot_number() {
            Ok(number) => number,
            Err(message) => {
                self.skip_rows = rows - 1;
                return Err(self.fault(None, FaultKind::Unnumbered { message }));
            }
        };
        self.counted += 1;
        frame.current = Some(Started {
            number,
            line: self.lines.line_no(),
            framed: false,
            suffix: None,
        });
        Ok(())
    }

    /// The number of the next frame without a `Frame` line: counted on from START_FRAME, which a
    /// crafted value near `i64::MAX` leaves no room for.
    fn snapshot_number(&self) -> Result<i64, String> {
        let start = self.start_frame.map_or(1, |(_, s)| s);
        let n = self.counted;
        i64::try_from(n)
            .ok()
            .and_then(|n| start.checked_add(n))
            .ok_or_else(|| {
                let from = self
                    .start_frame
                    .map_or_else(String::new, |(at, _)| format!(" (line {at})"));
                format!(
                    "frame {} of the file cannot be numbered: START_FRAME {start}{from} + {n} is \
                     beyond the largest frame number ({})",
                    n + 1,
                    i64::MAX
                )
            })
    }

    /// After the end of a recording (`@@`, or a header line `again` just read): false at the end of
    /// the input; true when another recording's header follows with frames of `grid`, whose frames
    /// are then read on; an error, and the stream stopped, when it cannot be read or its frames have
    /// another size.
    fn next_recording(&mut self, grid: Grid, again: bool) -> Result<bool, Stop> {
        if again {
            self.lines.unread();
        }
        loop {
            match self.lines.next(MAX_HEADER_LINE) {
                Ok(Line::End) => return Ok(false),
                Ok(Line::Text) => {
                    let line = self.lines.text().trim();
                    if !is_blank(line) && line != "@@" {
                        break;
                    }
                }
                Ok(Line::Bad(message)) => {
                    self.ended = true;
                    self.stopped = true;
                    let message = format!("after the end of a recording: {message}");
                    let line_no = self.lines.line_no();
                    return Err(Stop::Error(IoError::parse(
                        &self.source_name,
                        line_no,
                        message,
                    )));
                }
                Err(err) => return Err(Stop::Error(self.read_error(&err))),
            }
        }
        let line_no = self.lines.line_no();
        self.lines.unread();
        let message = match self.parse_header() {
            Ok(next) if next.grid == grid => {
                self.framed = None;
                self.counted = 0;
                self.last_framed = None;
                self.start_frame = next.start_frame;
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
        Err(Stop::Error(IoError::parse(
            &self.source_name,
            line_no,
            message,
        )))
    }
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
