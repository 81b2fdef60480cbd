//! Writing MCAP files: pressure frames as `sensor_msgs/msg/Image` (ROS 2, CDR) and JSON messages with a
//! JSON schema (what Foxglove shows as they are).

use std::collections::BTreeMap;
use std::io::Write;

use mcap::write::NoSeek;
use presrs_core::{Grid, Recording};

use super::cdr::{self, Stamp};
use crate::error::IoError;

/// How frames are stored in the image messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageEncoding {
    /// `mono16`: unsigned 16-bit integers (exact for integer values in 0..=65535).
    Mono16,
    /// `32FC1`: 32-bit floats (presrs's `f64` values rounded to `f32`).
    Float32,
}

impl ImageEncoding {
    /// `mono16` when every value is an integer in 0..=65535 (the raw counts of a TekScan sensor: stored
    /// exactly), else `32FC1`.
    pub fn for_values<'a>(mut values: impl Iterator<Item = &'a f64>) -> Self {
        let integers = values.all(|&v| v.fract() == 0.0 && (0.0..=65535.0).contains(&v));
        if integers {
            Self::Mono16
        } else {
            Self::Float32
        }
    }

    /// The ROS encoding name.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Mono16 => "mono16",
            Self::Float32 => "32FC1",
        }
    }
}

/// An MCAP file being written to any writer (no seeking: zstd chunks with their indexes and the
/// summary at the end). Nothing is complete before [`BagWriter::finish`].
pub struct BagWriter<W: Write> {
    writer: mcap::Writer<NoSeek<W>>,
    name: String,
    image_schema: Option<u16>,
    sequence: u32,
}

/// An MCAP error as an [`IoError`] naming the file.
fn mcap_error(name: &str, err: mcap::McapError) -> IoError {
    IoError::format(name, format!("cannot write MCAP: {err}"))
}

impl<W: Write> std::fmt::Debug for BagWriter<W> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BagWriter")
            .field("name", &self.name)
            .field("messages", &self.sequence)
            .finish_non_exhaustive()
    }
}

impl<W: Write> BagWriter<W> {
    /// Starts an MCAP file (profile `ros2`) on `writer`; `name` names it in errors.
    pub fn new(writer: W, name: &str) -> Result<Self, IoError> {
        let writer = mcap::WriteOptions::new()
            .profile("ros2")
            .library(concat!("presrs ", env!("CARGO_PKG_VERSION")))
            .disable_seeking(true)
            .create(NoSeek::new(writer))
            .map_err(|err| mcap_error(name, err))?;
        Ok(Self {
            writer,
            name: name.to_owned(),
            image_schema: None,
            sequence: 0,
        })
    }

    /// Adds a topic of `sensor_msgs/msg/Image` messages; returns its channel id.
    pub fn add_image_topic(&mut self, topic: &str) -> Result<u16, IoError> {
        self.add_image_topic_with(topic, &BTreeMap::new())
    }

    /// [`Self::add_image_topic`] with channel metadata (see [`sensor_metadata`]).
    pub fn add_image_topic_with(
        &mut self,
        topic: &str,
        metadata: &BTreeMap<String, String>,
    ) -> Result<u16, IoError> {
        let schema = match self.image_schema {
            Some(id) => id,
            None => {
                let id = self
                    .writer
                    .add_schema(
                        "sensor_msgs/msg/Image",
                        "ros2msg",
                        cdr::IMAGE_MSGDEF.as_bytes(),
                    )
                    .map_err(|err| mcap_error(&self.name, err))?;
                self.image_schema = Some(id);
                id
            }
        };
        self.writer
            .add_channel(schema, topic, "cdr", metadata)
            .map_err(|err| mcap_error(&self.name, err))
    }

    /// Adds a topic of JSON messages described by `json_schema` (a JSON Schema document) named
    /// `schema_name`; returns its channel id.
    pub fn add_json_topic(
        &mut self,
        topic: &str,
        schema_name: &str,
        json_schema: &str,
    ) -> Result<u16, IoError> {
        let schema = self
            .writer
            .add_schema(schema_name, "jsonschema", json_schema.as_bytes())
            .map_err(|err| mcap_error(&self.name, err))?;
        self.writer
            .add_channel(schema, topic, "json", &Default::default())
            .map_err(|err| mcap_error(&self.name, err))
    }

    fn write_message(&mut self, channel: u16, time_ns: u64, data: &[u8]) -> Result<(), IoError> {
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: self.sequence,
            log_time: time_ns,
            publish_time: time_ns,
        };
        self.sequence = self.sequence.wrapping_add(1);
        self.writer
            .write_to_known_channel(&header, data)
            .map_err(|err| mcap_error(&self.name, err))
    }

    /// Writes one frame (row-major `values` of `grid`) as an image stamped `time_ns` (header stamp and
    /// log time alike). With [`ImageEncoding::Mono16`] values are rounded and clamped to 0..=65535.
    pub fn write_image(
        &mut self,
        channel: u16,
        time_ns: u64,
        grid: Grid,
        values: &[f64],
        encoding: ImageEncoding,
    ) -> Result<(), IoError> {
        let pixels: Vec<u8> = match encoding {
            ImageEncoding::Mono16 => values
                .iter()
                .flat_map(|&v| (v.round().clamp(0.0, 65535.0) as u16).to_le_bytes())
                .collect(),
            ImageEncoding::Float32 => values
                .iter()
                .flat_map(|&v| (v as f32).to_le_bytes())
                .collect(),
        };
        let bytes_per_pixel = match encoding {
            ImageEncoding::Mono16 => 2,
            ImageEncoding::Float32 => 4,
        };
        let image = cdr::Image {
            stamp: Stamp::from_nanos(time_ns),
            frame_id: "presrs".to_owned(),
            height: grid.rows as u32,
            width: grid.cols as u32,
            encoding: encoding.as_str().to_owned(),
            is_bigendian: false,
            step: (grid.cols * bytes_per_pixel) as u32,
            data: &pixels,
        };
        self.write_message(channel, time_ns, &cdr::encode_image(&image))
    }

    /// Writes one JSON message (`text`, one JSON document) logged at `time_ns`.
    pub fn write_json(&mut self, channel: u16, time_ns: u64, text: &str) -> Result<(), IoError> {
        self.write_message(channel, time_ns, text.as_bytes())
    }

    /// Writes a metadata record `name` of `entries` (what the file as a whole is, e.g. where its
    /// times come from).
    pub fn write_metadata(
        &mut self,
        name: &str,
        entries: BTreeMap<String, String>,
    ) -> Result<(), IoError> {
        let metadata = mcap::records::Metadata {
            name: name.to_owned(),
            metadata: entries,
        };
        self.writer
            .write_metadata(&metadata)
            .map_err(|err| mcap_error(&self.name, err))
    }

    /// Writes the summary and the footer; returns the underlying writer.
    pub fn finish(mut self) -> Result<W, IoError> {
        self.writer
            .finish()
            .map_err(|err| mcap_error(&self.name, err))?;
        Ok(self.writer.into_inner().into_inner())
    }
}

/// What a recording's metadata says about its sensor, as channel metadata of its image topic (keys
/// `presrs.sensor`, `presrs.units`, `presrs.row_pitch_mm`, `presrs.col_pitch_mm`, and `presrs.present`:
/// one `1` or `0` per sensel, row-major, when some are absent), so that a converted recording keeps its
/// unit, pitch and outline. The reader takes them back ([`super::parse_mcap`]).
pub fn sensor_metadata(recording: &Recording) -> BTreeMap<String, String> {
    let meta = &recording.meta;
    let mut out = BTreeMap::new();
    if let Some(sensor) = &meta.sensor {
        out.insert("presrs.sensor".to_owned(), sensor.clone());
    }
    if let Some(units) = &meta.units {
        out.insert("presrs.units".to_owned(), units.as_tekscan().to_owned());
    }
    if let Some(pitch) = meta.row_pitch_mm {
        out.insert("presrs.row_pitch_mm".to_owned(), pitch.to_string());
    }
    if let Some(pitch) = meta.col_pitch_mm {
        out.insert("presrs.col_pitch_mm".to_owned(), pitch.to_string());
    }
    if let Some(present) = recording.present() {
        let mask = present.iter().map(|&p| if p { '1' } else { '0' }).collect();
        out.insert("presrs.present".to_owned(), mask);
    }
    out
}

/// Nanoseconds of frame `index` of a recording: `index` frame periods (1 s when it has none).
pub fn frame_time_ns(recording: &Recording, index: usize) -> u64 {
    let period = recording.frame_period_s().unwrap_or(1.0);
    (index as f64 * period * 1e9).round() as u64
}

/// Writes `recording` as an MCAP file of `sensor_msgs/msg/Image` messages on `topic` (encoding chosen
/// by [`ImageEncoding::for_values`]), frame `i` stamped `i` frame periods after time 0 (1 s apart when
/// the period is unknown). Absent sensels are written as 0 (and listed in the channel metadata, with
/// the unit and pitch: [`sensor_metadata`]).
pub fn write_recording_mcap(
    writer: &mut dyn Write,
    name: &str,
    recording: &Recording,
    topic: &str,
) -> Result<ImageEncoding, IoError> {
    let encoding = ImageEncoding::for_values(recording.data().iter());
    let mut bag = BagWriter::new(writer, name)?;
    let channel = bag.add_image_topic_with(topic, &sensor_metadata(recording))?;
    for (index, frame) in recording.frames().enumerate() {
        let time = frame_time_ns(recording, index);
        bag.write_image(channel, time, recording.grid(), frame.values(), encoding)?;
    }
    bag.finish()?;
    Ok(encoding)
}
