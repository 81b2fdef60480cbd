//! The frames after the header: `Frame N` lines and rows of `COLS` cells, up to `@@` or the end.

use presrs_core::{FrameInfo, Grid};

use super::header::Header;
use super::lines::{clip, frame_line};
use crate::ReadOptions;
use crate::error::IoError;
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

pub(super) fn parse_frames(
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
pub(super) const MAX_GAP_WARNINGS: usize = 5;

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

pub(super) fn check_frame_count(
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
