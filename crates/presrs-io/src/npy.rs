//! NumPy `.npy` arrays: 2-D (one frame, `rows x cols`) or 3-D (`frames x rows x cols`).
//!
//! Any integer or float dtype is read (`u1`..`u8`, `i1`..`i8`, `f2` (half), `f4`, `f8`; little or big
//! endian; `bool` as 0/1) and converted to `f64` (exactly, except as said next) (64-bit integers beyond 2^53 are rounded to the nearest `f64`). C and
//! Fortran order are both read (Fortran-order arrays are transposed into the row-major layout). NaN and
//! infinities are rejected, naming the element. The writers produce C-order little-endian `f8` or `u1`.
//!
//! **Axes.** A 3-D array is `frames x rows x cols` unless told otherwise ([`ArrayAxes`], `--axes` on the
//! command line). Some exporters write the time axis last (`rows x cols x frames`); read as frames
//! first, such a file gives a few very wide frames without an error. So, when nothing is said about the
//! axes, a shape `(a, b, c)` whose last axis is at least 3 times the first and 4 times the middle one
//! (frames read as `b x c`, at least 4 times wider than tall, an unlikely sensor) gets a warning naming
//! `--axes rows,cols,frames`.

use std::io::Write;
use std::path::Path;

use npyz::{DType, NpyFile, TypeChar, WriterBuilder};
use presrs_core::{Grid, Recording, SensorMeta};

use crate::error::{IoError, display_name};
use crate::message::{Message, Opt, Warnings};
use crate::parsed::{ArrayAxes, Axis};

/// The first bytes of every `.npy` file.
pub const NPY_MAGIC: &[u8] = b"\x93NUMPY";

/// Reads a 2-D or 3-D `.npy` file as a recording (no frame period, raw units, frames numbered from 1).
pub fn read_npy(path: &Path) -> Result<Recording, IoError> {
    let bytes = std::fs::read(path).map_err(|source| IoError::io("read", path, source))?;
    parse_npy(&bytes, &display_name(path))
}

/// Parses the bytes of a `.npy` file (a 3-D array as frames x rows x cols); `source_name` names it in
/// error messages.
pub fn parse_npy(bytes: &[u8], source_name: &str) -> Result<Recording, IoError> {
    parse_npy_with(bytes, source_name, Some(ArrayAxes::default())).map(|(recording, _)| recording)
}

/// The warning for a 3-D shape that looks like rows x cols x frames read as frames x rows x cols.
fn time_last_warning(file: &str, shape: &[u64]) -> Option<Message> {
    let &[a, b, c] = shape else {
        return None;
    };
    (c >= 3 * a && c >= 4 * b).then(|| {
        Message::from(format!(
            "{file}: read as {a} frames of {b} x {c} (axes frames,rows,cols); if its last axis is time \
             (rows x cols x frames, as some exporters write: {c} frames of {a} x {b}), give "
        ))
        .opt_text(Opt::Axes, "rows,cols,frames")
    })
}

/// Parses the bytes of a `.npy` file, a 3-D array's axes in the order `axes` says (`None`: frames x
/// rows x cols, with a warning when the shape looks otherwise). Returns the recording and the warnings.
pub fn parse_npy_with(
    bytes: &[u8],
    source_name: &str,
    axes: Option<ArrayAxes>,
) -> Result<(Recording, Warnings), IoError> {
    let file = source_name;
    let npy = open_npy(bytes, file)?;
    let shape: Vec<u64> = npy.shape().to_vec();
    let warnings: Warnings = match axes {
        Some(_) => Warnings::new(),
        None => time_last_warning(file, &shape).into_iter().collect(),
    };
    let axes = axes.unwrap_or_default();
    let (frames, rows, cols) = array_dims(&shape, axes, file)?;
    let order = npy.order();
    let strides: Vec<u64> = npy.strides().to_vec();
    let stored = read_values(bytes, npy, &shape, (frames, rows, cols), file)?;
    // Gather into frames x rows x cols, row-major, whatever the storage order and the axes' order.
    let in_order = shape.len() == 2 || axes == ArrayAxes::default();
    let data: Vec<f64> = if order == npyz::Order::C && in_order {
        stored
    } else {
        let strides = element_strides(order, &strides, &shape, axes);
        gather_row_major(&stored, strides, (frames, rows, cols))
    };
    check_finite(&data, shape.len(), (rows, cols), file)?;
    let recording = Recording::new(
        Grid::new(rows, cols),
        None,
        data,
        None,
        SensorMeta::default(),
    )
    .map_err(|source| IoError::Model {
        file: file.to_owned(),
        source,
    })?;
    Ok((recording, warnings))
}

/// The file's header, checked before npyz reads it: the magic bytes, a header that is all there, and a
/// claimed size that fits.
fn open_npy<'a>(bytes: &'a [u8], file: &str) -> Result<NpyFile<&'a [u8]>, IoError> {
    if !bytes.starts_with(NPY_MAGIC) {
        return Err(IoError::format(
            file,
            "not a NumPy .npy file (it does not start with the \\x93NUMPY magic bytes)",
        ));
    }
    // npyz multiplies the shape without checking for overflow (a panic in debug builds): reject a
    // claimed size that does not fit before handing it the header.
    // npyz also allocates whatever header length the file claims: check it is all there first.
    let header = header_text(bytes).ok_or_else(|| {
        IoError::format(
            file,
            "invalid .npy header: truncated (the file ends before the header length it declares)",
        )
    })?;
    check_header_sizes(&header)
        .map_err(|why| IoError::format(file, format!("invalid .npy header: {why}")))?;
    NpyFile::new(bytes).map_err(|err| IoError::format(file, format!("invalid .npy header: {err}")))
}

/// `(frames, rows, cols)` of a 2-D or 3-D shape, its axes in the order `axes` says; none of them 0.
fn array_dims(
    shape: &[u64],
    axes: ArrayAxes,
    file: &str,
) -> Result<(usize, usize, usize), IoError> {
    let (frames, rows, cols) = match *shape {
        [rows, cols] => (1, rows, cols),
        [..] if shape.len() == 3 => (
            shape[axes.position(Axis::Frames)],
            shape[axes.position(Axis::Rows)],
            shape[axes.position(Axis::Cols)],
        ),
        _ => {
            return Err(IoError::unsupported(
                file,
                format!(
                    "expected a 2-D (rows x cols) or 3-D (frames x rows x cols) array, found a {}-D array of shape {shape:?}",
                    shape.len()
                ),
            ));
        }
    };
    let dims = (
        usize::try_from(frames),
        usize::try_from(rows),
        usize::try_from(cols),
    );
    let (Ok(frames), Ok(rows), Ok(cols)) = dims else {
        return Err(IoError::format(
            file,
            format!("shape {shape:?} is too large"),
        ));
    };
    if frames == 0 || rows == 0 || cols == 0 {
        return Err(IoError::format(
            file,
            format!(
                "the array is empty (shape {shape:?}); expected at least one frame of one sensel"
            ),
        ));
    }
    Ok((frames, rows, cols))
}

/// Every stored value as `f64`, in storage order, once the dtype is known and the data all there.
fn read_values(
    bytes: &[u8],
    npy: NpyFile<&[u8]>,
    shape: &[u64],
    (frames, rows, cols): (usize, usize, usize),
    file: &str,
) -> Result<Vec<f64>, IoError> {
    let dtype = npy.dtype();
    let kind = scalar_kind(&dtype).ok_or_else(|| {
        IoError::unsupported(
            file,
            format!(
                "unsupported dtype {}; expected an integer, float or bool dtype (u1..u8, i1..i8, f2, f4, f8)",
                dtype.descr()
            ),
        )
    })?;
    let total = shape_len(frames, rows, cols)
        .ok_or_else(|| IoError::format(file, format!("shape {shape:?} is too large")))?;
    // Check the data is all there before allocating for it (a header can claim any shape).
    let item_size = kind.size();
    let needed = total.checked_mul(item_size);
    let available = npy.into_inner().len();
    let reader = NpyFile::new(bytes)
        .map_err(|err| IoError::format(file, format!("invalid .npy header: {err}")))?;
    match needed {
        Some(needed) if needed <= available => {}
        _ => {
            return Err(IoError::format(
                file,
                format!(
                    "truncated data: shape {shape:?} of {} needs {} bytes, the file holds {available}",
                    dtype.descr(),
                    needed.map_or_else(|| "too many".to_owned(), |n| n.to_string())
                ),
            ));
        }
    }
    let stored = kind
        .read_all(reader)
        .map_err(|err| IoError::format(file, format!("cannot read the array data: {err}")))?;
    if stored.len() != total {
        return Err(IoError::format(
            file,
            format!(
                "truncated data: expected {total} values, read {}",
                stored.len()
            ),
        ));
    }
    Ok(stored)
}

/// The strides, in elements, of the frame, row and column axes in the stored values (0 for the frame
/// of a 2-D array).
fn element_strides(
    order: npyz::Order,
    strides: &[u64],
    shape: &[u64],
    axes: ArrayAxes,
) -> (usize, usize, usize) {
    let strides: Vec<usize> = if order == npyz::Order::C {
        let dims: Vec<usize> = shape.iter().map(|&n| n as usize).collect();
        (0..dims.len())
            .map(|i| dims[i + 1..].iter().product())
            .collect()
    } else {
        strides.iter().map(|&s| s as usize).collect()
    };
    match *strides.as_slice() {
        [sr, sc] => (0, sr, sc),
        [..] if strides.len() == 3 => (
            strides[axes.position(Axis::Frames)],
            strides[axes.position(Axis::Rows)],
            strides[axes.position(Axis::Cols)],
        ),
        _ => (0, 0, 0),
    }
}

/// The stored values gathered into frames x rows x cols, row-major, through the axes' strides.
fn gather_row_major(
    stored: &[f64],
    (sf, sr, sc): (usize, usize, usize),
    (frames, rows, cols): (usize, usize, usize),
) -> Vec<f64> {
    let mut out = Vec::with_capacity(frames * rows * cols);
    for f in 0..frames {
        for r in 0..rows {
            for c in 0..cols {
                out.push(stored[f * sf + r * sr + c * sc]);
            }
        }
    }
    out
}

/// An error naming the first element that is NaN or infinite (its index in the array's own rank).
fn check_finite(
    data: &[f64],
    rank: usize,
    (rows, cols): (usize, usize),
    file: &str,
) -> Result<(), IoError> {
    let Some(at) = data.iter().position(|v| !v.is_finite()) else {
        return Ok(());
    };
    let per_frame = rows * cols;
    let (f, cell) = (at / per_frame, at % per_frame);
    let position = if rank == 3 {
        format!("[{f}, {}, {}]", cell / cols, cell % cols)
    } else {
        format!("[{}, {}]", cell / cols, cell % cols)
    };
    Err(IoError::format(
        file,
        format!(
            "element {position} is {}; expected finite numbers",
            data[at]
        ),
    ))
}

/// The header dictionary text of a `.npy` file (versions 1 to 3), when it is all there.
fn header_text(bytes: &[u8]) -> Option<String> {
    let major = *bytes.get(NPY_MAGIC.len())?;
    let (len, start): (usize, usize) = if major == 1 {
        let b = bytes.get(8..10)?;
        (usize::from(u16::from_le_bytes([b[0], b[1]])), 10)
    } else {
        let b = bytes.get(8..12)?;
        (u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize, 12)
    };
    let text = bytes.get(start..start.checked_add(len)?)?;
    Some(String::from_utf8_lossy(text).into_owned())
}

/// Deepest nesting of brackets (`(`, `[`, `{`) accepted in a header.
const MAX_HEADER_NESTING: usize = 8;

/// Checks that the integers of every tuple or list in a header (the shape, and subarray shapes in a
/// structured dtype) each fit in 64 bits and so does their product.
fn check_header_sizes(header: &str) -> Result<(), String> {
    let mut products: Vec<u64> = Vec::new();
    let mut token = String::new();
    let flush = |token: &mut String, products: &mut Vec<u64>| -> Result<(), String> {
        let digits = token.trim().trim_end_matches(['L', 'l']);
        if !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()) {
            let value: u64 = digits
                .parse()
                .map_err(|_| format!("dimension {digits} is too large"))?;
            if let Some(product) = products.last_mut() {
                *product = product
                    .checked_mul(value)
                    .ok_or_else(|| "the shape's size overflows 64 bits".to_owned())?;
            }
        }
        token.clear();
        Ok(())
    };
    for ch in header.chars() {
        match ch {
            '(' | '[' | '{' => {
                token.clear();
                products.push(1);
                // npyz's header parser backtracks exponentially in the nesting depth (a fuzzer found
                // headers of 120 `[` or `{` that take minutes); real headers nest 4 deep at most.
                if products.len() > MAX_HEADER_NESTING {
                    return Err(format!(
                        "brackets nested more than {MAX_HEADER_NESTING} deep"
                    ));
                }
            }
            ')' | ']' | '}' => {
                flush(&mut token, &mut products)?;
                products.pop();
            }
            ',' => flush(&mut token, &mut products)?,
            _ => token.push(ch),
        }
    }
    Ok(())
}

fn shape_len(frames: usize, rows: usize, cols: usize) -> Option<usize> {
    frames.checked_mul(rows)?.checked_mul(cols)
}

/// The element types read.
#[derive(Clone, Copy, Debug)]
enum Kind {
    Bool,
    U8,
    U16,
    U32,
    U64,
    I8,
    I16,
    I32,
    I64,
    /// IEEE half precision; `true` when stored big-endian.
    F16(bool),
    F32,
    F64,
}

fn scalar_kind(dtype: &DType) -> Option<Kind> {
    let DType::Plain(ty) = dtype else {
        return None;
    };
    Some(match (ty.type_char(), ty.size_field()) {
        (TypeChar::Bool, 1) => Kind::Bool,
        (TypeChar::Uint, 1) => Kind::U8,
        (TypeChar::Uint, 2) => Kind::U16,
        (TypeChar::Uint, 4) => Kind::U32,
        (TypeChar::Uint, 8) => Kind::U64,
        (TypeChar::Int, 1) => Kind::I8,
        (TypeChar::Int, 2) => Kind::I16,
        (TypeChar::Int, 4) => Kind::I32,
        (TypeChar::Int, 8) => Kind::I64,
        (TypeChar::Float, 2) => Kind::F16(ty.endianness() == npyz::Endianness::Big),
        (TypeChar::Float, 4) => Kind::F32,
        (TypeChar::Float, 8) => Kind::F64,
        _ => return None,
    })
}

impl Kind {
    fn size(self) -> usize {
        match self {
            Self::Bool | Self::U8 | Self::I8 => 1,
            Self::U16 | Self::I16 | Self::F16(_) => 2,
            Self::U32 | Self::I32 | Self::F32 => 4,
            Self::U64 | Self::I64 | Self::F64 => 8,
        }
    }

    /// Reads every element, in storage order, as `f64`.
    fn read_all(self, npy: NpyFile<&[u8]>) -> std::io::Result<Vec<f64>> {
        fn all<T: npyz::Deserialize>(
            npy: NpyFile<&[u8]>,
            convert: impl Fn(T) -> f64,
        ) -> std::io::Result<Vec<f64>> {
            let len = usize::try_from(npy.len()).unwrap_or(0);
            let reader = npy
                .data::<T>()
                .map_err(|err| std::io::Error::new(std::io::ErrorKind::InvalidData, err))?;
            let mut out = Vec::with_capacity(len);
            for value in reader {
                out.push(convert(value?));
            }
            Ok(out)
        }
        match self {
            Self::Bool => all::<bool>(npy, |v| f64::from(u8::from(v))),
            Self::U8 => all::<u8>(npy, f64::from),
            Self::U16 => all::<u16>(npy, f64::from),
            Self::U32 => all::<u32>(npy, f64::from),
            Self::U64 => all::<u64>(npy, |v| v as f64),
            Self::I8 => all::<i8>(npy, f64::from),
            Self::I16 => all::<i16>(npy, f64::from),
            Self::I32 => all::<i32>(npy, f64::from),
            Self::I64 => all::<i64>(npy, |v| v as f64),
            // npyz reads half floats only with its `half` feature: convert the bytes here.
            Self::F16(big) => {
                let len = usize::try_from(npy.len()).unwrap_or(0);
                let bytes = npy.into_inner();
                Ok(bytes
                    .chunks_exact(2)
                    .take(len)
                    .map(|b| {
                        let pair = [b[0], b[1]];
                        f16_to_f64(if big {
                            u16::from_be_bytes(pair)
                        } else {
                            u16::from_le_bytes(pair)
                        })
                    })
                    .collect())
            }
            Self::F32 => all::<f32>(npy, f64::from),
            Self::F64 => all::<f64>(npy, |v| v),
        }
    }
}

/// The value of an IEEE 754 half-precision number (1 sign bit, 5 exponent bits biased by 15, 10
/// fraction bits), exactly: every half is an `f64`.
fn f16_to_f64(bits: u16) -> f64 {
    let sign = if bits & 0x8000 == 0 { 1.0 } else { -1.0 };
    let exponent = i32::from((bits >> 10) & 0x1f);
    let fraction = bits & 0x3ff;
    let magnitude = match (exponent, fraction) {
        // Zero and subnormals: fraction x 2^-24.
        (0, _) => f64::from(fraction) * 2f64.powi(-24),
        (0x1f, 0) => f64::INFINITY,
        (0x1f, _) => f64::NAN,
        _ => (1.0 + f64::from(fraction) / 1024.0) * 2f64.powi(exponent - 15),
    };
    sign * magnitude
}

fn check_shape(shape: &[usize], len: usize) -> std::io::Result<Vec<u64>> {
    let product = shape.iter().try_fold(1usize, |acc, &n| acc.checked_mul(n));
    if product != Some(len) {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("shape {shape:?} does not hold {len} values"),
        ));
    }
    Ok(shape.iter().map(|&n| n as u64).collect())
}

/// Writes `data` (C order) as a little-endian `f8` array of `shape`.
pub fn write_npy_f64<W: Write>(w: W, shape: &[usize], data: &[f64]) -> std::io::Result<()> {
    let shape = check_shape(shape, data.len())?;
    let dtype = DType::Plain("<f8".parse().map_err(std::io::Error::other)?);
    let mut writer = npyz::WriteOptions::new()
        .dtype(dtype)
        .shape(&shape)
        .writer(w)
        .begin_nd()?;
    writer.extend(data.iter().copied())?;
    writer.finish()
}

/// Writes `data` (C order) as a `u1` array of `shape`.
pub fn write_npy_u8<W: Write>(w: W, shape: &[usize], data: &[u8]) -> std::io::Result<()> {
    let shape = check_shape(shape, data.len())?;
    let dtype = DType::Plain("|u1".parse().map_err(std::io::Error::other)?);
    let mut writer = npyz::WriteOptions::new()
        .dtype(dtype)
        .shape(&shape)
        .writer(w)
        .begin_nd()?;
    writer.extend(data.iter().copied())?;
    writer.finish()
}

/// Writes a recording's values as a 3-D `frames x rows x cols` `f8` array, atomically. The mask of
/// absent sensels, the frame period and the metadata are not stored (`.npy` holds only the array).
pub fn write_recording_npy(recording: &Recording, path: &Path) -> Result<(), IoError> {
    let grid = recording.grid();
    let shape = [recording.frame_count(), grid.rows, grid.cols];
    crate::atomic::write_atomic(path, |w| write_npy_f64(w, &shape, recording.data()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn npy_f64(shape: &[usize], data: &[f64]) -> Vec<u8> {
        let mut bytes = Vec::new();
        write_npy_f64(&mut bytes, shape, data).unwrap();
        bytes
    }

    /// A `.npy` file with an arbitrary header dict and raw data bytes (what numpy would write).
    fn raw_npy(descr: &str, fortran: bool, shape: &str, data: &[u8]) -> Vec<u8> {
        let mut dict = format!(
            "{{'descr': '{descr}', 'fortran_order': {}, 'shape': {shape}, }}",
            if fortran { "True" } else { "False" }
        );
        while (10 + dict.len() + 1) % 64 != 0 {
            dict.push(' ');
        }
        dict.push('\n');
        let mut out = Vec::new();
        out.extend_from_slice(b"\x93NUMPY\x01\x00");
        out.extend_from_slice(&(dict.len() as u16).to_le_bytes());
        out.extend_from_slice(dict.as_bytes());
        out.extend_from_slice(data);
        out
    }

    #[test]
    fn f64_round_trip_2d_and_3d() {
        let data: Vec<f64> = (0..12).map(|i| f64::from(i) * 0.5 - 1.0).collect();
        let rec = parse_npy(&npy_f64(&[3, 4], &data), "a.npy").unwrap();
        assert_eq!(rec.grid(), Grid::new(3, 4));
        assert_eq!(rec.frame_count(), 1);
        assert_eq!(rec.data(), data.as_slice());
        let rec = parse_npy(&npy_f64(&[2, 3, 2], &data), "b.npy").unwrap();
        assert_eq!(rec.grid(), Grid::new(3, 2));
        assert_eq!(rec.frame_count(), 2);
        assert_eq!(rec.frame(1).unwrap().get(2, 1), data[11]);
    }

    #[test]
    fn u8_writer_and_reader() {
        let mut bytes = Vec::new();
        write_npy_u8(&mut bytes, &[2, 2], &[0, 7, 200, 255]).unwrap();
        let rec = parse_npy(&bytes, "u.npy").unwrap();
        assert_eq!(rec.data(), &[0.0, 7.0, 200.0, 255.0]);
    }

    #[test]
    fn every_integer_and_float_dtype_both_endians() {
        let cases: Vec<(&str, Vec<u8>)> = vec![
            ("|u1", vec![1, 255]),
            ("|i1", vec![1, 0xFF]),
            ("<u2", vec![1, 0, 0, 1]),
            (">u2", vec![0, 1, 1, 0]),
            ("<i2", vec![1, 0, 0xFF, 0xFF]),
            ("<u4", [1u32.to_le_bytes(), 256u32.to_le_bytes()].concat()),
            (">i4", [1i32.to_be_bytes(), (-1i32).to_be_bytes()].concat()),
            ("<u8", [1u64.to_le_bytes(), 256u64.to_le_bytes()].concat()),
            (">i8", [1i64.to_be_bytes(), (-1i64).to_be_bytes()].concat()),
            ("<f4", [1f32.to_le_bytes(), 2.5f32.to_le_bytes()].concat()),
            (
                ">f8",
                [1f64.to_be_bytes(), (-2.5f64).to_be_bytes()].concat(),
            ),
            ("|b1", vec![1, 0]),
        ];
        let expected = |descr: &str| -> [f64; 2] {
            match descr {
                "|u1" => [1.0, 255.0],
                "|i1" | ">i4" | ">i8" => [1.0, -1.0],
                "<u2" | ">u2" | "<u4" | "<u8" => [1.0, 256.0],
                "<i2" => [1.0, -1.0],
                "<f4" => [1.0, 2.5],
                ">f8" => [1.0, -2.5],
                "|b1" => [1.0, 0.0],
                _ => unreachable!(),
            }
        };
        for (descr, data) in cases {
            let bytes = raw_npy(descr, false, "(1, 2)", &data);
            let rec = parse_npy(&bytes, "t.npy").unwrap_or_else(|e| panic!("{descr}: {e}"));
            assert_eq!(rec.data(), &expected(descr), "{descr}");
        }
    }

    #[test]
    fn half_precision_bit_patterns() {
        let cases: [(u16, f64); 10] = [
            (0x3C00, 1.0),
            (0xC000, -2.0),
            (0x7BFF, 65504.0),
            (0x0001, 2f64.powi(-24)),
            (0x03FF, 1023.0 * 2f64.powi(-24)),
            (0x0400, 2f64.powi(-14)),
            (0x3555, 0.333_251_953_125),
            (0x0000, 0.0),
            (0x7C00, f64::INFINITY),
            (0xFC00, f64::NEG_INFINITY),
        ];
        for (bits, value) in cases {
            assert_eq!(f16_to_f64(bits), value, "{bits:#06x}");
        }
        assert!(f16_to_f64(0x8000).is_sign_negative() && f16_to_f64(0x8000) == 0.0);
        assert!(f16_to_f64(0x7E00).is_nan() && f16_to_f64(0x7C01).is_nan());
    }

    #[test]
    fn half_precision_arrays_both_endians_and_fortran_order() {
        // [[1, -2, 65504], [2^-24, 0.5, 0]] as numpy's float16.
        let bits: [u16; 6] = [0x3C00, 0xC000, 0x7BFF, 0x0001, 0x3800, 0x0000];
        let expected = [1.0, -2.0, 65504.0, 2f64.powi(-24), 0.5, 0.0];
        let le: Vec<u8> = bits.iter().flat_map(|b| b.to_le_bytes()).collect();
        let be: Vec<u8> = bits.iter().flat_map(|b| b.to_be_bytes()).collect();
        for (descr, data) in [("<f2", &le), (">f2", &be)] {
            let rec = parse_npy(&raw_npy(descr, false, "(2, 3)", data), "h.npy")
                .unwrap_or_else(|e| panic!("{descr}: {e}"));
            assert_eq!(rec.data(), &expected, "{descr}");
        }
        // Fortran order: columns first.
        let stored: Vec<u8> = [0, 3, 1, 4, 2, 5]
            .iter()
            .flat_map(|&i| bits[i].to_le_bytes())
            .collect();
        let rec = parse_npy(&raw_npy("<f2", true, "(2, 3)", &stored), "h.npy").unwrap();
        assert_eq!(rec.data(), &expected);
        // 3-D, and faults: truncated data, infinities and NaN are errors naming the element.
        let rec = parse_npy(&raw_npy("<f2", false, "(3, 1, 2)", &le), "h.npy").unwrap();
        assert_eq!(rec.frame_count(), 3);
        let m = parse_npy(&raw_npy("<f2", false, "(2, 3)", &le[..11]), "h.npy")
            .unwrap_err()
            .to_string();
        assert!(m.contains("truncated") && m.contains("12 bytes"), "{m}");
        let inf: Vec<u8> = [0x3C00u16, 0x7C00]
            .iter()
            .flat_map(|b| b.to_le_bytes())
            .collect();
        let m = parse_npy(&raw_npy("<f2", false, "(1, 2)", &inf), "h.npy")
            .unwrap_err()
            .to_string();
        assert!(m.contains("[0, 1]") && m.contains("inf"), "{m}");
        let nan: Vec<u8> = [0x7E00u16, 0]
            .iter()
            .flat_map(|b| b.to_le_bytes())
            .collect();
        let m = parse_npy(&raw_npy("<f2", false, "(1, 2)", &nan), "h.npy")
            .unwrap_err()
            .to_string();
        assert!(m.contains("[0, 0]") && m.contains("NaN"), "{m}");
    }

    #[test]
    fn fortran_order_is_transposed() {
        // numpy: np.asfortranarray([[1, 2, 3], [4, 5, 6]], dtype='<i4') stores 1, 4, 2, 5, 3, 6.
        let stored: Vec<u8> = [1i32, 4, 2, 5, 3, 6]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let rec = parse_npy(&raw_npy("<i4", true, "(2, 3)", &stored), "f.npy").unwrap();
        assert_eq!(rec.data(), &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        // 3-D: element [f, r, c] = 100 f + 10 r + c, shape (2, 2, 3), Fortran order: f fastest.
        let mut stored = Vec::new();
        for c in 0..3 {
            for r in 0..2 {
                for f in 0..2 {
                    stored.extend_from_slice(&f64::from(100 * f + 10 * r + c).to_le_bytes());
                }
            }
        }
        let rec = parse_npy(&raw_npy("<f8", true, "(2, 2, 3)", &stored), "f3.npy").unwrap();
        let expected: Vec<f64> = (0..2)
            .flat_map(|f| {
                (0..2).flat_map(move |r| (0..3).map(move |c| f64::from(100 * f + 10 * r + c)))
            })
            .collect();
        assert_eq!(rec.data(), expected.as_slice());
    }

    #[test]
    fn errors_are_clear() {
        let msg = |bytes: &[u8]| parse_npy(bytes, "bad.npy").unwrap_err().to_string();
        let m = msg(&npy_f64(&[6], &[0.0; 6]));
        assert!(
            m.contains("bad.npy") && m.contains("1-D") && m.contains("expected a 2-D"),
            "{m}"
        );
        let m = msg(&npy_f64(&[1, 1, 2, 3], &[0.0; 6]));
        assert!(m.contains("4-D"), "{m}");
        let m = msg(&npy_f64(&[0, 3], &[]));
        assert!(m.contains("empty"), "{m}");
        let m = msg(&raw_npy("<c16", false, "(1, 1)", &[0; 16]));
        assert!(m.contains("unsupported dtype") && m.contains("c16"), "{m}");
        let m = msg(&raw_npy("<U3", false, "(1, 1)", &[0; 12]));
        assert!(m.contains("unsupported dtype"), "{m}");
        let full = npy_f64(&[2, 2], &[1.0, 2.0, 3.0, 4.0]);
        let m = msg(&full[..full.len() - 3]);
        assert!(m.contains("truncated") && m.contains("32 bytes"), "{m}");
        let m = msg(&npy_f64(&[2, 2], &[1.0, 2.0, f64::NAN, 4.0]));
        assert!(m.contains("[1, 0]") && m.contains("NaN"), "{m}");
        let m = msg(&npy_f64(&[2, 1, 2], &[1.0, 2.0, 3.0, f64::INFINITY]));
        assert!(m.contains("[1, 0, 1]") && m.contains("inf"), "{m}");
        let m = msg(b"PK\x03\x04 not npy");
        assert!(m.contains("not a NumPy"), "{m}");
        let m = msg(b"\x93NUMPY\x01\x00\xff\xff{'descr'");
        assert!(m.contains("invalid .npy header"), "{m}");
        // A header claiming a huge shape with no data must fail fast, not allocate.
        let m = msg(&raw_npy("<f8", false, "(100000, 100000, 100000)", &[]));
        assert!(m.contains("truncated") || m.contains("too large"), "{m}");
        let m = msg(&raw_npy("<f8", false, "(100000, 100000)", &[0; 8]));
        assert!(m.contains("truncated"), "{m}");
    }

    #[test]
    fn writer_rejects_bad_shape_and_recording_file_round_trips() {
        let mut sink = Vec::new();
        assert!(write_npy_f64(&mut sink, &[2, 2], &[1.0]).is_err());
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("r.npy");
        let rec = Recording::new(
            Grid::new(2, 3),
            Some(0.01),
            (0..12).map(f64::from).collect(),
            None,
            SensorMeta::default(),
        )
        .unwrap();
        write_recording_npy(&rec, &path).unwrap();
        let back = read_npy(&path).unwrap();
        assert_eq!(back.data(), rec.data());
        assert_eq!(back.grid(), rec.grid());
        assert_eq!(back.frame_count(), 2);
    }

    #[test]
    fn time_last_arrays_are_named_and_read_with_their_axes() {
        // rows x cols x frames = 6 x 3 x 40, element [r, c, f] = 1000 f + 10 r + c.
        let (rows, cols, frames) = (6, 3, 40);
        let mut data = Vec::new();
        for r in 0..rows {
            for c in 0..cols {
                for f in 0..frames {
                    data.push(f64::from(1000 * f + 10 * r + c));
                }
            }
        }
        let bytes = npy_f64(&[rows as usize, cols as usize, frames as usize], &data);
        // Nothing said: read as 6 frames of 3 x 40, with a warning that names --axes.
        let (rec, warnings) = parse_npy_with(&bytes, "walk.npy", None).unwrap();
        assert_eq!((rec.frame_count(), rec.grid()), (6, Grid::new(3, 40)));
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        assert!(
            warnings[0].to_string().contains("--axes rows,cols,frames"),
            "{warnings:?}"
        );
        assert!(
            warnings[0].to_string().contains("40 frames of 6 x 3"),
            "{warnings:?}"
        );
        assert!(
            warnings[0]
                .render(crate::Face::Python)
                .ends_with("give axes=\"rows,cols,frames\""),
            "{warnings:?}"
        );
        // Told: 40 frames of 6 x 3, frame f row r col c where it should be; no warning.
        let axes: ArrayAxes = "rows,cols,frames".parse().unwrap();
        let (rec, warnings) = parse_npy_with(&bytes, "walk.npy", Some(axes)).unwrap();
        assert!(warnings.is_empty());
        assert_eq!((rec.frame_count(), rec.grid()), (40, Grid::new(6, 3)));
        let frame = rec.frame(7).unwrap();
        assert_eq!(frame.values()[2 * 3 + 1], 7021.0);
        // An ordinary movie (frames first) is not warned about.
        let movie = npy_f64(&[40, 6, 3], &data);
        assert!(parse_npy_with(&movie, "m.npy", None).unwrap().1.is_empty());
    }

    #[test]
    fn array_dims_follow_the_axes_and_refuse_empty_or_other_ranks() {
        let time_last = ArrayAxes([Axis::Rows, Axis::Cols, Axis::Frames]);
        assert_eq!(array_dims(&[4, 5], time_last, "a.npy").unwrap(), (1, 4, 5));
        assert_eq!(
            array_dims(&[2, 3, 7], ArrayAxes::default(), "a.npy").unwrap(),
            (2, 3, 7)
        );
        assert_eq!(
            array_dims(&[2, 3, 7], time_last, "a.npy").unwrap(),
            (7, 2, 3)
        );
        let err = array_dims(&[2, 0, 7], time_last, "a.npy")
            .unwrap_err()
            .to_string();
        assert!(err.contains("a.npy") && err.contains("empty"), "{err}");
        let err = array_dims(&[2, 3, 4, 5], time_last, "a.npy")
            .unwrap_err()
            .to_string();
        assert!(err.contains("4-D"), "{err}");
    }

    #[test]
    fn gathering_through_strides_matches_indexing_every_axes_order() {
        use Axis::{Cols, Frames, Rows};
        let shape = [2u64, 3, 4];
        let stored: Vec<f64> = (0..24).map(f64::from).collect();
        let orders = [
            [Frames, Rows, Cols],
            [Frames, Cols, Rows],
            [Rows, Frames, Cols],
            [Rows, Cols, Frames],
            [Cols, Frames, Rows],
            [Cols, Rows, Frames],
        ];
        for order in orders {
            let axes = ArrayAxes(order);
            let dims = array_dims(&shape, axes, "a.npy").unwrap();
            let strides = element_strides(npyz::Order::C, &[], &shape, axes);
            let gathered = gather_row_major(&stored, strides, dims);
            // The oracle: place (frame, row, col) on the stored axes and index C-order.
            let mut expected = Vec::new();
            for f in 0..dims.0 {
                for r in 0..dims.1 {
                    for c in 0..dims.2 {
                        let mut at = [0usize; 3];
                        at[axes.position(Frames)] = f;
                        at[axes.position(Rows)] = r;
                        at[axes.position(Cols)] = c;
                        expected.push(stored[(at[0] * 3 + at[1]) * 4 + at[2]]);
                    }
                }
            }
            assert_eq!(gathered, expected, "{order:?}");
        }
    }

    #[test]
    fn the_first_non_finite_element_is_named_in_the_arrays_rank() {
        let mut data = vec![0.0; 12];
        assert!(check_finite(&data, 3, (2, 3), "a.npy").is_ok());
        data[10] = f64::NAN;
        data[11] = f64::INFINITY;
        let err = check_finite(&data, 3, (2, 3), "a.npy")
            .unwrap_err()
            .to_string();
        assert!(err.contains("element [1, 1, 1] is NaN"), "{err}");
        let err = check_finite(&data[6..], 2, (2, 3), "a.npy")
            .unwrap_err()
            .to_string();
        assert!(err.contains("element [1, 1] is NaN"), "{err}");
    }

    #[test]
    fn axes_are_three_different_names() {
        assert_eq!(
            "frames, rows, cols".parse::<ArrayAxes>(),
            Ok(ArrayAxes::default())
        );
        assert_eq!(
            "rows,cols,frames".parse::<ArrayAxes>().unwrap().to_string(),
            "rows,cols,frames"
        );
        for bad in ["rows,cols", "rows,rows,frames", "x,y,t", ""] {
            let err = bad.parse::<ArrayAxes>().unwrap_err();
            assert!(err.contains("rows,cols,frames"), "{bad}: {err}");
        }
    }
}
