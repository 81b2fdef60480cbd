//! Online classification of a live frame stream: the causal stance detector
//! ([`crate::stance::causal`]) decides when a stance starts and which frames to classify, a [`Session`]
//! classifies them.
//!
//! **The sample frame** is chosen without the future: the `k`-th frame after touchdown
//! ([`OnlineParams::sample_offset`]). The paper samples the mid-stance frame `(len - 1) / 2`, which
//! depends on the lift-off still to come; [`sample_offset_for`] learns `k = (L - 1) / 2` from the
//! training data's median stance length `L`, so that on a typical stance the online sample *is* the
//! paper's (offline) mid-stance frame. If frame `k` is not decidable when it arrives (the stance is not
//! yet confirmed, or frame `k` is a dropout inside the stance) the classifier keeps a copy of it and
//! decides as soon as it is; if the stance ends before frame `k`, it is not sampled.
//!
//! **Fusion** ([`OnlineParams::fusion_offsets`], optional): the loaded frames at these offsets after
//! touchdown are classified as they arrive and their posteriors averaged; the fused decision is a
//! separate event, emitted once the last offset has passed (or at lift-off, over the frames seen).
//!
//! **Whole-stance models** (trained on stance samples, [`SampleKind::Stance`]) classify a stance's
//! summary, not a frame: the classifier keeps each frame's summary column as it arrives
//! ([`StanceBuffer`], a ring of the model's stance length) and decides, with a
//! [`DecisionKind::Stance`] decision that says what it waited for ([`StanceDecision`]):
//! - at the stance's lift-off, on the whole stance, zero-padded to the model's length: the offline
//!   classification of the same stance (`classify`), to the bit when the detector finds the same
//!   touchdown and lift-off;
//! - or, with [`OnlineParams::decide_at`] `= K`, at frame `touchdown + K`, on the stance so far (its
//!   `K + 1` frames, zero-padded as offline padding does; if the lift-off comes first, at the lift-off)
//!   by the classifier the model holds for that point ([`crate::pipeline::EarlyDecisions`]: trained
//!   on stances cut there), or by the whole-stance one when `K` reaches the model's length;
//! - or, with `auto`, at the first of the model's decision points whose confidence passes the
//!   threshold learned at training, else at its deadline point, else at the lift-off, whole. A moment
//!   the model was not trained for is refused ([`TrainedModel::trained_for`]); each decision says why
//!   it was made then ([`EarlyDecision`]);
//! - a stance found longer than the model's length before its lift-off is decided then, on its first
//!   `length` frames (`cut`), as offline cuts it; their `area` channel counts contact against the
//!   highest sensel of those frames, where offline it is the whole stance's.
//!
//! Partial stances are not decided (in the one-contact mode the stream is one partial stance: it is,
//! at the end of the stream). The detector's one-frame settings do not apply: `sample_offset` is
//! ignored and fusion offsets are an error; `decide_at` on a one-frame model is an error.
//!
//! [`OnlineClassifier`] puts the segmenter and a [`Session`] together: one frame in, zero or more
//! [`OnlineEvent`]s out, with all buffers allocated up front (no allocation per frame in steady state).

use crate::error::{CoreError, Result};
use crate::frame::{FrameView, Grid};
use crate::novelty::Novelty;
use crate::pipeline::{Session, TrainedModel};
use crate::sample::SampleKind;
use crate::stance::ValidSegmentParams;
use crate::stance::causal::MAX_SEG_EVENTS;
// The causal detector's types, which this module's API speaks in, nameable from here as before they
// moved beside the offline segmentation.
pub use crate::stance::causal::{
    AutoWord, Calibration, CausalSegmenter, DecideAt, Levels, Liftoff, MAX_FUSION_FRAMES,
    MAX_OFFSET_FRAMES, MIN_QUIET_FRAMES, OnlineParams, OpenStance, PAPER_SAMPLE_OFFSET,
    RANGE_PRIOR_FRACTION, SegEvent, SegEvents, Touchdown, sample_offset_for, typical_stance_frames,
};
pub use profile::OnlineProfile;
pub use stance_buffer::StanceBuffer;

mod auto_step;
mod early;
mod events;
mod profile;
mod stance_buffer;
mod whole;
mod whole_state;

pub use early::{EarlyDecision, EarlyReason};
pub use events::{
    DecidedAt, Decision, DecisionKind, Failure, OnlineEvent, OnlineStats, StanceDecision, Step,
};
use whole_state::WholeStance;

/// What classifying one sample gives: its class, confidence and novelty.
type Verdict = (usize, f64, Option<Novelty>);

/// Causal segmentation + classification of a frame stream with one model (see the module docs).
#[derive(Debug)]
pub struct OnlineClassifier<'m> {
    session: Session<'m>,
    segmenter: CausalSegmenter,
    grid: Option<Grid>,
    held: Vec<f64>,
    held_present: Vec<bool>,
    held_has_mask: bool,
    held_valid: bool,
    fusion_sum: Vec<f64>,
    fusion_frames: usize,
    /// The sum of the fused frames' novelty scores and the threshold, when the model scores novelty.
    fusion_novelty: Option<(f64, f64)>,
    fusion_last: usize,
    /// The current frame's classification, once made in this push (the sample frame is usually also a
    /// fusion frame: it is classified once, not twice); `Err` holds the index of its error in `errors`.
    current: Option<std::result::Result<Verdict, usize>>,
    current_posteriors: Vec<f64>,
    /// The last stance that got its single decision (for [`Liftoff::sampled`]).
    decided_stance: Option<u64>,
    n_classes: usize,
    events: Vec<OnlineEvent>,
    posteriors: Vec<f64>,
    /// Why the frames of this step's [`Failure`]s could not be classified (empty unless one failed).
    errors: Vec<CoreError>,
    stats: OnlineStats,
    /// A whole-stance model's state (`None` for a one-frame model).
    whole: Option<WholeStance<'m>>,
}

/// What a one-frame or series model takes as a stream's frames, in words.
fn expected_stream_frame(model: &TrainedModel) -> String {
    let takes = format!(
        "a grid that the model's crop {} turns into its {} image",
        model.crop(),
        model.image_grid()
    );
    match model.sample() {
        SampleKind::Series { .. } => format!(
            "{takes} (this model classifies series, channels x time, one 2-D array per sample: it \
             was trained on series, not on a sensor's frames)"
        ),
        SampleKind::Frame | SampleKind::Stance { .. } => takes,
    }
}

impl<'m> OnlineClassifier<'m> {
    pub fn new(
        model: &'m TrainedModel,
        params: &ValidSegmentParams,
        online: &OnlineParams,
        calibration: Option<Calibration>,
    ) -> Result<Self> {
        let n_classes = model.class_names().len();
        let whole = WholeStance::for_model(model, params, online)?;
        Ok(Self {
            whole,
            session: model.session(),
            segmenter: CausalSegmenter::new(params, online, calibration)?,
            grid: None,
            held: Vec::new(),
            held_present: Vec::new(),
            held_has_mask: false,
            held_valid: false,
            fusion_sum: vec![0.0; n_classes],
            fusion_frames: 0,
            fusion_novelty: None,
            fusion_last: 0,
            current: None,
            current_posteriors: vec![0.0; n_classes],
            decided_stance: None,
            n_classes,
            events: Vec::with_capacity(MAX_SEG_EVENTS),
            posteriors: Vec::with_capacity(MAX_SEG_EVENTS * n_classes),
            errors: Vec::new(),
            stats: OnlineStats::default(),
        })
    }

    pub fn segmenter(&self) -> &CausalSegmenter {
        &self.segmenter
    }

    pub fn model(&self) -> &'m TrainedModel {
        self.session.model()
    }

    pub fn stats(&self) -> OnlineStats {
        self.stats
    }

    /// The grid every frame must have (set by the first frame).
    pub fn grid(&self) -> Option<Grid> {
        self.grid
    }

    /// Judges the next frame. A frame of another grid than the first one, a first frame whose grid the
    /// model cannot classify (its crop does not give the model's image), or a frame with a non-finite
    /// total load is an error and is not counted; the stream can go on. A counted frame whose
    /// classification fails (its values overflow the features) still gives its touchdown and lift-off
    /// events, with an [`OnlineEvent::Failed`] in place of the decision.
    pub fn push(&mut self, frame: &FrameView<'_>) -> Result<Step<'_>> {
        self.events.clear();
        self.posteriors.clear();
        self.errors.clear();
        let grid = frame.grid();
        match self.grid {
            None if self.whole.is_some() => {
                if let Some(whole) = &mut self.whole
                    && let Err(err) = self
                        .session
                        .model()
                        .check_sensor(grid)
                        .and_then(|()| whole.buffer.set_grid(grid))
                {
                    self.stats.rejected_frames += 1;
                    return Err(err);
                }
                self.grid = Some(grid);
            }
            None => {
                let model = self.session.model();
                if model.crop().output_grid(grid).ok() != Some(model.image_grid()) {
                    self.stats.rejected_frames += 1;
                    return Err(CoreError::Shape {
                        what: "stream frame",
                        expected: expected_stream_frame(model),
                        got: grid.to_string(),
                    });
                }
                self.grid = Some(grid);
                self.held = vec![0.0; grid.len()];
                self.held_present = vec![true; grid.len()];
            }
            Some(expected) if expected != grid => {
                self.stats.rejected_frames += 1;
                return Err(CoreError::Shape {
                    what: "stream frame",
                    expected: format!("a {expected} frame (the stream's first frame)"),
                    got: grid.to_string(),
                });
            }
            Some(_) => {}
        }
        let total = frame.total();
        let seg_events = match self.segmenter.push(total) {
            Ok(events) => events,
            Err(err) => {
                self.stats.rejected_frames += 1;
                return Err(err);
            }
        };
        self.stats.frames += 1;
        let t = self.segmenter.frames_seen() - 1;
        self.handle(seg_events, Some(frame), t);
        Ok(self.step())
    }

    /// The stream ended: closes the open stance.
    pub fn finish(&mut self) -> Result<Step<'_>> {
        self.events.clear();
        self.posteriors.clear();
        self.errors.clear();
        // A stream that ends in the warm-up has its stances found at the end, their frames past: they
        // are reported, not decided (as the one-frame path does).
        if self.segmenter.warming_up()
            && let Some(whole) = &mut self.whole
        {
            whole.report_only = true;
        }
        let seg_events = self.segmenter.finish()?;
        let t = self.segmenter.frames_seen().saturating_sub(1);
        self.handle(seg_events, None, t);
        Ok(self.step())
    }

    fn step(&self) -> Step<'_> {
        Step {
            events: &self.events,
            posteriors: &self.posteriors,
            errors: &self.errors,
            n_classes: self.n_classes,
        }
    }

    /// Keeps `err` for this step; its index in the error buffer.
    fn keep_error(&mut self, err: CoreError) -> usize {
        self.errors.push(err);
        self.errors.len() - 1
    }

    /// Classifies the current frame once per push; later requests reuse the result (or the failure:
    /// the index of its error).
    fn classify_current(&mut self, frame: &FrameView<'_>) -> std::result::Result<Verdict, usize> {
        if let Some(result) = self.current {
            return result;
        }
        let result = match self.session.classify(frame) {
            Ok(prediction) => {
                self.current_posteriors
                    .copy_from_slice(prediction.posteriors);
                Ok((prediction.class, prediction.confidence, prediction.novelty))
            }
            Err(err) => Err(self.keep_error(err)),
        };
        self.current = Some(result);
        result
    }

    /// Classifies the held copy of the sample frame (once: the copy is then released).
    fn classify_held(
        &mut self,
        stance_id: u64,
        sample_frame: usize,
    ) -> std::result::Result<Verdict, usize> {
        if !self.held_valid {
            return Err(self.keep_error(CoreError::NotEnoughData(format!(
                "stance {stance_id}: no copy of its sample frame {sample_frame} was kept"
            ))));
        }
        self.held_valid = false;
        let mask = self.held_has_mask.then_some(self.held_present.as_slice());
        let grid = self.grid.unwrap_or(Grid::new(0, 0));
        let outcome = FrameView::new(grid, &self.held, mask).and_then(|view| {
            self.session.classify(&view).map(|prediction| {
                self.posteriors.extend_from_slice(prediction.posteriors);
                (prediction.class, prediction.confidence, prediction.novelty)
            })
        });
        outcome.map_err(|err| self.keep_error(err))
    }

    /// Turns the segmenter's requests for one frame into events. Never fails: a frame that cannot be
    /// classified gives an [`OnlineEvent::Failed`], and the other events of the frame are kept.
    fn handle(&mut self, events: SegEvents, frame: Option<&FrameView<'_>>, t: usize) {
        self.current = None;
        if self.whole.is_some() {
            self.handle_whole(events, frame, t);
            return;
        }
        for event in events.iter() {
            match event {
                SegEvent::Touchdown(touchdown) => self.touchdown(touchdown),
                SegEvent::HoldCurrent { .. } => self.hold(frame),
                SegEvent::ClassifySample {
                    stance_id,
                    touchdown_frame,
                    frame: sample_frame,
                    held,
                } => self.decide_sample(stance_id, touchdown_frame, sample_frame, held, frame, t),
                SegEvent::FuseCurrent { stance_id } => self.fuse(stance_id, frame, t),
                SegEvent::FusionReady {
                    stance_id,
                    touchdown_frame,
                } => self.decide_fused(stance_id, touchdown_frame, t),
                SegEvent::Liftoff(liftoff) => self.liftoff(liftoff),
            }
        }
    }

    /// A stance began: its fusion starts empty.
    fn touchdown(&mut self, touchdown: Touchdown) {
        self.stats.stances += 1;
        self.fusion_sum.fill(0.0);
        self.fusion_frames = 0;
        self.fusion_novelty = None;
        self.events.push(OnlineEvent::Touchdown(touchdown));
    }

    /// Keeps a copy of the current frame (none at the end of the stream), to be classified later.
    fn hold(&mut self, frame: Option<&FrameView<'_>>) {
        if let Some(frame) = frame {
            self.held.copy_from_slice(frame.values());
            self.held_has_mask = frame.present().is_some();
            if let Some(mask) = frame.present() {
                self.held_present.copy_from_slice(mask);
            }
            self.held_valid = true;
        }
    }

    /// The single decision of a stance on its sample frame: the held copy, or the current frame (none
    /// at the end of the stream: no decision); a failure if it cannot be classified.
    fn decide_sample(
        &mut self,
        stance_id: u64,
        touchdown_frame: usize,
        sample_frame: usize,
        held: bool,
        frame: Option<&FrameView<'_>>,
        t: usize,
    ) {
        let outcome = if held {
            self.classify_held(stance_id, sample_frame)
        } else {
            let Some(frame) = frame else {
                return;
            };
            let outcome = self.classify_current(frame);
            if outcome.is_ok() {
                self.posteriors.extend_from_slice(&self.current_posteriors);
            }
            outcome
        };
        let (class, confidence, novelty) = match outcome {
            Ok(result) => result,
            Err(slot) => {
                self.events.push(OnlineEvent::Failed(Failure {
                    stance_id,
                    kind: DecisionKind::Single,
                    sample_frame,
                    frame: t,
                    slot,
                }));
                return;
            }
        };
        let slot = (self.posteriors.len() / self.n_classes.max(1)).saturating_sub(1);
        let decision = Decision {
            stance_id,
            kind: DecisionKind::Single,
            touchdown_frame,
            sample_frame,
            frame: t,
            frames_used: 1,
            class,
            confidence,
            stance: None,
            novelty,
            slot,
        };
        self.stats.decisions += 1;
        self.decided_stance = Some(stance_id);
        self.events.push(OnlineEvent::Decision(decision));
    }

    /// Adds the current frame's posteriors (none at the end of the stream) to the stance's fusion; a
    /// failure if it cannot be classified.
    fn fuse(&mut self, stance_id: u64, frame: Option<&FrameView<'_>>, t: usize) {
        if let Some(frame) = frame {
            match self.classify_current(frame) {
                Ok((_, _, novelty)) => {
                    if let Some(novelty) = novelty {
                        let (sum, _) = self.fusion_novelty.get_or_insert((0.0, novelty.threshold));
                        *sum += novelty.score;
                    }
                    for (sum, p) in self.fusion_sum.iter_mut().zip(&self.current_posteriors) {
                        *sum += p;
                    }
                    self.fusion_frames += 1;
                    self.fusion_last = t;
                }
                Err(slot) => self.events.push(OnlineEvent::Failed(Failure {
                    stance_id,
                    kind: DecisionKind::Fused,
                    sample_frame: t,
                    frame: t,
                    slot,
                })),
            }
        }
    }

    /// The fused decision of a stance: the mean of the posteriors fused (none if no frame was).
    fn decide_fused(&mut self, stance_id: u64, touchdown_frame: usize, t: usize) {
        if self.fusion_frames == 0 {
            return;
        }
        let slot = self.posteriors.len() / self.n_classes.max(1);
        let count = self.fusion_frames as f64;
        let start = self.posteriors.len();
        self.posteriors
            .extend(self.fusion_sum.iter().map(|sum| sum / count));
        let fused = &self.posteriors[start..];
        let (class, confidence) =
            fused
                .iter()
                .copied()
                .enumerate()
                .fold((0, f64::NEG_INFINITY), |best, (class, p)| {
                    if p > best.1 { (class, p) } else { best }
                });
        // The mean of the fused frames' scores, with its credibility; the confidence capped by it.
        let scorer = self.session.model().novelty();
        let novelty = self.fusion_novelty.map(|(sum, threshold)| match scorer {
            Some(scorer) => scorer.verdict(sum / count),
            None => Novelty::of(sum / count, threshold),
        });
        let confidence = novelty.map_or(confidence, |n| n.capped(confidence));
        self.events.push(OnlineEvent::Decision(Decision {
            stance_id,
            kind: DecisionKind::Fused,
            touchdown_frame,
            sample_frame: self.fusion_last,
            frame: t,
            frames_used: self.fusion_frames,
            class,
            confidence,
            stance: None,
            novelty,
            slot,
        }));
        self.stats.fused_decisions += 1;
        self.fusion_sum.fill(0.0);
        self.fusion_frames = 0;
        self.fusion_novelty = None;
    }

    /// A stance ended: the held copy is released, and the lift-off says whether it was decided.
    fn liftoff(&mut self, mut liftoff: Liftoff) {
        self.held_valid = false;
        let decided = self.decided_stance == Some(liftoff.stance_id);
        if self.whole.is_some() {
            liftoff.sampled = decided;
        } else {
            liftoff.sampled &= decided;
        }
        self.events.push(OnlineEvent::Liftoff(liftoff));
    }
}
