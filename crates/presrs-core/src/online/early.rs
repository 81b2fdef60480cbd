//! Early decisions of a whole-stance model online ([`OnlineParams::decide_at`](super::OnlineParams::decide_at)): the classifiers of the
//! decision points it was trained for ([`crate::pipeline::EarlyDecisions`]), the refusal of a moment it
//! was not trained for, `auto`'s step (the first point whose confidence passes the threshold), and what
//! each decision says about why it was made when it was ([`EarlyDecision`]).

use crate::error::{CoreError, Result};
use crate::pipeline::{Session, TrainedModel};

use super::{
    DecideAt, DecidedAt, DecisionKind, Failure, OnlineClassifier, OnlineEvent, StanceDecision,
    WholeStance,
};

/// Why a decision made with [`OnlineParams::decide_at`](super::OnlineParams::decide_at) was made when it was.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EarlyReason {
    /// `decide_at = K`: frame `touchdown + K` arrived.
    Fixed,
    /// `auto`: the point's confidence passed the threshold.
    Confident,
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

/// The classifiers `decide_at` uses on `model` (the point `K`, or every point for `auto`) and `auto`'s
/// threshold; an error when the model was not trained for that moment.
pub(super) fn points_for(
    model: &TrainedModel,
    decide_at: Option<DecideAt>,
) -> Result<(Vec<(usize, Session<'_>)>, Option<f64>)> {
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
    let threshold = decide_at
        .is_auto()
        .then(|| early.auto.map(|auto| auto.threshold))
        .flatten();
    Ok((sessions, threshold))
}

impl WholeStance<'_> {
    /// What a decision at the lift-off (or the model's length) says under `decide_at`: the stance
    /// ended before the first point, or (`auto`) no point was confident enough.
    pub(super) fn late_reason(&self) -> Option<EarlyDecision> {
        let rule = self.decide_at?;
        let reason = if rule.is_auto() && self.next_point > 0 {
            EarlyReason::NotConfident
        } else {
            EarlyReason::EndedFirst
        };
        Some(EarlyDecision {
            rule,
            reason,
            point: None,
            threshold: self.threshold,
        })
    }
}

impl OnlineClassifier<'_> {
    /// With `auto`, the points reached by frame `t` of the stance from `start` are tried in order: the
    /// first whose confidence is at least the threshold decides. Whether the stance was decided.
    pub(super) fn try_confident_point(&mut self, stance_id: u64, start: usize, t: usize) -> bool {
        let Some(whole) = self.whole.as_mut() else {
            return false;
        };
        let (Some(rule), Some(threshold)) = (whole.decide_at, whole.threshold) else {
            return false;
        };
        while let Some((k, session)) = whole.points.get_mut(whole.next_point)
            && t >= start + *k
        {
            let k = *k;
            whole.next_point += 1;
            let posteriors = &mut self.posteriors;
            let outcome = whole
                .buffer
                .sample_in(start, k + 1, k + 1)
                .and_then(|view| {
                    session.classify(&view).map(|p| {
                        if p.confidence >= threshold {
                            posteriors.extend_from_slice(p.posteriors);
                        }
                        (p.class, p.confidence)
                    })
                });
            let how = StanceDecision {
                decided_at: DecidedAt::Offset(k),
                waited_for: start + k,
                cut: false,
                early: Some(EarlyDecision {
                    rule,
                    reason: EarlyReason::Confident,
                    point: Some(k),
                    threshold: Some(threshold),
                }),
            };
            match outcome {
                Ok((_, confidence)) if confidence < threshold => {}
                Ok(decided) => {
                    whole.open = None;
                    self.push_whole_decision(stance_id, start, k + 1, how, t, Ok(decided));
                    return true;
                }
                Err(err) => {
                    let slot = self.keep_error(err);
                    self.events.push(OnlineEvent::Failed(Failure {
                        stance_id,
                        kind: DecisionKind::Stance,
                        sample_frame: start + k,
                        frame: t,
                        slot,
                    }));
                    return false;
                }
            }
        }
        false
    }
}
