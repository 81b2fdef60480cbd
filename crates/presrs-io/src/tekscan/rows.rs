//! One data row of a frame: its cells parsed onto the frame, checked against `COLS` and, when asked,
//! against the outline (`B` cells) of the first frame.

use crate::textutil::{CellError, for_each_cell, parse_cell};

/// What is wrong with a row. When a row has several faults, a file's reader reports the first in
/// this order: an empty cell, the cell count, then the first bad cell from the left (so that a last
/// row cut inside a number, `12,1e`, reads as truncated); a stream's reports the first bad cell first
/// (see [`Precedence`]).
#[derive(Clone, Debug, PartialEq)]
pub(super) enum RowFault {
    /// Cell `col` (0-based) is empty between two commas.
    Empty { col: usize },
    /// `found` cells where `cols` (`COLS`) are expected.
    Count { found: usize, cols: usize },
    /// Cell `col` is not a finite number or `B`.
    Cell {
        col: usize,
        cell: String,
        error: CellError,
    },
    /// Cell `col` is present (`present`) where the first frame (`first`) has `B`, or the other way.
    Outline {
        col: usize,
        present: bool,
        first: i64,
    },
}

/// Which fault of a row with several is reported.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Precedence {
    /// An empty cell, the count, then the first bad cell (a file).
    CountFirst,
    /// The first bad cell, an empty cell, then the count (a stream).
    CellsFirst,
}

/// The outline a row must follow: the first frame's number and its presence flags for this row.
pub(super) type RowOutline<'a> = (i64, &'a [bool]);

/// Appends the `cols` cells of `line` to `values` and `present`; returns whether some sensel is
/// absent. On a fault, appends nothing.
pub(super) fn parse_row(
    line: &str,
    cols: usize,
    values: &mut Vec<f64>,
    present: &mut Vec<bool>,
    outline: Option<RowOutline<'_>>,
    precedence: Precedence,
) -> Result<bool, RowFault> {
    let start_len = values.len();
    let mut cell_fault = None;
    let mut absent = false;
    let split = for_each_cell(line, |col, cell| {
        if col >= cols {
            return false;
        }
        let here = match parse_cell(cell) {
            Ok(parsed) => parsed.push_to(values, present),
            Err(error) => {
                cell_fault = Some(RowFault::Cell {
                    col,
                    cell: cell.to_owned(),
                    error,
                });
                return false;
            }
        };
        if let Some((first, expected)) = outline
            && expected.get(col).is_some_and(|&there| there != here)
        {
            cell_fault = Some(RowFault::Outline {
                col,
                present: here,
                first,
            });
            return false;
        }
        absent |= !here;
        true
    });
    let split_fault = match split {
        Err(col) => Some(RowFault::Empty { col }),
        Ok(found) if found != cols => Some(RowFault::Count { found, cols }),
        Ok(_) => None,
    };
    let fault = match precedence {
        Precedence::CountFirst => split_fault.or(cell_fault),
        Precedence::CellsFirst => cell_fault.or(split_fault),
    };
    match fault {
        Some(fault) => {
            values.truncate(start_len);
            present.truncate(start_len);
            Err(fault)
        }
        None => Ok(absent),
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    fn row(line: &str, outline: Option<RowOutline<'_>>) -> Result<Vec<f64>, RowFault> {
        let (mut values, mut present) = (vec![9.0], vec![true]);
        parse_row(
            line,
            3,
            &mut values,
            &mut present,
            outline,
            Precedence::CountFirst,
        )?;
        Ok(values[1..].to_vec())
    }

    #[test]
    fn faults_come_in_a_fixed_order() {
        assert_eq!(row("1, 2,B,", None), Ok(vec![1.0, 2.0, 0.0]));
        // An empty cell before a bad one or a wrong count.
        assert_eq!(row("x,,3,4", None), Err(RowFault::Empty { col: 1 }));
        // The count before a bad cell.
        assert_eq!(row("x,2", None), Err(RowFault::Count { found: 2, cols: 3 }));
        assert!(matches!(
            row("1,x,nan", None),
            Err(RowFault::Cell { col: 1, .. })
        ));
        let outline = [true, false, true];
        assert_eq!(
            row("1,2,x", Some((7, &outline))),
            Err(RowFault::Outline {
                col: 1,
                present: true,
                first: 7
            })
        );
        assert_eq!(row("1,B,3", Some((7, &outline))), Ok(vec![1.0, 0.0, 3.0]));
        // A stream names the bad cell first.
        let (mut values, mut present) = (Vec::new(), Vec::new());
        let fault = parse_row(
            "x,,3,4",
            3,
            &mut values,
            &mut present,
            None,
            Precedence::CellsFirst,
        );
        assert!(
            matches!(fault, Err(RowFault::Cell { col: 0, .. })),
            "{fault:?}"
        );
        assert!(values.is_empty() && present.is_empty());
    }
}
