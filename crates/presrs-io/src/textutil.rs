//! Shared helpers for the text formats: decoding, line splitting, cell splitting, number formatting.

use std::borrow::Cow;

/// Decodes file bytes as text: UTF-16 (little or big endian) when the file starts with a UTF-16
/// byte-order mark or looks like UTF-16 ASCII text (every other byte zero), as Windows "Unicode" exports
/// are; else UTF-8 (a leading byte-order mark is dropped), or, when the bytes are not valid UTF-8,
/// Latin-1 (every byte is one character), which is what older Windows exports use. Decoding never fails
/// (invalid UTF-16 becomes U+FFFD), so a stray byte in a comment does not make a file unreadable.
pub(crate) fn decode_text(bytes: &[u8]) -> Cow<'_, str> {
    if let Some(big_endian) = utf16_order(bytes) {
        let body = if bytes.starts_with(b"\xFF\xFE") || bytes.starts_with(b"\xFE\xFF") {
            &bytes[2..]
        } else {
            bytes
        };
        let units = body.chunks_exact(2).map(|pair| {
            if big_endian {
                u16::from_be_bytes([pair[0], pair[1]])
            } else {
                u16::from_le_bytes([pair[0], pair[1]])
            }
        });
        return Cow::Owned(
            char::decode_utf16(units)
                .map(|c| c.unwrap_or(char::REPLACEMENT_CHARACTER))
                .collect(),
        );
    }
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    match std::str::from_utf8(bytes) {
        Ok(text) => Cow::Borrowed(text),
        Err(_) => Cow::Owned(bytes.iter().map(|&b| char::from(b)).collect()),
    }
}

/// `Some(big_endian)` when `bytes` are UTF-16: a byte-order mark, or (without one) an even length with
/// a zero high byte in every code unit of the first 256 bytes and some non-zero low byte.
fn utf16_order(bytes: &[u8]) -> Option<bool> {
    if bytes.starts_with(b"\xFF\xFE") {
        return Some(false);
    }
    if bytes.starts_with(b"\xFE\xFF") {
        return Some(true);
    }
    if bytes.len() < 4 || bytes.len() % 2 != 0 {
        return None;
    }
    let head = &bytes[..bytes.len().min(256)];
    let units = || head.chunks_exact(2);
    if units().all(|u| u[1] == 0) && units().any(|u| u[0] != 0) {
        return Some(false);
    }
    if units().all(|u| u[0] == 0) && units().any(|u| u[1] != 0) {
        return Some(true);
    }
    None
}

/// The lines of `text` with their 1-based numbers. Line breaks are `\n`, `\r\n` or a lone `\r`, mixed
/// freely; the breaks themselves are not part of the lines. A final line break does not start a new line.
pub(crate) fn numbered_lines(text: &str) -> Vec<(usize, &str)> {
    let mut lines = Vec::with_capacity(text.len() / 32 + 1);
    let bytes = text.as_bytes();
    let mut start = 0;
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'\n' => {
                lines.push(&text[start..i]);
                i += 1;
                start = i;
            }
            b'\r' => {
                lines.push(&text[start..i]);
                i += if bytes.get(i + 1) == Some(&b'\n') {
                    2
                } else {
                    1
                };
                start = i;
            }
            _ => i += 1,
        }
    }
    if start < bytes.len() {
        lines.push(&text[start..]);
    }
    lines
        .into_iter()
        .enumerate()
        .map(|(i, line)| (i + 1, line))
        .collect()
}

/// Whether a line holds nothing: only whitespace and commas (spreadsheets write `,,,,` for blank lines).
pub(crate) fn is_blank(line: &str) -> bool {
    line.chars().all(|c| c == ',' || c.is_whitespace())
}

/// Splits a data line into cells. Commas and whitespace both separate cells (`1,2,3`, `1 2 3`, `1, 2, 3`);
/// trailing commas are allowed. Returns `Err(k)` when cell `k` (0-based) is empty between two commas
/// (`1,,3`).
pub(crate) fn split_cells<'a>(line: &'a str, cells: &mut Vec<&'a str>) -> Result<(), usize> {
    cells.clear();
    for_each_cell(line, |_, cell| {
        cells.push(cell);
        true
    })
    .map(|_| ())
}

/// Calls `visit(index, cell)` for each cell of a data line, split as [`split_cells`] splits it, until
/// `visit` returns false (without collecting the cells). Returns the number of cells (counting on past
/// a stop), or `Err(k)` when cell `k` is empty between two commas.
pub(crate) fn for_each_cell<'a>(
    line: &'a str,
    mut visit: impl FnMut(usize, &'a str) -> bool,
) -> Result<usize, usize> {
    let line = line.trim();
    let mut count = 0;
    let mut go = true;
    let mut cell = |c: &'a str, count: &mut usize| {
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

/// One parsed cell of a data line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Cell {
    Value(f64),
    /// `B`: no sensel at this position.
    Absent,
}

impl Cell {
    /// The value a frame holds for the cell: an absent sensel reads 0 (its mask entry says it is absent).
    pub(crate) fn value(self) -> f64 {
        match self {
            Cell::Value(v) => v,
            Cell::Absent => 0.0,
        }
    }

    /// Appends the cell to a frame's values and presence mask; true if the sensel is present.
    pub(crate) fn push_to(self, values: &mut Vec<f64>, present: &mut Vec<bool>) -> bool {
        let here = matches!(self, Cell::Value(_));
        values.push(self.value());
        present.push(here);
        here
    }
}

/// Why a cell is not a finite number or `B`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum CellError {
    NotANumber,
    NotFinite,
}

/// Parses a cell: a decimal number (integer, decimal or exponent notation) or `B` (absent sensel).
pub(crate) fn parse_cell(cell: &str) -> Result<Cell, CellError> {
    if cell == "B" || cell == "b" {
        return Ok(Cell::Absent);
    }
    // Rust's float parser accepts "inf", "infinity" and "nan"; those are reported as non-finite below.
    match cell.parse::<f64>() {
        Ok(value) if value.is_finite() => Ok(Cell::Value(value)),
        Ok(_) => Err(CellError::NotFinite),
        Err(_) => Err(CellError::NotANumber),
    }
}

impl CellError {
    /// What was expected, for error messages.
    pub(crate) fn expected(self, allow_absent: bool) -> &'static str {
        match (self, allow_absent) {
            (Self::NotANumber, true) => "expected a number or `B` (no sensel)",
            (Self::NotANumber, false) => "expected a number",
            (Self::NotFinite, _) => "expected a finite number",
        }
    }
}

/// Largest magnitude below which integral values are written without a decimal point: every integer up
/// to 2^53 is exact in `f64`, so `i64` formatting reproduces the value.
const EXACT_INT_LIMIT: f64 = 9_007_199_254_740_992.0;

/// Appends `value` so that parsing the text gives back exactly the same `f64`: integers without a decimal
/// point (`-0` for negative zero), anything else with Rust's shortest round-trip formatting.
pub(crate) fn push_number(buf: &mut Vec<u8>, value: f64) {
    use std::io::Write;
    if value == 0.0 {
        buf.extend_from_slice(if value.is_sign_negative() {
            b"-0"
        } else {
            b"0"
        });
    } else if value.fract() == 0.0 && value.abs() < EXACT_INT_LIMIT {
        // `as` is exact here: the value is integral and within i64 range.
        push_int(buf, value as i64);
    } else {
        // Writing to a Vec cannot fail.
        let _ = write!(buf, "{value}");
    }
}

/// Appends a decimal integer without going through the formatting machinery.
pub(crate) fn push_int(buf: &mut Vec<u8>, value: i64) {
    let mut digits = [0u8; 20];
    let mut n = value.unsigned_abs();
    let mut at = digits.len();
    loop {
        at -= 1;
        digits[at] = b'0' + (n % 10) as u8;
        n /= 10;
        if n == 0 {
            break;
        }
    }
    if value < 0 {
        buf.push(b'-');
    }
    buf.extend_from_slice(&digits[at..]);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_endings_mixed() {
        let lines = numbered_lines("a\r\nb\nc\rd\r\n\r\ne");
        assert_eq!(
            lines,
            vec![(1, "a"), (2, "b"), (3, "c"), (4, "d"), (5, ""), (6, "e")]
        );
        assert_eq!(numbered_lines("x\n"), vec![(1, "x")]);
        assert!(numbered_lines("").is_empty());
    }

    #[test]
    fn decoding() {
        assert_eq!(decode_text(b"\xEF\xBB\xBFROWS 1"), "ROWS 1");
        assert_eq!(decode_text(b"caf\xE9"), "caf\u{e9}");
        let utf16le: Vec<u8> = "\u{feff}ROWS 1\r\n"
            .encode_utf16()
            .flat_map(u16::to_le_bytes)
            .collect();
        assert_eq!(decode_text(&utf16le), "ROWS 1\r\n");
        assert_eq!(decode_text(&utf16le[2..]), "ROWS 1\r\n");
        let utf16be: Vec<u8> = "\u{feff}1 2\n"
            .encode_utf16()
            .flat_map(u16::to_be_bytes)
            .collect();
        assert_eq!(decode_text(&utf16be), "1 2\n");
        assert_eq!(decode_text(&utf16be[2..]), "1 2\n");
    }

    #[test]
    fn cells() {
        let mut cells = Vec::new();
        split_cells("1,2,B,", &mut cells).unwrap();
        assert_eq!(cells, ["1", "2", "B"]);
        split_cells(" 1  2\t3 ", &mut cells).unwrap();
        assert_eq!(cells, ["1", "2", "3"]);
        split_cells("1, 2 ,3,,", &mut cells).unwrap();
        assert_eq!(cells, ["1", "2", "3"]);
        assert_eq!(split_cells("1,,3", &mut cells), Err(1));
        assert!(is_blank(" ,,, \t"));
        assert!(!is_blank(",0,"));
        assert_eq!(parse_cell("B"), Ok(Cell::Absent));
        assert_eq!(parse_cell("1.5e2"), Ok(Cell::Value(150.0)));
        assert_eq!(parse_cell("NaN"), Err(CellError::NotFinite));
        assert_eq!(parse_cell("inf"), Err(CellError::NotFinite));
        assert_eq!(parse_cell("x1"), Err(CellError::NotANumber));
    }

    #[test]
    fn numbers_round_trip() {
        for value in [
            0.0,
            -0.0,
            1.0,
            -17.0,
            255.0,
            0.1,
            1e-300,
            -2.5e300,
            f64::MAX,
            f64::MIN_POSITIVE,
            5e-324,
            9_007_199_254_740_993.0,
            1234567.125,
            i64::MIN as f64,
        ] {
            let mut buf = Vec::new();
            push_number(&mut buf, value);
            let text = String::from_utf8(buf).unwrap();
            let back: f64 = text.parse().unwrap();
            assert_eq!(back.to_bits(), value.to_bits(), "{value} -> {text}");
        }
        let mut buf = Vec::new();
        push_number(&mut buf, 42.0);
        push_int(&mut buf, i64::MIN);
        assert_eq!(buf, b"42-9223372036854775808");
    }
}
