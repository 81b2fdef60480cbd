//! `presrs plot`: a pressure image as a heat map (PNG or SVG), or a recording as an animated GIF.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use presrs_core::stance::{SampleFrame, segment_recording};
use presrs_io::read_recording_with;
use presrs_report::render::{Format, save_figure};
use presrs_report::{MovieOptions, PressureFigure, PressureScale, write_movie};

/// Draw a pressure image in physical units (kPa when the file says, raw counts otherwise) with a colour
/// bar, at the sensor's true aspect ratio; or, with --movie, an animation of the whole recording with its
/// load curve.
#[derive(Debug, clap::Args)]
#[command(after_help = "Examples:
  presrs plot sim/recordings/wood_G2_000.asf --stance 3 --out wood.png
  presrs plot walk.asf --frame 120 --out frame.svg
  presrs plot walk.asf --movie --out walk.gif")]
pub struct PlotArgs {
    /// The recording (TekScan, .npy, PNG or text matrix).
    pub file: PathBuf,
    /// Frame to draw (0-based). Default: the frame with the largest total load.
    #[arg(long, conflicts_with_all = ["stance", "movie"])]
    pub frame: Option<usize>,
    /// Draw a frame of the N-th complete stance phase (0-based), chosen by --stance-frame.
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
    let read = presrs_io::ReadOptions {
        lenient: args.lenient,
        axes: args.axes.axes,
        topic: args.axes.topic.clone(),
    };
    let parsed = read_recording_with(&args.file, &read)?;
    for warning in &parsed.warnings {
        stderr_line!("warning: {warning}");
    }
    let recording = parsed.recording;
    anyhow::ensure!(
        recording.frame_count() > 0,
        "{}: the recording has no frames",
        args.file.display()
    );
    let name = args.file.file_name().map_or_else(
        || args.file.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    let format = Format::of(&args.out)?;
    if args.movie {
        anyhow::ensure!(
            format == Format::Gif,
            "--movie writes an animated GIF: give --out a .gif name"
        );
        let options = MovieOptions {
            stride: args.stride,
            max_frames: args.max_frames,
            segment: args.stance_options.segment_params()?,
            sample: args.stance_frame,
            title: name,
        };
        let frames = write_movie(&recording, &options, &args.out)
            .with_context(|| format!("cannot write {}", args.out.display()))?;
        writeln!(out, "wrote {} ({frames} frames)", args.out.display())?;
        return Ok(());
    }
    anyhow::ensure!(
        format != Format::Gif,
        "a .gif is an animation: add --movie (or write a .png or .svg)"
    );
    let count = recording.frame_count();
    let (index, what) = match (args.frame, args.stance) {
        (Some(frame), _) => {
            anyhow::ensure!(
                frame < count,
                "{}: --frame {frame} but the recording has {count} frame(s) (frames are 0-based)",
                args.file.display()
            );
            (frame, format!("frame {frame}"))
        }
        (None, Some(n)) => {
            let segmentation =
                segment_recording(&recording, &args.stance_options.segment_params()?)?;
            let stances: Vec<_> = segmentation.complete().collect();
            let stance = stances.get(n).with_context(|| {
                format!(
                    "{}: --stance {n} but {} complete stance phase(s) were found (0-based)",
                    args.file.display(),
                    stances.len()
                )
            })?;
            let frames = presrs_core::stance::sample_frames(stance, args.stance_frame)?;
            let frame = *frames
                .get(frames.len() / 2)
                .context("the stance gives no frame")?;
            (
                frame,
                format!("stance {n} ({} frame), frame {frame}", args.stance_frame),
            )
        }
        (None, None) => {
            let totals = recording.total_per_frame();
            let frame = totals
                .iter()
                .enumerate()
                .max_by(|a, b| a.1.total_cmp(b.1))
                .map_or(0, |(i, _)| i);
            let what = if count > 1 {
                format!("frame {frame} (largest load)")
            } else {
                String::new()
            };
            (frame, what)
        }
    };
    let frame = recording
        .frame(index)
        .with_context(|| format!("no frame {index}"))?;
    let scale = PressureScale::from_meta(Some(&recording.meta));
    let title = if what.is_empty() {
        name
    } else {
        format!("{name} — {what}")
    };
    let mut figure = PressureFigure::new(frame, scale, title);
    figure.vmax = args.vmax;
    if let Some(crop) = args.outline_crop {
        let (row, col, grid) = crop.window(frame.grid())?;
        figure.outline = Some(presrs_report::pressure::Outline { row, col, grid });
    }
    save_figure(&figure, &args.out)
        .with_context(|| format!("cannot write {}", args.out.display()))?;
    writeln!(out, "wrote {}", args.out.display())?;
    Ok(())
}
