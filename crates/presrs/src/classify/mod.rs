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

impl ClassifyOptions {
    /// These options with the sampling `model` was trained with in place of the settings left at
    /// their defaults ([`SampleOptions::or_model`]): a model trained on one-contact trials takes a
    /// trial whole, one trained with a stance baseline finds stances with it. [`classify_recording`]
    /// applies it; a caller that segments the same files again (a bag) applies it too.
    pub fn for_model(&self, model: &TrainedModel) -> Self {
        match model.sampling() {
            Some(sampling) => Self {
                frame: self.frame,
                samples: self.samples.or_model(sampling),
            },
            None => self.clone(),
        }
    }
}

/// The error of a classify run in which no file gave a sample: `files` files were read (each one's
/// warning says why it gave none).
pub fn nothing_classified(files: usize) -> Error {
    Error::data(format!(
        "nothing classified: {} gave no sample (the warnings above say why)",
        if files == 1 {
            "the file".to_owned()
        } else {
            format!("none of the {files} files")
        }
    ))
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
    let options = &options.for_model(model);
    if let SampleKind::Stance { .. } = model.sample() {
        return classify_stances(model, session, recording, name, options);
    }
    if let SampleKind::Series { .. } = model.sample()
        && recording.frame_count() > 1
        && options.frame.is_none()
    {
        return Err(Error::invalid(format!(
            "{name}: a movie of {} frames of {}, but the model classifies series (one 2-D array of \
             channels x time per file: it was trained on series samples, {}); give one such array \
             per file",
            recording.frame_count(),
            recording.grid(),
            series_shape(model)
        )));
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
                warnings.push(no_stance_warning(
                    name,
                    recording,
                    &segmentation,
                    options,
                    model.sample().is_frame(),
                ));
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
    if let Some(frame) = options.frame {
        return Err(Error::invalid(
            Message::from(format!(
                "{name}: the model classifies whole stances, touchdown to lift-off (it was trained \
                 on stance samples), and "
            ))
            .opt_is(Opt::Frame, frame)
            .text(" picks one frame: leave ")
            .opt(Opt::Frame)
            .text(" out to classify each stance of the movie whole, or classify frames with a model trained on ")
            .opt_text(Opt::Sample, "frame"),
        ));
    }
    if recording.frame_count() == 1 {
        return Err(Error::invalid(
            Message::from(format!(
                "{name}: the model classifies whole stances, touchdown to lift-off (it was trained \
                 on stance samples), so it takes movies, not one frame: give it a movie, or \
                 classify this frame with a model trained on "
            ))
            .opt_text(Opt::Sample, "frame"),
        ));
    }
    if let Err(err) = model.check_sensor(recording.grid()) {
        return Err(Error::invalid(format!(
            "{name}: {err}; crop or resample the recording to that grid, or train a model on its \
             sensor"
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
        warnings.push(no_stance_warning(
            name,
            recording,
            &segmentation,
            options,
            false,
        ));
    }
    Ok(FileClassification {
        warnings,
        frames: classified,
    })
}

/// Why a movie gave nothing to classify, and what to try: one sample per file when it is one contact
/// (loaded from its first frame to its last), partial stances, and a chosen frame for a one-frame
/// model.
fn no_stance_warning(
    name: &str,
    recording: &Recording,
    segmentation: &presrs_core::stance::Segmentation,
    options: &ClassifyOptions,
    one_frame_model: bool,
) -> Warning {
    let message = Message::from(format!(
        "{name}: {} frames but no complete stance phase; nothing classified (",
        recording.frame_count()
    ));
    let one_contact = segmentation.mode == presrs_core::stance::BaselineMode::Contact;
    let message = if one_contact && !options.samples.one_sample_per_file {
        message
            .text("it is one contact, loaded from its first frame to its last: try ")
            .opt(Opt::OneSamplePerFile)
    } else if one_contact {
        message.text(format!(
            "it is shorter than a stance of at least {} frames",
            options.samples.segment_params().params().min_stance_frames
        ))
    } else if !options.samples.include_partial() {
        message
            .text("its stances, if any, are cut by its start or end: try ")
            .opt(Opt::IncludePartial)
    } else {
        message.text("see `presrs inspect FILE`")
    };
    let message = match one_frame_model {
        true => message
            .text(", or choose a frame with ")
            .opt_is(Opt::Frame, "K"),
        false => message,
    };
    Warning::from(message.text(")"))
}

/// A series model's sample, in words: `12 channels x 100 time steps`.
fn series_shape(model: &TrainedModel) -> String {
    let grid = model.sensor().unwrap_or(model.image_grid());
    format!("{} channels x {} time steps", grid.rows, grid.cols)
}

/// The sample `model` takes from a recording's `frames` ([`SampleKind::sample_of`]): one frame as it
/// is, one 2-D array as a series, or a stance's movie (touchdown to lift-off) summarised as the model's
/// training stances were and laid into its length (the one its features take); the warning says when
/// the stance was longer and cut. Frames or a series of another sensor than the model's are an error
/// ([`TrainedModel::check_sensor`]).
pub fn model_sample(
    model: &TrainedModel,
    frames: &[FrameView<'_>],
) -> presrs_core::error::Result<(Frame, Option<Warning>)> {
    let length = match model.sample() {
        SampleKind::Stance { length, .. } => Some(length.unwrap_or(model.image_grid().cols)),
        SampleKind::Frame | SampleKind::Series { .. } => None,
    };
    // A stance's frames come from the sensor the model was trained on (when it says which).
    if let (SampleKind::Stance { .. }, Some(first)) = (model.sample(), frames.first()) {
        model.check_sensor(first.grid())?;
    }
    let (sample, cut) = model.sample().sample_of(frames, length)?;
    if let SampleKind::Series { .. } = model.sample() {
        model.check_sensor(sample.grid())?;
    }
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
            credibility: n.credibility,
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
