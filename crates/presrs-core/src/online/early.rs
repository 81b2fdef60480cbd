//! Early decisions of a whole-stance model online
//! ([`OnlineParams::decide_at`](crate::stance::causal::OnlineParams::decide_at)): the classifiers of the
//! decision points it was trained for ([`crate::pipeline::EarlyDecisions`]) and the refusal of a moment
//! it was not trained for, and what each decision says about why it was made when it was
//! ([`EarlyDecision`]). `auto`'s step (the first point whose confidence passes the threshold, else the
//! deadline point) is the online classifier's (`online/auto_step.rs`).

use crate::error::{CoreError, Result};
use crate::pipeline::{AutoRule, Session, TrainedModel};

use crate::stance::causal::DecideAt;

/// Why a decision made with [`OnlineParams::decide_at`](crate::stance::causal::OnlineParams::decide_at) was made when it was.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EarlyReason {
    /// `decide_at = K`: frame `touchdown + K` arrived.
    Fixed,
    /// `auto`: the point's confidence passed the threshold.
    Confident,
    /// `auto`: no point's confidence passed the threshold by the deadline point, which decided.
    Deadline,
    /// `auto`: no point's confidence passed the threshold before the lift-off (or the model's length).
    NotConfident,
    /// The stance ended (or reached the model's length) before the first point.
    EndedFirst,
}

impl EarlyReason {
    /// Its name in the stream protocol and the ROS 2 message (as serde writes it).
    pub fn name(self) -> &'static str {
        match self {
            Self::Fixed => "fixed",
            Self::Confident => "confident",
            Self::Deadline => "deadline",
            Self::NotConfident => "not_confident",
            Self::EndedFirst => "ended_first",
        }
    }
}

/// Which classifier decided, under which rule, and why then.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EarlyDecision {
    /// The `decide_at` in force.
    pub rule: DecideAt,
    pub reason: EarlyReason,
    /// The decision point whose classifier decided (frames after touchdown); `None`: the whole-stance
    /// classifier.
    pub point: Option<usize>,
    /// `auto`'s threshold.
    pub threshold: Option<f64>,
}

/// The classifiers of decision points in use, by their point (frames after touchdown), increasing.
pub(crate) type PointSessions<'m> = Vec<(usize, Session<'m>)>;

/// The classifiers `decide_at` uses on `model` (the point `K`, or every point for `auto`) and `auto`'s
/// rule; an error when the model was not trained for that moment.
pub(crate) fn points_for(
    model: &TrainedModel,
    decide_at: Option<DecideAt>,
) -> Result<(PointSessions<'_>, Option<AutoRule>)> {
    let Some(decide_at) = decide_at else {
        return Ok((Vec::new(), None));
    };
    if let Err(trained) = model.trained_for(decide_at) {
        return Err(CoreError::Param {
            name: "decide_at",
            reason: format!(
                "this model was not trained to decide at {decide_at}: it was trained for {trained}; \
                 train one for it (presrs train --decide-at {decide_at})"
            ),
        });
    }
    let Some(early) = model.early() else {
        return Ok((Vec::new(), None));
    };
    let sessions = early
        .points
        .iter()
        .filter(|point| decide_at.is_auto() || decide_at == DecideAt::Frames(point.frames))
        .map(|point| (point.frames, point.model.session()))
        .collect();
    let rule = decide_at
        .is_auto()
        .then(|| early.auto.map(|auto| auto.rule()))
        .flatten();
    Ok((sessions, rule))
}
