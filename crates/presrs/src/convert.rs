//! `presrs convert`: any readable recording to a ROS 2 bag (MCAP) of `sensor_msgs/msg/Image`.

use std::path::{Path, PathBuf};

use presrs_core::Grid;
use presrs_io::mcap::{ImageEncoding, write_recording_mcap};
use presrs_io::{ReadOptions, read_recording_with, write_atomic_with};

use crate::dataset::apply_frame_period_option;
use crate::error::{Error, Result};
use presrs_io::message::Warnings;

/// The topic `convert` writes frames on unless told otherwise.
pub const DEFAULT_FRAMES_TOPIC: &str = "/presrs/frames";

/// How to convert.
#[derive(Clone, Debug)]
pub struct ConvertOptions {
    /// How the input is read (its `topic` when it is a bag).
    pub read: ReadOptions,
    /// The topic of the frames in the output bag.
    pub topic: String,
    /// Frame period of an input whose format states none, seconds (frames are stamped with it; 1 s
    /// apart without one).
    pub frame_period_s: Option<f64>,
}

impl Default for ConvertOptions {
    fn default() -> Self {
        Self {
            read: ReadOptions::default(),
            topic: DEFAULT_FRAMES_TOPIC.to_owned(),
            frame_period_s: None,
        }
    }
}

/// What a conversion wrote.
#[derive(Clone, Debug, PartialEq)]
pub struct Converted {
    pub output: PathBuf,
    pub frames: usize,
    pub grid: Grid,
    pub frame_period_s: Option<f64>,
    pub encoding: ImageEncoding,
    /// The reader's warnings about the input.
    pub warnings: Warnings,
}

/// Converts `input` (any format [`read_recording_with`] reads) into the MCAP file `output`, written
/// atomically: frame `i` stamped `i` frame periods after time 0, `mono16` for integer counts, else
/// `32FC1` (see [`presrs_io::mcap`]).
pub fn convert(input: &Path, output: &Path, options: &ConvertOptions) -> Result<Converted> {
    let is_mcap = output
        .extension()
        .is_some_and(|ext| ext.eq_ignore_ascii_case("mcap"));
    if !is_mcap {
        return Err(Error::invalid(format!(
            "{}: the output must be an MCAP file (.mcap); other formats are not written by convert",
            output.display()
        )));
    }
    let parsed = read_recording_with(input, &options.read)?;
    let mut recording = parsed.recording;
    apply_frame_period_option(&mut recording, options.frame_period_s)?;
    let name = presrs_io::error::display_name(output);
    let encoding = write_atomic_with(output, |w| {
        write_recording_mcap(w, &name, &recording, &options.topic)
    })?;
    Ok(Converted {
        output: output.to_path_buf(),
        frames: recording.frame_count(),
        grid: recording.grid(),
        frame_period_s: recording.frame_period_s(),
        encoding,
        warnings: parsed.warnings,
    })
}
