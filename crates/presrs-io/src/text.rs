//! Plain text matrices (`.txt`, `.dat`, headerless `.csv`): one frame, one row per line.
//!
//! Values are separated by whitespace and/or commas (`1 2 3`, `1,2,3`, `1, 2, 3`, trailing commas allowed).
//! Blank lines, comma-only lines and comments (from `#` to the end of the line) are skipped. Every row must
//! have the same number of values. A `B` cell marks an absent sensel, as in TekScan files. NaN and
//! infinities are rejected.

use std::path::Path;

use presrs_core::{Grid, Recording, SensorMeta};

use crate::error::{IoError, display_name};
use crate::textutil::{decode_text, is_blank, numbered_lines, parse_cell, split_cells};

/// Reads a text matrix file as a one-frame recording (raw units, no frame period).
pub fn read_text_matrix(path: &Path) -> Result<Recording, IoError> {
    let bytes = std::fs::read(path).map_err(|source| IoError::io("read", path, source))?;
    parse_text_matrix(&decode_text(&bytes), &display_name(path))
}

/// Parses the text of a matrix file; `source_name` names it in error messages.
pub fn parse_text_matrix(text: &str, source_name: &str) -> Result<Recording, IoError> {
    let file = source_name;
    let mut values = Vec::new();
    let mut present = Vec::new();
    let mut any_absent = false;
    // (line number of the first row, number of values per row)
    let mut width: Option<(usize, usize)> = None;
    let mut rows = 0usize;
    let mut cells = Vec::new();
    for (line_no, raw) in numbered_lines(text) {
        let line = raw.split_once('#').map_or(raw, |(data, _comment)| data);
        if is_blank(line) {
            continue;
        }
        split_cells(line, &mut cells).map_err(|at| {
            IoError::parse(
                file,
                line_no,
                format!(
                    "value {} of row {} is empty; expected a number",
                    at + 1,
                    rows + 1
                ),
            )
        })?;
        match width {
            None => width = Some((line_no, cells.len())),
            Some((first_line, n)) if n != cells.len() => {
                return Err(IoError::parse(
                    file,
                    line_no,
                    format!(
                        "row {} has {} values, expected {n} like the first row (line {first_line})",
                        rows + 1,
                        cells.len()
                    ),
                ));
            }
            Some(_) => {}
        }
        for (col, cell) in cells.iter().enumerate() {
            match parse_cell(cell) {
                Ok(parsed) => any_absent |= !parsed.push_to(&mut values, &mut present),
                Err(err) => {
                    return Err(IoError::parse(
                        file,
                        line_no,
                        format!(
                            "row {} column {}: {}, found `{cell}`",
                            rows + 1,
                            col + 1,
                            err.expected(false)
                        ),
                    ));
                }
            }
        }
        rows += 1;
    }
    let Some((_, cols)) = width else {
        return Err(IoError::format(
            file,
            "no data: expected rows of numbers separated by spaces or commas",
        ));
    };
    let grid = Grid::new(rows, cols);
    let present = any_absent.then_some(present);
    Recording::new(grid, None, values, present, SensorMeta::default()).map_err(|source| {
        IoError::Model {
            file: file.to_owned(),
            source,
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_whitespace_comma_comments_and_blank_lines() {
        let text = "# a map\r\n1 2 3\n\n4,5,6,\r\n,,,\n 7, 8\t9  # trailing comment\n";
        let rec = parse_text_matrix(text, "m.txt").unwrap();
        assert_eq!(rec.grid(), Grid::new(3, 3));
        assert_eq!(rec.frame_count(), 1);
        assert_eq!(rec.data(), &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]);
        assert!(rec.present().is_none());
    }

    #[test]
    fn decimals_exponents_and_absent_cells() {
        let rec = parse_text_matrix("0.5 -1e3\nB 2.25\n", "d.dat").unwrap();
        assert_eq!(rec.data(), &[0.5, -1000.0, 0.0, 2.25]);
        assert_eq!(rec.present(), Some(&[true, true, false, true][..]));
    }

    #[test]
    fn ragged_rows_name_line_and_counts() {
        let err = parse_text_matrix("1 2 3\n# c\n4 5 6\n\n7 8\n", "r.txt").unwrap_err();
        assert_eq!(err.line(), Some(5));
        assert_eq!(
            err.to_string(),
            "r.txt line 5: row 3 has 2 values, expected 3 like the first row (line 1)"
        );
    }

    #[test]
    fn bad_values_and_empty() {
        let err = parse_text_matrix("1 2\n3 x\n", "b.txt")
            .unwrap_err()
            .to_string();
        assert_eq!(
            err,
            "b.txt line 2: row 2 column 2: expected a number, found `x`"
        );
        let err = parse_text_matrix("1 nan\n", "n.txt")
            .unwrap_err()
            .to_string();
        assert!(err.contains("line 1") && err.contains("finite"), "{err}");
        let err = parse_text_matrix("1,,2\n", "e.txt")
            .unwrap_err()
            .to_string();
        assert!(err.contains("line 1") && err.contains("value 2"), "{err}");
        let err = parse_text_matrix("# only a comment\n\n", "z.txt")
            .unwrap_err()
            .to_string();
        assert!(err.contains("z.txt") && err.contains("no data"), "{err}");
    }
}
