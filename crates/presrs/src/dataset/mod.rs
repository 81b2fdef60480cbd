//! From a manifest to samples: reads every file a manifest lists and picks the frames to use.
//!
//! A manifest row names a file and, optionally, a frame. A row with a frame gives that frame; a row of a
//! one-frame file gives its frame; a row of a movie without a frame gives one sample per complete stance
//! phase (the mid-stance frame by default, see [`SampleFrame`](presrs_core::stance::SampleFrame)). Files are read once each, in parallel.
//!
//! Dead sensels (silent in every frame while their neighbours carry load) are found and filled from
//! their neighbours in every recording of at least three frames before any frame is taken from it
//! ([`presrs_core::dead_sensels::correct_dead_sensels`]), unless [`SampleOptions::dead_sensels`] is
//! `None`; [`LoadedSamples::dead_sensels`] says what was filled.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

pub use presrs_core::sample::{SampleChoice, SampleKind, Sampling};
use presrs_core::stance::summary::pad_to;
use presrs_core::stance::{BaselineMode, Segmentation, Stance, segment_recording};
use presrs_core::{FrameView, Grid, Recording};
use sha2::{Digest, Sha256};

use presrs_io::IoError;
use presrs_io::manifest::{Manifest, ManifestRow, read_manifest};

use crate::error::{Error, Result};

mod options;
mod read;

use crate::progress::Progress;
pub use options::{GivenSampleSettings, SampleOptions, check_sample_settings};
use presrs_io::message::{Message, Opt, Warning, Warnings};
pub(crate) use read::apply_frame_period_option;
pub use read::{DeadSenselFills, MovieLoad, read_corrected, read_movie_loads};
use read::{read_recordings, row_key};

pub use presrs_core::Sample;

/// The samples of a manifest, with what did not stop loading (a movie without stances, reader warnings).
#[derive(Clone, Debug, Default)]
pub struct LoadedSamples {
    pub samples: Vec<Sample>,
    pub warnings: Warnings,
    /// The dead sensels filled (with [`SampleOptions::dead_sensels`]), by recording.
    pub dead_sensels: DeadSenselFills,
    /// Every movie read, by file and topic: what an online profile is learned from.
    pub movie_loads: Vec<MovieLoad>,
    /// The one sensor of stance and series samples (see [`Dataset::sensor`]).
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

/// A data set: a manifest and the samples its files give, stance sampling and dead-sensel correction
/// done ([`Dataset::load`]).
#[derive(Clone, Debug)]
pub struct Dataset {
    pub manifest: Manifest,
    /// Every sample, in manifest order (a movie row gives its stances in time order).
    pub samples: Vec<Sample>,
    /// What did not stop loading (a movie without a stance, a reader's warning), each naming the file
    /// and line.
    pub warnings: Warnings,
    /// The dead sensels filled, by recording.
    pub dead_sensels: DeadSenselFills,
    /// What a sample is (one frame, a whole stance, a series): models trained on the set say so.
    pub sample: SampleKind,
    /// The total load per frame of every movie read (none for samples made in memory), as read for
    /// the samples: the online profile is learned from them, not from a second reading.
    pub movie_loads: Vec<MovieLoad>,
    /// Whole-stance samples: each stance's length and its cuts at the decision points asked.
    pub stances: StanceCuts,
    /// The sensor of stance and series samples, which a model trained on them refuses any other
    /// than: the grid of the recordings' frames whose stances were summarised, or the series' grid
    /// (channels x time, as the samples hold them). `None` for frame samples.
    pub sensor: Option<Grid>,
    /// How the samples were taken from the manifest's recordings (`None` for samples made in
    /// memory): a model trained on the set stores it.
    pub sampling: Option<Sampling>,
}

impl Dataset {
    /// Reads the manifest at `path` and every file it lists (each once, in parallel). A manifest that
    /// gives no sample is an error.
    pub fn load(path: &Path, options: &SampleOptions, progress: &dyn Progress) -> Result<Self> {
        let manifest = read_manifest(path)?;
        Self::from_manifest(manifest, options, progress)
    }

    /// The samples of an already parsed manifest.
    pub fn from_manifest(
        manifest: Manifest,
        options: &SampleOptions,
        progress: &dyn Progress,
    ) -> Result<Self> {
        progress.start(&format!("reading {} files", manifest.rows.len()), None);
        let loaded = load_samples(&manifest, options);
        progress.finish();
        let loaded = loaded?;
        if loaded.samples.is_empty() {
            // The summary of the files that gave none says why (it is the last warning).
            let message = Message::from(format!(
                "{}: the manifest gives no samples",
                manifest.source.display()
            ));
            let message = match loaded.warnings.last().filter(|w| is_no_sample_summary(w)) {
                Some(why) => message.text(": ").then(why.message().clone()),
                None => message,
            };
            return Err(Error::data(message));
        }
        Ok(Self {
            manifest,
            samples: loaded.samples,
            warnings: loaded.warnings,
            dead_sensels: loaded.dead_sensels,
            sample: options.kind,
            movie_loads: loaded.movie_loads,
            stances: loaded.stances,
            sensor: loaded.sensor,
            sampling: Some(options.sampling()),
        })
    }

    /// A data set of samples already in memory (arrays from Python, images made by a program), named
    /// `name` in messages. Its stand-in manifest has the columns the samples fill (`path`, `label`,
    /// `condition`, `group`) and no rows; its SHA-256 identifies the samples' images and fields, so a
    /// model's provenance still names the data it came from. No samples, or samples of different grids,
    /// is an error.
    pub fn from_samples(name: impl Into<PathBuf>, samples: Vec<Sample>) -> Result<Self> {
        let source = name.into();
        let Some(first) = samples.first() else {
            return Err(Error::data(format!("{}: no samples", source.display())));
        };
        let grid = first.frame.grid();
        if let Some((index, odd)) = samples
            .iter()
            .enumerate()
            .find(|(_, sample)| sample.frame.grid() != grid)
        {
            return Err(Error::data(format!(
                "{}: sample {index} is {} where the first is {grid}; every image must have one size",
                source.display(),
                odd.frame.grid()
            )));
        }
        let mut columns = vec!["path".to_owned()];
        for (column, filled) in [
            ("label", samples.iter().any(|s| s.label.is_some())),
            ("condition", samples.iter().any(|s| s.condition.is_some())),
            ("group", samples.iter().any(|s| s.group.is_some())),
        ] {
            if filled {
                columns.push(column.to_owned());
            }
        }
        let manifest = Manifest {
            sha256: samples_sha256(&samples),
            source,
            columns,
            rows: Vec::new(),
        };
        Ok(Self {
            manifest,
            samples,
            warnings: Warnings::new(),
            dead_sensels: DeadSenselFills::default(),
            sample: SampleKind::Frame,
            movie_loads: Vec::new(),
            stances: StanceCuts::default(),
            sensor: None,
            sampling: None,
        })
    }

    /// [`Dataset::from_samples`] for samples of `kind`, made in memory as [`Dataset::load`] makes them
    /// from files: a whole stance's sample is its movie's summary
    /// ([`summarise`](presrs_core::stance::summary::summarise)), laid here into the kind's length (or
    /// the longest stance's), with the warning of [`pad_stance_samples`]; a series' sample is its
    /// channels x time array, whose grid is the set's [`Dataset::sensor`]. A stance's movies are
    /// summarised before: their caller states their sensor.
    pub fn from_samples_of(
        name: impl Into<PathBuf>,
        mut samples: Vec<Sample>,
        kind: SampleKind,
    ) -> Result<Self> {
        let mut warnings = Warnings::new();
        let name: PathBuf = name.into();
        if let SampleKind::Stance { length, .. } = kind {
            let shown = name.display().to_string();
            warnings.extend(pad_stance_samples(&shown, &mut samples, length)?);
        }
        let mut dataset = Self::from_samples(name, samples)?;
        dataset.sample = kind;
        dataset.warnings = warnings;
        if let SampleKind::Series { .. } = kind {
            dataset.sensor = Some(dataset.grid());
        }
        Ok(dataset)
    }

    /// Why a draw of `need` samples per class cannot be made, when that is the cause: every class of
    /// the manifest's rows (of `condition`, if given) with fewer than `need` samples, with its count,
    /// then why files gave no sample and the option to try (the data set's one-line summary), e.g.
    /// `too few samples per class: "grass" has 1, "gravel" 0 (at least 3 needed); 599 of 600 files
    /// gave no sample: ... ; they are one contact each: try --one-sample-per-file`. `None` when every
    /// class has enough.
    pub fn too_few_samples(&self, condition: Option<&str>, need: usize) -> Option<Message> {
        self.classes_short_of(condition, need, false)
    }

    /// [`Dataset::too_few_samples`], where a data set made in memory (no manifest rows) takes the
    /// samples' own labels for its classes: why training failed, e.g. one image per class.
    pub fn too_few_samples_to_train(
        &self,
        condition: Option<&str>,
        need: usize,
    ) -> Option<Message> {
        self.classes_short_of(condition, need, true)
    }

    fn classes_short_of(
        &self,
        condition: Option<&str>,
        need: usize,
        labels_without_rows: bool,
    ) -> Option<Message> {
        let mut classes: Vec<&str> = self
            .manifest
            .rows
            .iter()
            .filter(|row| condition.is_none() || row.condition.as_deref() == condition)
            .filter_map(|row| row.label.as_deref())
            .collect();
        let labels: Vec<&str> = self
            .samples
            .iter()
            .filter(|sample| condition.is_none() || sample.condition.as_deref() == condition)
            .filter_map(|sample| sample.label.as_deref())
            .collect();
        // Samples made in memory have no manifest rows: their own labels are the classes.
        if labels_without_rows && self.manifest.rows.is_empty() {
            classes.clone_from(&labels);
        }
        classes.sort_unstable();
        classes.dedup();
        let short = presrs_core::split::classes_short_of(&labels, &classes, need);
        if short.is_empty() {
            return None;
        }
        let counts: Vec<String> = short
            .iter()
            .enumerate()
            .map(|(i, (class, count))| {
                if i == 0 {
                    format!("{class:?} has {count}")
                } else {
                    format!("{class:?} {count}")
                }
            })
            .collect();
        let why = self
            .warnings
            .iter()
            .rev()
            .find(|w| is_no_sample_summary(w))
            .map_or_else(Message::new, |w| {
                Message::from("; ").then(w.message().clone())
            });
        Some(
            Message::from(format!(
                "too few samples per class: {} (at least {need} needed, {} sample{} in all)",
                counts.join(", "),
                labels.len(),
                if labels.len() == 1 { "" } else { "s" }
            ))
            .then(why),
        )
    }

    /// The manifest file.
    pub fn path(&self) -> &Path {
        &self.manifest.source
    }

    /// The image grid of the first sample (readers check that a recording's frames share one).
    pub fn grid(&self) -> Grid {
        self.samples[0].frame.grid()
    }

    /// The samples of `condition` (all of them for `None`); none is an error listing the conditions
    /// there are.
    pub fn of_condition(&self, condition: Option<&str>) -> Result<Vec<&Sample>> {
        let Some(condition) = condition else {
            return Ok(self.samples.iter().collect());
        };
        let pool: Vec<&Sample> = self
            .samples
            .iter()
            .filter(|sample| sample.condition.as_deref() == Some(condition))
            .collect();
        if pool.is_empty() {
            let known = self.conditions();
            return Err(Error::data(format!(
                "{}: no sample has condition {condition:?} (conditions present: {})",
                self.path().display(),
                if known.is_empty() {
                    "none".to_owned()
                } else {
                    known.join(", ")
                }
            )));
        }
        Ok(pool)
    }

    /// The distinct conditions of the samples, sorted.
    pub fn conditions(&self) -> Vec<&str> {
        let mut known: Vec<&str> = self
            .samples
            .iter()
            .filter_map(|s| s.condition.as_deref())
            .collect();
        known.sort_unstable();
        known.dedup();
        known
    }

    /// An error unless the manifest has a `label` column; `why` says what needs it.
    pub fn require_labels(&self, why: &str) -> Result<()> {
        Ok(self.manifest.require_column("label", why)?)
    }
}

/// The label of every sample; a sample without one is an error naming its manifest line and `why` a
/// label is needed ("training needs a label for every sample").
pub fn sample_labels<'s>(
    manifest: &Path,
    samples: &[&'s Sample],
    why: &str,
) -> Result<Vec<&'s str>> {
    samples
        .iter()
        .map(|sample| {
            sample.label.as_deref().ok_or_else(|| {
                Error::data(format!(
                    "{}: field `label` is empty; {why}",
                    sample.origin(manifest)
                ))
            })
        })
        .collect()
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
fn is_no_sample_summary(warning: &Warning) -> bool {
    warning.to_string().contains(NO_SAMPLE)
}

/// A manifest row's fields as written, by column name (empty ones left out).
/// SHA-256 (hex) of samples in memory: each image's grid and values, then its label, condition and
/// group, so that the same images with the same fields give the same digest.
fn samples_sha256(samples: &[Sample]) -> String {
    let mut hasher = Sha256::new();
    for sample in samples {
        let grid = sample.frame.grid();
        hasher.update((grid.rows as u64).to_le_bytes());
        hasher.update((grid.cols as u64).to_le_bytes());
        for value in sample.frame.values() {
            hasher.update(value.to_le_bytes());
        }
        for field in [&sample.label, &sample.condition, &sample.group] {
            let text = field.as_deref().unwrap_or("");
            hasher.update((text.len() as u64).to_le_bytes());
            hasher.update(text.as_bytes());
        }
    }
    hasher
        .finalize()
        .iter()
        .map(|byte| format!("{byte:02x}"))
        .collect()
}

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

/// How many times the longest stance a `stance length` may be: beyond it a sample is mostly the zeros
/// after lift-off (features of padding), and a length typed with a few digits too many would take all
/// the memory there is (12 channels x 100 000 000 frames is 9.6 GB a sample).
pub const MAX_STANCE_LENGTH_PER_LONGEST: usize = 4;

/// Lays every whole-stance sample into one length: `length`, or the longest stance's. The warning, when
/// some were longer, says how many were cut to their first `length` frames. A `length` over
/// [`MAX_STANCE_LENGTH_PER_LONGEST`] times the longest stance is refused before anything is
/// allocated ([`check_stance_length`]); `name` (the manifest or the arrays) names the data in the error.
pub fn pad_stance_samples(
    name: &str,
    samples: &mut [Sample],
    length: Option<usize>,
) -> std::result::Result<Option<Warning>, IoError> {
    let longest = samples
        .iter()
        .map(|s| s.frame.grid().cols)
        .max()
        .unwrap_or(0);
    if let Some(length) = length {
        check_stance_length(name, length, longest)?;
    }
    let length = length.unwrap_or(longest);
    let mut cut = 0;
    for sample in samples.iter_mut() {
        let (padded, was_cut) = pad_to(&sample.frame.view(), length)
            .map_err(|err| IoError::format(name, err.to_string()))?;
        sample.frame = padded;
        cut += usize::from(was_cut);
    }
    Ok((cut > 0).then(|| {
        Warning::from(Message::from(format!(
            "{cut} of {} stances are longer than {length} frames: their first {length} frames are \
             used (the longest has {longest})",
            samples.len()
        )))
    }))
}

/// An error unless a stance length of `length` frames suits stances whose longest has `longest`
/// frames: at most [`MAX_STANCE_LENGTH_PER_LONGEST`] times it. The error says the longest stance
/// found and what to give (a stance length in the face's words: `--stance-length`, `stance_length=`).
pub fn check_stance_length(
    name: &str,
    length: usize,
    longest: usize,
) -> std::result::Result<(), IoError> {
    let most = longest.saturating_mul(MAX_STANCE_LENGTH_PER_LONGEST);
    if longest == 0 || length <= most {
        return Ok(());
    }
    Err(IoError::format(
        name,
        Message::new()
            .opt_is(Opt::StanceLength, length)
            .text(format!(
                " is far longer than the longest stance found ({longest} frames): every stance would \
                 be mostly zeros after lift-off; give at most {most} frames \
                 ({MAX_STANCE_LENGTH_PER_LONGEST} x the longest), or leave "
            ))
            .opt(Opt::StanceLength)
            .text(format!(" out to lay each stance into the longest's {longest} frames")),
    ))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]

    use super::*;
    use presrs_core::SensorMeta;

    /// A 10-frame 12 x 12 movie loaded by a smooth dome (radius 4 around (5, 5)) from frame 2 on, with
    /// sensel (5, 4) dead, written as a 3-D NPY with a manifest naming frame 6.
    fn movie_manifest(dir: &std::path::Path) -> Manifest {
        let mut data = Vec::new();
        for f in 0..10 {
            for r in 0..12 {
                for c in 0..12 {
                    let d2 = (r as f64 - 5.0).powi(2) + (c as f64 - 5.0).powi(2);
                    let v = if f >= 2 && d2 <= 16.0 && (r, c) != (5, 4) {
                        80.0 - 3.0 * d2
                    } else {
                        0.0
                    };
                    data.push(v);
                }
            }
        }
        let rec = Recording::new(
            Grid::new(12, 12),
            Some(0.01),
            data,
            None,
            SensorMeta::default(),
        )
        .unwrap();
        presrs_io::npy::write_recording_npy(&rec, &dir.join("walk.npy")).unwrap();
        let path = dir.join("manifest.csv");
        std::fs::write(&path, "path,label,frame\nwalk.npy,wood,6\n").unwrap();
        presrs_io::manifest::read_manifest(&path).unwrap()
    }

    #[test]
    fn sample_column_gives_path_frame_and_load_too() {
        // `--leave-one-out path|frame|load` asks Sample::column for these: they used to be `None`
        // on every row ("field `load` is empty").
        let dir = tempfile::tempdir().unwrap();
        movie_manifest(dir.path());
        let path = dir.path().join("loads.csv");
        std::fs::write(
            &path,
            "path,label,frame,load,subject\nwalk.npy,wood,6,12.5,s1\nwalk.npy,wood,7,,\n",
        )
        .unwrap();
        let manifest = presrs_io::manifest::read_manifest(&path).unwrap();
        let loaded = load_samples(&manifest, &SampleOptions::default()).unwrap();
        let [first, second] = loaded.samples.as_slice() else {
            panic!("{} samples", loaded.samples.len());
        };
        for (name, value) in [
            ("path", Some("walk.npy")),
            ("label", Some("wood")),
            ("frame", Some("6")),
            ("load", Some("12.5")),
            ("subject", Some("s1")),
            ("condition", None),
        ] {
            assert_eq!(first.column(name), value, "{name}");
        }
        assert_eq!(second.column("path"), Some("walk.npy"));
        assert_eq!(second.column("frame"), Some("7"));
        assert_eq!(second.column("load"), None);
        assert_eq!(second.frame_index, 7);
    }

    /// A frame sample at an offset past a stance is refused, unless asked to leave such stances out
    /// (the one-frame model beside a late decision point), which leaves them out without a warning.
    #[test]
    fn an_offset_past_a_stance_is_refused_or_left_out_on_request() {
        let dir = tempfile::tempdir().unwrap();
        movie_manifest(dir.path());
        let path = dir.path().join("contacts.csv");
        std::fs::write(&path, "path,label\nwalk.npy,wood\nwalk.npy,sand\n").unwrap();
        let manifest = presrs_io::manifest::read_manifest(&path).unwrap();
        let at = |k: usize, skip: bool| SampleOptions {
            sample: presrs_core::stance::SampleFrame::Offset(k),
            one_sample_per_file: true,
            skip_short_stances: skip,
            ..SampleOptions::default()
        };
        for skip in [false, true] {
            let loaded = load_samples(&manifest, &at(3, skip)).unwrap();
            let frames: Vec<usize> = loaded.samples.iter().map(|s| s.frame_index).collect();
            assert_eq!(frames, vec![3, 3], "skip {skip}");
        }
        let err = load_samples(&manifest, &at(40, false)).unwrap_err();
        assert!(
            err.to_string()
                .contains("frame offset 40 is past the stance"),
            "{err}"
        );
        let left_out = load_samples(&manifest, &at(40, true)).unwrap();
        assert!(left_out.samples.is_empty());
        assert!(left_out.warnings.is_empty(), "{:?}", left_out.warnings);
    }

    #[test]
    fn dead_sensels_are_filled_by_default_and_kept_on_request() {
        let dir = tempfile::tempdir().unwrap();
        let manifest = movie_manifest(dir.path());
        let loaded = load_samples(&manifest, &SampleOptions::default()).unwrap();
        let frame = loaded.samples[0].frame.view();
        // Close to its neighbours (80 - 3 = 77 the true value; 4-neighbour mean 77 - 3 = 74).
        assert!(
            (frame.get(5, 4) - 77.0).abs() <= 3.0 + 1e-9,
            "{}",
            frame.get(5, 4)
        );
        assert_eq!(loaded.dead_sensels.sensels(), 1);
        assert_eq!(
            loaded.dead_sensels.summary().as_deref(),
            Some("filled 1 dead sensel in 1 recording")
        );
        // Edge of the contact area: untouched.
        assert_eq!(frame.get(5, 10), 0.0);
        assert_eq!(frame.get(1, 5), 32.0);
        let kept = load_samples(
            &manifest,
            &SampleOptions {
                dead_sensels: None,
                ..SampleOptions::default()
            },
        )
        .unwrap();
        assert_eq!(kept.samples[0].frame.view().get(5, 4), 0.0);
        assert_eq!(kept.dead_sensels.summary(), None);
    }
}
