//! Reading a manifest's recordings for a data set: each file (and each bag topic) read once, in
//! parallel, with the read options, dead sensels filled as asked, and the frame periods of the option
//! and of the `frame_period_s` column; the movies' total loads an online profile is learned from.

use std::collections::HashMap;
use std::path::PathBuf;

use presrs_core::Recording;
use presrs_core::dead_sensels::{DeadSensel, DeadSenselConfig, correct_dead_sensels};
use presrs_io::manifest::{Manifest, ManifestRow};
use presrs_io::message::{Message, Opt};
use presrs_io::{IoError, Parsed, ReadOptions, read_recording_with};
use rayon::prelude::*;

use super::options::SampleOptions;
use crate::error::{Error, Result};

/// Reads a recording and, with `dead_sensels`, fills its dead sensels
/// ([`correct_dead_sensels`]); also returns the sensels filled.
pub fn read_corrected(
    path: &std::path::Path,
    read: &ReadOptions,
    dead_sensels: Option<&DeadSenselConfig>,
) -> std::result::Result<(Parsed, Vec<DeadSensel>), IoError> {
    let parsed = read_recording_with(path, read)?;
    let Some(config) = dead_sensels else {
        return Ok((parsed, Vec::new()));
    };
    let Parsed {
        recording,
        warnings,
    } = parsed;
    let (recording, filled) = correct_dead_sensels(recording, config).map_err(|err| {
        IoError::format(
            &presrs_io::error::display_name(path),
            format!("cannot fill dead sensels: {err}"),
        )
    })?;
    Ok((
        Parsed {
            recording,
            warnings,
        },
        filled,
    ))
}

/// Dead sensels filled per recording, and a one-line summary of them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DeadSenselFills {
    /// The recordings in which some were filled, with the sensels (0-based row, column).
    pub recordings: Vec<(PathBuf, Vec<DeadSensel>)>,
}

impl DeadSenselFills {
    /// Notes what one recording had filled (nothing when `filled` is empty).
    pub fn add(&mut self, path: PathBuf, filled: Vec<DeadSensel>) {
        if !filled.is_empty() {
            self.recordings.push((path, filled));
        }
    }

    /// Sensels filled over all recordings.
    pub fn sensels(&self) -> usize {
        self.recordings.iter().map(|(_, d)| d.len()).sum()
    }

    /// `filled 3 dead sensels in 2 recordings`, or `None` when nothing was filled.
    pub fn summary(&self) -> Option<String> {
        let (n, m) = (self.sensels(), self.recordings.len());
        (n > 0).then(|| {
            format!(
                "filled {n} dead sensel{} in {m} recording{}",
                if n == 1 { "" } else { "s" },
                if m == 1 { "" } else { "s" }
            )
        })
    }
}

/// A movie of a manifest, as read for its data set (its row's topic and the read options, dead sensels
/// filled as asked): its total load per frame, what an online profile is learned from.
#[derive(Clone, Debug, PartialEq)]
pub struct MovieLoad {
    pub path: PathBuf,
    /// The topic of a bag's row (its `topic` column), else the read options' topic.
    pub topic: Option<String>,
    pub total_per_frame: Vec<f64>,
}

/// The total load per frame of every movie (a recording of more than one frame) `manifest` lists, each
/// read once as [`load_samples`](super::load_samples) reads it (`options`' reading settings; no sample is taken).
pub fn read_movie_loads(
    manifest: &Manifest,
    options: &SampleOptions,
) -> std::result::Result<Vec<MovieLoad>, IoError> {
    Ok(read_recordings(manifest, options)?.movie_loads())
}

/// Every recording of a manifest, read once, and the dead sensels filled in them.
pub(super) struct ReadRecordings<'m> {
    pub(super) by_key: HashMap<RecordingKey<'m>, Parsed>,
    pub(super) fills: DeadSenselFills,
}

impl ReadRecordings<'_> {
    /// The movies' total loads, ordered by file and topic.
    pub(super) fn movie_loads(&self) -> Vec<MovieLoad> {
        let mut movies: Vec<(&RecordingKey<'_>, &Parsed)> = self
            .by_key
            .iter()
            .filter(|(_, parsed)| parsed.recording.frame_count() > 1)
            .collect();
        movies.sort_by(|a, b| a.0.cmp(b.0));
        movies
            .into_iter()
            .map(|(&(path, topic), parsed)| MovieLoad {
                path: path.clone(),
                topic: topic.map(str::to_owned),
                total_per_frame: parsed.recording.total_per_frame(),
            })
            .collect()
    }
}

/// Reads every recording of `manifest` once, in parallel: a file and, for a bag, the topic of the row's
/// `topic` column (else the options'), with the read options, dead sensels filled as asked, and the
/// frame period of the option and of the `frame_period_s` column.
pub(super) fn read_recordings<'m>(
    manifest: &'m Manifest,
    options: &SampleOptions,
) -> std::result::Result<ReadRecordings<'m>, IoError> {
    let mut unique: Vec<RecordingKey<'_>> = manifest.rows.iter().map(row_key).collect();
    unique.sort();
    unique.dedup();
    type Read = std::result::Result<(Parsed, Vec<DeadSensel>), IoError>;
    let recordings: Vec<(RecordingKey<'_>, Read)> = unique
        .par_iter()
        .map(|&(path, topic)| {
            let read = match topic {
                Some(topic) => {
                    let read = ReadOptions {
                        topic: Some(topic.to_owned()),
                        ..options.read.clone()
                    };
                    read_corrected(path, &read, options.dead_sensels.as_ref())
                }
                None => read_corrected(path, &options.read, options.dead_sensels.as_ref()),
            };
            ((path, topic), read)
        })
        .collect();
    let mut by_key: HashMap<RecordingKey<'_>, Parsed> = HashMap::with_capacity(recordings.len());
    let mut fills = DeadSenselFills::default();
    for (key, parsed) in recordings {
        let path = key.0;
        let parsed = parsed.map_err(|err| {
            let row = manifest.rows.iter().find(|row| row_key(row) == key);
            match row {
                Some(row) => {
                    manifest.row_error(row, format!("cannot use `{}`: {err}", row.path_text))
                }
                None => err,
            }
        })?;
        let (mut parsed, filled) = parsed;
        if let Some(period) = options.frame_period_s {
            parsed
                .recording
                .set_frame_period_if_unknown(period)
                .map_err(|err| IoError::format(&path.display().to_string(), err.to_string()))?;
        }
        fills.add(path.clone(), filled);
        by_key.insert(key, parsed);
    }
    apply_frame_period_column(manifest, &mut by_key)?;
    Ok(ReadRecordings { by_key, fills })
}

/// A recording of a manifest: a file, and the topic of its row's `topic` column (a bag's).
pub(super) type RecordingKey<'m> = (&'m PathBuf, Option<&'m str>);

pub(super) fn row_key(row: &ManifestRow) -> RecordingKey<'_> {
    (&row.path, row.column("topic"))
}

/// Sets a recording's frame period from the frame-period option when its file states none; a value that
/// is not a period names the option.
pub(crate) fn apply_frame_period_option(
    recording: &mut Recording,
    period: Option<f64>,
) -> Result<()> {
    if let Some(period) = period {
        recording
            .set_frame_period_if_unknown(period)
            .map_err(|err| {
                Error::invalid(
                    Message::new()
                        .opt(Opt::FramePeriod)
                        .text(format!(": {err}")),
                )
            })?;
    }
    Ok(())
}

/// Sets the frame period of the recordings whose rows give a `frame_period_s` (when the file states
/// none); a value that is not a positive number is an error naming the line.
fn apply_frame_period_column<'m>(
    manifest: &'m Manifest,
    by_path: &mut HashMap<RecordingKey<'m>, Parsed>,
) -> std::result::Result<(), IoError> {
    for row in &manifest.rows {
        let Some(text) = row.column("frame_period_s") else {
            continue;
        };
        let period: f64 = text.trim().parse().map_err(|_| {
            manifest.row_error(
                row,
                format!("field `frame_period_s` must be a number of seconds, got {text:?}"),
            )
        })?;
        if let Some(parsed) = by_path.get_mut(&row_key(row)) {
            parsed
                .recording
                .set_frame_period_if_unknown(period)
                .map_err(|err| manifest.row_error(row, format!("field `frame_period_s`: {err}")))?;
        }
    }
    Ok(())
}
