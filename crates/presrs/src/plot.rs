//! `presrs plot`: what to draw of a recording (a frame chosen by number, by stance or by load, or the
//! whole recording as a movie) and drawing it ([`presrs_report`]).

use std::path::Path;

use presrs_core::Recording;
use presrs_core::stance::{SampleFrame, ValidSegmentParams, sample_frames, segment_recording};
use presrs_report::pressure::Outline;
use presrs_report::render::{Format, save_figure};
use presrs_report::{MovieOptions, PressureFigure, PressureScale, write_movie};

use crate::error::{Context, Error, Result};

/// Which frame a still figure shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Still {
    /// This frame (0-based).
    Frame(usize),
    /// A frame of the N-th stance phase (0-based), chosen by `sample`. Stances are numbered as
    /// `presrs inspect` numbers them: every stance found, partial ones (cut by the recording's start
    /// or end) included.
    Stance { stance: usize, sample: SampleFrame },
    /// The frame with the largest total load.
    LargestLoad,
}

/// What `plot` draws.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Drawing {
    /// One frame as a heat map (PNG or SVG).
    Still(Still),
    /// The recording as an animated GIF, with its load curve and stances.
    Movie {
        /// Show every N-th frame (at least 1).
        stride: usize,
        /// At most this many frames (the stride grows to fit).
        max_frames: usize,
        /// Which frame of each stance is marked.
        sample: SampleFrame,
    },
}

/// How a recording is drawn.
#[derive(Clone, Debug)]
pub struct PlotOptions {
    pub drawing: Drawing,
    /// Top of the colour scale, in the shown unit (`None`: the image's maximum).
    pub vmax: Option<f64>,
    /// Outline the region a classifier with this crop would use.
    pub outline_crop: Option<presrs_core::Crop>,
    /// How stance phases are found.
    pub segment: ValidSegmentParams,
}

/// What [`plot`] wrote.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Plotted {
    /// A still figure of this frame.
    Still { frame: usize },
    /// A movie of this many frames.
    Movie { frames: usize },
}

/// Draws `recording` (read from `file`, whose name titles the figure) into `out`: a still figure
/// (.png or .svg) or, for [`Drawing::Movie`], an animated GIF.
pub fn plot(
    recording: &Recording,
    file: &Path,
    options: &PlotOptions,
    out: &Path,
) -> Result<Plotted> {
    if recording.frame_count() == 0 {
        return Err(Error::data(format!(
            "{}: the recording has no frames",
            file.display()
        )));
    }
    let name = file.file_name().map_or_else(
        || file.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    let format = Format::of(out)?;
    let still = match options.drawing {
        Drawing::Movie {
            stride,
            max_frames,
            sample,
        } => {
            if format != Format::Gif {
                return Err(Error::invalid(
                    "--movie writes an animated GIF: give --out a .gif name",
                ));
            }
            let movie = MovieOptions {
                stride,
                max_frames,
                segment: options.segment.clone(),
                sample,
                title: name,
            };
            let frames = write_movie(recording, &movie, out)
                .with_context(|| format!("cannot write {}", out.display()))?;
            return Ok(Plotted::Movie { frames });
        }
        Drawing::Still(still) => still,
    };
    if format == Format::Gif {
        return Err(Error::invalid(
            "a .gif is an animation: add --movie (or write a .png or .svg)",
        ));
    }
    let (index, what) = still_frame(recording, file, still, &options.segment)?;
    let frame = recording
        .frame(index)
        .ok_or_else(|| Error::data(format!("no frame {index}")))?;
    let title = if what.is_empty() {
        name
    } else {
        format!("{name} — {what}")
    };
    let mut figure = PressureFigure::new(
        frame,
        PressureScale::from_meta(Some(&recording.meta)),
        title,
    );
    figure.vmax = options.vmax;
    if let Some(crop) = options.outline_crop {
        let (row, col, grid) = crop.window(frame.grid())?;
        figure.outline = Some(Outline { row, col, grid });
    }
    save_figure(&figure, out).with_context(|| format!("cannot write {}", out.display()))?;
    Ok(Plotted::Still { frame: index })
}

/// The frame a still figure shows, and how its title names it (empty for a one-frame recording).
fn still_frame(
    recording: &Recording,
    file: &Path,
    still: Still,
    segment: &ValidSegmentParams,
) -> Result<(usize, String)> {
    let count = recording.frame_count();
    match still {
        Still::Frame(frame) if frame >= count => Err(Error::invalid(format!(
            "{}: --frame {frame} but the recording has {count} frame(s) (frames are 0-based)",
            file.display()
        ))),
        Still::Frame(frame) => Ok((frame, format!("frame {frame}"))),
        Still::Stance { stance: n, sample } => {
            let segmentation = segment_recording(recording, segment)?;
            let stance = segmentation.stances.get(n).ok_or_else(|| {
                Error::data(format!(
                    "{}: --stance {n} but {} stance phase(s) were found (0-based, as `presrs \
                     inspect` lists them)",
                    file.display(),
                    segmentation.stances.len()
                ))
            })?;
            let frames = sample_frames(stance, sample)?;
            let frame = *frames
                .get(frames.len() / 2)
                .ok_or_else(|| Error::data("the stance gives no frame"))?;
            let partial = if stance.partial { ", partial" } else { "" };
            Ok((
                frame,
                format!("stance {n} ({sample} frame{partial}), frame {frame}"),
            ))
        }
        Still::LargestLoad => {
            let frame = recording
                .total_per_frame()
                .iter()
                .enumerate()
                .max_by(|a, b| a.1.total_cmp(b.1))
                .map_or(0, |(i, _)| i);
            let what = if count > 1 {
                format!("frame {frame} (largest load)")
            } else {
                String::new()
            };
            Ok((frame, what))
        }
    }
}
