//! Reading pressure frames from an MCAP file (a ROS 2 bag), message by message.

use std::collections::BTreeMap;
use std::io::Read;
use std::sync::Arc;

use mcap::sans_io::LinearReaderOptions;
use presrs_core::{Grid, PressureUnit, Recording, SensorMeta};

use super::cdr::{self, ArrayElement};
use crate::error::IoError;
use crate::message::{Message, Opt, Warnings};
use crate::parsed::Parsed;

/// Largest MCAP record accepted (a longer claimed length is a damaged file, not a reason to allocate).
const MAX_RECORD_BYTES: usize = 1 << 28;

/// A gap between two frames longer than this many frame periods is reported.
const GAP_PERIODS: f64 = 1.5;

/// The message types a frame can be read from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameType {
    /// `sensor_msgs/msg/Image` (mono8, 8UC1, mono16, 16UC1, 32FC1).
    Image,
    /// `std_msgs/msg/Float32MultiArray` with a 2-D layout (rows, cols).
    Float32MultiArray,
    /// `std_msgs/msg/UInt16MultiArray` with a 2-D layout (rows, cols).
    UInt16MultiArray,
}

impl FrameType {
    /// The frame type of a schema name (`sensor_msgs/msg/Image` or the ROS 1 style `sensor_msgs/Image`).
    pub fn of_schema(name: &str) -> Option<Self> {
        match name.replace("/msg/", "/").as_str() {
            "sensor_msgs/Image" => Some(Self::Image),
            "std_msgs/Float32MultiArray" => Some(Self::Float32MultiArray),
            "std_msgs/UInt16MultiArray" => Some(Self::UInt16MultiArray),
            _ => None,
        }
    }
}

/// What the file holds on one topic.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TopicInfo {
    pub topic: String,
    /// The schema name (e.g. `sensor_msgs/msg/Image`), empty when the channel has none.
    pub schema: String,
    /// The message encoding (`cdr` for ROS 2).
    pub message_encoding: String,
    /// Messages read on the topic.
    pub messages: u64,
}

impl TopicInfo {
    /// Whether presrs can read frames from this topic.
    pub fn has_frames(&self) -> bool {
        FrameType::of_schema(&self.schema).is_some() && self.message_encoding == "cdr"
    }
}

/// One frame read from a bag.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BagFrame {
    pub grid: Grid,
    /// The frame's time, nanoseconds: the header stamp of an image (when set), else the log time.
    pub time_ns: u64,
    /// 0-based index of the message among its topic's messages.
    pub index: u64,
}

/// The frames of one topic of an MCAP file, read message by message from any reader (a file, stdin).
///
/// Without a topic, the first topic whose messages are frames is read; a second such topic is an error
/// asking for one (`--topic`), as is a topic that does not hold frames. Other topics are skipped (and
/// counted in [`Self::topics`]).
pub struct BagFrames<R: Read> {
    messages: mcap::io::MessageReader<R>,
    name: String,
    wanted: Option<String>,
    chosen: Option<(String, FrameType)>,
    grid: Option<Grid>,
    topics: BTreeMap<String, TopicInfo>,
    count: u64,
    failed: bool,
    metadata: BTreeMap<String, String>,
}

impl<R: Read> std::fmt::Debug for BagFrames<R> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BagFrames")
            .field("name", &self.name)
            .field("topic", &self.chosen)
            .field("messages", &self.count)
            .finish_non_exhaustive()
    }
}

impl<R: Read> BagFrames<R> {
    /// Frames of `topic` (`None`: the only topic with frames) from `reader`; `name` names the source in
    /// errors.
    pub fn new(reader: R, name: &str, topic: Option<&str>) -> Self {
        let options = LinearReaderOptions::default().with_record_length_limit(MAX_RECORD_BYTES);
        Self {
            messages: mcap::io::MessageReader::new_with_options(reader, options),
            name: name.to_owned(),
            wanted: topic.map(str::to_owned),
            chosen: None,
            grid: None,
            topics: BTreeMap::new(),
            count: 0,
            failed: false,
            metadata: BTreeMap::new(),
        }
    }

    /// The topics seen so far (all of them once [`Self::next_frame`] returned `None`).
    pub fn topics(&self) -> Vec<TopicInfo> {
        self.topics.values().cloned().collect()
    }

    /// The metadata of the topic's channel (what presrs writes about the sensor: see
    /// [`super::sensor_metadata`]).
    pub fn channel_metadata(&self) -> &BTreeMap<String, String> {
        &self.metadata
    }

    /// The topic being read, once known.
    pub fn topic(&self) -> Option<&str> {
        self.chosen.as_ref().map(|(topic, _)| topic.as_str())
    }

    fn error(&mut self, message: impl Into<Message>) -> IoError {
        self.failed = true;
        IoError::format(&self.name, message)
    }

    /// Reads the next frame into `values` (row-major); `None` at the end of the file. Errors name the
    /// topic and the message index; after one, the reader is done.
    pub fn next_frame(&mut self, values: &mut Vec<f64>) -> Result<Option<BagFrame>, IoError> {
        if self.failed {
            return Ok(None);
        }
        loop {
            let message = match self.messages.next() {
                None => return self.at_end().map(|()| None),
                Some(Ok(message)) => message,
                Some(Err(err)) => {
                    let at = match &self.chosen {
                        Some((topic, _)) => {
                            format!(" after {} messages of topic {topic}", self.count)
                        }
                        None => String::new(),
                    };
                    return Err(self.error(format!("not a readable MCAP file{at}: {err}")));
                }
            };
            let channel = Arc::clone(&message.channel);
            let schema = channel
                .schema
                .as_ref()
                .map(|s| s.name.clone())
                .unwrap_or_default();
            let info = self
                .topics
                .entry(channel.topic.clone())
                .or_insert_with(|| TopicInfo {
                    topic: channel.topic.clone(),
                    schema: schema.clone(),
                    message_encoding: channel.message_encoding.clone(),
                    messages: 0,
                });
            info.messages += 1;
            let frame_type = FrameType::of_schema(&schema);
            let topic = channel.topic.as_str();
            let kind = match (&self.wanted, &self.chosen) {
                (_, Some((chosen, kind))) if chosen == topic => *kind,
                (Some(wanted), _) if wanted != topic => continue,
                (Some(_), _) => match frame_type {
                    Some(kind) => kind,
                    None => {
                        let schema = if schema.is_empty() {
                            "no schema"
                        } else {
                            &schema
                        };
                        return Err(self.error(format!(
                            "topic {topic} holds {schema} messages, not frames (expected \
                             sensor_msgs/msg/Image, std_msgs/msg/Float32MultiArray or \
                             std_msgs/msg/UInt16MultiArray)"
                        )));
                    }
                },
                (None, None) => match frame_type {
                    Some(kind) => kind,
                    None => continue,
                },
                (None, Some((chosen, _))) => {
                    if frame_type.is_none() {
                        continue;
                    }
                    let chosen = chosen.clone();
                    return Err(self.error(
                        Message::from(format!(
                            "it holds frames on several topics ({chosen}, {topic}, ...); choose one \
                             with "
                        ))
                        .opt(Opt::Topic)
                        .text(" (`presrs inspect` lists them)"),
                    ));
                }
            };
            if self.chosen.is_none() {
                self.chosen = Some((topic.to_owned(), kind));
                self.metadata = channel.metadata.clone();
            }
            let index = self.count;
            self.count += 1;
            if channel.message_encoding != "cdr" {
                let encoding = channel.message_encoding.clone();
                return Err(self.error(format!(
                    "topic {topic}: message encoding {encoding:?}, expected \"cdr\" (ROS 2)"
                )));
            }
            let decoded = decode_frame(kind, &message.data, values);
            let (grid, stamp) = match decoded {
                Ok(decoded) => decoded,
                Err(why) => {
                    let topic = topic.to_owned();
                    return Err(self.error(format!("topic {topic} message {index}: {why}")));
                }
            };
            if let Some(first) = self.grid
                && first != grid
            {
                let topic = topic.to_owned();
                return Err(self.error(format!(
                    "topic {topic} message {index}: a {grid} frame, the earlier ones are {first} (the \
                     size must not change within a recording)"
                )));
            }
            self.grid = Some(grid);
            let time_ns = stamp
                .and_then(cdr::Stamp::nanos)
                .filter(|&t| t > 0)
                .unwrap_or(message.log_time);
            return Ok(Some(BagFrame {
                grid,
                time_ns,
                index,
            }));
        }
    }

    fn at_end(&mut self) -> Result<(), IoError> {
        if self.chosen.is_some() {
            return Ok(());
        }
        let listed = self
            .topics
            .values()
            .map(|t| format!("{} ({}, {} messages)", t.topic, t.schema, t.messages))
            .collect::<Vec<_>>()
            .join(", ");
        let listed = if listed.is_empty() {
            "it holds no messages".to_owned()
        } else {
            format!("its topics: {listed}")
        };
        let message = match &self.wanted {
            Some(wanted) => format!("no messages on topic {wanted}; {listed}"),
            None => format!(
                "no topic with frames (sensor_msgs/msg/Image, std_msgs/msg/Float32MultiArray or \
                 std_msgs/msg/UInt16MultiArray); {listed}"
            ),
        };
        Err(self.error(message))
    }
}

/// Decodes one message of `kind` into `values`; returns the frame size and the header stamp.
pub fn decode_frame(
    kind: FrameType,
    data: &[u8],
    values: &mut Vec<f64>,
) -> Result<(Grid, Option<cdr::Stamp>), String> {
    values.clear();
    match kind {
        FrameType::Image => {
            let image = cdr::decode_image(data)?;
            let grid = image_pixels(&image, values)?;
            Ok((grid, Some(image.stamp)))
        }
        FrameType::Float32MultiArray | FrameType::UInt16MultiArray => {
            let element = if kind == FrameType::Float32MultiArray {
                ArrayElement::F32
            } else {
                ArrayElement::U16
            };
            let array = cdr::decode_multi_array(data, element)?;
            let grid = array_values(&array, values)?;
            Ok((grid, None))
        }
    }
}

/// The pixels of a mono image as `f64`, row by row (any row step).
fn image_pixels(image: &cdr::Image<'_>, values: &mut Vec<f64>) -> Result<Grid, String> {
    let bytes_per_pixel = match image.encoding.as_str() {
        "mono8" | "8UC1" => 1,
        "mono16" | "16UC1" => 2,
        "32FC1" => 4,
        other => {
            return Err(format!(
                "image encoding {other:?} is not supported (expected mono8, 8UC1, mono16, 16UC1 or \
                 32FC1: one channel of pressure)"
            ));
        }
    };
    let (rows, cols) = (image.height as usize, image.width as usize);
    if rows == 0 || cols == 0 {
        return Err(format!("an empty image ({rows} x {cols})"));
    }
    let row_bytes = cols * bytes_per_pixel;
    let step = image.step as usize;
    if step < row_bytes {
        return Err(format!(
            "field `step` is {step} bytes, less than a row of {cols} {} pixels ({row_bytes} bytes)",
            image.encoding
        ));
    }
    let needed = step * (rows - 1) + row_bytes;
    if image.data.len() < needed {
        return Err(format!(
            "field `data` has {} bytes, a {rows} x {cols} {} image with step {step} needs {needed}",
            image.data.len(),
            image.encoding
        ));
    }
    values.reserve(rows * cols);
    let big = image.is_bigendian;
    for r in 0..rows {
        let row = &image.data[r * step..r * step + row_bytes];
        match bytes_per_pixel {
            1 => values.extend(row.iter().map(|&b| f64::from(b))),
            2 => values.extend(row.chunks_exact(2).map(|b| {
                let b = [b[0], b[1]];
                f64::from(if big {
                    u16::from_be_bytes(b)
                } else {
                    u16::from_le_bytes(b)
                })
            })),
            _ => {
                for (c, b) in row.chunks_exact(4).enumerate() {
                    let b = [b[0], b[1], b[2], b[3]];
                    let value = if big {
                        f32::from_be_bytes(b)
                    } else {
                        f32::from_le_bytes(b)
                    };
                    if !value.is_finite() {
                        return Err(format!("pixel (row {r}, col {c}) is {value}"));
                    }
                    values.push(f64::from(value));
                }
            }
        }
    }
    Ok(Grid::new(rows, cols))
}

/// The values of a 2-D multi-array (`dim[0]` rows, `dim[1]` columns, `dim[1].stride` apart).
fn array_values(array: &cdr::MultiArray, values: &mut Vec<f64>) -> Result<Grid, String> {
    let [rows_dim, cols_dim] = array.dims.as_slice() else {
        return Err(format!(
            "field `layout.dim` has {} dimensions, expected 2 (rows, cols)",
            array.dims.len()
        ));
    };
    let (rows, cols) = (rows_dim.size as usize, cols_dim.size as usize);
    if rows == 0 || cols == 0 {
        return Err(format!("an empty array ({rows} x {cols})"));
    }
    let stride = match cols_dim.stride as usize {
        0 => cols,
        s => s,
    };
    if stride < cols {
        return Err(format!(
            "field `layout.dim[1].stride` is {stride}, less than the {cols} columns"
        ));
    }
    let offset = array.data_offset as usize;
    let needed = offset + stride * (rows - 1) + cols;
    if array.data.len() < needed {
        return Err(format!(
            "field `data` has {} values, a {rows} x {cols} layout (offset {offset}, stride {stride}) \
             needs {needed}",
            array.data.len()
        ));
    }
    for r in 0..rows {
        let start = offset + r * stride;
        for (c, &value) in array.data[start..start + cols].iter().enumerate() {
            if !value.is_finite() {
                return Err(format!("value (row {r}, col {c}) is {value}"));
            }
            values.push(value);
        }
    }
    Ok(Grid::new(rows, cols))
}

/// Reads one topic of an MCAP file into a recording: the frame period is the median time between
/// frames (header stamps, else log times); gaps longer than 1.5 periods and times that go back are
/// reported in the warnings.
pub fn parse_mcap<R: Read>(reader: R, name: &str, topic: Option<&str>) -> Result<Parsed, IoError> {
    let mut frames = BagFrames::new(reader, name, topic);
    let mut data = Vec::new();
    let mut values = Vec::new();
    let mut times = Vec::new();
    let mut grid = None;
    while let Some(frame) = frames.next_frame(&mut values)? {
        data.extend_from_slice(&values);
        times.push(frame.time_ns);
        grid = Some(frame.grid);
    }
    let topic = frames.topic().unwrap_or_default().to_owned();
    let grid = grid.ok_or_else(|| IoError::format(name, format!("topic {topic} has no frames")))?;
    let (period, mut warnings) = frame_timing(name, &topic, &times);
    let metadata = frames.channel_metadata();
    let number = |key: &str| {
        metadata
            .get(key)
            .and_then(|v| v.parse::<f64>().ok())
            .filter(|v| v.is_finite() && *v > 0.0)
    };
    let meta = SensorMeta {
        sensor: metadata.get("presrs.sensor").cloned(),
        units: metadata.get("presrs.units").map(|u| PressureUnit::parse(u)),
        row_pitch_mm: number("presrs.row_pitch_mm"),
        col_pitch_mm: number("presrs.col_pitch_mm"),
        extra: vec![("MCAP_TOPIC".to_owned(), topic.clone())],
        ..SensorMeta::default()
    };
    let present = match metadata.get("presrs.present") {
        Some(mask) if mask.len() == grid.len() && mask.bytes().all(|b| b == b'0' || b == b'1') => {
            Some(mask.bytes().map(|b| b == b'1').collect())
        }
        Some(_) => {
            warnings.push(format!(
                "{name}: topic {topic}: channel metadata `presrs.present` is not one 0 or 1 per \
                 sensel of a {grid} frame; ignored (every sensel taken as present)"
            ));
            None
        }
        None => None,
    };
    let recording =
        Recording::new(grid, period, data, present, meta).map_err(|source| IoError::Model {
            file: name.to_owned(),
            source,
        })?;
    Ok(Parsed {
        recording,
        warnings,
    })
}

/// The frame period of frames at `times` (ns): the median of the positive differences; and a warning
/// for each gap (up to 10, then a count) and for times that do not increase.
pub fn frame_timing(name: &str, topic: &str, times: &[u64]) -> (Option<f64>, Warnings) {
    let mut steps: Vec<u64> = times
        .windows(2)
        .filter_map(|w| w[1].checked_sub(w[0]))
        .filter(|&d| d > 0)
        .collect();
    let mut warnings = Warnings::new();
    let backwards = times.windows(2).filter(|w| w[1] <= w[0]).count();
    if backwards > 0 {
        warnings.push(format!(
            "{name}: topic {topic}: {backwards} frame time(s) do not increase (kept in file order)"
        ));
    }
    if steps.is_empty() {
        return (None, warnings);
    }
    steps.sort_unstable();
    let median = steps[steps.len() / 2];
    let period = median as f64 * 1e-9;
    let gaps: Vec<(usize, u64)> = times
        .windows(2)
        .enumerate()
        .filter_map(|(i, w)| w[1].checked_sub(w[0]).map(|d| (i + 1, d)))
        .filter(|&(_, d)| d as f64 > GAP_PERIODS * median as f64)
        .collect();
    for &(index, d) in gaps.iter().take(10) {
        let missing = (d as f64 / median as f64).round() as u64 - 1;
        warnings.push(format!(
            "{name}: topic {topic}: a gap of {:.6} s before message {index} (about {missing} frame(s) \
             missing at the frame period of {period:.6} s)",
            d as f64 * 1e-9
        ));
    }
    if gaps.len() > 10 {
        warnings.push(format!(
            "{name}: topic {topic}: {} more gaps in the frame times",
            gaps.len() - 10
        ));
    }
    (Some(period), warnings)
}

/// Every topic of an MCAP file with its schema and message count (read to the end, nothing decoded).
pub fn list_topics<R: Read>(reader: R, name: &str) -> Result<Vec<TopicInfo>, IoError> {
    let options = LinearReaderOptions::default().with_record_length_limit(MAX_RECORD_BYTES);
    let mut topics: BTreeMap<String, TopicInfo> = BTreeMap::new();
    for message in mcap::io::MessageReader::new_with_options(reader, options) {
        let message = message
            .map_err(|err| IoError::format(name, format!("not a readable MCAP file: {err}")))?;
        let channel = &message.channel;
        topics
            .entry(channel.topic.clone())
            .or_insert_with(|| TopicInfo {
                topic: channel.topic.clone(),
                schema: channel
                    .schema
                    .as_ref()
                    .map(|s| s.name.clone())
                    .unwrap_or_default(),
                message_encoding: channel.message_encoding.clone(),
                messages: 0,
            })
            .messages += 1;
    }
    Ok(topics.into_values().collect())
}
