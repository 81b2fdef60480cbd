//! MCAP files (ROS 2 bags): pressure frames in and out.
//!
//! **Reading** ([`parse_mcap`], [`BagFrames`]): one topic of `sensor_msgs/msg/Image` (encodings mono8,
//! 8UC1, mono16, 16UC1 and 32FC1; either byte order, any row step) or `std_msgs/msg/Float32MultiArray` /
//! `UInt16MultiArray` with a 2-D layout (`dim[0]` rows, `dim[1]` columns), CDR-encoded (either byte
//! order), in plain, zstd or lz4 chunks. The file is read message by message. The topic is the one asked
//! for (`--topic`), else the only one holding frames. Frame times are the image header stamps (when
//! set), else the log times; the frame period is the median time between frames, and gaps are
//! reported as warnings. A frame whose size differs from the first, an unsupported encoding, a topic
//! that is not frames or a damaged file is an error naming the topic and the message index.
//!
//! **Writing** ([`BagWriter`], [`write_recording_mcap`]): frames as `sensor_msgs/msg/Image` in CDR
//! (little endian), `mono16` when every value is an integer in 0..=65535, else `32FC1` (the `f64`
//! values rounded to `f32`), with the ROS 2 message definition as the schema; other messages as JSON
//! with a JSON schema. Both kinds open in Foxglove and in the `mcap` Python readers. The sensor's unit,
//! pitch and outline (absent sensels) go in the image channel's metadata ([`sensor_metadata`]) and are
//! read back.

mod cdr;
mod decisions;
mod reader;
mod writer;

pub use cdr::{IMAGE_MSGDEF, Image, Stamp, decode_image, encode_image};
pub use decisions::{
    DECISIONS_SCHEMA, DECISIONS_SCHEMA_NAME, DECISIONS_TOPIC, DecisionBag, FRAMES_TOPIC,
};
pub use reader::{
    BagFrame, BagFrames, FrameType, TopicInfo, decode_frame, frame_timing, list_topics, parse_mcap,
};
pub use writer::{BagWriter, ImageEncoding, frame_time_ns, sensor_metadata, write_recording_mcap};

/// The first bytes of every MCAP file.
pub const MCAP_MAGIC: &[u8] = b"\x89MCAP0\r\n";
