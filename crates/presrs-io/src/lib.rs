#![doc = include_str!("../README.md")]

pub mod atomic;
pub mod error;
pub mod frame_protocol;
pub mod manifest;
pub mod mcap;
pub mod message;
pub mod model_file;
pub mod npy;
pub mod output_path;
mod parsed;
pub mod png;
pub mod tekscan;
pub mod text;
mod textutil;

use std::path::Path;

use presrs_core::Recording;

pub use atomic::{write_atomic, write_atomic_with};
pub use error::IoError;
pub use message::{Face, Message, Opt, Warning, Warnings};
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
    /// An MCAP file (a ROS 2 bag).
    Mcap,
}

/// Reads any supported recording file strictly (see [`read_recording_with`]).
pub fn read_recording(path: &Path) -> Result<Recording, IoError> {
    Ok(read_recording_with(path, &ReadOptions::default())?.recording)
}

/// Reads any supported recording file: a TekScan ASCII movie or snapshot, a `.npy` array, a greyscale
/// PNG, an MCAP file (a ROS 2 bag: one topic, [`ReadOptions::topic`]; see [`mcap`]) or a plain text
/// matrix. The format is chosen by content first (NumPy, PNG and MCAP magic bytes, a TekScan header), then by extension (see [`detect_kind`]).
pub fn read_recording_with(path: &Path, options: &ReadOptions) -> Result<Parsed, IoError> {
    if is_mcap_file(path)? {
        // Read message by message: a bag may be much larger than the frames of one topic.
        let file = std::fs::File::open(path).map_err(|source| IoError::io("read", path, source))?;
        let reader = std::io::BufReader::with_capacity(1 << 16, file);
        return mcap::parse_mcap(reader, &error::display_name(path), options.topic.as_deref());
    }
    let bytes = std::fs::read(path).map_err(|source| IoError::io("read", path, source))?;
    let name = error::display_name(path);
    let plain = |recording| Parsed {
        recording,
        warnings: Warnings::new(),
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
        FileKind::Mcap => mcap::parse_mcap(bytes.as_slice(), &name, options.topic.as_deref()),
    }
}

/// Whether the file at `path` starts with the MCAP magic bytes (read without loading the file).
pub fn is_mcap_file(path: &Path) -> Result<bool, IoError> {
    Ok(read_head(path, mcap::MCAP_MAGIC.len())? == mcap::MCAP_MAGIC)
}

/// The first `len` bytes of the file at `path` (fewer when it is shorter), without reading the rest.
pub(crate) fn read_head(path: &Path, len: usize) -> Result<Vec<u8>, IoError> {
    use std::io::Read;
    let file = std::fs::File::open(path).map_err(|source| IoError::io("read", path, source))?;
    let mut head = Vec::with_capacity(len);
    file.take(len as u64)
        .read_to_end(&mut head)
        .map_err(|source| IoError::io("read", path, source))?;
    Ok(head)
}

/// Decides the format of a file from its content and extension:
///
/// 1. NumPy, PNG or MCAP magic bytes win whatever the extension says;
/// 2. a file named `.npy`, `.png` or `.mcap` without the matching magic bytes is an error (it is not what its
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
    if bytes.starts_with(mcap::MCAP_MAGIC) {
        return Ok(FileKind::Mcap);
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
        "mcap" => {
            return Err(IoError::format(
                &name,
                "named .mcap but not an MCAP file (it does not start with the \\x89MCAP0 magic bytes)",
            ));
        }
        _ => {}
    }
    if model_file::looks_like_model(bytes) {
        return Err(IoError::unsupported(&name, model_file::MODEL_NOT_RECORDING));
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
             a greyscale PNG, an MCAP file (.mcap) or a text matrix (.txt, .dat)",
        ));
    }
    Ok(FileKind::TextMatrix)
}
