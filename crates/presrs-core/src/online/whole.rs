//! Whole-stance models online: the stance's summary columns kept as frames arrive, and the decision at
//! lift-off, at a decision point, at `auto`'s threshold or deadline, or when the stance outgrows the
//! model's length (the module documentation of [`super`]). Methods of [`OnlineClassifier`] kept apart
//! from `mod.rs`; the state they read is `whole_state.rs`'s.

use super::early::{EarlyDecision, EarlyReason};
use super::events::{DecidedAt, Decision, DecisionKind, Failure, OnlineEvent, StanceDecision};
use super::whole_state::WholeStance;
use super::{OnlineClassifier, Verdict};
use crate::error::Result;
use crate::frame::FrameView;
use crate::stance::causal::{DecideAt, Liftoff, SegEvent, SegEvents};

impl OnlineClassifier<'_> {
    /// A whole-stance model's step: the frame is kept (unless the stance under way already has the
    /// model's length of frames), touchdowns open a stance, lift-offs decide it, and so do frame K
    /// after touchdown and a stance found longer than the model's length. The detector's one-frame
    /// requests (sample, fusion) do not apply.
    pub(super) fn handle_whole(
        &mut self,
        events: SegEvents,
        frame: Option<&FrameView<'_>>,
        t: usize,
    ) {
        if let (Some(frame), Some(whole)) = (frame, self.whole.as_mut()) {
            let length = whole.buffer.length();
            if whole.open.is_none_or(|(_, start)| t < start + length) {
                whole.buffer.keep(t, frame);
            }
        }
        for event in events.iter() {
            match event {
                SegEvent::Touchdown(touchdown) => {
                    self.touchdown(touchdown);
                    if let Some(whole) = &mut self.whole
                        && !whole.report_only
                        && (!touchdown.partial || whole.decide_partial)
                    {
                        whole.open = Some((touchdown.stance_id, touchdown.touchdown_frame));
                        whole.next_point = 0;
                    }
                }
                SegEvent::Liftoff(liftoff) => {
                    self.decide_at_liftoff(&liftoff);
                    self.liftoff(liftoff);
                }
                SegEvent::HoldCurrent { .. }
                | SegEvent::ClassifySample { .. }
                | SegEvent::FuseCurrent { .. }
                | SegEvent::FusionReady { .. } => {}
            }
        }
        self.decide_before_liftoff(t);
    }

    /// The lift-off of the stance under way, not yet decided: decided on the whole stance (its first
    /// `length` frames if longer), unless it is partial (cut by the end of the stream).
    fn decide_at_liftoff(&mut self, liftoff: &Liftoff) {
        let Some(whole) = &mut self.whole else {
            return;
        };
        if whole.open.map(|(id, _)| id) != Some(liftoff.stance_id) {
            return;
        }
        whole.open = None;
        if liftoff.stance.partial && !whole.decide_partial {
            return;
        }
        let how = StanceDecision {
            decided_at: DecidedAt::Liftoff,
            waited_for: liftoff.frame,
            cut: liftoff.stance.len > whole.buffer.length(),
            early: whole.late_reason(),
        };
        self.decide_whole(
            liftoff.stance_id,
            liftoff.stance.start,
            liftoff.stance.len,
            how,
            liftoff.frame,
        );
    }

    /// The stance under way is decided before its lift-off at frame `touchdown + K` (with
    /// [`OnlineParams::decide_at`] `= K`, by the classifier of that point, or the whole-stance one
    /// when `K` reaches the model's length), at the first decision point whose confidence passes the
    /// threshold (`auto`), or once it is known to be longer than the model's length.
    fn decide_before_liftoff(&mut self, t: usize) {
        let Some(whole) = &self.whole else {
            return;
        };
        let Some((stance_id, start)) = whole.open else {
            return;
        };
        let length = whole.buffer.length();
        if let Some(DecideAt::Frames(k)) = whole.decide_at
            && t >= start + k
        {
            let point = whole.points.iter().position(|(frames, _)| *frames == k);
            let how = StanceDecision {
                decided_at: DecidedAt::Offset(k),
                waited_for: start + k,
                cut: k + 1 > length,
                early: Some(EarlyDecision {
                    rule: DecideAt::Frames(k),
                    reason: EarlyReason::Fixed,
                    point: point.map(|_| k),
                    threshold: None,
                }),
            };
            self.decide_whole_with(stance_id, start, k + 1, how, t, point);
            return;
        }
        if self.try_confident_point(stance_id, start, t) {
            return;
        }
        let longer = self
            .segmenter
            .open_stance()
            .is_some_and(|open| open.stance_id == stance_id && open.known_len > length);
        if longer {
            let early = self.whole.as_ref().and_then(WholeStance::late_reason);
            let how = StanceDecision {
                decided_at: DecidedAt::Length(length),
                waited_for: t,
                cut: true,
                early,
            };
            self.decide_whole(stance_id, start, length, how, t);
        }
    }

    /// Classifies the summary of `frames` frames from `start` (at most the model's length) at frame
    /// `t` with the whole-stance classifier: a [`DecisionKind::Stance`] decision, or a failure.
    fn decide_whole(
        &mut self,
        stance_id: u64,
        start: usize,
        frames: usize,
        how: StanceDecision,
        t: usize,
    ) {
        self.decide_whole_with(stance_id, start, frames, how, t, None);
    }

    /// [`Self::decide_whole`] with the classifier of decision point `point` (an index into the
    /// points in use), or the whole-stance one (`None`).
    fn decide_whole_with(
        &mut self,
        stance_id: u64,
        start: usize,
        frames: usize,
        how: StanceDecision,
        t: usize,
        point: Option<usize>,
    ) {
        let Some(whole) = self.whole.as_mut() else {
            return;
        };
        whole.open = None;
        let frames = frames.min(whole.buffer.length());
        // A decision point's classifier takes samples of its own length, K + 1 frames.
        let length = match point.and_then(|index| whole.points.get(index)) {
            Some((k, _)) => k + 1,
            None => whole.buffer.length(),
        };
        let session = match point.and_then(|index| whole.points.get_mut(index)) {
            Some((_, session)) => session,
            None => &mut self.session,
        };
        let outcome = whole
            .buffer
            .sample_in(start, frames, length)
            .and_then(|view| {
                session.classify(&view).map(|prediction| {
                    self.posteriors.extend_from_slice(prediction.posteriors);
                    (prediction.class, prediction.confidence, prediction.novelty)
                })
            });
        self.push_whole_decision(stance_id, start, frames, how, t, outcome);
    }

    /// The event of a whole-stance classification (or its failure).
    pub(super) fn push_whole_decision(
        &mut self,
        stance_id: u64,
        start: usize,
        frames: usize,
        how: StanceDecision,
        t: usize,
        outcome: Result<Verdict>,
    ) {
        let (class, confidence, novelty) = match outcome {
            Ok(result) => result,
            Err(err) => {
                let slot = self.keep_error(err);
                self.events.push(OnlineEvent::Failed(Failure {
                    stance_id,
                    kind: DecisionKind::Stance,
                    sample_frame: start,
                    frame: t,
                    slot,
                }));
                return;
            }
        };
        let slot = (self.posteriors.len() / self.n_classes.max(1)).saturating_sub(1);
        self.stats.decisions += 1;
        self.decided_stance = Some(stance_id);
        self.events.push(OnlineEvent::Decision(Decision {
            stance_id,
            kind: DecisionKind::Stance,
            touchdown_frame: start,
            sample_frame: start + frames.saturating_sub(1),
            frame: t,
            frames_used: frames,
            class,
            confidence,
            stance: Some(how),
            novelty,
            slot,
        }));
    }
}
