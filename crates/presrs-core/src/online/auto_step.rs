//! `auto`'s step of a whole-stance model online: at each decision point the stance has reached, the
//! point's classifier decides if its confidence passes the threshold learned at training, or if the
//! point is the deadline learned with it; and what a decision made later (at the lift-off or the
//! model's length) says about why. Methods of
//! [`OnlineClassifier`] kept apart from `mod.rs` and `whole.rs`, which hold the rest of its step.

use super::{
    DecidedAt, DecisionKind, EarlyDecision, EarlyReason, Failure, OnlineClassifier, OnlineEvent,
    StanceDecision, WholeStance,
};

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
            threshold: self.auto.map(|rule| rule.threshold),
        })
    }
}

impl OnlineClassifier<'_> {
    /// With `auto`, the points reached by frame `t` of the stance from `start` are tried in order: the
    /// first whose confidence is at least the threshold decides, else the deadline point. Whether the
    /// stance was decided.
    pub(super) fn try_confident_point(&mut self, stance_id: u64, start: usize, t: usize) -> bool {
        let Some(whole) = self.whole.as_mut() else {
            return false;
        };
        let (Some(rule), Some(auto)) = (whole.decide_at, whole.auto) else {
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
                        if auto.decides(k, p.confidence) {
                            posteriors.extend_from_slice(p.posteriors);
                        }
                        (p.class, p.confidence, p.novelty)
                    })
                });
            match outcome {
                Ok((_, confidence, _)) if !auto.decides(k, confidence) => {}
                Ok(decided) => {
                    let reason = if decided.1 >= auto.threshold {
                        EarlyReason::Confident
                    } else {
                        EarlyReason::Deadline
                    };
                    let how = StanceDecision {
                        decided_at: DecidedAt::Offset(k),
                        waited_for: start + k,
                        cut: false,
                        early: Some(EarlyDecision {
                            rule,
                            reason,
                            point: Some(k),
                            threshold: Some(auto.threshold),
                        }),
                    };
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
