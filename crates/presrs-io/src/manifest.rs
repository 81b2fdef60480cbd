//! Dataset manifests: a CSV file with a header row naming each sample (see `docs/interface.md`).
//!
//! ```text
//! path,label,condition,group,frame,load
//! recordings/wood_G1_000.asf,wood,G1,trial0,,
//! ```
//! `path` is required; `label`, `condition`, `group`, `frame` (0-based) and `load` are optional; any other
//! column is kept (it can be named by `--leave-one-out`). Paths are relative to the manifest's folder.
//!
//! The known column names are matched whatever their case (`Path,Label` reads as `path,label`); other
//! column names are kept as written. Every row has as many fields as the header (empty fields are
//! written as nothing between commas: `a.png,wood,,,,`); a row with fewer or more is an error naming its
//! line, as is a `"` that does not open and close a whole quoted field (an unterminated quote would
//! otherwise swallow the rest of the file into one field).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};

use crate::error::IoError;

/// The columns the manifest format gives a meaning to.
pub const KNOWN_COLUMNS: [&str; 6] = ["path", "label", "condition", "group", "frame", "load"];

/// One sample line of a manifest.
#[derive(Clone, Debug, PartialEq)]
pub struct ManifestRow {
    /// 1-based line number in the manifest file (for error messages).
    pub line: usize,
    /// The path as written in the manifest.
    pub path_text: String,
    /// The path resolved against the manifest's folder.
    pub path: PathBuf,
    pub label: Option<String>,
    pub condition: Option<String>,
    pub group: Option<String>,
    /// 0-based frame index inside a movie.
    pub frame: Option<usize>,
    /// The `frame` field as written (for [`Self::column`]).
    pub frame_text: Option<String>,
    pub load: Option<f64>,
    /// The `load` field as written (for [`Self::column`]).
    pub load_text: Option<String>,
    /// Every other column, by header name (empty cells omitted).
    pub extra: BTreeMap<String, String>,
}

impl ManifestRow {
    /// The value of any column by its header name, as written in the manifest (`path`, `label`,
    /// `condition`, `group`, `frame`, `load`, or an extra column); `None` when the field is empty.
    pub fn column(&self, name: &str) -> Option<&str> {
        match name {
            "path" => Some(&self.path_text),
            "label" => self.label.as_deref(),
            "condition" => self.condition.as_deref(),
            "group" => self.group.as_deref(),
            "frame" => self.frame_text.as_deref(),
            "load" => self.load_text.as_deref(),
            _ => self.extra.get(name).map(String::as_str),
        }
    }
}

/// A parsed manifest.
#[derive(Clone, Debug, PartialEq)]
pub struct Manifest {
    /// The manifest file.
    pub source: PathBuf,
    /// Header names in file order.
    pub columns: Vec<String>,
    pub rows: Vec<ManifestRow>,
    /// SHA-256 of the manifest's bytes, hex: identifies the dataset in a model's provenance.
    pub sha256: String,
}

impl Manifest {
    /// Whether the header has this column.
    pub fn has_column(&self, name: &str) -> bool {
        self.columns.iter().any(|column| column == name)
    }

    /// An error unless the header has column `name`, for callers that need it (`label` for training
    /// and evaluation). It names line 1, the missing column, the columns there are, and `why`.
    pub fn require_column(&self, name: &str, why: &str) -> Result<(), IoError> {
        if self.has_column(name) {
            return Ok(());
        }
        Err(IoError::parse(
            &self.source.display().to_string(),
            1,
            format!(
                "the header has no `{name}` column (columns: {}); {why}",
                self.columns.join(",")
            ),
        ))
    }

    /// An error naming a manifest line, for callers that find a problem with a row later (e.g. its file).
    pub fn row_error(
        &self,
        row: &ManifestRow,
        message: impl Into<crate::message::Message>,
    ) -> IoError {
        IoError::parse(&self.source.display().to_string(), row.line, message)
    }
}

/// Reads and checks a manifest file.
pub fn read_manifest(path: &Path) -> Result<Manifest, IoError> {
    let bytes = std::fs::read(path).map_err(|source| IoError::io("read", path, source))?;
    let base = path.parent().unwrap_or(Path::new(""));
    parse_manifest(&bytes, path, base)
}

/// Parses manifest bytes; `source` names the file in errors and `base` is the folder paths are relative to.
pub fn parse_manifest(bytes: &[u8], source: &Path, base: &Path) -> Result<Manifest, IoError> {
    let file = source.display().to_string();
    let sha256 = hex(&Sha256::digest(bytes));
    let text = manifest_text(bytes, &file)?;
    check_quotes(text).map_err(|(line, message)| IoError::parse(&file, line, message))?;
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        // Rows of the wrong length are errors below, with a message naming the line.
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let csv_error = |err: csv::Error| csv_error_at_line(&file, text, err);
    let header = ManifestHeader::parse(reader.headers().map_err(csv_error)?, &file)?;
    let mut rows = Vec::new();
    for record in reader.records() {
        let record = record.map_err(csv_error)?;
        let line = record.position().map_or(0, |pos| line_at(text, pos.byte()));
        if record.iter().all(str::is_empty) {
            continue;
        }
        rows.push(header.row(&record, &file, line, base)?);
    }
    if rows.is_empty() {
        return Err(IoError::format(
            &file,
            "the manifest lists no samples (only a header)",
        ));
    }
    Ok(Manifest {
        source: source.to_path_buf(),
        columns: header.columns,
        rows,
        sha256,
    })
}

/// The manifest's text: UTF-8 (UTF-16 and other bytes are errors naming the line), without a BOM.
fn manifest_text<'a>(bytes: &'a [u8], file: &str) -> Result<&'a str, IoError> {
    let text = std::str::from_utf8(bytes).map_err(|err| {
        let line = 1 + bytes[..err.valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        let utf16 = bytes.starts_with(b"\xFF\xFE") || bytes.starts_with(b"\xFE\xFF");
        if utf16 {
            IoError::parse(
                file,
                1,
                "UTF-16 text; a manifest is a UTF-8 CSV file (save it as \"CSV UTF-8\")",
            )
        } else {
            IoError::parse(file, line, "not UTF-8 text; a manifest is a CSV file")
        }
    })?;
    Ok(text.strip_prefix('\u{feff}').unwrap_or(text))
}

/// The 1-based line of byte offset `byte` in `text`. The csv crate's own line count skips blank lines,
/// so newlines are counted up to the offset instead; a record's position can point at the line end
/// before it (CRLF), so line ends are skipped first.
fn line_at(text: &str, byte: u64) -> usize {
    let bytes = text.as_bytes();
    let mut at = (byte as usize).min(bytes.len());
    while at < bytes.len() && matches!(bytes[at], b'\r' | b'\n') {
        at += 1;
    }
    1 + bytes[..at].iter().filter(|&&b| b == b'\n').count()
}

/// A csv reader's error as a parse error naming the manifest line.
fn csv_error_at_line(file: &str, text: &str, err: csv::Error) -> IoError {
    let line = err.position().map_or(1, |pos| line_at(text, pos.byte()));
    let message = match err.kind() {
        csv::ErrorKind::UnequalLengths {
            expected_len, len, ..
        } => format!("{len} fields, expected {expected_len} (as many as the header)"),
        _ => err.to_string(),
    };
    IoError::parse(file, line, message)
}

/// The header row: the column names (known names lower-cased) and where the known columns are.
#[derive(Debug)]
struct ManifestHeader {
    columns: Vec<String>,
    path: usize,
    label: Option<usize>,
    condition: Option<usize>,
    group: Option<usize>,
    frame: Option<usize>,
    load: Option<usize>,
}

impl ManifestHeader {
    /// Checks the header: not empty, a `path` column, no name twice. Errors name line 1.
    fn parse(record: &csv::StringRecord, file: &str) -> Result<Self, IoError> {
        // The known names in any case (`Path` is `path`); other names as written.
        let columns: Vec<String> = record
            .iter()
            .map(|name| {
                let lower = name.to_ascii_lowercase();
                if KNOWN_COLUMNS.contains(&lower.as_str()) {
                    lower
                } else {
                    name.to_owned()
                }
            })
            .collect();
        if columns.iter().all(String::is_empty) {
            return Err(IoError::parse(
                file,
                1,
                "empty manifest: expected a header row starting with `path`",
            ));
        }
        let index_of = |name: &str| columns.iter().position(|column| column == name);
        let path = index_of("path").ok_or_else(|| {
            IoError::parse(
                file,
                1,
                format!(
                    "the header has no `path` column (found: {})",
                    columns.join(",")
                ),
            )
        })?;
        for (i, name) in columns.iter().enumerate() {
            if columns[..i].contains(name) {
                return Err(IoError::parse(
                    file,
                    1,
                    format!("column `{name}` appears twice in the header"),
                ));
            }
        }
        let [label, condition, group, frame, load] =
            ["label", "condition", "group", "frame", "load"].map(index_of);
        Ok(Self {
            columns,
            path,
            label,
            condition,
            group,
            frame,
            load,
        })
    }

    /// One sample row (not blank) at 1-based `line`; paths resolved against `base`.
    fn row(
        &self,
        record: &csv::StringRecord,
        file: &str,
        line: usize,
        base: &Path,
    ) -> Result<ManifestRow, IoError> {
        self.check_field_count(record, file, line)?;
        let cell = |index: Option<usize>| -> Option<String> {
            index
                .and_then(|i| record.get(i))
                .filter(|value| !value.is_empty())
                .map(str::to_owned)
        };
        let path_text = cell(Some(self.path))
            .ok_or_else(|| IoError::parse(file, line, "field `path` is empty"))?;
        let frame_text = cell(self.frame);
        let frame = parse_frame_field(frame_text.as_deref(), file, line)?;
        let load_text = cell(self.load);
        let load = parse_load_field(load_text.as_deref(), file, line)?;
        let extra = self
            .columns
            .iter()
            .enumerate()
            .filter(|(_, name)| !KNOWN_COLUMNS.contains(&name.as_str()))
            .filter_map(|(i, name)| cell(Some(i)).map(|value| (name.clone(), value)))
            .collect();
        let path = {
            let given = PathBuf::from(&path_text);
            if given.is_absolute() {
                given
            } else {
                base.join(given)
            }
        };
        Ok(ManifestRow {
            line,
            path_text,
            path,
            label: cell(self.label),
            condition: cell(self.condition),
            group: cell(self.group),
            frame,
            frame_text,
            load,
            load_text,
            extra,
        })
    }

    /// An error naming the line unless the row has as many fields as the header.
    fn check_field_count(
        &self,
        record: &csv::StringRecord,
        file: &str,
        line: usize,
    ) -> Result<(), IoError> {
        let columns = &self.columns;
        if record.len() == columns.len() {
            return Ok(());
        }
        Err(IoError::parse(
            file,
            line,
            format!(
                "{} fields, expected {} (as many as the header: {}){}",
                record.len(),
                columns.len(),
                columns.join(","),
                if record.len() < columns.len() {
                    "; write an empty field as nothing between commas (`a.png,wood,,`)"
                } else {
                    ""
                }
            ),
        ))
    }
}

/// The `frame` field: a 0-based frame index, or nothing when empty.
fn parse_frame_field(
    text: Option<&str>,
    file: &str,
    line: usize,
) -> Result<Option<usize>, IoError> {
    let Some(text) = text else {
        return Ok(None);
    };
    let frame = text.parse::<usize>().map_err(|_| {
        IoError::parse(
            file,
            line,
            format!("field `frame` is {text:?}, expected a 0-based frame index (a whole number) or empty"),
        )
    })?;
    Ok(Some(frame))
}

/// The `load` field: a positive finite number, or nothing when empty.
fn parse_load_field(text: Option<&str>, file: &str, line: usize) -> Result<Option<f64>, IoError> {
    let Some(text) = text else {
        return Ok(None);
    };
    let value = text
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite() && *v > 0.0);
    let load = value.ok_or_else(|| {
        IoError::parse(
            file,
            line,
            format!("field `load` is {text:?}, expected a positive number or empty"),
        )
    })?;
    Ok(Some(load))
}

/// Checks that every `"` opens or closes a quoted field (CSV as RFC 4180 writes it: a quoted field
/// starts with `"`, doubles the `"` it holds and ends with `"`). The csv reader takes a quote that is
/// never closed as the start of one field running to the end of the file, and a `"` inside an
/// unquoted field as text: both are errors here, at the 1-based line and column of the quote.
fn check_quotes(text: &str) -> Result<(), (usize, String)> {
    let (mut line, mut col) = (1, 0);
    // Where the open quoted field started, if in one.
    let mut open: Option<(usize, usize)> = None;
    let mut field_start = true;
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        col += 1;
        if let Some((open_line, open_col)) = open {
            match c {
                '"' if chars.peek() == Some(&'"') => {
                    chars.next();
                    col += 1;
                }
                '"' => {
                    open = None;
                    // Only blanks may follow the closing quote before the next field or line.
                    while let Some(&next) = chars.peek() {
                        if next == ',' || next == '\n' || next == '\r' {
                            break;
                        }
                        col += 1;
                        if !next.is_whitespace() {
                            return Err((
                                line,
                                format!(
                                    "column {col}: `{next}` after the quoted field that starts at \
                                     line {open_line} column {open_col}; expected `,` or the end of \
                                     the line (write a `\"` inside a quoted field as `\"\"`)"
                                ),
                            ));
                        }
                        chars.next();
                    }
                }
                '\n' => {
                    line += 1;
                    col = 0;
                }
                _ => {}
            }
            continue;
        }
        match c {
            '"' if field_start => {
                open = Some((line, col));
                field_start = false;
            }
            '"' => {
                return Err((
                    line,
                    format!(
                        "column {col}: a `\"` inside an unquoted field; a quoted field starts with \
                         `\"` right after the comma (no blanks before it) and doubles the quotes it \
                         holds (`\"a\"\"b\"`)"
                    ),
                ));
            }
            ',' | '\r' => field_start = true,
            '\n' => {
                line += 1;
                col = 0;
                field_start = true;
            }
            _ => field_start = false,
        }
    }
    match open {
        Some((open_line, open_col)) => Err((
            open_line,
            format!(
                "column {open_col}: this `\"` opens a quoted field that is never closed (the rest of \
                 the file would be one field); close it with `\"`"
            ),
        )),
        None => Ok(()),
    }
}

/// Lower-case hex of bytes.
pub(crate) fn hex(bytes: &[u8]) -> String {
    use std::fmt::Write;
    bytes
        .iter()
        .fold(String::with_capacity(bytes.len() * 2), |mut out, b| {
            let _ = write!(out, "{b:02x}");
            out
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Manifest, IoError> {
        parse_manifest(text.as_bytes(), Path::new("m.csv"), Path::new("/data"))
    }

    #[test]
    fn the_header_finds_the_known_columns_in_any_case() {
        let record = csv::StringRecord::from(vec!["Label", "PATH", "subject", "Frame"]);
        let header = ManifestHeader::parse(&record, "m.csv").unwrap();
        assert_eq!(header.columns, ["label", "path", "subject", "frame"]);
        assert_eq!(header.path, 1);
        assert_eq!((header.label, header.frame), (Some(0), Some(3)));
        assert_eq!(
            (header.condition, header.group, header.load),
            (None, None, None)
        );
        let twice = csv::StringRecord::from(vec!["path", "Path"]);
        let err = ManifestHeader::parse(&twice, "m.csv")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("line 1") && err.contains("`path` appears twice"),
            "{err}"
        );
        let empty = csv::StringRecord::from(vec![""]);
        let err = ManifestHeader::parse(&empty, "m.csv")
            .unwrap_err()
            .to_string();
        assert!(err.contains("empty manifest"), "{err}");
    }

    #[test]
    fn lines_are_counted_from_byte_offsets_past_line_ends() {
        let text = "path\r\n\r\na.png\nb.png\n";
        assert_eq!(line_at(text, 0), 1);
        // The offset of the CRLF ending line 1 counts as the line after the blank line 2.
        assert_eq!(line_at(text, 4), 3);
        assert_eq!(line_at(text, 8), 3);
        assert_eq!(line_at(text, 14), 4);
        assert_eq!(line_at(text, 1000), 5);
    }

    #[test]
    fn frame_and_load_fields_parse_or_name_the_line() {
        assert_eq!(parse_frame_field(None, "m.csv", 2).unwrap(), None);
        assert_eq!(parse_frame_field(Some("7"), "m.csv", 2).unwrap(), Some(7));
        let err = parse_frame_field(Some("-1"), "m.csv", 9)
            .unwrap_err()
            .to_string();
        assert!(err.contains("line 9") && err.contains("`frame`"), "{err}");
        assert_eq!(
            parse_load_field(Some("2.5"), "m.csv", 2).unwrap(),
            Some(2.5)
        );
        assert_eq!(parse_load_field(None, "m.csv", 2).unwrap(), None);
        for bad in ["0", "-3", "inf", "NaN", "x"] {
            assert!(parse_load_field(Some(bad), "m.csv", 2).is_err(), "{bad}");
        }
    }

    #[test]
    fn reads_the_contract_example() {
        let m = parse(
            "path,label,condition,group,frame,load,subject\n\
             recordings/wood_G1_000.asf,wood,G1,trial0,,,s1\n\
             images/carpet_17.png,carpet,G2,,,,\n\
             /abs/S3_air_B1.txt,Air,,S3,4,12.5,\n",
        )
        .unwrap();
        assert_eq!(m.rows.len(), 3);
        let first = &m.rows[0];
        assert_eq!(
            first.path,
            PathBuf::from("/data/recordings/wood_G1_000.asf")
        );
        assert_eq!(first.label.as_deref(), Some("wood"));
        assert_eq!(first.condition.as_deref(), Some("G1"));
        assert_eq!(first.frame, None);
        assert_eq!(first.column("subject"), Some("s1"));
        assert_eq!(first.line, 2);
        let third = &m.rows[2];
        assert_eq!(third.path, PathBuf::from("/abs/S3_air_B1.txt"));
        assert_eq!(third.frame, Some(4));
        assert_eq!(third.load, Some(12.5));
        assert_eq!(third.group.as_deref(), Some("S3"));
        assert_eq!(m.sha256.len(), 64);
    }

    #[test]
    fn errors_name_the_line_and_field() {
        let err = parse("path,label,frame\na.png,wood,x\n")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("m.csv line 2") && err.contains("`frame`"),
            "{err}"
        );
        let err = parse("path,label\na.png,wood\nb.png,wood,extra\n")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("line 3") && err.contains("3 fields, expected 2"),
            "{err}"
        );
        let err = parse("file,label\na.png,wood\n").unwrap_err().to_string();
        assert!(err.contains("no `path` column"), "{err}");
        let err = parse("path,label\n,wood\n").unwrap_err().to_string();
        assert!(
            err.contains("line 2") && err.contains("`path` is empty"),
            "{err}"
        );
        let err = parse("path,load\na.png,-3\n").unwrap_err().to_string();
        assert!(err.contains("`load`"), "{err}");
        assert!(parse("").is_err());
        assert!(parse("path,label\n").is_err());
    }

    #[test]
    fn column_gives_every_field_as_written() {
        let m =
            parse("path,label,frame,load,subject\nr/a.asf,wood,3,12.50,s1\nb.png,,,,\n").unwrap();
        let row = &m.rows[0];
        for (name, value) in [
            ("path", "r/a.asf"),
            ("label", "wood"),
            ("frame", "3"),
            ("load", "12.50"),
            ("subject", "s1"),
        ] {
            assert_eq!(row.column(name), Some(value), "{name}");
        }
        assert_eq!((row.frame, row.load), (Some(3), Some(12.5)));
        let row = &m.rows[1];
        assert_eq!(row.column("path"), Some("b.png"));
        for name in ["label", "frame", "load", "subject", "nope"] {
            assert_eq!(row.column(name), None, "{name}");
        }
    }

    #[test]
    fn rows_must_have_as_many_fields_as_the_header() {
        let err = parse("path,label,condition\na.png,wood,G1\nb.png,wood\n")
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("m.csv line 3: 2 fields, expected 3 (as many as the header: path,label,condition); write an empty field"),
            "{err}"
        );
        let err = parse("path,label\na.png\n").unwrap_err().to_string();
        assert!(err.contains("line 2: 1 fields, expected 2"), "{err}");
        // Empty trailing fields written out are fine; a line of commas only is a blank line.
        let m = parse("path,label,condition\na.png,wood,\n,,\nb.png,,\n").unwrap();
        assert_eq!(m.rows.len(), 2);
    }

    #[test]
    fn unbalanced_quotes_are_errors_naming_line_and_column() {
        let err = parse("path,label\na.png,wood\n\"b.png,clay\nc.png,wood\n")
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with(
                "m.csv line 3: column 1: this `\"` opens a quoted field that is never closed"
            ),
            "{err}"
        );
        let err = parse("path,label\na\"b.png,wood\n")
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("m.csv line 2: column 2: a `\"` inside an unquoted field"),
            "{err}"
        );
        let err = parse("path,label\n\"a.png\"x,wood\n")
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with(
                "m.csv line 2: column 8: `x` after the quoted field that starts at line 2 column 1"
            ),
            "{err}"
        );
        let err = parse("path,label\na.png, \"wood\"\n")
            .unwrap_err()
            .to_string();
        assert!(err.contains("line 2: column 8"), "{err}");
        // Well-formed quoting: commas, doubled quotes and line breaks inside quotes.
        let m = parse("path,label\n\"q,uoted \"\"x\"\".png\",\"wo\nod\"\r\nb.png,clay\n").unwrap();
        assert_eq!(m.rows[0].path_text, "q,uoted \"x\".png");
        assert_eq!(m.rows[0].label.as_deref(), Some("wo\nod"));
        assert_eq!(m.rows[1].line, 4);
    }

    #[test]
    fn known_column_names_in_any_case_and_required_columns() {
        let m = parse("Path,LABEL,Condition,Subject\na.png,wood,G1,s1\n").unwrap();
        assert_eq!(m.columns, ["path", "label", "condition", "Subject"]);
        assert_eq!(m.rows[0].label.as_deref(), Some("wood"));
        assert_eq!(m.rows[0].column("Subject"), Some("s1"));
        assert!(m.require_column("label", "evaluation needs labels").is_ok());
        let err = parse("path,Path\na.png,b.png\n").unwrap_err().to_string();
        assert!(err.contains("column `path` appears twice"), "{err}");
        let m = parse("path,condition\na.png,G1\n").unwrap();
        let err = m
            .require_column("label", "evaluation needs a label for every sample")
            .unwrap_err()
            .to_string();
        assert_eq!(
            err,
            "m.csv line 1: the header has no `label` column (columns: path,condition); evaluation \
             needs a label for every sample"
        );
    }

    #[test]
    fn blank_lines_and_crlf_are_fine() {
        let m = parse("path,label\r\na.png,wood\r\n\r\nb.png,clay\r\n").unwrap();
        assert_eq!(m.rows.len(), 2);
        assert_eq!(m.rows[1].line, 4);
        assert_eq!(m.rows[1].label.as_deref(), Some("clay"));
    }
}
