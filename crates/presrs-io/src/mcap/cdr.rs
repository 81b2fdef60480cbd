//! CDR (the ROS 2 wire format) of the few messages presrs reads and writes: `sensor_msgs/msg/Image`,
//! `std_msgs/msg/Float32MultiArray` and `UInt16MultiArray`.
//!
//! A CDR message starts with a 4-byte encapsulation header whose second byte says the byte order
//! (`0x00`: big endian, `0x01`: little endian; plain CDR and XCDR2 alike, which agree for these
//! messages); each primitive is aligned to its size, counted from the end of that header.

/// The ROS 2 message definition of `sensor_msgs/msg/Image` with its dependencies, as `ros2msg` schemas
/// carry it (what Foxglove and the Python readers parse).
pub const IMAGE_MSGDEF: &str = "std_msgs/Header header
uint32 height
uint32 width
string encoding
uint8 is_bigendian
uint32 step
uint8[] data
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
";

/// A stamp: seconds and nanoseconds since the epoch (ROS `builtin_interfaces/Time`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stamp {
    pub sec: i32,
    pub nanosec: u32,
}

impl Stamp {
    /// Nanoseconds since the epoch (`None` before it).
    pub fn nanos(self) -> Option<u64> {
        u64::try_from(self.sec)
            .ok()
            .map(|sec| sec * 1_000_000_000 + u64::from(self.nanosec))
    }

    /// The stamp of `nanos` nanoseconds since the epoch (seconds beyond `i32` saturate).
    pub fn from_nanos(nanos: u64) -> Self {
        Self {
            sec: i32::try_from(nanos / 1_000_000_000).unwrap_or(i32::MAX),
            nanosec: (nanos % 1_000_000_000) as u32,
        }
    }
}

/// A decoded `sensor_msgs/msg/Image` (the pixel bytes borrowed from the message).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Image<'a> {
    pub stamp: Stamp,
    pub frame_id: String,
    pub height: u32,
    pub width: u32,
    pub encoding: String,
    pub is_bigendian: bool,
    pub step: u32,
    pub data: &'a [u8],
}

/// One dimension of a `std_msgs/MultiArrayLayout`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Dimension {
    pub label: String,
    pub size: u32,
    pub stride: u32,
}

/// A decoded `Float32MultiArray` or `UInt16MultiArray`, its values widened to `f64`.
#[derive(Clone, Debug, PartialEq)]
pub struct MultiArray {
    pub dims: Vec<Dimension>,
    pub data_offset: u32,
    pub data: Vec<f64>,
}

/// The element type of a multi-array message.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ArrayElement {
    F32,
    U16,
}

/// A cursor over one CDR message; every read checks the bounds (a short message is an error, not a
/// panic).
struct Cursor<'a> {
    bytes: &'a [u8],
    /// Position in `bytes`; alignment counts from 4 (after the encapsulation header).
    at: usize,
    little: bool,
}

impl<'a> Cursor<'a> {
    fn new(bytes: &'a [u8]) -> Result<Self, String> {
        let header = bytes
            .get(..4)
            .ok_or_else(|| format!("{} bytes, too short for a CDR header", bytes.len()))?;
        let little = match (header[0], header[1]) {
            // CDR_BE, CDR_LE, and XCDR2's PLAIN_CDR2 (the same layout for these messages).
            (0, 0) | (0, 6) | (0, 0x10) => false,
            (0, 1) | (0, 7) | (0, 0x11) => true,
            (a, b) => {
                return Err(format!(
                    "unsupported CDR encapsulation 0x{a:02x}{b:02x} (expected plain CDR, 0x0000 or 0x0001)"
                ));
            }
        };
        Ok(Self {
            bytes,
            at: 4,
            little,
        })
    }

    fn align(&mut self, size: usize) {
        let offset = self.at - 4;
        self.at += (size - offset % size) % size;
    }

    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        let end = self
            .at
            .checked_add(n)
            .filter(|&end| end <= self.bytes.len());
        match end {
            Some(end) => {
                let slice = &self.bytes[self.at..end];
                self.at = end;
                Ok(slice)
            }
            None => Err(format!(
                "message ends in field `{what}` (needs {n} bytes at offset {}, the message has {})",
                self.at,
                self.bytes.len()
            )),
        }
    }

    fn u8(&mut self, what: &str) -> Result<u8, String> {
        Ok(self.take(1, what)?[0])
    }

    fn u32(&mut self, what: &str) -> Result<u32, String> {
        self.align(4);
        let b: [u8; 4] = self
            .take(4, what)?
            .try_into()
            .map_err(|_| what.to_owned())?;
        Ok(if self.little {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        })
    }

    fn string(&mut self, what: &str) -> Result<String, String> {
        let len = self.u32(what)? as usize;
        let bytes = self.take(len, what)?;
        // The length counts a terminating NUL.
        let text = bytes.strip_suffix(&[0]).unwrap_or(bytes);
        String::from_utf8(text.to_vec()).map_err(|_| format!("field `{what}` is not UTF-8"))
    }

    fn stamp(&mut self) -> Result<Stamp, String> {
        let sec = self.u32("header.stamp.sec")? as i32;
        let nanosec = self.u32("header.stamp.nanosec")?;
        Ok(Stamp { sec, nanosec })
    }
}

/// Decodes a CDR `sensor_msgs/msg/Image`; the error says which field is short or wrong.
pub fn decode_image(bytes: &[u8]) -> Result<Image<'_>, String> {
    let mut c = Cursor::new(bytes)?;
    let stamp = c.stamp()?;
    let frame_id = c.string("header.frame_id")?;
    let height = c.u32("height")?;
    let width = c.u32("width")?;
    let encoding = c.string("encoding")?;
    let is_bigendian = c.u8("is_bigendian")? != 0;
    let step = c.u32("step")?;
    let len = c.u32("data")? as usize;
    let data = c.take(len, "data")?;
    Ok(Image {
        stamp,
        frame_id,
        height,
        width,
        encoding,
        is_bigendian,
        step,
        data,
    })
}

/// Decodes a CDR `Float32MultiArray` or `UInt16MultiArray`.
pub fn decode_multi_array(bytes: &[u8], element: ArrayElement) -> Result<MultiArray, String> {
    let mut c = Cursor::new(bytes)?;
    let count = c.u32("layout.dim")? as usize;
    // Each dimension takes at least 12 bytes: a claimed count the message cannot hold is an error
    // before anything is allocated for it.
    if count > bytes.len() / 12 {
        return Err(format!(
            "field `layout.dim` claims {count} dimensions in a {}-byte message",
            bytes.len()
        ));
    }
    let mut dims = Vec::with_capacity(count);
    for _ in 0..count {
        let label = c.string("layout.dim.label")?;
        let size = c.u32("layout.dim.size")?;
        let stride = c.u32("layout.dim.stride")?;
        dims.push(Dimension {
            label,
            size,
            stride,
        });
    }
    let data_offset = c.u32("layout.data_offset")?;
    let len = c.u32("data")? as usize;
    let data = match element {
        ArrayElement::F32 => {
            c.align(4);
            let raw = c.take(len.saturating_mul(4), "data")?;
            raw.chunks_exact(4)
                .map(|b| {
                    let b = [b[0], b[1], b[2], b[3]];
                    f64::from(if c.little {
                        f32::from_le_bytes(b)
                    } else {
                        f32::from_be_bytes(b)
                    })
                })
                .collect()
        }
        ArrayElement::U16 => {
            c.align(2);
            let raw = c.take(len.saturating_mul(2), "data")?;
            raw.chunks_exact(2)
                .map(|b| {
                    let b = [b[0], b[1]];
                    f64::from(if c.little {
                        u16::from_le_bytes(b)
                    } else {
                        u16::from_be_bytes(b)
                    })
                })
                .collect()
        }
    };
    Ok(MultiArray {
        dims,
        data_offset,
        data,
    })
}

/// A little-endian CDR writer.
struct Encoder {
    bytes: Vec<u8>,
}

impl Encoder {
    fn new(capacity: usize) -> Self {
        let mut bytes = Vec::with_capacity(capacity + 64);
        bytes.extend_from_slice(&[0, 1, 0, 0]);
        Self { bytes }
    }

    fn align(&mut self, size: usize) {
        while (self.bytes.len() - 4) % size != 0 {
            self.bytes.push(0);
        }
    }

    fn u32(&mut self, value: u32) {
        self.align(4);
        self.bytes.extend_from_slice(&value.to_le_bytes());
    }

    fn string(&mut self, text: &str) {
        self.u32(text.len() as u32 + 1);
        self.bytes.extend_from_slice(text.as_bytes());
        self.bytes.push(0);
    }
}

/// Encodes a `sensor_msgs/msg/Image` as little-endian CDR (`image.is_bigendian` is written as given).
pub fn encode_image(image: &Image<'_>) -> Vec<u8> {
    let mut e = Encoder::new(image.data.len());
    e.u32(image.stamp.sec as u32);
    e.u32(image.stamp.nanosec);
    e.string(&image.frame_id);
    e.u32(image.height);
    e.u32(image.width);
    e.string(&image.encoding);
    e.bytes.push(u8::from(image.is_bigendian));
    e.u32(image.step);
    e.u32(image.data.len() as u32);
    e.bytes.extend_from_slice(image.data);
    e.bytes
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    #[test]
    fn image_round_trips_and_short_messages_name_the_field() {
        let data = [1u8, 2, 3, 4, 5, 6];
        let image = Image {
            stamp: Stamp {
                sec: 12,
                nanosec: 345,
            },
            frame_id: "foot".to_owned(),
            height: 1,
            width: 3,
            encoding: "mono16".to_owned(),
            is_bigendian: false,
            step: 6,
            data: &data,
        };
        let bytes = encode_image(&image);
        assert_eq!(decode_image(&bytes).unwrap(), image);
        let err = decode_image(&bytes[..bytes.len() - 1]).unwrap_err();
        assert!(err.contains("field `data`"), "{err}");
        let err = decode_image(&bytes[..20]).unwrap_err();
        assert!(
            err.contains("field `height`") || err.contains("frame_id"),
            "{err}"
        );
        assert!(
            decode_image(&[9, 9, 0, 0])
                .unwrap_err()
                .contains("encapsulation")
        );
    }
}
