//! What the detector asks its user to do for each frame ([`SegEvent`]), and the fixed-capacity list
//! of one frame's events ([`SegEvents`]).

use crate::stance::offline::Stance;

/// A stance confirmed by the detector (enough frames, on level reached).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Touchdown {
    /// Stance number in this stream, from 0.
    pub stance_id: u64,
    /// First loaded frame.
    pub touchdown_frame: usize,
    /// Frame at which the stance was confirmed.
    pub frame: usize,
    /// The stance was already under way when detection began: it is not sampled.
    pub partial: bool,
}

/// A stance that ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Liftoff {
    pub stance_id: u64,
    /// The stance, as [`segment`](crate::stance::segment()) reports it.
    pub stance: Stance,
    /// Frame at which the end was decided (`max_gap_frames + 1` frames after the last loaded frame, or
    /// the last frame of the stream).
    pub frame: usize,
    /// Whether the stance got its (single-frame) decision. From [`CausalSegmenter`](crate::stance::CausalSegmenter), whether it asked
    /// for one; from [`OnlineClassifier`](crate::online::OnlineClassifier), whether a decision was made (false when the sample frame
    /// could not be classified, see [`OnlineEvent::Failed`](crate::online::OnlineEvent::Failed)); for a
    /// whole-stance model, whether the stance was decided.
    pub sampled: bool,
}

/// What the segmenter asks its user to do, in order, for one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SegEvent {
    Touchdown(Touchdown),
    /// Keep a copy of the current frame: it is the sample frame but cannot be decided yet.
    HoldCurrent {
        stance_id: u64,
    },
    /// Classify the sample frame `frame` of the stance: the current frame, or the held copy.
    ClassifySample {
        stance_id: u64,
        touchdown_frame: usize,
        frame: usize,
        held: bool,
    },
    /// Classify the current frame and add its posteriors to the stance's fusion.
    FuseCurrent {
        stance_id: u64,
    },
    /// The fusion of the stance is complete: decide.
    FusionReady {
        stance_id: u64,
        touchdown_frame: usize,
    },
    Liftoff(Liftoff),
}

/// At most this many [`SegEvent`]s come out of one frame.
pub(crate) const MAX_SEG_EVENTS: usize = 8;

/// A fixed-capacity list of the events of one frame (no allocation).
#[derive(Clone, Copy, Debug)]
pub struct SegEvents {
    items: [Option<SegEvent>; MAX_SEG_EVENTS],
    len: usize,
}

impl SegEvents {
    pub(super) const EMPTY: Self = Self {
        items: [None; MAX_SEG_EVENTS],
        len: 0,
    };

    pub(super) fn push(&mut self, event: SegEvent) {
        // Capacity: per frame at most liftoff + fusion of a closing stance, then touchdown, hold, sample,
        // fuse and fusion-ready of the current one (7).
        if let Some(slot) = self.items.get_mut(self.len) {
            *slot = Some(event);
            self.len += 1;
        }
    }

    pub fn iter(&self) -> impl Iterator<Item = SegEvent> + '_ {
        self.items[..self.len].iter().flatten().copied()
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    pub fn len(&self) -> usize {
        self.len
    }
}
