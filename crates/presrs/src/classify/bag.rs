//! `presrs classify --mcap OUT.mcap`: the classified recordings as one ROS 2 bag — their frames on
//! [`FRAMES_TOPIC`](presrs_io::mcap::FRAMES_TOPIC) and, on [`DECISIONS_TOPIC`](presrs_io::mcap::DECISIONS_TOPIC), each stance's `touchdown` and `liftoff` and each sample's
//! `classification` (file, frame, label, confidence, posteriors, gait), stamped with their frames.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use presrs_core::stance::segment_recording;
use presrs_io::mcap::ImageEncoding;
use serde_json::json;

use crate::classify::{Classified, ClassifyOptions};
use crate::dataset::{apply_frame_period_option, read_corrected};
use crate::error::{Error, Result};
use presrs_io::mcap::DecisionBag;

/// A bag of classified recordings being written; it appears under its name at [`Self::finish`].
pub struct ClassifyBag {
    bag: DecisionBag,
    /// Where the next recording starts, ns (recordings follow each other, one period apart).
    next_ns: u64,
    recordings: usize,
}

impl std::fmt::Debug for ClassifyBag {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ClassifyBag")
            .field("path", &self.bag.path())
            .field("recordings", &self.recordings)
            .finish_non_exhaustive()
    }
}

impl ClassifyBag {
    /// Starts the bag at `path` (a hidden temporary file beside it until [`Self::finish`]).
    pub fn create(path: &Path) -> Result<Self> {
        Ok(Self {
            bag: DecisionBag::create(path)?,
            next_ns: 0,
            recordings: 0,
        })
    }

    /// Adds one classified recording: its frames (read again as `options` say), its stances (found as
    /// classify finds them) and `results` (what classify gave for it), with `gait_table`'s gait per
    /// label when there is one.
    pub fn add(
        &mut self,
        path: &Path,
        options: &ClassifyOptions,
        results: &[Classified],
        gait_table: Option<&BTreeMap<String, String>>,
    ) -> Result<()> {
        let samples = &options.samples;
        let (parsed, _) = read_corrected(path, &samples.read, samples.dead_sensels.as_ref())?;
        let mut recording = parsed.recording;
        apply_frame_period_option(&mut recording, samples.frame_period_s)?;
        let file = path.display().to_string();
        let segmentation = segment_recording(&recording, &samples.segment_params())
            .map_err(|err| Error::data(format!("{file}: cannot segment: {err}")))?;
        // The events at each frame, in the order a stream would say them.
        let mut events: BTreeMap<usize, Vec<String>> = BTreeMap::new();
        for (id, stance) in segmentation.stances.iter().enumerate() {
            let touchdown = json!({"event": "touchdown", "file": file, "stance": id,
                "touchdown_frame": stance.start, "frame": stance.start, "partial": stance.partial});
            events
                .entry(stance.start)
                .or_default()
                .push(touchdown.to_string());
        }
        for result in results {
            let stance = segmentation
                .stances
                .iter()
                .position(|s| (s.start..s.start + s.len).contains(&result.frame));
            let gait = gait_table.and_then(|table| table.get(&result.label));
            let mut line = json!({"event": "classification", "kind": "offline", "file": file,
                "stance": stance, "frame": result.frame, "sample_frame": result.frame,
                "label": result.label, "confidence": result.confidence,
                "posteriors": result.posteriors, "gait": gait});
            if let (Some(novelty), Some(fields)) = (&result.novelty, line.as_object_mut()) {
                fields.insert("unknown".into(), json!(novelty.unknown));
                fields.insert("nearest".into(), json!(novelty.nearest));
                fields.insert("novelty".into(), json!(novelty.novelty));
                fields.insert("novelty_threshold".into(), json!(novelty.novelty_threshold));
                if let Some(credibility) = novelty.credibility {
                    fields.insert("credibility".into(), json!(credibility));
                }
            }
            events
                .entry(result.frame)
                .or_default()
                .push(line.to_string());
        }
        for (id, stance) in segmentation.stances.iter().enumerate() {
            let end = stance.start + stance.len - 1;
            let liftoff = json!({"event": "liftoff", "file": file, "stance": id,
                "touchdown_frame": stance.start, "end_frame": end, "len": stance.len,
                "peak_frame": stance.peak_frame, "peak_load": stance.peak_load,
                "partial": stance.partial, "frame": end});
            events.entry(end).or_default().push(liftoff.to_string());
        }
        let period_ns = (recording.frame_period_s().unwrap_or(1.0) * 1e9).round() as u64;
        let start = self.next_ns;
        let time = |index: usize| start + index as u64 * period_ns;
        for (index, frame) in recording.frames().enumerate() {
            let values = frame.values();
            let encoding = ImageEncoding::for_values(values.iter());
            self.bag
                .write_image(time(index), recording.grid(), values, encoding)?;
            for line in events.remove(&index).unwrap_or_default() {
                self.bag.write_json(time(index), &line)?;
            }
        }
        self.next_ns = time(recording.frame_count());
        self.recordings += 1;
        Ok(())
    }

    /// Ends the bag and renames it into place; returns its path.
    pub fn finish(self) -> Result<PathBuf> {
        Ok(self.bag.finish()?)
    }
}
