//! What one stream connection did: the counts its `end` event reports.

use presrs_core::online::OnlineStats;

/// What a connection did.
#[derive(Clone, Copy, Debug, Default)]
pub struct ConnectionSummary {
    /// The classifier's counters; its `rejected_frames` counts only the frames it refused itself.
    pub stats: OnlineStats,
    /// Every frame that came and was not used: unreadable (skipped by the reader), of a size the model
    /// cannot use, or refused by the classifier (another size than the first frame, non-finite values).
    /// Each is also an error.
    pub rejected_frames: u64,
    /// Error events: the rejected frames, classifications that failed and a fatal fault.
    pub errors: u64,
    pub dropped_events: u64,
    /// The input could not go on (bad magic, a frame over the size cap, cut inside a frame, no header).
    pub fatal: bool,
    /// Frames the warm-up calibration used (0 with a calibration given); stances in them were not
    /// classified.
    pub warmup_frames: u64,
    /// The input ended during the warm-up calibration: no stance was classified.
    pub warmup_unfinished: bool,
}

impl ConnectionSummary {
    /// Why the connection made no decision, when that is not the input's fault: the input ended during
    /// the warm-up calibration. The `end` line carries it to the client as `note`.
    pub fn note(&self) -> Option<String> {
        self.warmup_unfinished.then(|| {
            format!(
                "the stream ended during the warm-up calibration ({} frames): no stance was \
                 classified; a calibration (presrs stream --calibrate MANIFEST or --profile, or a \
                 model trained with --online-profile) classifies from the first frame",
                self.warmup_frames
            )
        })
    }

    /// Whether anything went wrong in the connection (a rejected frame or an error).
    pub fn had_errors(&self) -> bool {
        self.errors > 0 || self.rejected_frames > 0 || self.fatal
    }
}
