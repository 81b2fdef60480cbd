//! `presrs classify`: label recordings with a trained model.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use presrs::dataset::DeadSenselFills;
use presrs_core::stance::{ValidSegmentParams, segment_recording};
use presrs_io::model_file::load_model;
use serde::Serialize;

use super::common::{SampleArgs, note_dead_sensels, write_json};

/// Classify frames of recording files: one line per sample (file, frame, label, confidence).
#[derive(Debug, clap::Args)]
#[command(
    after_help = "A file that cannot be read or classified is reported on stderr and skipped; the other \
files are still classified, and the exit code is then 1 (with --json, the document lists them under \
`errors`).\n\nThe confidence is the posterior of the label (equal priors). Every classifier's posteriors are \
calibrated when it is trained (a temperature fitted on held-out or leave-one-out scores), so that a confidence of 0.9 is \
right about nine times in ten on data like the training data; `presrs eval` measures how well that holds \
(mean confidence when right and when wrong, calibration error).\n\nExample:\n  presrs classify --model g2.model.json sim/recordings/wood_G1_000.asf foot.png --json"
)]
pub struct ClassifyArgs {
    /// A model file written by `presrs train`.
    #[arg(long)]
    pub model: PathBuf,
    /// Recording files; for a movie every stance phase's sample frame is classified.
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// Classify this 0-based frame of every file instead of the stance sample frames (a warning says
    /// when it lies outside every stance phase; for an image, when it carries no load).
    #[arg(long)]
    pub frame: Option<usize>,
    /// Print one JSON document instead of a table.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub samples: SampleArgs,
}

#[derive(Debug, Serialize)]
struct ClassifiedSample {
    file: String,
    frame: usize,
    label: String,
    confidence: f64,
    posteriors: BTreeMap<String, f64>,
    /// Why this label may mean little: the frame lies outside every stance phase, or carries no load.
    #[serde(skip_serializing_if = "Option::is_none")]
    warning: Option<String>,
}

/// A file that could not be classified.
#[derive(Debug, Serialize)]
struct FileError {
    file: String,
    error: String,
}

#[derive(Debug, Serialize)]
struct ClassifyReport {
    model: String,
    results: Vec<ClassifiedSample>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    errors: Vec<FileError>,
}

pub fn run(args: &ClassifyArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let model_file = load_model(&args.model)?;
    let model = &model_file.model;
    let mut session = model.session();
    let mut results = Vec::new();
    let mut errors = Vec::new();
    let mut fills = DeadSenselFills::default();
    if !args.json {
        writeln!(
            out,
            "{:<40} {:>6}  {:<12} {:>10}",
            "file", "frame", "label", "confidence"
        )?;
    }
    for path in &args.files {
        let name = path.display().to_string();
        let samples = match classify_file(args, path, model, &mut session, &mut fills) {
            Ok(samples) => samples,
            Err(err) => {
                // what was printed so far comes first
                out.flush()?;
                stderr_line!("error: {}", crate::error_message(&err));
                errors.push(FileError {
                    file: name,
                    error: crate::error_message(&err),
                });
                continue;
            }
        };
        for sample in samples {
            if let Some(warning) = &sample.warning {
                out.flush()?;
                stderr_line!("warning: {}: {warning}", sample.file);
            }
            if args.json {
                results.push(sample);
            } else {
                writeln!(
                    out,
                    "{:<40} {:>6}  {:<12} {:>10.4}",
                    sample.file, sample.frame, sample.label, sample.confidence
                )?;
            }
        }
    }
    note_dead_sensels(&fills);
    let failed = errors.len();
    if args.json {
        write_json(
            out,
            &ClassifyReport {
                model: args.model.display().to_string(),
                results,
                errors,
            },
        )?;
    }
    if failed > 0 {
        anyhow::bail!(
            "{failed} of {} file(s) could not be classified (each reported above)",
            args.files.len()
        );
    }
    Ok(())
}

/// The classified samples of one file: `--frame`, or every stance's sample frame.
fn classify_file(
    args: &ClassifyArgs,
    path: &std::path::Path,
    model: &presrs_core::pipeline::TrainedModel,
    session: &mut presrs_core::pipeline::Session<'_>,
    fills: &mut DeadSenselFills,
) -> anyhow::Result<Vec<ClassifiedSample>> {
    let name = path.display().to_string();
    let recording = &args.samples.read(path, fills)?;
    let frames = match args.frame {
        Some(frame) if frame >= recording.frame_count() => anyhow::bail!(
            "{name}: --frame {frame} is past the end ({})",
            super::common::frames_numbered(recording.frame_count())
        ),
        Some(frame) => vec![(frame, unloaded_frame_warning(recording, frame))],
        None if recording.frame_count() == 1 => vec![(0, unloaded_frame_warning(recording, 0))],
        None => {
            let segmentation = segment_recording(recording, &ValidSegmentParams::default())
                .with_context(|| format!("{name}: cannot segment"))?;
            let frames = segmentation
                .samples(args.samples.stance_frame, args.samples.include_partial)
                .with_context(|| name.clone())?;
            if frames.is_empty() {
                stderr_line!(
                    "warning: {name}: {} frames but no complete stance phase; nothing classified \
                     (choose a frame with --frame K)",
                    recording.frame_count()
                );
            }
            frames.into_iter().map(|frame| (frame, None)).collect()
        }
    };
    let mut samples = Vec::with_capacity(frames.len());
    for (index, warning) in frames {
        let Some(frame) = recording.frame(index) else {
            continue;
        };
        let prediction = session
            .classify(&frame)
            .map_err(|err| anyhow::anyhow!("{name}: frame {index}: {err}"))?;
        samples.push(ClassifiedSample {
            file: name.clone(),
            frame: index,
            label: prediction.label.to_owned(),
            confidence: prediction.confidence,
            posteriors: model
                .class_names()
                .iter()
                .cloned()
                .zip(prediction.posteriors.iter().copied())
                .collect(),
            warning,
        });
    }
    Ok(samples)
}

/// Why frame `index` (chosen with `--frame`) is no foot contact, if it is none: in a movie, a frame
/// outside every stance phase the segmentation finds (its load above the baseline is at most the
/// segmentation's `off_level`, or it is a short blip); in a one-frame file, a frame without load.
fn unloaded_frame_warning(recording: &presrs_core::Recording, index: usize) -> Option<String> {
    let totals = recording.total_per_frame();
    let total = *totals.get(index)?;
    if recording.frame_count() == 1 {
        return (total <= 0.0).then(|| {
            format!(
                "frame {index} carries no load (total {total}): the label of an empty image means \
                 nothing"
            )
        });
    }
    let segmentation = segment_recording(recording, &ValidSegmentParams::default()).ok()?;
    if segmentation.stances.iter().any(|s| s.contains(index)) {
        return None;
    }
    let baseline = segmentation.baseline.get(index).copied().unwrap_or(0.0);
    let round = |x: f64| (x * 1e3).round() / 1e3;
    Some(format!(
        "frame {index} lies outside every stance phase (total load {}, {} above the baseline; a \
         stance frame carries more than {} above it): the foot is not on the ground, so its label \
         means little",
        round(total),
        round(total - baseline),
        round(segmentation.off_level)
    ))
}
