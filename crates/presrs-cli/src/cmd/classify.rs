//! `presrs classify`: label recordings with a trained model.

use std::io::Write;
use std::path::PathBuf;

use presrs::classify::bag::ClassifyBag;
use presrs::classify::{ClassifyOptions, classify_file, nothing_classified};
use presrs::dataset::DeadSenselFills;
use presrs_io::model_file::load_model;

use presrs_core::novelty::UNKNOWN_LABEL;

use super::common::{NoveltyArgs, SampleArgs, note_dead_sensels, write_json};
use crate::printer::classify_document::{ClassifyJson, FileError};

/// Classify frames of recording files: one line per sample (file, frame, label, confidence).
#[derive(Debug, clap::Args)]
#[command(
    after_help = "A file that cannot be read or classified is reported on stderr and skipped; the other \
files are still classified, and the exit code is then 1 (with --json, the document lists them under \
`errors`); so is a run in which no file gave a sample (each file's warning says why).\n\nStances are \
found and sampled as the model's training did (one sample per file, the stance baseline and settings, \
the stance frame, partial stances: the model file's `sampling`) unless given here: any --stance-* \
option replaces the model's stance settings.\n\nThe confidence is the posterior of the label (equal priors). Every classifier's posteriors are \
calibrated when it is trained (a temperature fitted on held-out or leave-one-out scores), so that a confidence of 0.9 is \
right about nine times in ten on data like the training data; `presrs eval` measures how well that holds \
(mean confidence when right and when wrong, calibration error).\n\nExample:
  presrs classify --model g2.model.json \\
    sim/recordings/wood_G1_000.asf foot.png --json"
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
    /// Also write the classified recordings as a ROS 2 bag (MCAP): their frames on /presrs/frames
    /// (sensor_msgs/msg/Image) and each stance's touchdown and liftoff and each sample's classification
    /// (file, frame, label, confidence, posteriors, gait) on /presrs/decisions (JSON with a JSON schema).
    /// Recordings follow each other in time. Written when every file is done.
    #[arg(long, value_name = "OUT.mcap")]
    pub mcap: Option<PathBuf>,
    #[command(flatten)]
    pub samples: SampleArgs,
    #[command(flatten)]
    pub novelty: NoveltyArgs,
}

pub fn run(args: &ClassifyArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    args.mcap
        .as_deref()
        .map(presrs_io::output_path::check_output_file)
        .transpose()?;
    let model_file = args.novelty.apply(load_model(&args.model)?);
    let model = &model_file.model;
    let scores_novelty = model.novelty().is_some();
    let mut session = model.session();
    let mut results = Vec::new();
    let mut errors = Vec::new();
    let mut fills = DeadSenselFills::default();
    let mut bag = args.mcap.as_deref().map(ClassifyBag::create).transpose()?;
    // Columns as wide as the longest file name and label: the table stays aligned with long paths.
    let file_width = args
        .files
        .iter()
        .map(|path| path.display().to_string().chars().count())
        .max()
        .unwrap_or(0)
        .max(4);
    let label_width = model
        .class_names()
        .iter()
        .map(|name| name.chars().count())
        .max()
        .unwrap_or(0)
        .max(5);
    // The header comes with the first row: a run whose files all fail prints only the errors.
    let mut header = !args.json;
    let mut classified = 0;
    for path in &args.files {
        // The model's own sampling for the settings left at their defaults (the bag segments as
        // classify did).
        let options = ClassifyOptions {
            frame: args.frame,
            samples: args.samples.options()?,
        }
        .for_model(model);
        let classification = classify_file(model, &mut session, path, &options, &mut fills);
        let samples = match classification {
            Ok(classification) => {
                for warning in &classification.warnings {
                    out.flush()?;
                    stderr_line!("warning: {warning}");
                }
                if let Some(bag) = &mut bag {
                    let gaits = model_file.online.as_ref().map(|p| &p.gait_table);
                    bag.add(path, &options, &classification.frames, gaits)?;
                }
                classification.frames
            }
            Err(err) => {
                let error = crate::error_message(&anyhow::Error::from(err));
                // what was printed so far comes first
                out.flush()?;
                stderr_line!("error: {error}");
                let file = path.display().to_string();
                errors.push(FileError { file, error });
                continue;
            }
        };
        classified += samples.len();
        for sample in samples {
            if let Some(warning) = &sample.warning {
                out.flush()?;
                stderr_line!("warning: {}: {warning}", sample.file);
            }
            if args.json {
                results.push(sample);
            } else {
                let label_width = if scores_novelty {
                    label_width.max(UNKNOWN_LABEL.len())
                } else {
                    label_width
                };
                if std::mem::take(&mut header) {
                    write!(
                        out,
                        "{:<file_width$} {:>6}  {:<label_width$} {:>10}",
                        "file", "frame", "label", "confidence"
                    )?;
                    writeln!(out, "{}", if scores_novelty { "  novelty" } else { "" })?;
                }
                write!(
                    out,
                    "{:<file_width$} {:>6}  {:<label_width$} {:>10.4}",
                    sample.file, sample.frame, sample.label, sample.confidence
                )?;
                // With a novelty score: the score, and for an unknown sample its nearest class.
                match &sample.novelty {
                    Some(n) if n.unknown => {
                        writeln!(out, "  {:>7.2}  (nearest {})", n.novelty, n.nearest)?;
                    }
                    Some(n) => writeln!(out, "  {:>7.2}", n.novelty)?,
                    None => writeln!(out)?,
                }
            }
        }
    }
    note_dead_sensels(&fills);
    if let Some(bag) = bag {
        let path = bag.finish()?;
        stderr_line!("wrote {}", path.display());
    }
    let failed = errors.len();
    if args.json {
        write_json(
            out,
            &ClassifyJson {
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
    if classified == 0 {
        return Err(nothing_classified(args.files.len()).into());
    }
    Ok(())
}
