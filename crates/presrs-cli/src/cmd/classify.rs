//! `presrs classify`: label recordings with a trained model.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use presrs_core::stance::{ValidSegmentParams, segment_recording};
use presrs_io::dataset::DeadSenselFills;
use presrs_io::model_file::load_model;
use serde::Serialize;

use super::common::{SampleArgs, note_dead_sensels, write_json};

/// Classify frames of recording files: one line per sample (file, frame, label, confidence).
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Example:\n  presrs classify --model g2.model.json sim/wood_G1_t0.asf foot.png --json"
)]
pub struct ClassifyArgs {
    /// A model file written by `presrs train`.
    #[arg(long)]
    pub model: PathBuf,
    /// Recording files; for a movie every stance phase's sample frame is classified.
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// Classify this 0-based frame of every file instead of the stance sample frames.
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
}

#[derive(Debug, Serialize)]
struct ClassifyReport {
    model: String,
    results: Vec<ClassifiedSample>,
}

pub fn run(args: &ClassifyArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let model_file = load_model(&args.model)?;
    let model = &model_file.model;
    let mut session = model.session();
    let mut results = Vec::new();
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
        let recording = &args.samples.read(path, &mut fills)?;
        let frames = match args.frame {
            Some(frame) if frame >= recording.frame_count() => anyhow::bail!(
                "{name}: --frame {frame} is past the end ({} frames, numbered from 0)",
                recording.frame_count()
            ),
            Some(frame) => vec![frame],
            None if recording.frame_count() == 1 => vec![0],
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
                frames
            }
        };
        for index in frames {
            let Some(frame) = recording.frame(index) else {
                continue;
            };
            let prediction = session
                .classify(&frame)
                .map_err(|err| anyhow::anyhow!("{name}: frame {index}: {err}"))?;
            let sample = ClassifiedSample {
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
            };
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
    if args.json {
        write_json(
            out,
            &ClassifyReport {
                model: args.model.display().to_string(),
                results,
            },
        )?;
    }
    Ok(())
}
