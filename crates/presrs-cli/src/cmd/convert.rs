//! `presrs convert`: a recording to a ROS 2 bag (MCAP).

use std::io::Write;
use std::path::PathBuf;

use presrs::convert::{ConvertOptions, DEFAULT_FRAMES_TOPIC, convert};

use super::common::AxesArg;

/// Convert a recording (any format presrs reads) to a ROS 2 bag (MCAP) of sensor_msgs/msg/Image.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Frames are written as sensor_msgs/msg/Image (CDR, little endian): mono16 when \
every value is an integer in 0..65535 (raw TekScan counts, exact), else 32FC1 (32-bit floats: values \
are rounded to f32). Frame i is stamped i frame periods after time 0 (header stamp and log time; 1 s \
apart when the period is unknown: give --frame-period). The file appears complete or not at all.\n\n\
Example:\n  presrs convert sim/recordings/wood_G2_000.asf wood.mcap"
)]
pub struct ConvertArgs {
    /// The recording to convert (TekScan ASCII, .npy, .png, text matrix, or another MCAP file).
    pub input: PathBuf,
    /// The MCAP file to write (.mcap).
    pub output: PathBuf,
    /// The topic of the frames in the output.
    #[arg(long, default_value = DEFAULT_FRAMES_TOPIC, value_name = "NAME")]
    pub out_topic: String,
    /// Frame period in seconds of an input whose format states none (.npy, text, PNG).
    #[arg(long, value_name = "SECONDS", value_parser = super::usage::positive_seconds)]
    pub frame_period: Option<f64>,
    /// Accept a TekScan file whose last frame is truncated.
    #[arg(long)]
    pub lenient: bool,
    #[command(flatten)]
    pub read: AxesArg,
}

pub fn run(args: &ConvertArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    presrs_io::output_path::check_output_file(&args.output)?;
    let options = ConvertOptions {
        read: args.read.read_options(args.lenient),
        topic: args.out_topic.clone(),
        frame_period_s: args.frame_period,
    };
    let converted = convert(&args.input, &args.output, &options)?;
    for warning in &converted.warnings {
        stderr_line!("warning: {warning}");
    }
    let period = converted.frame_period_s.map_or_else(
        || "period unknown: 1 s apart".to_owned(),
        |p| format!("{p} s apart"),
    );
    writeln!(
        out,
        "wrote {}: {} frames of {} on {} ({}, {period})",
        converted.output.display(),
        converted.frames,
        converted.grid,
        args.out_topic,
        converted.encoding.as_str()
    )?;
    Ok(())
}
