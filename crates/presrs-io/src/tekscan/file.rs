//! The whole-file reader: drives the stream ([`super::stream`]) over a file's text and collects its
//! frames into a [`Recording`], with the checks only a whole file allows (see [`crate::tekscan`]):
//! the file is not empty, frame numbers increase (gaps are reported), a truncated last frame is an
//! error or (reading leniently) dropped, there is at least one frame, and START_FRAME/END_FRAME agree
//! with the frames found.

use presrs_core::{FrameInfo, Recording};

use super::fault::{Fault, FaultKind, Reading};
use super::header::Header;
use super::rows::RowFault;
use super::stream::{Stop, TekscanStream};
use crate::error::IoError;
use crate::message::Warnings;
use crate::textutil::{is_blank, numbered_lines};
use crate::{Parsed, ReadOptions};

/// Parses the text of a TekScan ASCII file; `file` names it in messages.
pub(super) fn parse_file(text: &str, file: &str, options: &ReadOptions) -> Result<Parsed, IoError> {
    let lines = numbered_lines(text);
    let Some(last_nonblank) = lines.iter().rev().find(|(_, line)| !is_blank(line)) else {
        return Err(IoError::format(
            file,
            "empty file: expected a TekScan ASCII header (`DATA_TYPE MOVIE`, `ROWS`, `COLS`, ..., \
             `ASCII_DATA`) followed by frames",
        ));
    };
    let has_ascii_data = lines
        .iter()
        .any(|(_, line)| super::lines::is_ascii_data(line.split_whitespace().next().unwrap_or("")));
    let ends = FileEnds {
        last_line: lines.last().map_or(1, |&(n, _)| n),
        last_nonblank: last_nonblank.0,
    };
    let mut stream = TekscanStream::of_file(text.as_bytes(), file, has_ascii_data);
    stream.read_header()?;
    let Some((header, mut warnings)) = stream.take_header() else {
        return Err(IoError::format(file, "the TekScan header was not kept"));
    };
    let body = Collector::new(&header, text.len(), file, options, &mut warnings)
        .collect(&mut stream, ends)?;
    check_frame_count(&header, &body, file, options, &mut warnings)?;
    let recording = Recording::with_info(
        header.grid,
        header.period,
        body.data,
        body.mask,
        body.info,
        header.meta,
    )
    .map_err(|source| IoError::Model {
        file: file.to_owned(),
        source,
    })?;
    Ok(Parsed {
        recording,
        warnings,
    })
}

/// Where the file ends: its last line and its last non-blank line.
#[derive(Clone, Copy)]
struct FileEnds {
    last_line: usize,
    last_nonblank: usize,
}

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

/// Collects the stream's frames and checks their numbers.
struct Collector<'a> {
    header: &'a Header,
    file: &'a str,
    options: &'a ReadOptions,
    warnings: &'a mut Warnings,
    data: Vec<f64>,
    mask: Option<Vec<bool>>,
    info: Vec<FrameInfo>,
    /// The last frame read: its number and its `Frame` line.
    last: Option<(i64, usize)>,
    /// Jumps in the frame numbers: (line, previous number, number, numbers missing).
    gaps: Vec<(usize, i64, i64, i128)>,
}

impl<'a> Collector<'a> {
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
            mask: None,
            info: Vec::new(),
            last: None,
            gaps: Vec::new(),
        }
    }

    /// Reads every frame of `stream` (the file ends as `ends` says).
    fn collect(
        mut self,
        stream: &mut TekscanStream<&[u8]>,
        ends: FileEnds,
    ) -> Result<Body, IoError> {
        let (mut values, mut present) = (Vec::new(), Vec::new());
        let mut dropped_truncated = false;
        loop {
            match stream.read_frame(&mut values, &mut present) {
                Ok(Some(frame)) => {
                    self.check_step(frame.number, frame.line)?;
                    if self.info.is_empty() && frame.has_absent {
                        self.mask = Some(present.clone());
                    }
                    self.data.extend_from_slice(&values);
                    self.info.push(FrameInfo {
                        number: frame.number,
                        suffix: stream.take_suffix(),
                    });
                    self.last = Some((frame.number, frame.line));
                }
                Ok(None) => break,
                Err(Stop::Error(err)) => return Err(err),
                Err(Stop::Fault(fault)) => {
                    self.truncated(fault, ends.last_nonblank)?;
                    dropped_truncated = true;
                    break;
                }
            }
        }
        report_gaps(&self.gaps, self.file, self.warnings);
        if self.info.is_empty() {
            let Self { header, file, .. } = self;
            let (rows, cols) = (header.grid.rows, header.grid.cols);
            return Err(IoError::parse(
                file,
                ends.last_line,
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
            data: self.data,
            mask: self.mask,
            info: self.info,
            terminator: stream.terminator(),
            dropped_truncated,
        })
    }

    /// A fault ends the file: an error, unless it is a truncated last frame (the input ends inside
    /// it, or its last row, the file's last non-blank line, is short) read leniently, which is dropped
    /// with a warning. The frame's number is checked first: its `Frame` line came before the fault.
    fn truncated(&mut self, fault: Fault, last_nonblank: usize) -> Result<(), IoError> {
        if let Some(at) = fault.frame.as_ref().filter(|at| at.framed) {
            self.check_step(at.number, at.line)?;
        }
        let number = fault.frame.as_ref().map_or(0, |at| at.number);
        let message = match &fault.kind {
            FaultKind::EndedInsideFrame { .. } => fault.message(Reading::File),
            FaultKind::Row {
                row,
                fault: RowFault::Count { found, cols },
            } if found < cols && fault.line == last_nonblank => format!(
                "frame {number} is truncated: its row {} has {found} of {cols} values (COLS) at the \
                 end of the file",
                row + 1,
            ),
            _ => return Err(fault.into_error(self.file, Reading::File)),
        };
        let (file, line_no) = (self.file, fault.line);
        if !self.options.lenient {
            return Err(IoError::parse(
                file,
                line_no,
                format!("{message} (read leniently to drop it)"),
            ));
        }
        self.warnings
            .push(format!("{file} line {line_no}: {message}; frame dropped"));
        Ok(())
    }

    /// Frame `number` (its `Frame` line `line_no`) after the last one: going back or repeating is an
    /// error (a warning when lenient); a jump is noted for the gap warnings.
    fn check_step(&mut self, number: i64, line_no: usize) -> Result<(), IoError> {
        let Some((prev, prev_line)) = self.last else {
            return Ok(());
        };
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
