//! Classifying recordings with a trained model: the chosen frame of each file, or the sample frame of
//! every stance phase of a movie, with a warning where the label may mean little.

pub mod bag;

use std::collections::BTreeMap;
use std::path::Path;

use presrs_core::novelty::UNKNOWN_LABEL;
use presrs_core::pipeline::{Prediction, Session, TrainedModel};
use presrs_core::sample::SampleKind;
use presrs_core::stance::{ValidSegmentParams, segment_recording};
use presrs_core::{Frame, FrameView, Recording};
use serde::Serialize;

use crate::dataset::{DeadSenselFills, SampleOptions, read_corrected};
use crate::error::{Context, Error, Result};
use crate::session::NoveltyVerdict;
use presrs_io::message::{Message, Opt, Warning, Warnings};

/// One classified frame.
#[derive(Clone, Debug, Serialize)]
pub struct Classified {
    pub file: String,
    pub frame: usize,
    pub label: String,
    pub confidence: f64,
    /// The posterior of every class (equal priors), by class name.
    pub posteriors: BTreeMap<String, f64>,
    /// Why this label may mean little: the frame lies outside every stance phase, or carries no load.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub warning: Option<Warning>,
    /// The novelty verdict, with a model that scores novelty: when `unknown`, `label` is `unknown`
    /// and `nearest` names the nearest class (whose posterior `confidence` is).
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub novelty: Option<NoveltyVerdict>,
}

/// What was classified in one file, and what the user should know about the file.
#[derive(Clone, Debug, Default)]
pub struct FileClassification {
    /// The reader's warnings, and a movie without a complete stance phase.
    pub warnings: Warnings,
    pub frames: Vec<Classified>,
}

/// Which frames of a file are classified.
#[derive(Clone, Debug, Default)]
pub struct ClassifyOptions {
    /// This 0-based frame of every file, instead of the stance sample frames.
    pub frame: Option<usize>,
    /// How files are read and stances sampled (the sample frame, partial stances, dead sensels).
    pub samples: SampleOptions,
}

/// Reads `path` (its dead sensels filled as `options` say, noted in `fills`) and classifies its
/// frames with `session` (a session of `model`).
pub fn classify_file(
    model: &TrainedModel,
    session: &mut Session<'_>,
    path: &Path,
    options: &ClassifyOptions,
    fills: &mut DeadSenselFills,
) -> Result<FileClassification> {
    let (parsed, filled) = read_corrected(
        path,
        &options.samples.read,
        options.samples.dead_sensels.as_ref(),
    )?;
    fills.add(path.to_path_buf(), filled);
    let name = path.display().to_string();
    let mut classification = classify_recording(model, session, &parsed.recording, &name, options)?;
    let mut warnings = parsed.warnings;
    warnings.extend(std::mem::take(&mut classification.warnings));
    classification.warnings = warnings;
    Ok(classification)
}

/// Classifies the frames `options` choose in `recording` (named `name` in messages).
pub fn classify_recording(
    model: &TrainedModel,
    session: &mut Session<'_>,
    recording: &Recording,
    name: &str,
    options: &ClassifyOptions,
) -> Result<FileClassification> {
    if let SampleKind::Stance { .. } = model.sample() {
        return classify_stances(model, session, recording, name, options);
    }
    let mut warnings = Warnings::new();
    let frames = match options.frame {
        Some(frame) if frame >= recording.frame_count() => {
            return Err(Error::invalid(
                Message::from(format!("{name}: "))
                    .opt_is(Opt::Frame, frame)
                    .text(format!(
                        " is past the end ({})",
                        frames_numbered(recording.frame_count())
                    )),
            ));
        }
        Some(frame) => vec![(
            frame,
            unloaded_frame_warning(recording, frame).map(Warning::from),
        )],
        // A series (taxels over time) may sum to zero or less: only a pressure image can be empty.
        None if recording.frame_count() == 1 && model.sample().is_frame() => {
            vec![(0, unloaded_frame_warning(recording, 0).map(Warning::from))]
        }
        None if recording.frame_count() == 1 => vec![(0, None)],
        None => {
            let segmentation = segment_recording(recording, &options.samples.segment_params())
                .with_context(|| format!("{name}: cannot segment"))?;
            let frames = segmentation
                .samples(options.samples.sample, options.samples.include_partial())
                .context(name)?;
            if frames.is_empty() {
                warnings.push(
                    Message::from(format!(
                        "{name}: {} frames but no complete stance phase; nothing classified (choose \
                         a frame with ",
                        recording.frame_count()
                    ))
                    .opt_is(Opt::Frame, "K")
                    .text(")"),
                );
            }
            frames.into_iter().map(|frame| (frame, None)).collect()
        }
    };
    let mut classified = Vec::with_capacity(frames.len());
    for (index, warning) in frames {
        let Some(frame) = recording.frame(index) else {
            continue;
        };
        let at = || format!("{name}: frame {index}");
        let (sample, _) = model_sample(model, &[frame]).with_context(at)?;
        let prediction = session.classify(&sample.view()).with_context(at)?;
        classified.push(classified_of(model, name, index, &prediction, warning));
    }
    Ok(FileClassification {
        warnings,
        frames: classified,
    })
}

/// Classifies every stance of `recording` whole, as a whole-stance model does: each summarised and laid
/// into the model's length. A result's frame is the stance's touchdown.
fn classify_stances(
    model: &TrainedModel,
    session: &mut Session<'_>,
    recording: &Recording,
    name: &str,
    options: &ClassifyOptions,
) -> Result<FileClassification> {
    let mut warnings = Warnings::new();
    if options.frame.is_some() || recording.frame_count() == 1 {
        return Err(Error::invalid(format!(
            "{name}: the model classifies whole stances (it was trained on stance samples), so it \
             takes movies, not one frame"
        )));
    }
    let segmentation = segment_recording(recording, &options.samples.segment_params())
        .with_context(|| format!("{name}: cannot segment"))?;
    let include_partial = options.samples.include_partial();
    let mut classified = Vec::new();
    for stance in segmentation
        .stances
        .iter()
        .filter(|s| include_partial || !s.partial)
    {
        let frames: Vec<_> = (stance.start..stance.end())
            .filter_map(|index| recording.frame(index))
            .collect();
        let at = || format!("{name}: the stance at frame {}", stance.start);
        let (padded, warning) = model_sample(model, &frames).with_context(at)?;
        let prediction = session.classify(&padded.view()).with_context(at)?;
        classified.push(classified_of(
            model,
            name,
            stance.start,
            &prediction,
            warning,
        ));
    }
    if classified.is_empty() {
        warnings.push(format!(
            "{name}: {} frames but no complete stance phase; nothing classified",
            recording.frame_count()
        ));
    }
    Ok(FileClassification {
        warnings,
        frames: classified,
    })
}

/// The sample `model` takes from a recording's `frames` ([`SampleKind::sample_of`]): one frame as it
/// is, one 2-D array as a series, or a stance's movie (touchdown to lift-off) summarised as the model's
/// training stances were and laid into its length (the one its features take); the warning says when
/// the stance was longer and cut.
pub fn model_sample(
    model: &TrainedModel,
    frames: &[FrameView<'_>],
) -> presrs_core::error::Result<(Frame, Option<Warning>)> {
    let length = match model.sample() {
        SampleKind::Stance { length, .. } => Some(length.unwrap_or(model.image_grid().cols)),
        SampleKind::Frame | SampleKind::Series { .. } => None,
    };
    let (sample, cut) = model.sample().sample_of(frames, length)?;
    let warning = length.filter(|_| cut).map(|length| {
        Warning::from(format!(
            "the stance has {} frames, more than the model's {length}: its first {length} were used",
            frames.len()
        ))
    });
    Ok((sample, warning))
}

fn classified_of(
    model: &TrainedModel,
    name: &str,
    frame: usize,
    prediction: &Prediction<'_>,
    warning: Option<Warning>,
) -> Classified {
    let unknown = prediction.novelty.is_some_and(|n| n.unknown);
    Classified {
        file: name.to_owned(),
        frame,
        label: if unknown {
            UNKNOWN_LABEL.to_owned()
        } else {
            prediction.label.to_owned()
        },
        novelty: prediction.novelty.map(|n| NoveltyVerdict {
            unknown: n.unknown,
            nearest: prediction.label.to_owned(),
            novelty: n.score,
            novelty_threshold: n.threshold,
        }),
        confidence: prediction.confidence,
        posteriors: model
            .class_names()
            .iter()
            .cloned()
            .zip(prediction.posteriors.iter().copied())
            .collect(),
        warning,
    }
}

/// Why frame `index` (chosen by number) is no foot contact, if it is none: in a movie, a frame
/// outside every stance phase the segmentation finds (its load above the baseline is at most the
/// segmentation's `off_level`, or it is a short blip); in a one-frame file, a frame without load.
pub fn unloaded_frame_warning(recording: &Recording, index: usize) -> Option<String> {
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

/// How many frames a recording has and how they are numbered, for errors about a frame number:
/// "1 frame, frame 0", "205 frames, numbered 0 to 204".
pub fn frames_numbered(count: usize) -> String {
    match count {
        0 => "no frames".to_owned(),
        1 => "1 frame, frame 0".to_owned(),
        n => format!("{n} frames, numbered 0 to {}", n - 1),
    }
}
