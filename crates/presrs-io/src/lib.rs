#![doc = include_str!("../README.md")]

pub mod atomic;
pub mod error;
pub mod frame_protocol;
pub mod manifest;
pub mod model_file;
pub mod npy;
mod parsed;
pub mod png;
pub mod tekscan;
pub mod tekscan_stream;
pub mod text;
mod textutil;

use std::path::Path;

use presrs_core::Recording;

pub use atomic::{write_atomic, write_atomic_with};
pub use error::IoError;
pub use parsed::{ArrayAxes, Axis, Parsed, ReadOptions};
pub use tekscan::{parse_tekscan, read_tekscan, write_tekscan, write_tekscan_file};

/// How strictly to read.
/// The file formats [`read_recording`] knows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileKind {
    TekScan,
    Npy,
    Png,
    TextMatrix,
}

/// Reads any supported recording file strictly (see [`read_recording_with`]).
pub fn read_recording(path: &Path) -> Result<Recording, IoError> {
    Ok(read_recording_with(path, &ReadOptions::default())?.recording)
}

/// Reads any supported recording file: a TekScan ASCII movie or snapshot, a `.npy` array, a greyscale
/// PNG or a plain text matrix. The format is chosen by content first (NumPy and PNG magic bytes, a
/// TekScan header), then by extension (see [`detect_kind`]).
pub fn read_recording_with(path: &Path, options: &ReadOptions) -> Result<Parsed, IoError> {
    let bytes = std::fs::read(path).map_err(|source| IoError::io("read", path, source))?;
    let name = error::display_name(path);
    let plain = |recording| Parsed {
        recording,
        warnings: Vec::new(),
    };
    match detect_kind(path, &bytes)? {
        FileKind::Npy => {
            npy::parse_npy_with(&bytes, &name, options.axes).map(|(recording, warnings)| Parsed {
                recording,
                warnings,
            })
        }
        FileKind::Png => png::parse_png(&bytes, &name).map(plain),
        FileKind::TekScan => tekscan::parse_tekscan(&textutil::decode_text(&bytes), &name, options),
        FileKind::TextMatrix => {
            text::parse_text_matrix(&textutil::decode_text(&bytes), &name).map(plain)
        }
    }
}

/// Decides the format of a file from its content and extension:
///
/// 1. NumPy or PNG magic bytes win whatever the extension says;
/// 2. a file named `.npy` or `.png` without the matching magic bytes is an error (it is not what its
///    name says: a clearer message than a parse error from another format);
/// 3. text with a TekScan header (`DATA_TYPE` or `ASCII_DATA` among the first lines) is TekScan, as is
///    any `.asf` file (which then gets TekScan's error messages);
/// 4. anything else is a plain text matrix.
pub fn detect_kind(path: &Path, bytes: &[u8]) -> Result<FileKind, IoError> {
    if bytes.starts_with(npy::NPY_MAGIC) {
        return Ok(FileKind::Npy);
    }
    if bytes.starts_with(png::PNG_MAGIC) {
        return Ok(FileKind::Png);
    }
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let name = error::display_name(path);
    match ext.as_str() {
        "npy" => {
            return Err(IoError::format(
                &name,
                "named .npy but not a NumPy file (it does not start with the \\x93NUMPY magic bytes)",
            ));
        }
        "png" => {
            return Err(IoError::format(
                &name,
                "named .png but not a PNG image (the PNG signature is missing)",
            ));
        }
        _ => {}
    }
    // Only the start of the file is needed to recognise a TekScan header.
    let head = &bytes[..bytes.len().min(64 * 1024)];
    if ext == "asf" || tekscan::looks_like_tekscan(&textutil::decode_text(head)) {
        return Ok(FileKind::TekScan);
    }
    // Zero bytes are binary, unless the file is UTF-16 text (decoded, it has none).
    if bytes.contains(&0) && textutil::decode_text(bytes).contains('\0') {
        return Err(IoError::unsupported(
            &name,
            "binary file of unknown format; expected a TekScan ASCII file (.asf), a NumPy array (.npy), \
             a greyscale PNG or a text matrix (.txt, .dat)",
        ));
    }
    Ok(FileKind::TextMatrix)
}
