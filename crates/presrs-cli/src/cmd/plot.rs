//! `presrs plot`: a pressure image as a heat map (PNG or SVG), or a recording as an animated GIF.

use std::io::Write;
use std::path::PathBuf;

use presrs::plot::{Drawing, PlotOptions, Plotted, Still, plot};
use presrs_core::stance::SampleFrame;
use presrs_io::read_recording_with;

/// Draw a pressure image in physical units (kPa when the file says, raw counts otherwise) with a colour
/// bar, at the sensor's true aspect ratio; or, with --movie, an animation of the whole recording with its
/// load curve.
#[derive(Debug, clap::Args)]
#[command(after_help = "Examples:
  presrs plot sim/recordings/wood_G2_000.asf --stance 3 --out wood.png
  presrs plot walk.asf --frame 120 --out frame.svg
  presrs plot walk.asf --movie --out walk.gif")]
pub struct PlotArgs {
    /// The recording (TekScan ASCII, .npy, PNG, text matrix or MCAP).
    pub file: PathBuf,
    /// Frame to draw (0-based). Default: the frame with the largest total load.
    #[arg(long, conflicts_with_all = ["stance", "movie"])]
    pub frame: Option<usize>,
    /// Draw a frame of stance phase N, chosen by --stance-frame; stances are numbered as `presrs
    /// inspect` lists them (0-based, every stance found, those cut by the recording's start or end
    /// included).
    #[arg(long, conflicts_with = "movie")]
    pub stance: Option<usize>,
    /// Which frame of the stance: mid, peak or an offset K after touchdown.
    #[arg(long, default_value = "mid", value_parser = |t: &str| t.parse::<SampleFrame>().map_err(|e| e.to_string()))]
    pub stance_frame: SampleFrame,
    /// Output file: .png or .svg (a .gif with --movie).
    #[arg(long)]
    pub out: PathBuf,
    /// Animate the recording (GIF), with its load curve and detected stances under it.
    #[arg(long)]
    pub movie: bool,
    /// Movie: show every N-th frame (at least 1).
    #[arg(long, default_value_t = 1, value_parser = super::usage::positive_count)]
    pub stride: usize,
    /// Movie: at most this many frames, at least 1 (the stride grows to fit).
    #[arg(long, default_value_t = 300, value_parser = super::usage::positive_count)]
    pub max_frames: usize,
    /// Top of the colour scale, in the shown unit, a finite number above 0 (default: the image's
    /// maximum).
    #[arg(long, value_parser = super::usage::positive_number)]
    pub vmax: Option<f64>,
    /// Outline the region a classifier with this crop would use (default: none drawn).
    #[arg(long = "outline-crop", value_parser = |t: &str| presrs_core::Crop::parse(t).map_err(|e| e.to_string()))]
    pub outline_crop: Option<presrs_core::Crop>,
    /// Accept a TekScan file whose last frame is truncated.
    #[arg(long)]
    pub lenient: bool,
    #[command(flatten)]
    pub axes: super::common::AxesArg,
    #[command(flatten)]
    pub stance_options: super::common::StanceArgs,
}

pub fn run(args: &PlotArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    presrs_io::output_path::check_output_file(&args.out)?;
    let parsed = read_recording_with(&args.file, &args.axes.read_options(args.lenient))?;
    for warning in &parsed.warnings {
        stderr_line!("warning: {warning}");
    }
    let drawing = match (args.movie, args.frame, args.stance) {
        (true, ..) => Drawing::Movie {
            stride: args.stride,
            max_frames: args.max_frames,
            sample: args.stance_frame,
        },
        (false, Some(frame), _) => Drawing::Still(Still::Frame(frame)),
        (false, None, Some(stance)) => Drawing::Still(Still::Stance {
            stance,
            sample: args.stance_frame,
        }),
        (false, None, None) => Drawing::Still(Still::LargestLoad),
    };
    let options = PlotOptions {
        drawing,
        vmax: args.vmax,
        outline_crop: args.outline_crop,
        segment: args.stance_options.segment_params()?,
    };
    match plot(&parsed.recording, &args.file, &options, &args.out)? {
        Plotted::Movie { frames } => {
            writeln!(out, "wrote {} ({frames} frames)", args.out.display())?
        }
        Plotted::Still { frame } => writeln!(out, "wrote {} (frame {frame})", args.out.display())?,
    }
    Ok(())
}
