//! `--sample auto`: one frame against the whole sample, chosen by validation inside the training data.
//!
//! The paper judges a stance from one frame; a whole-stance model reads the stance's movie (or a
//! taxel-time array as a series). Which one a data set rewards is an empirical question, so the
//! automatic choice is run on each: the data set is read twice (the frame of each stance, and the
//! whole sample: the stance summary for movies, the series for one-frame files), each is trained with
//! the same draw seed and method, and the sample whose chosen candidate validates better wins; a tie
//! goes to the frame (the paper's sample, cheaper and decidable before lift-off). The loser's score
//! is kept, so the user reads what the choice was made on.

use std::path::Path;

use presrs_core::sample::SampleKind;
use presrs_core::stance::summary::SummaryConfig;
use presrs_io::message::{Message, Opt, Warning};

use crate::dataset::{Dataset, SampleOptions};
use crate::error::{Error, Result};
use crate::progress::Progress;
use crate::train::{TrainOptions, Training, train_with_progress, trained_on_movies};
use presrs_core::pipeline::TrainedModel;

/// What the whole sample of `--sample auto` is when the data decide: the settings the whole kinds take.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WholeSample {
    /// Frames each stance is laid into (`None`: the longest stance).
    pub stance_length: Option<usize>,
    /// A series' time runs down the rows (else along the columns).
    pub time_in_rows: bool,
}

impl WholeSample {
    /// The whole sample of a data set whose frames are `frames`: the stance for movies, the series for
    /// one-frame files.
    pub fn kind_for(&self, frames: &Dataset) -> SampleKind {
        if trained_on_movies(frames) {
            SampleKind::Stance {
                summary: SummaryConfig::default(),
                length: self.stance_length,
            }
        } else {
            SampleKind::Series {
                time_in_rows: self.time_in_rows,
            }
        }
    }
}

/// One contender of the race.
#[derive(Clone, Debug)]
pub struct RaceEntry {
    pub kind: SampleKind,
    /// Samples the data set gave (0 when it could not be read this way).
    pub samples: usize,
    /// The chosen candidate's mean validation accuracy and its name, or why this sample could not be
    /// trained.
    pub outcome: std::result::Result<(f64, String), String>,
}

/// The race's outcome: both contenders, the frame first, and the winner.
#[derive(Clone, Debug)]
pub struct SampleRace {
    pub entries: Vec<RaceEntry>,
    pub chosen: usize,
}

impl SampleRace {
    /// The winner's kind.
    pub fn chosen_kind(&self) -> SampleKind {
        self.entries[self.chosen].kind
    }

    /// One line per contender (`stance: 95.8 % in validation (rocket + svm), 120 samples, chosen`)
    /// and the reason for the choice.
    pub fn lines(&self) -> Vec<String> {
        let mut lines: Vec<String> = self
            .entries
            .iter()
            .enumerate()
            .map(|(i, entry)| {
                let mark = if i == self.chosen { ", chosen" } else { "" };
                match &entry.outcome {
                    Ok((accuracy, method)) => format!(
                        "sample {}: {:.1} % in validation ({method}), {} samples{mark}",
                        entry.kind.name(),
                        100.0 * accuracy,
                        entry.samples
                    ),
                    Err(why) => format!("sample {}: not trained: {why}", entry.kind.name()),
                }
            })
            .collect();
        lines.push(self.reason());
        lines
    }

    /// The race of `entries` (the frame first): the best validation score wins; a tie, or a contender
    /// that could not be trained, goes to the earlier.
    pub fn decide(entries: Vec<RaceEntry>) -> Self {
        let score = |e: &RaceEntry| e.outcome.as_ref().map_or(f64::NEG_INFINITY, |(a, _)| *a);
        let mut chosen = 0;
        for (i, entry) in entries.iter().enumerate() {
            if score(entry) > score(&entries[chosen]) {
                chosen = i;
            }
        }
        Self { entries, chosen }
    }

    /// The contenders' validation scores, of those that could be trained.
    fn scores(&self) -> Vec<f64> {
        self.entries
            .iter()
            .filter_map(|e| e.outcome.as_ref().ok().map(|(a, _)| *a))
            .collect()
    }

    /// Every contender was trained and they validated equally: the choice was the rule's, not the
    /// data's.
    pub fn is_tie(&self) -> bool {
        let scores = self.scores();
        scores.len() == self.entries.len()
            && scores.len() > 1
            && scores.windows(2).all(|w| w[0] == w[1])
    }

    /// Why the winner won, in one sentence.
    pub fn reason(&self) -> String {
        let winner = &self.entries[self.chosen];
        if self.scores().len() < self.entries.len() {
            format!(
                "the {} sample is the only one that could be trained",
                winner.kind.name()
            )
        } else if self.is_tie() {
            "a tie in validation goes to one frame (the paper's sample, decided before lift-off)"
                .to_owned()
        } else {
            format!(
                "the {} sample validates best inside the training data",
                winner.kind.name()
            )
        }
    }
}

/// The race of one fold: which fold, and both contenders' validation scores.
#[derive(Clone, Debug)]
pub struct FoldRace {
    /// The repeat's seed.
    pub seed: u64,
    /// The fold's place in its repeat.
    pub fold: usize,
    /// With leave-one-out, the held-out value.
    pub held_out: Option<String>,
    pub race: SampleRace,
}

impl FoldRace {
    /// One line: `seed 1, group S1 held out: sample frame 70.0 % (fft1d + pwe), sample stance 95.0 %
    /// (rocket + ridge): stance; the stance sample validates best inside the training data`.
    pub fn line(&self) -> String {
        let fold = match &self.held_out {
            Some(value) => format!("seed {}, {value} held out", self.seed),
            None => format!("seed {}", self.seed),
        };
        let entries: Vec<String> = self.race.entries.iter().map(entry_text).collect();
        format!(
            "{fold}: {}: {}; {}",
            entries.join(", "),
            self.race.chosen_kind().name(),
            self.race.reason()
        )
    }
}

fn entry_text(entry: &RaceEntry) -> String {
    match &entry.outcome {
        Ok((accuracy, method)) => {
            format!("{} {:.1} % ({method})", entry.kind.name(), 100.0 * accuracy)
        }
        Err(why) => format!("{} not trained ({why})", entry.kind.name()),
    }
}

/// A training whose sample kind was raced: the winner's data set and model, and the race.
#[derive(Debug)]
pub struct RacedTraining {
    pub dataset: Dataset,
    pub training: Training,
    pub race: SampleRace,
}

/// The data set of `manifest` read as `kind` samples, the other options as given.
pub(crate) fn read_as(
    manifest: &Path,
    options: &SampleOptions,
    kind: SampleKind,
    progress: &dyn Progress,
) -> Result<Dataset> {
    let options = SampleOptions {
        kind,
        ..options.clone()
    };
    Dataset::load(manifest, &options, progress)
}

/// Reads `manifest` as frames (with `options`, whose kind is ignored) and as its whole sample
/// ([`WholeSample::kind_for`]), trains each with `train_options` (an automatic choice: its validation
/// scores decide) and keeps the better.
pub fn train_racing_samples(
    manifest: &Path,
    options: &SampleOptions,
    whole: WholeSample,
    train_options: &TrainOptions,
    progress: &dyn Progress,
) -> Result<RacedTraining> {
    if !train_options.method.is_auto() {
        return Err(fixed_method_cannot_race());
    }
    let read = |kind| read_as(manifest, options, kind, progress);
    let frames = read(SampleKind::Frame)?;
    let whole_kind = whole.kind_for(&frames);
    let train_on = |dataset: &Dataset| {
        progress.start(
            &format!("training on the {} sample", dataset.sample.name()),
            None,
        );
        let training = train_with_progress(dataset, train_options, progress);
        progress.finish();
        training
    };
    let frame_training = train_on(&frames);
    let mut contenders = vec![(frames, frame_training)];
    let unread = match read(whole_kind) {
        Ok(dataset) => {
            let training = train_on(&dataset);
            contenders.push((dataset, training));
            None
        }
        // The user's stance length, not the data, is at fault: the frame winning by default would
        // hide it.
        Err(err) if names_the_stance_length(&err) => return Err(err),
        Err(err) => Some(RaceEntry {
            kind: whole_kind,
            samples: 0,
            outcome: Err(err.to_string()),
        }),
    };
    finish_race(contenders, unread)
}

/// Whether `err` is about the stance length given (one the data cannot take).
fn names_the_stance_length(err: &Error) -> bool {
    match err {
        Error::Io(
            presrs_io::IoError::Format { message, .. } | presrs_io::IoError::Parse { message, .. },
        ) => message.options().any(|opt| opt == Opt::StanceLength),
        Error::Context { source, .. } => names_the_stance_length(source),
        _ => false,
    }
}

/// The error of `--sample auto` with a fixed method (which gives no validation score to race on).
pub(crate) fn fixed_method_cannot_race() -> Error {
    Error::invalid(
        Message::new().opt_text(Opt::Sample, "auto").text(
            " chooses the sample kind by the automatic choice's validation scores: leave the \
             features and the classifier to auto, or name the sample kind (frame, stance or series)",
        ),
    )
}

impl RaceEntry {
    /// The entry of a contender of `kind` on `samples` units: its model's chosen candidate, or why it
    /// could not be trained.
    pub fn of_model(
        kind: SampleKind,
        samples: usize,
        model: std::result::Result<&TrainedModel, String>,
    ) -> Self {
        let outcome = model.and_then(|model| {
            model
                .selection()
                .and_then(|s| s.chosen())
                .map(|c| {
                    (
                        c.accuracy.mean,
                        format!("{} + {}", c.features, c.classifier),
                    )
                })
                .ok_or_else(|| "no validation score".to_owned())
        });
        Self {
            kind,
            samples,
            outcome,
        }
    }
}

/// The better of the trained contenders (the first, the frame, on a tie or when the other failed);
/// `unread` is the whole sample's entry when the data set could not be read that way.
fn finish_race(
    contenders: Vec<(Dataset, Result<Training>)>,
    unread: Option<RaceEntry>,
) -> Result<RacedTraining> {
    let mut entries: Vec<RaceEntry> = contenders
        .iter()
        .map(|(dataset, training)| {
            let model = training
                .as_ref()
                .map(|t| &t.model)
                .map_err(ToString::to_string);
            RaceEntry::of_model(dataset.sample, dataset.samples.len(), model)
        })
        .collect();
    entries.extend(unread);
    let race = SampleRace::decide(entries);
    let chosen = race.chosen;
    let (dataset, training) = contenders
        .into_iter()
        .nth(chosen)
        .ok_or_else(|| Error::data("no sample kind could be trained"))?;
    let mut training = training?;
    training.warnings.extend(race.tie_warning());
    Ok(RacedTraining {
        dataset,
        training,
        race,
    })
}

impl SampleRace {
    /// On a tie, what the race measured and that the rule, not the data, kept the frame, with the
    /// option that trains the other kind: the training data could not tell the kinds apart, and on
    /// new data the other may be far better (as `eval` of each kind alone shows).
    pub fn tie_warning(&self) -> Option<Warning> {
        if !self.is_tie() {
            return None;
        }
        let kept = self.chosen_kind();
        let other = self
            .entries
            .iter()
            .map(|entry| entry.kind)
            .find(|kind| kind.name() != kept.name())?;
        let measured: Vec<String> = self.entries.iter().map(entry_text).collect();
        Some(Warning::from(
            Message::from(format!(
                "the sample race tied in validation ({}): the {} sample was kept by rule (a tie goes \
                 to one frame), not because it is better; the training data cannot tell the kinds \
                 apart, and on new data the {} may be far better: train it with ",
                measured.join(", "),
                kept.name(),
                other.name()
            ))
            .opt_text(Opt::Sample, other.name())
            .text(", and evaluate each kind alone to compare them"),
        ))
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use presrs_io::message::Face;

    fn entry(kind: &str, accuracy: f64, method: &str) -> RaceEntry {
        RaceEntry {
            kind: kind.parse().unwrap(),
            samples: 60,
            outcome: Ok((accuracy, method.to_owned())),
        }
    }

    #[test]
    fn a_tie_is_a_warning_naming_the_option_that_trains_the_other_kind() {
        let race = SampleRace::decide(vec![
            entry("frame", 1.0, "fft1d + mle"),
            entry("stance", 1.0, "rocket + pwe"),
        ]);
        assert_eq!(race.chosen_kind(), SampleKind::Frame);
        let warning = race.tie_warning().unwrap();
        let cli = warning.render(Face::Cli);
        assert!(
            cli.starts_with(
                "the sample race tied in validation (frame 100.0 % (fft1d + mle), stance 100.0 % \
                 (rocket + pwe)): the frame sample was kept by rule"
            ) && cli.contains("train it with --sample stance"),
            "{cli}"
        );
        assert!(
            warning
                .render(Face::Python)
                .contains("train it with sample=\"stance\"")
        );
        let won = SampleRace::decide(vec![
            entry("frame", 0.9, "fft1d + mle"),
            entry("stance", 1.0, "rocket + pwe"),
        ]);
        assert!(won.tie_warning().is_none());
    }
}
