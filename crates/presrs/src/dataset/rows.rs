//! A manifest's rows read into samples ([`load_samples`]): each row's file read once, its frames, stances
//! or series taken as the sample options say, every stance or series sample checked against the first
//! row's sensor, and the files that gave no sample summed up in one warning.

use std::collections::BTreeMap;

use presrs_core::stance::summary::pad_to;
use presrs_core::stance::{BaselineMode, Segmentation, Stance, segment_recording};
use presrs_core::{FrameView, Grid, Recording};
use presrs_io::IoError;
use presrs_io::manifest::{Manifest, ManifestRow};
use presrs_io::message::{Message, Opt, Warning, Warnings};

use super::options::SampleOptions;
use super::read::{DeadSenselFills, MovieLoad, read_recordings, row_key};
use super::stance_length::pad_stance_samples;
use presrs_core::Sample;
use presrs_core::sample::SampleKind;

/// The samples of a manifest, with what did not stop loading (a movie without stances, reader warnings).
#[derive(Clone, Debug, Default)]
pub struct LoadedSamples {
    pub samples: Vec<Sample>,
    pub warnings: Warnings,
    /// The dead sensels filled (with [`SampleOptions::dead_sensels`]), by recording.
    pub dead_sensels: DeadSenselFills,
    /// Every movie read, by file and topic: what an online profile is learned from.
    pub movie_loads: Vec<MovieLoad>,
    /// The one sensor of stance and series samples (see [`Dataset::sensor`](super::Dataset::sensor)).
    pub sensor: Option<Grid>,
    /// Whole-stance samples: each stance's length, and the stance cut at each decision point asked.
    pub stances: StanceCuts,
}

/// What whole-stance samples need for early decisions, in the samples' order: each stance's length, and
/// each stance cut at every decision point of [`SampleOptions::decision_points`] (its first `K + 1`
/// frames summarised, laid into `K + 1` frames: a stance that ends first is padded with zeros). Empty
/// for other kinds.
#[derive(Clone, Debug, Default)]
pub struct StanceCuts {
    /// Each sample's stance length, frames.
    pub stance_frames: Vec<usize>,
    /// Each sample's frame period, seconds, when its recording states one.
    pub frame_periods: Vec<Option<f64>>,
    /// Per decision point (frames after touchdown, increasing), each sample's stance cut there.
    pub points: Vec<(usize, Vec<presrs_core::Frame>)>,
}

/// Reads every file of `manifest` (each once, in parallel) and picks samples as described in the module
/// documentation. Errors name the manifest line (and the file's own line for a parse error).
pub fn load_samples(
    manifest: &Manifest,
    options: &SampleOptions,
) -> std::result::Result<LoadedSamples, IoError> {
    let read = read_recordings(manifest, options)?;
    let mut loaded = LoadedSamples {
        movie_loads: read.movie_loads(),
        dead_sensels: read.fills,
        ..LoadedSamples::default()
    };
    for parsed in read.by_key.values() {
        loaded.warnings.extend(parsed.warnings.iter().cloned());
    }
    loaded.warnings.sort_by_text();
    let mut empty = EmptyFiles::default();
    let mut sensor = OneSensor::default();
    for row in &manifest.rows {
        let Some(parsed) = read.by_key.get(&row_key(row)) else {
            continue;
        };
        let recording = &parsed.recording;
        for (frame_index, frames) in row_units(manifest, row, recording, options, &mut empty)? {
            let (frame, _) = options
                .kind
                .sample_of(&frames, None)
                .map_err(|err| manifest.row_error(row, format!("`{}`: {err}", row.path_text)))?;
            sensor.check(manifest, row, options.kind, recording.grid(), frame.grid())?;
            if let SampleKind::Stance { .. } = options.kind {
                loaded
                    .stances
                    .frame_periods
                    .push(recording.frame_period_s());
                cut_stance(&mut loaded.stances, &frames, options).map_err(|err| {
                    manifest.row_error(row, format!("`{}`: {err}", row.path_text))
                })?;
            }
            loaded.samples.push(Sample {
                frame,
                label: row.label.clone(),
                condition: row.condition.clone(),
                group: row.group.clone(),
                load: row.load,
                source: row.path.clone(),
                frame_index,
                line: Some(row.line),
                columns: row_columns(row),
            });
        }
    }
    if let SampleKind::Stance { length, .. } = options.kind {
        loaded.warnings.extend(pad_stance_samples(
            &manifest.source.display().to_string(),
            &mut loaded.samples,
            length,
        )?);
        // A point's samples are its own length, K + 1 frames: no padding after the frames it sees.
        for (k, cuts) in &mut loaded.stances.points {
            for cut in cuts.iter_mut() {
                *cut = pad_to(&cut.view(), *k + 1)
                    .map_err(|err| IoError::format("stance samples", err.to_string()))?
                    .0;
            }
        }
    }
    loaded
        .warnings
        .extend(empty.summary(manifest.rows.len(), options));
    loaded.sensor = sensor.first.map(|(grid, _)| grid);
    Ok(loaded)
}

/// Records a whole stance's length and its summaries cut at the decision points of `options`.
fn cut_stance(
    cuts: &mut StanceCuts,
    frames: &[FrameView<'_>],
    options: &SampleOptions,
) -> presrs_core::error::Result<()> {
    cuts.stance_frames.push(frames.len());
    if cuts.points.is_empty() {
        let mut points = options.decision_points.clone();
        points.sort_unstable();
        points.dedup();
        cuts.points = points.into_iter().map(|k| (k, Vec::new())).collect();
    }
    for (k, samples) in &mut cuts.points {
        let used = frames.len().min(*k + 1);
        samples.push(options.kind.sample_of(&frames[..used], None)?.0);
    }
    Ok(())
}

/// The one sensor of a data set's stance or series samples: the first row's grid, which every other
/// row must share (a model of a summary or a series takes one sensor; frame samples are checked by
/// the model's crop instead).
#[derive(Debug, Default)]
struct OneSensor {
    /// The grid, and the row that set it (its path and line).
    first: Option<(Grid, (String, usize))>,
}

impl OneSensor {
    /// Notes the sensor of a sample of `kind` from `row`: its `recording`'s frames for a stance, the
    /// `sample`'s grid for a series. Another grid than the first row's is an error naming both files
    /// and grids.
    fn check(
        &mut self,
        manifest: &Manifest,
        row: &ManifestRow,
        kind: SampleKind,
        recording: Grid,
        sample: Grid,
    ) -> std::result::Result<(), IoError> {
        let (grid, what) = match kind {
            SampleKind::Frame => return Ok(()),
            SampleKind::Stance { .. } => (recording, "frames"),
            SampleKind::Series { .. } => (sample, "series (channels x time)"),
        };
        match &self.first {
            None => {
                self.first = Some((grid, (row.path_text.clone(), row.line)));
                Ok(())
            }
            Some((first, _)) if *first == grid => Ok(()),
            Some((first, (path, line))) => Err(manifest.row_error(
                row,
                format!(
                    "`{}` has {grid} {what} where `{path}` (line {line}) has {first}: a {} model \
                     is trained on one sensor; crop or resample the recordings to one grid, or \
                     train a model per sensor",
                    row.path_text,
                    kind.name()
                ),
            )),
        }
    }
}

/// What one manifest row gives, as the frames each sample is made of, with the 0-based frame it
/// starts at: a whole stance's frames (each stance of a movie), one 2-D array (a series), or one
/// frame (each frame the row or its stances choose).
fn row_units<'r>(
    manifest: &Manifest,
    row: &ManifestRow,
    recording: &'r Recording,
    options: &SampleOptions,
    empty: &mut EmptyFiles,
) -> std::result::Result<Vec<(usize, Vec<FrameView<'r>>)>, IoError> {
    Ok(match options.kind {
        SampleKind::Stance { .. } => row_stances(manifest, row, recording, options, empty)?
            .into_iter()
            .map(|stance| {
                let frames = (stance.start..stance.end())
                    .filter_map(|index| recording.frame(index))
                    .collect();
                (stance.start, frames)
            })
            .collect(),
        SampleKind::Series { .. } => vec![(0, vec![row_series(manifest, row, recording)?])],
        SampleKind::Frame => row_frames(manifest, row, recording, options, empty)?
            .into_iter()
            .filter_map(|index| Some((index, vec![recording.frame(index)?])))
            .collect(),
    })
}

/// Why a movie gave no sample, for the one-line summary of [`EmptyFiles`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum NoSample {
    /// Loaded from the first frame to the last: one contact, partial at both ends.
    OneContact,
    /// Stances found, all cut by the start or end of the recording.
    OnlyPartial,
    /// No stance at all.
    NoStance,
}

/// The movies that gave no sample, summarised in one line rather than one warning a file.
#[derive(Debug, Default)]
struct EmptyFiles {
    files: Vec<(String, NoSample)>,
}

impl EmptyFiles {
    fn add(&mut self, path_text: &str, segmentation: &Segmentation) {
        let why = if segmentation.mode == BaselineMode::Contact {
            NoSample::OneContact
        } else if segmentation.stances.is_empty() {
            NoSample::NoStance
        } else {
            NoSample::OnlyPartial
        };
        self.files.push((path_text.to_owned(), why));
    }

    /// `412 of 600 files gave no sample: a.npy, b.npy, ... ; they are one contact each: try
    /// --one-sample-per-file`, or `None` when every file gave one. `rows` is the manifest's row count.
    fn summary(&self, rows: usize, options: &SampleOptions) -> Option<Message> {
        const NAMED: usize = 5;
        let count = self.files.len();
        if count == 0 {
            return None;
        }
        let mut names: Vec<&str> = self
            .files
            .iter()
            .take(NAMED)
            .map(|(p, _)| p.as_str())
            .collect();
        if count > NAMED {
            names.push("...");
        }
        let most = |why: NoSample| self.files.iter().filter(|(_, w)| *w == why).count() * 2 > count;
        let hint = if most(NoSample::OneContact) && options.one_sample_per_file {
            // Each file was its own stance already: it is too short to be one.
            Message::from(format!(
                "each is shorter than a stance (at least {} frames)",
                options.segment_params().params().min_stance_frames
            ))
        } else if most(NoSample::OneContact) {
            Message::from(
                "they are one contact each (loaded from the first frame to the last): try ",
            )
            .opt(Opt::OneSamplePerFile)
        } else if most(NoSample::OnlyPartial) && !options.include_partial() {
            Message::from("their stances are cut by the start or end of the recording: try ")
                .opt(Opt::IncludePartial)
        } else {
            Message::from(format!(
                "no stance was found in them (baseline mode {}): see `presrs inspect FILE`, or give \
                 a `frame` column to use one frame anyway",
                options.segment.params().baseline
            ))
        };
        Some(
            Message::from(format!(
                "{count} of {rows} file{} {NO_SAMPLE}: {} ; ",
                if rows == 1 { "" } else { "s" },
                names.join(", ")
            ))
            .then(hint),
        )
    }
}

/// What the warning that sums up the files without a sample says after their count.
const NO_SAMPLE: &str = "gave no sample";

/// Whether `warning` is the summary of the files that gave no sample (an error about too few samples
/// repeats it as the reason).
pub(super) fn is_no_sample_summary(warning: &Warning) -> bool {
    warning.to_string().contains(NO_SAMPLE)
}

/// A manifest row's fields as written, by column name (empty ones left out).
fn row_columns(row: &ManifestRow) -> BTreeMap<String, String> {
    let mut columns = row.extra.clone();
    let known = [
        ("path", Some(&row.path_text)),
        ("label", row.label.as_ref()),
        ("condition", row.condition.as_ref()),
        ("group", row.group.as_ref()),
        ("frame", row.frame_text.as_ref()),
        ("load", row.load_text.as_ref()),
    ];
    for (name, value) in known {
        if let Some(value) = value {
            columns.insert(name.to_owned(), value.clone());
        }
    }
    columns
}

/// The frame indices one manifest row contributes.
fn row_frames(
    manifest: &Manifest,
    row: &ManifestRow,
    recording: &Recording,
    options: &SampleOptions,
    empty: &mut EmptyFiles,
) -> std::result::Result<Vec<usize>, IoError> {
    let count = recording.frame_count();
    if let Some(frame) = row.frame {
        if frame >= count {
            return Err(manifest.row_error(
                row,
                format!(
                    "field `frame` is {frame} but `{}` has {count} frame(s) (frames are 0-based)",
                    row.path_text
                ),
            ));
        }
        return Ok(vec![frame]);
    }
    if count == 1 {
        return Ok(vec![0]);
    }
    let segmentation = row_segmentation(manifest, row, recording, options)?;
    if let (true, presrs_core::stance::SampleFrame::Offset(k)) =
        (options.skip_short_stances, options.sample)
    {
        // Only the stances that reach frame K; a file none of whose stances does is no empty file.
        return Ok(segmentation
            .stances
            .iter()
            .filter(|stance| (options.include_partial() || !stance.partial) && k < stance.len)
            .map(|stance| stance.start + k)
            .collect());
    }
    let frames = segmentation
        .samples(options.sample, options.include_partial())
        .map_err(|err| manifest.row_error(row, format!("`{}`: {err}", row.path_text)))?;
    if frames.is_empty() {
        empty.add(&row.path_text, &segmentation);
    }
    Ok(frames)
}

fn row_segmentation(
    manifest: &Manifest,
    row: &ManifestRow,
    recording: &Recording,
    options: &SampleOptions,
) -> std::result::Result<Segmentation, IoError> {
    segment_recording(recording, &options.segment_params()).map_err(|err| {
        manifest.row_error(row, format!("cannot segment `{}`: {err}", row.path_text))
    })
}

/// The stances one manifest row contributes as whole-stance samples: every complete stance (and the
/// partial ones when asked). A row that names a frame, or a one-frame file, has no stance to give.
fn row_stances(
    manifest: &Manifest,
    row: &ManifestRow,
    recording: &Recording,
    options: &SampleOptions,
    empty: &mut EmptyFiles,
) -> std::result::Result<Vec<Stance>, IoError> {
    if row.frame.is_some() {
        return Err(manifest.row_error(
            row,
            "field `frame` names one frame, but whole-stance samples take every frame of a stance: \
             leave the `frame` column empty, or use frame samples"
                .to_owned(),
        ));
    }
    if recording.frame_count() == 1 {
        return Err(manifest.row_error(
            row,
            format!(
                "`{}` is one frame, not a movie: whole-stance samples need movies (a 2-D array \
                 of taxels over time is a series sample)",
                row.path_text
            ),
        ));
    }
    let segmentation = row_segmentation(manifest, row, recording, options)?;
    let include_partial = options.include_partial();
    let stances: Vec<Stance> = segmentation
        .stances
        .iter()
        .filter(|stance| include_partial || !stance.partial)
        .copied()
        .collect();
    if stances.is_empty() {
        empty.add(&row.path_text, &segmentation);
    }
    Ok(stances)
}

/// The one 2-D array of a one-frame file, for a series sample (a movie, or a row naming a frame, is an
/// error).
fn row_series<'r>(
    manifest: &Manifest,
    row: &ManifestRow,
    recording: &'r Recording,
) -> std::result::Result<FrameView<'r>, IoError> {
    match recording.frame(0) {
        Some(frame) if recording.frame_count() == 1 && row.frame.is_none() => Ok(frame),
        _ => Err(manifest.row_error(
            row,
            format!(
                "`{}` is a movie (or the row names a frame): a series sample is one 2-D array of \
                 channels x time; for a movie of pressure images use whole-stance samples",
                row.path_text
            ),
        )),
    }
}
