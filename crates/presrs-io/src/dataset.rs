//! From a manifest to samples: reads every file a manifest lists and picks the frames to use.
//!
//! A manifest row names a file and, optionally, a frame. A row with a frame gives that frame; a row of a
//! one-frame file gives its frame; a row of a movie without a frame gives one sample per complete stance
//! phase (the mid-stance frame by default, see [`SampleFrame`]). Files are read once each, in parallel.

use std::collections::{BTreeMap, HashMap};
use std::path::PathBuf;

use presrs_core::stance::{SampleFrame, ValidSegmentParams, segment_recording};
use presrs_core::{Frame, Recording};
use rayon::prelude::*;

use crate::error::IoError;
use crate::manifest::{Manifest, ManifestRow};
use crate::{ReadOptions, read_recording_with};

/// How samples are picked from movies.
#[derive(Clone, Debug, Default)]
pub struct SampleOptions {
    /// Which frame(s) of each stance.
    pub sample: SampleFrame,
    pub segment: ValidSegmentParams,
    /// Also sample stances cut by the start or end of a recording.
    pub include_partial: bool,
    pub read: ReadOptions,
}

/// One image with everything the manifest says about it.
#[derive(Clone, Debug)]
pub struct Sample {
    pub frame: Frame,
    /// The file it came from and the 0-based frame index in it.
    pub source: PathBuf,
    pub frame_index: usize,
    /// The manifest line that produced it.
    pub manifest_line: usize,
    pub label: Option<String>,
    pub condition: Option<String>,
    pub group: Option<String>,
    pub load: Option<f64>,
    /// Other manifest columns (for `--leave-one-out COLUMN`).
    pub extra: BTreeMap<String, String>,
}

impl Sample {
    /// The value of a manifest column for this sample (`label`, `condition`, `group`, or an extra column).
    pub fn column(&self, name: &str) -> Option<&str> {
        match name {
            "label" => self.label.as_deref(),
            "condition" => self.condition.as_deref(),
            "group" => self.group.as_deref(),
            _ => self.extra.get(name).map(String::as_str),
        }
    }
}

/// The samples of a manifest, with what did not stop loading (a movie without stances, reader warnings).
#[derive(Clone, Debug, Default)]
pub struct LoadedSamples {
    pub samples: Vec<Sample>,
    pub warnings: Vec<String>,
}

/// Reads every file of `manifest` (each once, in parallel) and picks samples as described in the module
/// documentation. Errors name the manifest line (and the file's own line for a parse error).
pub fn load_samples(
    manifest: &Manifest,
    options: &SampleOptions,
) -> Result<LoadedSamples, IoError> {
    let mut unique: Vec<&PathBuf> = manifest.rows.iter().map(|row| &row.path).collect();
    unique.sort();
    unique.dedup();
    let recordings: Vec<(&PathBuf, Result<crate::Parsed, IoError>)> = unique
        .par_iter()
        .map(|&path| (path, read_recording_with(path, &options.read)))
        .collect();
    let mut by_path: HashMap<&PathBuf, crate::Parsed> = HashMap::with_capacity(recordings.len());
    for (path, parsed) in recordings {
        let parsed = parsed.map_err(|err| {
            let row = manifest.rows.iter().find(|row| &row.path == path);
            match row {
                Some(row) => {
                    manifest.row_error(row, format!("cannot use `{}`: {err}", row.path_text))
                }
                None => err,
            }
        })?;
        by_path.insert(path, parsed);
    }
    let mut loaded = LoadedSamples::default();
    for parsed in by_path.values() {
        loaded.warnings.extend(parsed.warnings.iter().cloned());
    }
    loaded.warnings.sort();
    for row in &manifest.rows {
        let Some(parsed) = by_path.get(&row.path) else {
            continue;
        };
        let frames = row_frames(
            manifest,
            row,
            &parsed.recording,
            options,
            &mut loaded.warnings,
        )?;
        for frame_index in frames {
            let Some(view) = parsed.recording.frame(frame_index) else {
                continue;
            };
            loaded.samples.push(Sample {
                frame: view.to_frame(),
                source: row.path.clone(),
                frame_index,
                manifest_line: row.line,
                label: row.label.clone(),
                condition: row.condition.clone(),
                group: row.group.clone(),
                load: row.load,
                extra: row.extra.clone(),
            });
        }
    }
    Ok(loaded)
}

/// The frame indices one manifest row contributes.
fn row_frames(
    manifest: &Manifest,
    row: &ManifestRow,
    recording: &Recording,
    options: &SampleOptions,
    warnings: &mut Vec<String>,
) -> Result<Vec<usize>, IoError> {
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
    let segmentation = segment_recording(recording, &options.segment).map_err(|err| {
        manifest.row_error(row, format!("cannot segment `{}`: {err}", row.path_text))
    })?;
    let frames = segmentation
        .samples(options.sample, options.include_partial)
        .map_err(|err| manifest.row_error(row, format!("`{}`: {err}", row.path_text)))?;
    if frames.is_empty() {
        warnings.push(format!(
            "{} line {}: `{}` has {count} frames but no complete stance phase; it gives no sample \
             (give a `frame` to use one anyway)",
            manifest.source.display(),
            row.line,
            row.path_text
        ));
    }
    Ok(frames)
}
