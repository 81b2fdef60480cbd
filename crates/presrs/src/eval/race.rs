//! `eval --sample auto` and `report --sample auto`: the sample race ([`crate::train::sample_race`]) inside
//! every fold of an evaluation.
//!
//! The data set is read twice, as frames and as its whole sample (the stance for movies, the series
//! for one-frame files). Both readings must give the same units in the same order (one sample per
//! complete stance, or per file), so that one draw of units serves both. In each fold the automatic
//! choice is run on the fold's training data in each reading, the reading whose chosen candidate
//! validates better wins (a tie goes to the frame, as in `train`), and the winner is tested on the
//! fold's held-out units in its own reading: the held-out units never inform the choice. Each
//! automatic choice has the method's budget, so a fold's race may take twice what one model takes.

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Mutex;

use presrs_core::evaluation::{FoldModel, FoldSets};
use presrs_core::pipeline::{LabeledImage, TrainedModel};
use presrs_core::sample::{Sample, SampleKind};
use presrs_core::selection::Selection;
use presrs_io::message::{Message, Opt};
use serde::Serialize;

use crate::dataset::{Dataset, SampleOptions};
use crate::error::{Context, Error, Result};
use crate::eval::{EvalOptions, EvalOutcome, EvalSetup, run_counted};
use crate::progress::Progress;
use crate::train::sample_race::{FoldRace, RaceEntry, SampleRace, WholeSample};

/// A data set read both ways for the race: as frames, and as its whole sample.
#[derive(Debug)]
pub struct RaceReadings {
    /// Its warnings are both readings' (each said once).
    pub frames: Dataset,
    pub whole: Dataset,
}

impl RaceReadings {
    /// Reads `manifest` as frames (with `options`, whose kind is ignored) and as its whole sample
    /// ([`WholeSample::kind_for`]), and checks that both give the same units in the same order.
    pub fn load(
        manifest: &Path,
        options: &SampleOptions,
        whole: WholeSample,
        progress: &dyn Progress,
    ) -> Result<Self> {
        let read = |kind| crate::train::sample_race::read_as(manifest, options, kind, progress);
        let frames = read(SampleKind::Frame)?;
        let whole_kind = whole.kind_for(&frames);
        let whole = read(whole_kind).with_context(|| {
            format!(
                "{}: the race needs the set read as its {} sample too",
                manifest.display(),
                whole_kind.name()
            )
        })?;
        same_units(&frames, &whole)?;
        let mut frames = frames;
        // What only the whole reading found (a stance too short to summarise) is said with the rest.
        let said: Vec<String> = frames.warnings.iter().map(ToString::to_string).collect();
        let new: Vec<_> = (whole.warnings.iter())
            .filter(|w| !said.contains(&w.to_string()))
            .cloned()
            .collect();
        frames.warnings.extend(new);
        Ok(Self { frames, whole })
    }
}

/// An error unless `frames` and `whole` are the same units in the same order: as many samples, each
/// from the same manifest line with the same label, condition and group, and each frame inside (at
/// or after the start of) the whole sample it stands for.
pub fn same_units(frames: &Dataset, whole: &Dataset) -> Result<()> {
    let name = frames.path().display();
    let (f, w) = (frames.samples.len(), whole.samples.len());
    if f != w {
        return Err(Error::data(
            Message::from(format!(
                "{name}: cannot race the sample kinds: read as frames the set gives {f} samples, as \
                 its {} sample {w}; the race tests both on the same units (one sample per complete \
                 stance, or per file with ",
                whole.sample.name()
            ))
            .opt(Opt::OneSamplePerFile)
            .text("): sample one frame per stance, or name the sample kind with ")
            .opt(Opt::Sample),
        ));
    }
    let unit = |s: &Sample| {
        (
            s.source.clone(),
            s.line,
            s.label.clone(),
            s.condition.clone(),
            s.group.clone(),
        )
    };
    let differs = frames
        .samples
        .iter()
        .zip(&whole.samples)
        .position(|(a, b)| {
            unit(a) != unit(b) || (a.line.is_some() && a.frame_index < b.frame_index)
        });
    match differs {
        None => Ok(()),
        Some(i) => {
            let (a, b) = (&frames.samples[i], &whole.samples[i]);
            Err(Error::data(
                Message::from(format!(
                    "{name}: cannot race the sample kinds: sample {} is frame {} of {} read as \
                     frames but the {} sample from frame {} of {} (line {:?} against {:?}): the two \
                     readings do not give the same units in the same order; name the sample kind \
                     with ",
                    i + 1,
                    a.frame_index,
                    a.source.display(),
                    whole.sample.name(),
                    b.frame_index,
                    b.source.display(),
                    a.line,
                    b.line
                ))
                .opt(Opt::Sample),
            ))
        }
    }
}

/// How many folds each sample kind won, by kind name.
pub fn wins(races: &[FoldRace]) -> BTreeMap<&'static str, usize> {
    let mut wins = BTreeMap::new();
    for race in races {
        *wins.entry(race.race.chosen_kind().name()).or_default() += 1;
    }
    wins
}

/// The lines the eval and the report show: the folds each kind won, then one line per fold.
pub fn race_lines(races: &[FoldRace]) -> Vec<String> {
    if races.is_empty() {
        return Vec::new();
    }
    let won: Vec<String> = wins(races)
        .iter()
        .map(|(kind, n)| format!("{kind} {n}"))
        .collect();
    let mut lines = vec![format!(
        "sample race (each fold's training data only; the winner tested in its own sample), folds \
         won of {}: {}",
        races.len(),
        won.join(", ")
    )];
    let ties = races.iter().filter(|r| r.race.is_tie()).count();
    if ties > 0 {
        lines.push(format!(
            "{ties} of {} race(s) tied in validation: there the fold's training data cannot tell the \
             sample kinds apart and the frame was kept by rule, so the test above may not show the \
             better kind; evaluate each sample kind on its own to compare them on the held-out data",
            races.len()
        ));
    }
    lines.extend(races.iter().map(FoldRace::line));
    lines
}

/// One fold's race as the `--json` document holds it.
#[derive(Clone, Debug, Serialize)]
pub struct FoldRaceJson {
    pub seed: u64,
    pub fold: usize,
    pub held_out: Option<String>,
    pub entries: Vec<RaceEntryJson>,
    /// The winner's sample kind (`frame`, `stance`, `series`).
    pub chosen: &'static str,
    pub reason: String,
}

/// One contender of a fold's race.
#[derive(Clone, Debug, Serialize)]
pub struct RaceEntryJson {
    pub sample: &'static str,
    /// Training + validation units of the fold.
    pub samples: usize,
    /// The chosen candidate's mean validation accuracy (`null` when it could not be trained).
    pub validation_accuracy: Option<f64>,
    /// The chosen candidate (`features + classifier`).
    pub method: Option<String>,
    /// Why it could not be trained.
    pub error: Option<String>,
}

impl FoldRaceJson {
    pub fn of(race: &FoldRace) -> Self {
        let entries = race
            .race
            .entries
            .iter()
            .map(|entry| {
                let (accuracy, method, error) = match &entry.outcome {
                    Ok((a, m)) => (Some(*a), Some(m.clone()), None),
                    Err(why) => (None, None, Some(why.clone())),
                };
                RaceEntryJson {
                    sample: entry.kind.name(),
                    samples: entry.samples,
                    validation_accuracy: accuracy,
                    method,
                    error,
                }
            })
            .collect();
        Self {
            seed: race.seed,
            fold: race.fold,
            held_out: race.held_out.clone(),
            entries,
            chosen: race.race.chosen_kind().name(),
            reason: race.race.reason(),
        }
    }
}

/// What [`evaluate_racing_samples`] found.
#[derive(Debug)]
pub struct RacedEvaluation {
    /// Its `sample_races` say per fold which kind won and why; its report is the winners' (the
    /// set-up's warnings included in its warnings).
    pub outcome: EvalOutcome,
    /// Test labels no training set can hold, by held-out value.
    pub never_trained: BTreeMap<String, Vec<String>>,
}

/// Evaluates `options` (an automatic choice) on `readings`, racing the sample kinds in every fold.
pub fn evaluate_racing_samples(
    readings: &RaceReadings,
    options: &EvalOptions,
    progress: &dyn Progress,
) -> Result<RacedEvaluation> {
    let method = &options.method;
    if !method.is_auto() {
        return Err(crate::train::sample_race::fixed_method_cannot_race());
    }
    let frames = EvalSetup::new(&readings.frames, options)?;
    let whole = EvalSetup::new(&readings.whole, options)?;
    let mut candidates = Vec::new();
    for setup in [&frames, &whole] {
        let samples = setup.samples();
        let grid = samples[0].frame.grid();
        candidates.push(method.candidates_for(
            grid,
            false,
            &setup.dataset().sample,
            crate::method::race_draws_for(samples.len()),
        )?);
    }
    let kinds = [readings.frames.sample, readings.whole.sample];
    let views: [&[LabeledImage<'_>]; 2] = [frames.samples(), whole.samples()];
    let done: Mutex<Vec<(FoldRace, Option<Selection>)>> = Mutex::new(Vec::new());
    let contenders = Contenders {
        views,
        kinds,
        candidates: &candidates,
        method,
    };
    let trainer = |fold: &FoldSets<'_>| {
        let (model, race) = contenders.race(fold)?;
        if let Ok(mut done) = done.lock() {
            done.push((race, model.model.selection().cloned()));
        }
        Ok(model)
    };
    let evaluation_of = |evaluation: &presrs_core::evaluation::Evaluation<'_, '_>| {
        evaluation.run_views(&views, &trainer)
    };
    let total = (frames.folds() * options.repeats) as u64;
    let (report, first_model) = run_counted(
        frames.samples(),
        frames.protocol(),
        (options.repeats, options.seed),
        ("racing the sample kinds", total),
        progress,
        evaluation_of,
    )
    .with_context(|| readings.frames.path().display().to_string())?;
    let mut done = done.into_inner().unwrap_or_default();
    // (folds train in parallel: in the draws' order)
    done.sort_by_key(|(race, _)| (race.seed, race.fold));
    let (sample_races, selections): (Vec<FoldRace>, Vec<Option<Selection>>) =
        done.into_iter().unzip();
    let selections: Vec<Selection> = selections.into_iter().flatten().collect();
    let mut warnings = frames.warnings.clone();
    warnings.extend(crate::method::selection_warnings(&selections));
    let outcome = EvalOutcome {
        report,
        selections,
        warnings,
        first_model,
        sample_races,
    };
    Ok(RacedEvaluation {
        outcome,
        never_trained: frames.never_trained.clone(),
    })
}

/// The two readings of a race and what each trains with.
struct Contenders<'r, 's> {
    views: [&'r [LabeledImage<'s>]; 2],
    kinds: [SampleKind; 2],
    candidates: &'r [Vec<presrs_core::CheckedTrainConfig>],
    method: &'r crate::method::Method,
}

impl Contenders<'_, '_> {
    /// The race of one fold: the automatic choice on the fold's training units in each reading, and
    /// the winner's model with the reading it is tested in.
    fn race(&self, fold: &FoldSets<'_>) -> presrs_core::error::Result<(FoldModel, FoldRace)> {
        let mut trained = Vec::with_capacity(2);
        for (k, view) in self.views.iter().enumerate() {
            let images =
                |set: &[usize]| -> Vec<LabeledImage<'_>> { set.iter().map(|&i| view[i]).collect() };
            let model = presrs_core::selection::train_auto(
                &images(fold.train),
                &images(fold.validation),
                &self.method.auto_choice(&self.candidates[k]),
                fold.seed,
            )
            .and_then(|model| model.with_sample(self.kinds[k]));
            trained.push(model);
        }
        let units = fold.train.len() + fold.validation.len();
        let entries: Vec<RaceEntry> = (trained.iter().zip(self.kinds))
            .map(|(model, kind)| {
                RaceEntry::of_model(kind, units, model.as_ref().map_err(ToString::to_string))
            })
            .collect();
        let race = SampleRace::decide(entries);
        let view = race.chosen;
        let model: TrainedModel = trained.swap_remove(view)?;
        let race = FoldRace {
            seed: fold.seed,
            fold: fold.fold,
            held_out: fold.held_out.map(str::to_owned),
            race,
        };
        Ok((FoldModel { model, view }, race))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn race(held_out: &str, frame: f64, stance: f64) -> FoldRace {
        let entry = |kind, score: f64| RaceEntry {
            kind,
            samples: 60,
            outcome: Ok((score, "fft1d + pwe".to_owned())),
        };
        let stance_kind = SampleKind::Stance {
            summary: Default::default(),
            length: None,
        };
        FoldRace {
            seed: 1,
            fold: 0,
            held_out: Some(held_out.to_owned()),
            race: SampleRace::decide(vec![
                entry(SampleKind::Frame, frame),
                entry(stance_kind, stance),
            ]),
        }
    }

    /// A tie is the rule's choice, not the data's: the lines say how many folds it decided.
    #[test]
    fn tied_races_are_counted_and_said() {
        let races = [
            race("s00", 1.0, 1.0),
            race("s01", 0.9, 1.0),
            race("s02", 1.0, 1.0),
        ];
        assert!(races[0].race.is_tie() && !races[1].race.is_tie());
        let lines = race_lines(&races);
        assert!(
            lines[0].ends_with("folds won of 3: frame 2, stance 1"),
            "{lines:?}"
        );
        assert!(
            lines[1].starts_with("2 of 3 race(s) tied in validation")
                && lines[1].contains("the frame was kept by rule"),
            "{lines:?}"
        );
        assert_eq!(lines.len(), 2 + races.len());
        let untied = race_lines(&races[1..2]);
        assert!(untied.iter().all(|l| !l.contains("tied")), "{untied:?}");
    }
}
