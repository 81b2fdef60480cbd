//! Greyscale PNG images as single frames, and an 8-bit greyscale writer.
//!
//! Reading keeps the raw grey levels as values (0-255 for 8-bit, 0-65535 for 16-bit, 0-1/3/15 for 1/2/4-bit
//! images): no gamma or scaling is applied. Greyscale images with an alpha channel are read when every
//! pixel is opaque (the alpha channel then carries nothing). Colour and palette images are rejected with a
//! message suggesting a conversion to greyscale, since a colour image has no single pressure value per pixel.

use std::io::{Cursor, Write};
use std::path::Path;

use presrs_core::{FrameView, Grid, Recording, SensorMeta};

use crate::error::{IoError, display_name};

/// The first bytes of every PNG file.
pub const PNG_MAGIC: &[u8] = b"\x89PNG\r\n\x1a\n";

/// Reads a greyscale PNG as a one-frame recording (raw units, no frame period).
pub fn read_png(path: &Path) -> Result<Recording, IoError> {
    let bytes = std::fs::read(path).map_err(|source| IoError::io("read", path, source))?;
    parse_png(&bytes, &display_name(path))
}

/// Parses the bytes of a PNG file; `source_name` names it in error messages.
pub fn parse_png(bytes: &[u8], source_name: &str) -> Result<Recording, IoError> {
    let file = source_name;
    if !bytes.starts_with(PNG_MAGIC) {
        return Err(IoError::format(
            file,
            "not a PNG file (the PNG signature is missing)",
        ));
    }
    let decoder = png::Decoder::new(Cursor::new(bytes));
    let mut reader = decoder
        .read_info()
        .map_err(|err| IoError::format(file, format!("invalid PNG: {err}")))?;
    let (color, depth) = reader.output_color_type();
    let bits = depth as u8;
    let channels = match color {
        png::ColorType::Grayscale => 1,
        png::ColorType::GrayscaleAlpha => 2,
        png::ColorType::Rgb | png::ColorType::Rgba | png::ColorType::Indexed => {
            return Err(IoError::unsupported(
                file,
                format!(
                    "{color:?} PNG images are not supported: a pressure image has one value per pixel; \
                     convert it to 8- or 16-bit greyscale (e.g. `magick in.png -colorspace Gray -depth 8 out.png`)"
                ),
            ));
        }
    };
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| IoError::format(file, "the image is too large"))?;
    // The header can claim any size: deflate expands at most 1032:1, so a real image's pixels fit in
    // about 1032 times the file's size. Check before allocating (and cap at 1 GiB in any case).
    let info = reader.info();
    if size > bytes.len().saturating_mul(1032).saturating_add(1 << 16) || size > 1 << 30 {
        return Err(IoError::format(
            file,
            format!(
                "the header claims {} x {} pixels, more than the file's {} bytes of data can hold",
                info.width,
                info.height,
                bytes.len()
            ),
        ));
    }
    let mut buf = vec![0u8; size];
    let out = reader
        .next_frame(&mut buf)
        .map_err(|err| IoError::format(file, format!("invalid or truncated PNG data: {err}")))?;
    let (width, height) = (out.width as usize, out.height as usize);
    if width == 0 || height == 0 {
        return Err(IoError::format(file, "the image is empty"));
    }
    let grid = Grid::new(height, width);
    let mut values = Vec::with_capacity(grid.len());
    let max = (1u32 << bits) - 1;
    for (r, line) in buf.chunks(out.line_size).take(height).enumerate() {
        for c in 0..width {
            let sample = |k: usize| -> u32 {
                let index = c * channels + k;
                match bits {
                    16 => u32::from(u16::from_be_bytes([line[2 * index], line[2 * index + 1]])),
                    8 => u32::from(line[index]),
                    _ => {
                        let per_byte = 8 / usize::from(bits);
                        let byte = line[index / per_byte];
                        let shift = 8 - usize::from(bits) * (index % per_byte + 1);
                        (u32::from(byte) >> shift) & max
                    }
                }
            };
            if channels == 2 && sample(1) != max {
                return Err(IoError::unsupported(
                    file,
                    format!(
                        "pixel row {} column {} is not opaque: greyscale+alpha images are read only when \
                         fully opaque; save the image as plain greyscale without transparency",
                        r + 1,
                        c + 1
                    ),
                ));
            }
            values.push(f64::from(sample(0)));
        }
    }
    if values.len() != grid.len() {
        return Err(IoError::format(file, "truncated PNG data"));
    }
    let frame = presrs_core::Frame::new(grid, values).map_err(|source| IoError::Model {
        file: file.to_owned(),
        source,
    })?;
    Recording::from_frame(frame, SensorMeta::default()).map_err(|source| IoError::Model {
        file: file.to_owned(),
        source,
    })
}

/// Writes `pixels` (row-major, `grid.rows x grid.cols`) as an 8-bit greyscale PNG.
pub fn write_png_gray8<W: Write>(w: W, grid: Grid, pixels: &[u8]) -> std::io::Result<()> {
    if pixels.len() != grid.len() || grid.is_empty() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!(
                "{} pixels do not make a non-empty {grid} image",
                pixels.len()
            ),
        ));
    }
    let too_big =
        |_| std::io::Error::new(std::io::ErrorKind::InvalidInput, "image too large for PNG");
    let width = u32::try_from(grid.cols).map_err(too_big)?;
    let height = u32::try_from(grid.rows).map_err(too_big)?;
    let mut encoder = png::Encoder::new(w, width, height);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(std::io::Error::other)?;
    writer
        .write_image_data(pixels)
        .map_err(std::io::Error::other)?;
    writer.finish().map_err(std::io::Error::other)
}

/// Writes an 8-bit greyscale PNG file atomically.
pub fn write_png_gray8_file(path: &Path, grid: Grid, pixels: &[u8]) -> Result<(), IoError> {
    crate::atomic::write_atomic(path, |w| write_png_gray8(w, grid, pixels))
}

/// Maps a frame to 8-bit grey levels for viewing: `0` -> black, `full_scale` (default: the frame's
/// largest value) -> white, linearly, clamped. Absent sensels and non-finite values are black.
pub fn frame_to_gray8(frame: FrameView<'_>, full_scale: Option<f64>) -> Vec<u8> {
    let values = frame.values();
    let top = full_scale.unwrap_or_else(|| {
        values
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .fold(0.0, f64::max)
    });
    let usable_top = top.is_finite() && top > 0.0;
    let present = frame.present();
    values
        .iter()
        .enumerate()
        .map(|(i, &v)| {
            let here = present.is_none_or(|mask| mask[i]);
            if !here || !v.is_finite() || !usable_top {
                0
            } else {
                // In [0, 255] after clamping, so the cast is exact.
                (v / top * 255.0).round().clamp(0.0, 255.0) as u8
            }
        })
        .collect()
}

/// Writes a frame as an 8-bit greyscale PNG file for viewing (see [`frame_to_gray8`]).
pub fn write_frame_png(
    frame: FrameView<'_>,
    full_scale: Option<f64>,
    path: &Path,
) -> Result<(), IoError> {
    write_png_gray8_file(path, frame.grid(), &frame_to_gray8(frame, full_scale))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn encode(
        width: u32,
        height: u32,
        color: png::ColorType,
        depth: png::BitDepth,
        data: &[u8],
    ) -> Vec<u8> {
        let mut bytes = Vec::new();
        let mut encoder = png::Encoder::new(&mut bytes, width, height);
        encoder.set_color(color);
        encoder.set_depth(depth);
        let mut writer = encoder.write_header().unwrap();
        writer.write_image_data(data).unwrap();
        writer.finish().unwrap();
        bytes
    }

    #[test]
    fn gray8_round_trip() {
        let grid = Grid::new(2, 3);
        let mut bytes = Vec::new();
        write_png_gray8(&mut bytes, grid, &[0, 1, 2, 100, 254, 255]).unwrap();
        let rec = parse_png(&bytes, "g.png").unwrap();
        assert_eq!(rec.grid(), grid);
        assert_eq!(rec.frame_count(), 1);
        assert_eq!(rec.data(), &[0.0, 1.0, 2.0, 100.0, 254.0, 255.0]);
    }

    #[test]
    fn gray16_keeps_raw_levels() {
        let data: Vec<u8> = [0u16, 1, 300, 65535]
            .iter()
            .flat_map(|v| v.to_be_bytes())
            .collect();
        let bytes = encode(
            2,
            2,
            png::ColorType::Grayscale,
            png::BitDepth::Sixteen,
            &data,
        );
        let rec = parse_png(&bytes, "g16.png").unwrap();
        assert_eq!(rec.data(), &[0.0, 1.0, 300.0, 65535.0]);
    }

    #[test]
    fn low_bit_depths_unpacked_raw() {
        // 3 pixels per row at 2 bits: 0b11_01_10_00 -> 3, 1, 2 (last 2 bits are padding).
        let bytes = encode(
            3,
            2,
            png::ColorType::Grayscale,
            png::BitDepth::Two,
            &[0b1101_1000, 0b0001_1000],
        );
        let rec = parse_png(&bytes, "g2.png").unwrap();
        assert_eq!(rec.data(), &[3.0, 1.0, 2.0, 0.0, 1.0, 2.0]);
        let bytes = encode(
            9,
            1,
            png::ColorType::Grayscale,
            png::BitDepth::One,
            &[0b1010_0000, 0b1000_0000],
        );
        let rec = parse_png(&bytes, "g1.png").unwrap();
        assert_eq!(rec.data(), &[1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]);
    }

    #[test]
    fn opaque_grey_alpha_accepted_transparent_rejected() {
        let bytes = encode(
            2,
            1,
            png::ColorType::GrayscaleAlpha,
            png::BitDepth::Eight,
            &[7, 255, 9, 255],
        );
        assert_eq!(parse_png(&bytes, "ga.png").unwrap().data(), &[7.0, 9.0]);
        let bytes = encode(
            2,
            1,
            png::ColorType::GrayscaleAlpha,
            png::BitDepth::Eight,
            &[7, 255, 9, 10],
        );
        let m = parse_png(&bytes, "ga.png").unwrap_err().to_string();
        assert!(
            m.contains("ga.png") && m.contains("column 2") && m.contains("opaque"),
            "{m}"
        );
    }

    #[test]
    fn colour_rejected_with_advice() {
        let bytes = encode(1, 1, png::ColorType::Rgb, png::BitDepth::Eight, &[1, 2, 3]);
        let m = parse_png(&bytes, "c.png").unwrap_err().to_string();
        assert!(
            m.contains("c.png") && m.contains("Rgb") && m.contains("greyscale"),
            "{m}"
        );
    }

    #[test]
    fn garbage_and_truncation() {
        let m = parse_png(b"GIF89a", "x.png").unwrap_err().to_string();
        assert!(m.contains("not a PNG"), "{m}");
        let mut bytes = Vec::new();
        write_png_gray8(&mut bytes, Grid::new(20, 20), &[9; 400]).unwrap();
        let m = parse_png(&bytes[..bytes.len() / 2], "t.png")
            .unwrap_err()
            .to_string();
        assert!(m.contains("t.png"), "{m}");
        assert!(write_png_gray8(&mut Vec::new(), Grid::new(2, 2), &[0; 3]).is_err());
    }

    #[test]
    fn frame_to_grey_levels_and_file() {
        let frame = presrs_core::Frame::with_mask(
            Grid::new(1, 4),
            vec![0.0, 5.0, 10.0, 20.0],
            Some(vec![true, true, true, false]),
        )
        .unwrap();
        assert_eq!(frame_to_gray8(frame.view(), None), vec![0, 128, 255, 0]);
        assert_eq!(
            frame_to_gray8(frame.view(), Some(20.0)),
            vec![0, 64, 128, 0]
        );
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("f.png");
        write_frame_png(frame.view(), None, &path).unwrap();
        assert_eq!(read_png(&path).unwrap().data(), &[0.0, 128.0, 255.0, 0.0]);
    }
}
