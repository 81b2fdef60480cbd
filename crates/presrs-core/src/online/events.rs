//! What the online classifier says: its events (decisions, failures, touchdowns and lift-offs), one
//! step's view of them, and its running counts.

use serde::{Deserialize, Serialize};

use super::early::EarlyDecision;
use crate::error::CoreError;
use crate::novelty::Novelty;
use crate::stance::causal::{Liftoff, Touchdown};

/// Whether a decision is the single sample frame, the fusion of several, or a whole stance.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DecisionKind {
    Single,
    Fused,
    /// A whole-stance model's decision on the stance's summary (see [`StanceDecision`]).
    Stance,
}

impl DecisionKind {
    /// Its name in the stream protocol and the ROS 2 message (as serde writes it).
    pub fn name(self) -> &'static str {
        match self {
            Self::Single => "single",
            Self::Fused => "fused",
            Self::Stance => "stance",
        }
    }
}

/// What a whole-stance decision waited for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DecidedAt {
    /// The stance's lift-off: the whole stance.
    Liftoff,
    /// Frame `K` after touchdown ([`OnlineParams::decide_at`](super::OnlineParams::decide_at)): the stance so far.
    Offset(usize),
    /// The model's stance length, reached before the lift-off: the stance's first `length` frames.
    Length(usize),
}

/// How a whole-stance model's decision was made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StanceDecision {
    pub decided_at: DecidedAt,
    /// The frame the decision waited for: the lift-off frame, touchdown + K, or the frame at which the
    /// stance was known to be longer than the model's length.
    pub waited_for: usize,
    /// The stance is longer than the model's length: its first `length` frames were used.
    pub cut: bool,
    /// With [`OnlineParams::decide_at`](super::OnlineParams::decide_at): which classifier decided and why then.
    pub early: Option<EarlyDecision>,
}

/// A classification of a stance. The posteriors are in [`Step::posteriors`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Decision {
    pub stance_id: u64,
    pub kind: DecisionKind,
    pub touchdown_frame: usize,
    /// The frame classified (single), or the last frame fused.
    pub sample_frame: usize,
    /// Frame whose arrival triggered the decision.
    pub frame: usize,
    /// Frames whose posteriors were averaged (1 for single); for a whole stance, the frames
    /// summarised.
    pub frames_used: usize,
    pub class: usize,
    pub confidence: f64,
    /// For a whole-stance decision ([`DecisionKind::Stance`]): what it waited for.
    pub stance: Option<StanceDecision>,
    /// How far the sample lies from every class, when the model scores novelty (for a fused decision:
    /// the mean score of the frames fused); `unknown` says it is none of them.
    pub novelty: Option<Novelty>,
    /// Index of this decision's posteriors in the step's posterior buffer.
    pub(super) slot: usize,
}

/// A frame the classifier was asked for but could not classify (e.g. its values are so large that its
/// features overflow). The reason is in [`Step::error`]; the stance goes on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Failure {
    pub stance_id: u64,
    /// The decision the frame was for: the single sample (which the stance then does not get), or one
    /// frame of the fusion (which goes on without it).
    pub kind: DecisionKind,
    /// The frame that could not be classified.
    pub sample_frame: usize,
    /// Frame whose arrival triggered the attempt.
    pub frame: usize,
    /// Index of the error in the step's error buffer.
    pub(super) slot: usize,
}

/// One output of [`OnlineClassifier::push`](super::OnlineClassifier::push).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum OnlineEvent {
    Touchdown(Touchdown),
    Decision(Decision),
    /// A frame to classify could not be: no decision from it (see [`Failure`]).
    Failed(Failure),
    Liftoff(Liftoff),
}

/// The events of one frame, borrowing the classifier's buffers.
#[derive(Clone, Copy, Debug)]
pub struct Step<'a> {
    pub events: &'a [OnlineEvent],
    pub(super) posteriors: &'a [f64],
    pub(super) errors: &'a [CoreError],
    pub(super) n_classes: usize,
}

impl<'a> Step<'a> {
    /// The posteriors of `decision` (one per class, class-index order).
    pub fn posteriors(&self, decision: &Decision) -> &'a [f64] {
        let start = decision.slot * self.n_classes;
        self.posteriors
            .get(start..start + self.n_classes)
            .unwrap_or(&[])
    }

    /// Why the frame of `failure` could not be classified.
    pub fn error(&self, failure: &Failure) -> Option<&'a CoreError> {
        self.errors.get(failure.slot)
    }
}

/// Counters of an [`OnlineClassifier`](super::OnlineClassifier).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct OnlineStats {
    pub frames: u64,
    pub stances: u64,
    pub decisions: u64,
    pub fused_decisions: u64,
    /// Frames refused (wrong grid, non-finite values).
    pub rejected_frames: u64,
}
