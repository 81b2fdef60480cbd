//! The frames after the header: `Frame N` lines and rows of `COLS` cells, up to `@@` or the end.

use presrs_core::FrameInfo;

use super::header::Header;
use super::lines::{clip, frame_line};
use crate::ReadOptions;
use crate::error::IoError;
use crate::message::Warnings;
use crate::textutil::{Cell, is_blank, parse_cell, split_cells};

/// The frames read.
pub(super) struct Body {
    pub(super) data: Vec<f64>,
    pub(super) mask: Option<Vec<bool>>,
    pub(super) info: Vec<FrameInfo>,
    /// Line of the `@@` terminator, when present.
    pub(super) terminator: Option<usize>,
    /// A truncated last frame was dropped (lenient reading).
    pub(super) dropped_truncated: bool,
}

/// The frame being read.
struct Current {
    number: i64,
    suffix: Option<String>,
    first_line: usize,
    rows_done: usize,
}

/// Where the frame reader is: a small state machine over the non-blank lines after the header.
enum State {
    /// No frame yet: whether frames start with `Frame N` lines is not known.
    Start,
    /// Inside a frame (`framed`: it began with a `Frame N` line), fewer than ROWS rows read.
    InFrame { frame: Current, framed: bool },
    /// After a complete frame that began with a `Frame N` line (its number and that line).
    AfterFrame { number: i64, first_line: usize },
    /// After a complete frame of a file without `Frame` lines (snapshots).
    AfterSnapshot,
    /// After the `@@` terminator (its line): only blank lines may follow.
    Terminated(usize),
    /// A truncated last frame was dropped (lenient reading): only blank lines follow.
    Dropped,
}

/// The frames read so far and what reading them needs.
struct Reader<'a> {
    header: &'a Header,
    file: &'a str,
    options: &'a ReadOptions,
    warnings: &'a mut Warnings,
    data: Vec<f64>,
    mask: Vec<bool>,
    any_absent: bool,
    info: Vec<FrameInfo>,
    cells: Vec<&'a str>,
    /// Jumps in the frame numbers: (line, previous number, number, numbers missing).
    gaps: Vec<(usize, i64, i64, i128)>,
}

pub(super) fn parse_frames(
    header: &Header,
    lines: &[(usize, &str)],
    input_len: usize,
    file: &str,
    options: &ReadOptions,
    warnings: &mut Warnings,
) -> Result<Body, IoError> {
    let mut reader = Reader::new(header, input_len, file, options, warnings);
    let last_nonblank = lines
        .iter()
        .rposition(|(_, line)| !is_blank(line))
        .unwrap_or(0);
    let mut state = State::Start;
    for (index, &(line_no, raw)) in lines.iter().enumerate() {
        let line = raw.trim();
        if is_blank(line) {
            continue;
        }
        state = if let State::Terminated(at) = state {
            return Err(reader.after_terminator(at, line_no, line));
        } else if line == "@@" {
            reader.terminator(state, line_no)?
        } else if let Some(parsed) = frame_line(line) {
            reader.frame_line(state, line_no, parsed)?
        } else {
            reader.data_row(state, line_no, line, index == last_nonblank)?
        };
    }
    reader.finish(state, lines)
}

impl<'a> Reader<'a> {
    fn new(
        header: &'a Header,
        input_len: usize,
        file: &'a str,
        options: &'a ReadOptions,
        warnings: &'a mut Warnings,
    ) -> Self {
        // Reserve for the announced frames, but never more than the input could hold (>= 2 bytes per
        // value). In i128: `END_FRAME - START_FRAME + 1` overflows i64 for extreme (crafted) values.
        let announced = match (header.start_frame, header.end_frame) {
            (Some((_, s)), Some((_, e))) if e >= s => {
                usize::try_from(i128::from(e) - i128::from(s) + 1).unwrap_or(usize::MAX)
            }
            _ => 1,
        };
        let cap = announced
            .saturating_mul(header.grid.len())
            .min(input_len / 2 + 1);
        Self {
            header,
            file,
            options,
            warnings,
            data: Vec::with_capacity(cap),
            mask: Vec::new(),
            any_absent: false,
            info: Vec::new(),
            cells: Vec::new(),
            gaps: Vec::new(),
        }
    }

    fn rows(&self) -> usize {
        self.header.grid.rows
    }

    /// Any non-blank line after `@@`.
    fn after_terminator(&self, at: usize, line_no: usize, line: &str) -> IoError {
        IoError::parse(
            self.file,
            line_no,
            format!(
                "expected nothing after the `@@` terminator on line {at}, found `{}`",
                clip(line)
            ),
        )
    }

    /// `@@`: the data ends; a frame still missing rows is an error.
    fn terminator(&self, state: State, line_no: usize) -> Result<State, IoError> {
        if let State::InFrame { frame: cur, .. } = &state {
            return Err(IoError::parse(
                self.file,
                line_no,
                format!(
                    "frame {} (from line {}) has {} rows, expected {} (ROWS) before the `@@` terminator",
                    cur.number,
                    cur.first_line,
                    cur.rows_done,
                    self.rows()
                ),
            ));
        }
        Ok(State::Terminated(line_no))
    }

    /// `Frame N`: a new frame, after a complete one whose number it must follow.
    fn frame_line(
        &mut self,
        state: State,
        line_no: usize,
        parsed: Result<(i64, Option<&str>), String>,
    ) -> Result<State, IoError> {
        let (number, suffix) =
            parsed.map_err(|message| IoError::parse(self.file, line_no, message))?;
        match state {
            State::InFrame { framed: false, .. } | State::AfterSnapshot => {
                return Err(IoError::parse(
                    self.file,
                    line_no,
                    "found a `Frame` line after frame data that had none; expected every frame to \
                     start with a `Frame N` line, or none to",
                ));
            }
            State::InFrame { frame: cur, .. } => {
                return Err(IoError::parse(
                    self.file,
                    line_no,
                    format!(
                        "frame {} (from line {}) has {} rows, expected {} (ROWS), before the next `Frame` line",
                        cur.number,
                        cur.first_line,
                        cur.rows_done,
                        self.rows()
                    ),
                ));
            }
            State::AfterFrame {
                number: prev,
                first_line,
            } => self.check_step(line_no, prev, first_line, number)?,
            State::Start | State::Terminated(_) | State::Dropped => {}
        }
        Ok(State::InFrame {
            frame: Current {
                number,
                suffix: suffix.map(str::to_owned),
                first_line: line_no,
                rows_done: 0,
            },
            framed: true,
        })
    }

    /// Frame `number` after frame `prev` (from `prev_line`): going back or repeating is an error (a
    /// warning when lenient); a jump is noted for the gap warnings.
    fn check_step(
        &mut self,
        line_no: usize,
        prev: i64,
        prev_line: usize,
        number: i64,
    ) -> Result<(), IoError> {
        let step = i128::from(number) - i128::from(prev);
        if step <= 0 {
            let message = format!(
                "frame {number} {} frame {prev} (line {prev_line}): expected increasing frame numbers \
                 (time runs backwards or repeats here)",
                if step == 0 { "repeats" } else { "comes after" },
            );
            if !self.options.lenient {
                return Err(IoError::parse(
                    self.file,
                    line_no,
                    format!("{message}; read leniently to keep the frames anyway"),
                ));
            }
            let file = self.file;
            self.warnings
                .push(format!("{file} line {line_no}: {message}; frames kept"));
        } else if step > 1 {
            self.gaps.push((line_no, prev, number, step - 1));
        }
        Ok(())
    }

    /// A row of cells: the next row of the frame being read, or the first of a new snapshot frame.
    fn data_row(
        &mut self,
        state: State,
        line_no: usize,
        line: &'a str,
        last: bool,
    ) -> Result<State, IoError> {
        let (mut cur, framed) = match state {
            State::InFrame { frame, framed } => (frame, framed),
            State::AfterFrame { number, first_line } => {
                return Err(IoError::parse(
                    self.file,
                    line_no,
                    format!(
                        "frame {number} (from line {first_line}) already has {} rows (ROWS); expected a \
                         `Frame` line or the `@@` terminator, found another row of data",
                        self.rows()
                    ),
                ));
            }
            State::Start | State::AfterSnapshot | State::Terminated(_) | State::Dropped => (
                Current {
                    number: self.next_snapshot_number(line_no)?,
                    suffix: None,
                    first_line: line_no,
                    rows_done: 0,
                },
                false,
            ),
        };
        if !self.read_cells(&cur, line_no, line, last)? {
            return Ok(State::Dropped);
        }
        cur.rows_done += 1;
        if cur.rows_done < self.rows() {
            return Ok(State::InFrame { frame: cur, framed });
        }
        self.info.push(FrameInfo {
            number: cur.number,
            suffix: cur.suffix.take(),
        });
        Ok(if framed {
            State::AfterFrame {
                number: cur.number,
                first_line: cur.first_line,
            }
        } else {
            State::AfterSnapshot
        })
    }

    /// Frames without `Frame` lines are numbered from START_FRAME; a crafted START_FRAME near i64::MAX
    /// leaves no room for the next number.
    fn next_snapshot_number(&self, line_no: usize) -> Result<i64, IoError> {
        let start = self.header.start_frame.map_or(1, |(_, s)| s);
        let n = self.info.len();
        i64::try_from(n)
            .ok()
            .and_then(|n| start.checked_add(n))
            .ok_or_else(|| {
                let from = self
                    .header
                    .start_frame
                    .map_or_else(String::new, |(at, _)| format!(" (line {at})"));
                IoError::parse(
                    self.file,
                    line_no,
                    format!(
                        "frame {} of the file cannot be numbered: START_FRAME {start}{from} + {n} is \
                         beyond the largest frame number ({})",
                        n + 1,
                        i64::MAX
                    ),
                )
            })
    }

    /// Reads row `cur.rows_done` of frame `cur` into the data; `Ok(false)` when it was the file's
    /// truncated last line and the frame was dropped (lenient reading).
    fn read_cells(
        &mut self,
        cur: &Current,
        line_no: usize,
        line: &'a str,
        last: bool,
    ) -> Result<bool, IoError> {
        let (file, cols, row) = (self.file, self.header.grid.cols, cur.rows_done);
        split_cells(line, &mut self.cells).map_err(|at| {
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
        if self.cells.len() != cols {
            return self.wrong_cell_count(cur, line_no, last);
        }
        let first_frame = self.info.is_empty();
        for col in 0..cols {
            let cell = self.cells[col];
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
                self.mask.push(present);
                self.any_absent |= !present;
            } else if self.mask[row * cols + col] != present {
                return Err(self.outline_changed(cur, line_no, row, col, present));
            }
            self.data.push(parsed.value());
        }
        Ok(true)
    }

    /// A row of another length than COLS: the truncated last line of the file (dropped when lenient,
    /// `Ok(false)`), else an error.
    fn wrong_cell_count(
        &mut self,
        cur: &Current,
        line_no: usize,
        last: bool,
    ) -> Result<bool, IoError> {
        let (file, cols, row, found) = (
            self.file,
            self.header.grid.cols,
            cur.rows_done,
            self.cells.len(),
        );
        if last && found < cols {
            let message = format!(
                "frame {} is truncated: its row {} has {found} of {cols} values (COLS) at the end of the file",
                cur.number,
                row + 1,
            );
            if self.options.lenient {
                self.warnings
                    .push(format!("{file} line {line_no}: {message}; frame dropped"));
                self.data.truncate(self.info.len() * self.header.grid.len());
                if self.info.is_empty() {
                    self.mask.clear();
                }
                return Ok(false);
            }
            return Err(IoError::parse(
                file,
                line_no,
                format!("{message} (read leniently to drop it)"),
            ));
        }
        Err(IoError::parse(
            file,
            line_no,
            format!(
                "frame {} has {found} values in row {}, expected {cols} (COLS)",
                cur.number,
                row + 1
            ),
        ))
    }

    /// A cell present where the first frame has `B`, or the other way round.
    fn outline_changed(
        &self,
        cur: &Current,
        line_no: usize,
        row: usize,
        col: usize,
        present: bool,
    ) -> IoError {
        let first = self.info[0].number;
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
        IoError::parse(self.file, line_no, message)
    }

    /// The end of the input: a frame still missing rows is truncated (dropped when lenient); at least
    /// one frame must have been read.
    fn finish(mut self, state: State, lines: &[(usize, &str)]) -> Result<Body, IoError> {
        let (file, rows, cols) = (self.file, self.header.grid.rows, self.header.grid.cols);
        let last_line = lines.last().map_or(self.header.end_line, |&(n, _)| n);
        let mut dropped_truncated = matches!(state, State::Dropped);
        if let State::InFrame { frame: cur, .. } = &state {
            let message = format!(
                "frame {} (from line {}) is truncated: the file ends after {} of {rows} rows (ROWS)",
                cur.number, cur.first_line, cur.rows_done
            );
            if !self.options.lenient {
                return Err(IoError::parse(
                    file,
                    last_line,
                    format!("{message} (read leniently to drop it)"),
                ));
            }
            self.warnings
                .push(format!("{file} line {last_line}: {message}; frame dropped"));
            self.data.truncate(self.info.len() * self.header.grid.len());
            dropped_truncated = true;
        }
        report_gaps(&self.gaps, file, self.warnings);
        if self.info.is_empty() {
            return Err(IoError::parse(
                file,
                last_line,
                format!(
                    "expected frame data ({rows} rows of {cols} values) after the header ending on line {}, found {}",
                    self.header.end_line,
                    if dropped_truncated {
                        "only a truncated frame"
                    } else {
                        "none"
                    }
                ),
            ));
        }
        Ok(Body {
            data: self.data,
            mask: self.any_absent.then_some(self.mask),
            info: self.info,
            terminator: match state {
                State::Terminated(at) => Some(at),
                _ => None,
            },
            dropped_truncated,
        })
    }
}

/// Gap warnings given one by one; more are summed up in one warning.
pub(super) const MAX_GAP_WARNINGS: usize = 5;

/// Warns of jumps in the frame numbers (`Frame 49` then `Frame 150`): frames are missing there, so time
/// is not contiguous across the jump.
fn report_gaps(gaps: &[(usize, i64, i64, i128)], file: &str, warnings: &mut Warnings) {
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

pub(super) fn check_frame_count(
    header: &Header,
    body: &Body,
    file: &str,
    options: &ReadOptions,
    warnings: &mut Warnings,
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
