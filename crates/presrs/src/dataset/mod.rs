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

use std::path::{Path, PathBuf};

use presrs_core::Grid;
pub use presrs_core::sample::{SampleChoice, SampleKind, Sampling};
use sha2::{Digest, Sha256};

use presrs_io::manifest::{Manifest, read_manifest};

use crate::error::{Error, Result};

mod options;
mod read;
mod rows;
mod stance_length;

use crate::progress::Progress;
pub use options::{GivenSampleSettings, SampleOptions, check_sample_settings};
use presrs_io::message::{Message, Warnings};
pub(crate) use read::apply_frame_period_option;
pub use read::{DeadSenselFills, MovieLoad, read_corrected, read_movie_loads};
use rows::is_no_sample_summary;
pub use rows::{LoadedSamples, StanceCuts, load_samples};
pub use stance_length::{MAX_STANCE_LENGTH_PER_LONGEST, check_stance_length, pad_stance_samples};

pub use presrs_core::Sample;

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

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]

    use super::*;
    use presrs_core::{Recording, SensorMeta};

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
