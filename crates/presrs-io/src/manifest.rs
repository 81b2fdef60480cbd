//! Dataset manifests: a CSV file with a header row naming each sample (see `shared/docs/interface.md`).
//!
//! ```text
//! path,label,condition,group,frame,load
//! recordings/wood_G1_000.asf,wood,G1,trial0,,
//! ```
//! `path` is required; `label`, `condition`, `group`, `frame` (0-based) and `load` are optional; any other
//! column is kept (it can be named by `--leave-one-out`). Paths are relative to the manifest's folder.

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
    pub load: Option<f64>,
    /// Every other column, by header name (empty cells omitted).
    pub extra: BTreeMap<String, String>,
}

impl ManifestRow {
    /// The value of any column by its header name (`label`, `condition`, `group`, or an extra column).
    pub fn column(&self, name: &str) -> Option<&str> {
        match name {
            "path" => Some(&self.path_text),
            "label" => self.label.as_deref(),
            "condition" => self.condition.as_deref(),
            "group" => self.group.as_deref(),
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

    /// An error naming a manifest line, for callers that find a problem with a row later (e.g. its file).
    pub fn row_error(&self, row: &ManifestRow, message: impl Into<String>) -> IoError {
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
    let text = std::str::from_utf8(bytes).map_err(|err| {
        let line = 1 + bytes[..err.valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        let utf16 = bytes.starts_with(b"\xFF\xFE") || bytes.starts_with(b"\xFE\xFF");
        if utf16 {
            IoError::parse(
                &file,
                1,
                "UTF-16 text; a manifest is a UTF-8 CSV file (save it as \"CSV UTF-8\")",
            )
        } else {
            IoError::parse(&file, line, "not UTF-8 text; a manifest is a CSV file")
        }
    })?;
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        // Short rows are fine (missing trailing cells are empty); long rows are an error below.
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    // The csv crate's own line count skips blank lines; count newlines up to the byte offset instead.
    // A record's position can point at the line end before it (CRLF), so skip line ends first.
    let line_at = |byte: u64| {
        let bytes = text.as_bytes();
        let mut at = (byte as usize).min(bytes.len());
        while at < bytes.len() && matches!(bytes[at], b'\r' | b'\n') {
            at += 1;
        }
        1 + bytes[..at].iter().filter(|&&b| b == b'\n').count()
    };
    let csv_error = |err: csv::Error| {
        let line = err.position().map_or(1, |pos| line_at(pos.byte()));
        let message = match err.kind() {
            csv::ErrorKind::UnequalLengths {
                expected_len, len, ..
            } => format!("{len} fields, expected {expected_len} (as many as the header)"),
            _ => err.to_string(),
        };
        IoError::parse(&file, line, message)
    };
    let columns: Vec<String> = reader
        .headers()
        .map_err(csv_error)?
        .iter()
        .map(str::to_owned)
        .collect();
    if columns.iter().all(String::is_empty) {
        return Err(IoError::parse(
            &file,
            1,
            "empty manifest: expected a header row starting with `path`",
        ));
    }
    let index_of = |name: &str| columns.iter().position(|column| column == name);
    let path_index = index_of("path").ok_or_else(|| {
        IoError::parse(
            &file,
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
                &file,
                1,
                format!("column `{name}` appears twice in the header"),
            ));
        }
    }
    let [label_i, condition_i, group_i, frame_i, load_i] =
        ["label", "condition", "group", "frame", "load"].map(index_of);
    let mut rows = Vec::new();
    for record in reader.records() {
        let record = record.map_err(csv_error)?;
        let line = record.position().map_or(0, |pos| line_at(pos.byte()));
        if record.iter().all(str::is_empty) {
            continue;
        }
        if record.len() > columns.len() {
            return Err(IoError::parse(
                &file,
                line,
                format!(
                    "{} fields, expected {} (as many as the header)",
                    record.len(),
                    columns.len()
                ),
            ));
        }
        let cell = |index: Option<usize>| -> Option<String> {
            index
                .and_then(|i| record.get(i))
                .filter(|value| !value.is_empty())
                .map(str::to_owned)
        };
        let path_text = cell(Some(path_index))
            .ok_or_else(|| IoError::parse(&file, line, "field `path` is empty"))?;
        let frame = match cell(frame_i) {
            Some(text) => Some(text.parse::<usize>().map_err(|_| {
                IoError::parse(
                    &file,
                    line,
                    format!("field `frame` is {text:?}, expected a 0-based frame index (a whole number) or empty"),
                )
            })?),
            None => None,
        };
        let load = match cell(load_i) {
            Some(text) => {
                let value = text
                    .parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite() && *v > 0.0);
                Some(value.ok_or_else(|| {
                    IoError::parse(
                        &file,
                        line,
                        format!("field `load` is {text:?}, expected a positive number or empty"),
                    )
                })?)
            }
            None => None,
        };
        let extra = columns
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
        rows.push(ManifestRow {
            line,
            path_text,
            path,
            label: cell(label_i),
            condition: cell(condition_i),
            group: cell(group_i),
            frame,
            load,
            extra,
        });
    }
    if rows.is_empty() {
        return Err(IoError::format(
            &file,
            "the manifest lists no samples (only a header)",
        ));
    }
    Ok(Manifest {
        source: source.to_path_buf(),
        columns,
        rows,
        sha256,
    })
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
    fn reads_the_contract_example() {
        let m = parse(
            "path,label,condition,group,frame,load,subject\n\
             recordings/wood_G1_000.asf,wood,G1,trial0,,,s1\n\
             images/carpet_17.png,carpet,G2,,,\n\
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
    fn blank_lines_and_crlf_are_fine() {
        let m = parse("path,label\r\na.png,wood\r\n\r\nb.png,clay\r\n").unwrap();
        assert_eq!(m.rows.len(), 2);
        assert_eq!(m.rows[1].line, 4);
        assert_eq!(m.rows[1].label.as_deref(), Some("clay"));
    }
}
