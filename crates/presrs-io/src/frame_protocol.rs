//! A small length-prefixed binary protocol for live pressure frames (`presrs stream --listen`,
//! `presrs replay --connect`). Also described in `docs/stream-protocol.md`.
//!
//! Every message is one frame, all integers little-endian:
//!
//! | offset | size | field |
//! |---|---|---|
//! | 0 | 4 | magic `PRSF` (`0x50 0x52 0x53 0x46`) |
//! | 4 | 4 | `u32` length of the rest of the message: `16 + rows x cols x size(dtype)` |
//! | 8 | 2 | `u16` rows (>= 1) |
//! | 10 | 2 | `u16` cols (>= 1) |
//! | 12 | 1 | `u8` dtype: 1 = `u8`, 2 = `u16`, 3 = `f32`, 4 = `f64` |
//! | 13 | 3 | reserved, must be zero |
//! | 16 | 8 | `u64` timestamp, microseconds on the sender's clock (passed through, not interpreted) |
//! | 24 | ... | `rows x cols` values, row-major, of type dtype |
//!
//! The stream ends when the sender closes its side of the connection (between two messages). There is no
//! mask: absent sensels are sent as 0.
//!
//! **Faults.** [`FrameReader::read_frame`] never allocates more than its size cap
//! ([`FrameReader::max_payload_bytes`], checked against the declared length *before* reading the
//! payload). A message whose header is well formed but whose content is not usable (unknown dtype,
//! non-zero reserved bytes, a length that disagrees with `rows x cols`, zero rows, non-finite values) is
//! read to its end and reported as [`FrameError::Skipped`]: the stream is still in sync and the next
//! message can be read. A bad magic, a declared length over the cap, a connection closed inside a message
//! and I/O errors are [`FrameError::Fatal`]: the stream cannot be resynchronised and must be closed.

use std::io::{self, Read, Write};

/// The first four bytes of every message.
pub const MAGIC: [u8; 4] = *b"PRSF";
/// Bytes before the payload.
pub const HEADER_BYTES: usize = 24;
/// Bytes counted by the length field before the payload (rows .. timestamp).
const LENGTH_OVERHEAD: usize = 16;
/// Default cap on a payload: 1 MiB (a 44 x 44 `f64` frame is 15 KiB; 362 x 362 `f64` fits).
pub const DEFAULT_MAX_PAYLOAD_BYTES: usize = 1 << 20;

/// The type of the payload's values.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dtype {
    U8 = 1,
    U16 = 2,
    F32 = 3,
    F64 = 4,
}

impl Dtype {
    pub fn size(self) -> usize {
        match self {
            Self::U8 => 1,
            Self::U16 => 2,
            Self::F32 => 4,
            Self::F64 => 8,
        }
    }

    pub fn from_code(code: u8) -> Option<Self> {
        match code {
            1 => Some(Self::U8),
            2 => Some(Self::U16),
            3 => Some(Self::F32),
            4 => Some(Self::F64),
            _ => None,
        }
    }

    /// The smallest type that holds every value exactly: `u8`/`u16` for non-negative integers in range,
    /// `f32` when every value survives the round trip, `f64` otherwise.
    pub fn smallest_exact(values: &[f64]) -> Self {
        let integral = |max: f64| {
            values
                .iter()
                .all(|&v| v.fract() == 0.0 && (0.0..=max).contains(&v))
        };
        if integral(255.0) {
            Self::U8
        } else if integral(65535.0) {
            Self::U16
        } else if values.iter().all(|&v| f64::from(v as f32) == v) {
            Self::F32
        } else {
            Self::F64
        }
    }
}

/// The header of a received frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameHeader {
    pub rows: usize,
    pub cols: usize,
    pub dtype: Dtype,
    pub timestamp_us: u64,
}

/// Why a message could not be used.
#[derive(Debug, thiserror::Error)]
pub enum FrameError {
    /// The message was read to its end and dropped; the stream is still in sync.
    #[error("{source_name}: message {index} skipped: {message}")]
    Skipped {
        source_name: String,
        index: u64,
        message: String,
    },
    /// The stream cannot go on (bad magic, oversized, closed mid-message, I/O error).
    #[error("{source_name}: message {index}: {message}")]
    Fatal {
        source_name: String,
        index: u64,
        message: String,
    },
}

impl FrameError {
    pub fn is_fatal(&self) -> bool {
        matches!(self, Self::Fatal { .. })
    }
}

/// Encodes one frame into `out` (cleared first). Values are converted to `dtype` (rounded and saturated
/// for the integer types: use [`Dtype::smallest_exact`] to avoid any loss).
pub fn encode_frame(
    out: &mut Vec<u8>,
    rows: usize,
    cols: usize,
    dtype: Dtype,
    timestamp_us: u64,
    values: &[f64],
) -> io::Result<()> {
    let invalid = |message: String| io::Error::new(io::ErrorKind::InvalidInput, message);
    let rows16 = u16::try_from(rows)
        .ok()
        .filter(|&r| r > 0)
        .ok_or_else(|| invalid(format!("rows must be in 1..=65535, got {rows}")))?;
    let cols16 = u16::try_from(cols)
        .ok()
        .filter(|&c| c > 0)
        .ok_or_else(|| invalid(format!("cols must be in 1..=65535, got {cols}")))?;
    if values.len() != rows * cols {
        return Err(invalid(format!(
            "{} values for a {rows}x{cols} frame",
            values.len()
        )));
    }
    let length = u32::try_from(LENGTH_OVERHEAD + values.len() * dtype.size())
        .map_err(|_| invalid("frame too large for the protocol".to_owned()))?;
    out.clear();
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(&length.to_le_bytes());
    out.extend_from_slice(&rows16.to_le_bytes());
    out.extend_from_slice(&cols16.to_le_bytes());
    out.extend_from_slice(&[dtype as u8, 0, 0, 0]);
    out.extend_from_slice(&timestamp_us.to_le_bytes());
    for &v in values {
        match dtype {
            Dtype::U8 => out.push(v.round().clamp(0.0, 255.0) as u8),
            Dtype::U16 => {
                out.extend_from_slice(&(v.round().clamp(0.0, 65535.0) as u16).to_le_bytes())
            }
            Dtype::F32 => out.extend_from_slice(&(v as f32).to_le_bytes()),
            Dtype::F64 => out.extend_from_slice(&v.to_le_bytes()),
        }
    }
    Ok(())
}

/// Encodes and writes one frame.
pub fn write_frame(
    w: &mut impl Write,
    scratch: &mut Vec<u8>,
    rows: usize,
    cols: usize,
    dtype: Dtype,
    timestamp_us: u64,
    values: &[f64],
) -> io::Result<()> {
    encode_frame(scratch, rows, cols, dtype, timestamp_us, values)?;
    w.write_all(scratch)
}

/// Reads frames from a byte stream with reused buffers.
#[derive(Debug)]
pub struct FrameReader {
    source_name: String,
    max_payload_bytes: usize,
    payload: Vec<u8>,
    index: u64,
}

impl FrameReader {
    /// `source_name` names the stream in errors (e.g. the peer address).
    pub fn new(source_name: &str, max_payload_bytes: usize) -> Self {
        Self {
            source_name: source_name.to_owned(),
            max_payload_bytes,
            payload: Vec::new(),
            index: 0,
        }
    }

    pub fn max_payload_bytes(&self) -> usize {
        self.max_payload_bytes
    }

    /// Messages read so far (good or skipped).
    pub fn messages(&self) -> u64 {
        self.index
    }

    fn fatal(&self, message: String) -> FrameError {
        FrameError::Fatal {
            source_name: self.source_name.clone(),
            index: self.index,
            message,
        }
    }

    fn skipped(&self, message: String) -> FrameError {
        FrameError::Skipped {
            source_name: self.source_name.clone(),
            index: self.index,
            message,
        }
    }

    /// Reads the next frame into `values` (resized to `rows x cols`, reusing its allocation). `Ok(None)`
    /// when the stream ends cleanly between two messages.
    pub fn read_frame(
        &mut self,
        r: &mut impl Read,
        values: &mut Vec<f64>,
    ) -> Result<Option<FrameHeader>, FrameError> {
        let mut header = [0u8; HEADER_BYTES];
        // The first byte decides between a clean end and a message.
        let got = loop {
            match r.read(&mut header[..1]) {
                Ok(n) => break n,
                Err(err) if err.kind() == io::ErrorKind::Interrupted => continue,
                Err(err) => return Err(self.fatal(format!("cannot read: {err}"))),
            }
        };
        if got == 0 {
            return Ok(None);
        }
        self.read_exact(r, &mut header[1..], 1, HEADER_BYTES)?;
        self.index += 1;
        if header[..4] != MAGIC {
            return Err(self.fatal(format!(
                "bad magic {:02x?}, expected \"PRSF\" (not a presrs frame stream, or out of sync)",
                &header[..4]
            )));
        }
        let field = |range: std::ops::Range<usize>| -> u64 {
            header[range]
                .iter()
                .rev()
                .fold(0u64, |acc, &b| (acc << 8) | u64::from(b))
        };
        let length = field(4..8) as usize;
        let rows = field(8..10) as usize;
        let cols = field(10..12) as usize;
        let dtype_code = header[12];
        let timestamp_us = field(16..24);
        if length < LENGTH_OVERHEAD {
            return Err(self.fatal(format!(
                "declared length {length} is shorter than the {LENGTH_OVERHEAD}-byte header rest"
            )));
        }
        let payload_len = length - LENGTH_OVERHEAD;
        if payload_len > self.max_payload_bytes {
            return Err(self.fatal(format!(
                "declared payload of {payload_len} bytes ({rows}x{cols}) exceeds the limit of {} bytes",
                self.max_payload_bytes
            )));
        }
        self.payload.resize(payload_len, 0);
        let mut payload = std::mem::take(&mut self.payload);
        let read = self.read_exact(r, &mut payload, HEADER_BYTES, HEADER_BYTES + payload_len);
        self.payload = payload;
        read?;

        let Some(dtype) = Dtype::from_code(dtype_code) else {
            return Err(self.skipped(format!(
                "unknown dtype {dtype_code} (expected 1 = u8, 2 = u16, 3 = f32, 4 = f64)"
            )));
        };
        if header[13..16] != [0, 0, 0] {
            return Err(self.skipped("reserved bytes 13..16 are not zero".to_owned()));
        }
        if rows == 0 || cols == 0 {
            return Err(self.skipped(format!("empty frame ({rows}x{cols})")));
        }
        if rows * cols * dtype.size() != payload_len {
            return Err(self.skipped(format!(
                "payload of {payload_len} bytes does not match {rows}x{cols} values of {} bytes ({})",
                dtype.size(),
                rows * cols * dtype.size()
            )));
        }
        values.clear();
        let bytes = &self.payload;
        match dtype {
            Dtype::U8 => values.extend(bytes.iter().map(|&b| f64::from(b))),
            Dtype::U16 => values.extend(
                bytes
                    .chunks_exact(2)
                    .map(|c| f64::from(u16::from_le_bytes([c[0], c[1]]))),
            ),
            Dtype::F32 => values.extend(
                bytes
                    .chunks_exact(4)
                    .map(|c| f64::from(f32::from_le_bytes([c[0], c[1], c[2], c[3]]))),
            ),
            Dtype::F64 => values.extend(
                bytes
                    .chunks_exact(8)
                    .map(|c| f64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]])),
            ),
        }
        if let Some(at) = values.iter().position(|v| !v.is_finite()) {
            return Err(self.skipped(format!(
                "value {at} (row {}, column {}) is not finite",
                at / cols + 1,
                at % cols + 1
            )));
        }
        Ok(Some(FrameHeader {
            rows,
            cols,
            dtype,
            timestamp_us,
        }))
    }

    /// `read_exact` with a clear message when the stream ends inside a message.
    fn read_exact(
        &self,
        r: &mut impl Read,
        buf: &mut [u8],
        done_before: usize,
        total: usize,
    ) -> Result<(), FrameError> {
        let mut filled = 0;
        while filled < buf.len() {
            match r.read(&mut buf[filled..]) {
                Ok(0) => {
                    return Err(self.fatal(format!(
                        "the stream ended inside a message ({} of {total} bytes received)",
                        done_before + filled
                    )));
                }
                Ok(n) => filled += n,
                Err(err) if err.kind() == io::ErrorKind::Interrupted => {}
                Err(err) => {
                    return Err(self.fatal(format!(
                        "cannot read ({} of {total} bytes received): {err}",
                        done_before + filled
                    )));
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    fn encoded(dtype: Dtype, values: &[f64]) -> Vec<u8> {
        let mut buf = Vec::new();
        encode_frame(&mut buf, 2, 3, dtype, 42, values).unwrap();
        buf
    }

    #[test]
    fn round_trips_every_dtype() {
        let values = [0.0, 1.0, 2.0, 255.0, 7.0, 3.0];
        for dtype in [Dtype::U8, Dtype::U16, Dtype::F32, Dtype::F64] {
            let buf = encoded(dtype, &values);
            assert_eq!(buf.len(), HEADER_BYTES + 6 * dtype.size());
            let mut reader = FrameReader::new("t", 1024);
            let mut out = Vec::new();
            let mut r = &buf[..];
            let header = reader.read_frame(&mut r, &mut out).unwrap().unwrap();
            assert_eq!(
                header,
                FrameHeader {
                    rows: 2,
                    cols: 3,
                    dtype,
                    timestamp_us: 42
                }
            );
            assert_eq!(out, values);
            assert!(reader.read_frame(&mut r, &mut out).unwrap().is_none());
        }
        assert_eq!(Dtype::smallest_exact(&values), Dtype::U8);
        assert_eq!(Dtype::smallest_exact(&[300.0]), Dtype::U16);
        assert_eq!(Dtype::smallest_exact(&[0.5]), Dtype::F32);
        assert_eq!(Dtype::smallest_exact(&[0.1]), Dtype::F64);
    }

    #[test]
    fn faults_are_skipped_or_fatal() {
        let good = encoded(Dtype::U8, &[1.0; 6]);
        let mut reader = FrameReader::new("peer", 1024);
        let mut out = Vec::new();

        // Unknown dtype: skipped, next message still readable.
        let mut bad = good.clone();
        bad[12] = 9;
        let stream = [bad.clone(), good.clone()].concat();
        let mut r = &stream[..];
        let err = reader.read_frame(&mut r, &mut out).unwrap_err();
        assert!(
            !err.is_fatal() && err.to_string().contains("unknown dtype 9"),
            "{err}"
        );
        assert!(reader.read_frame(&mut r, &mut out).unwrap().is_some());

        // Length that disagrees with rows x cols: skipped.
        let mut bad = good.clone();
        bad[8] = 3;
        let err = reader.read_frame(&mut &bad[..], &mut out).unwrap_err();
        assert!(
            !err.is_fatal() && err.to_string().contains("does not match"),
            "{err}"
        );

        // Bad magic, oversized, truncated: fatal.
        let mut bad = good.clone();
        bad[0] = b'X';
        let err = reader.read_frame(&mut &bad[..], &mut out).unwrap_err();
        assert!(
            err.is_fatal() && err.to_string().contains("bad magic"),
            "{err}"
        );
        let mut bad = good.clone();
        bad[4..8].copy_from_slice(&(1u32 << 30).to_le_bytes());
        let err = reader.read_frame(&mut &bad[..], &mut out).unwrap_err();
        assert!(
            err.is_fatal() && err.to_string().contains("exceeds the limit"),
            "{err}"
        );
        let err = reader
            .read_frame(&mut &good[..good.len() - 2], &mut out)
            .unwrap_err();
        assert!(
            err.is_fatal() && err.to_string().contains("ended inside a message (28 of 30"),
            "{err}"
        );

        // Non-finite value: skipped.
        let nan = {
            let mut buf = Vec::new();
            encode_frame(&mut buf, 1, 2, Dtype::F64, 0, &[1.0, f64::NAN]).unwrap();
            buf
        };
        let err = reader.read_frame(&mut &nan[..], &mut out).unwrap_err();
        assert!(
            !err.is_fatal() && err.to_string().contains("not finite"),
            "{err}"
        );
    }
}
