//! What can be wrong in the frames of a TekScan text, as one typed fault, and its wording for each
//! reader: the whole-file reader's (a file is one recording: the first fault ends it) and the
//! stream's (it reads on after a fault, and says how). Where the two wordings differ, it is because
//! their messages were settled (and pinned by tests) before the readers shared a parser.

use super::lines::clip;
use super::rows::RowFault;
use crate::error::IoError;

/// Which reader reads the text: it decides the policy (see [`super::stream`]) and the wording.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Reading {
    /// A whole file: one recording, faults end it.
    File,
    /// A live stream: recordings one after another, faults are skipped.
    Stream,
}

/// The frame being read when a fault was met.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct FrameAt {
    pub(super) number: i64,
    /// Its `Frame` line (its first row without `Frame` lines).
    pub(super) line: usize,
    /// Whether it began with a `Frame` line.
    pub(super) framed: bool,
    /// Rows read so far.
    pub(super) rows_done: usize,
}

/// Why a frame could not be read.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum FaultKind {
    /// A data row (`row`, 0-based) of the frame is wrong.
    Row { row: usize, fault: RowFault },
    /// A line where the frame's row `row` should be cannot be read as text (too long, not UTF-8).
    Unreadable { row: usize, why: String },
    /// The frame has fewer than `rows` rows before the next `Frame` line.
    ShortBeforeFrameLine { rows: usize },
    /// The frame has fewer than `rows` rows before `@@`.
    ShortBeforeTerminator { rows: usize },
    /// The input ends inside the frame (fewer than `rows` rows).
    EndedInsideFrame { rows: usize },
    /// A data row after frame `number` (from `first_line`) had its `rows` rows.
    RowAfterFrame {
        number: i64,
        first_line: usize,
        rows: usize,
    },
    /// A `Frame` line whose number cannot be read (why), in frames of `rows` rows.
    BadFrameLine { message: String, rows: usize },
    /// A `Frame` line in a file whose frames so far had none.
    FrameLineAfterSnapshots,
    /// A non-blank line (`found`) after the `@@` terminator on line `at`, in a file.
    AfterTerminator { at: usize, found: String },
    /// A frame without `Frame` line cannot be numbered from START_FRAME (why).
    Unnumbered { message: String },
}

/// A fault on line `line`, inside `frame` when one was being read.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Fault {
    pub(super) line: usize,
    pub(super) frame: Option<FrameAt>,
    pub(super) kind: FaultKind,
}

impl Fault {
    /// The error naming `file` and the line, in `reading`'s words.
    pub(super) fn into_error(self, file: &str, reading: Reading) -> IoError {
        IoError::parse(file, self.line, self.message(reading))
    }

    /// What is wrong, in `reading`'s words.
    pub(super) fn message(&self, reading: Reading) -> String {
        let stream = reading == Reading::Stream;
        let (number, first_line, rows_done) = self
            .frame
            .as_ref()
            .map_or((0, 0, 0), |f| (f.number, f.line, f.rows_done));
        match &self.kind {
            FaultKind::Row { row, fault } => row_message(number, *row, fault, reading),
            FaultKind::Unreadable { row, why } => format!("frame {number} row {}: {why}", row + 1),
            FaultKind::ShortBeforeFrameLine { rows } if stream => {
                format!("frame {number} has {rows_done} rows, expected {rows} (ROWS)")
            }
            FaultKind::ShortBeforeFrameLine { rows } => format!(
                "frame {number} (from line {first_line}) has {rows_done} rows, expected {rows} (ROWS), \
                 before the next `Frame` line"
            ),
            FaultKind::ShortBeforeTerminator { rows } if stream => {
                format!("`@@` inside frame {number} ({rows_done} of {rows} rows)")
            }
            FaultKind::ShortBeforeTerminator { rows } => format!(
                "frame {number} (from line {first_line}) has {rows_done} rows, expected {rows} (ROWS) \
                 before the `@@` terminator"
            ),
            FaultKind::EndedInsideFrame { rows } if stream => {
                format!("the stream ended inside frame {number} ({rows_done} of {rows} rows)")
            }
            FaultKind::EndedInsideFrame { rows } => format!(
                "frame {number} (from line {first_line}) is truncated: the file ends after \
                 {rows_done} of {rows} rows (ROWS)"
            ),
            FaultKind::RowAfterFrame {
                number,
                first_line,
                rows,
            } => format!(
                "a row of data after a complete frame: frame {number} (from line {first_line}) already \
                 has {rows} rows (ROWS); expected a `Frame` line or the `@@` terminator{}",
                if stream {
                    ". Skipping to the next `Frame` line"
                } else {
                    ", found another row of data"
                }
            ),
            FaultKind::BadFrameLine { message, rows } if stream => match &self.frame {
                Some(_) => format!(
                    "{message}; and frame {number} has {rows_done} rows, expected {rows} (ROWS)"
                ),
                None => format!("{message}; its rows are skipped"),
            },
            FaultKind::BadFrameLine { message, .. } | FaultKind::Unnumbered { message } => {
                message.clone()
            }
            FaultKind::FrameLineAfterSnapshots => "found a `Frame` line after frame data that had \
                none; expected every frame to start with a `Frame N` line, or none to"
                .to_owned(),
            FaultKind::AfterTerminator { at, found } => format!(
                "expected nothing after the `@@` terminator on line {at}, found `{}`",
                clip(found)
            ),
        }
    }
}

/// A row fault of frame `number`, row `row` (0-based).
fn row_message(number: i64, row: usize, fault: &RowFault, reading: Reading) -> String {
    let row = row + 1;
    match (fault, reading) {
        (RowFault::Empty { col }, _) => format!(
            "frame {number} row {row} column {} is empty; expected a number or `B` (no sensel)",
            col + 1
        ),
        (RowFault::Count { found, cols }, Reading::Stream) => {
            format!("frame {number} row {row} has {found} values, expected {cols} (COLS)")
        }
        (RowFault::Count { found, cols }, Reading::File) => {
            format!("frame {number} has {found} values in row {row}, expected {cols} (COLS)")
        }
        (RowFault::Cell { col, cell, error }, Reading::Stream) => format!(
            "frame {number} row {row} column {}: `{cell}`: {}",
            col + 1,
            error.expected(true)
        ),
        (RowFault::Cell { col, cell, error }, Reading::File) => format!(
            "frame {number} row {row} column {}: {}, found `{}`",
            col + 1,
            error.expected(true),
            clip(cell)
        ),
        (
            RowFault::Outline {
                col,
                present,
                first,
            },
            _,
        ) => {
            let (here, there) = if *present {
                ("holds a value", "has `B` (no sensel)")
            } else {
                ("is `B` (no sensel)", "has a value")
            };
            format!(
                "frame {number} row {row} column {} {here} but frame {first} {there} there; expected \
                 the same sensel outline in every frame",
                col + 1
            )
        }
    }
}
