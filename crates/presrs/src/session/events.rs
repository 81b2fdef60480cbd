//! The events of a session as types: what every face receives (`docs/stream-protocol.md`, "Server ->
//! client"). Their JSON, through serde, is the protocol's line; a face that builds messages of its own
//! (the ROS 2 node, the live view, Python) reads the fields, never the line.

use presrs_core::novelty::UNKNOWN_LABEL;
use presrs_core::online::{
    DecidedAt, Decision, DecisionKind, EarlyReason, OnlineEvent, OnlineProfile, Step,
};
use presrs_core::pipeline::TrainedModel;
use serde::ser::SerializeMap;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::summary::ConnectionSummary;

/// One event of a session, tagged by `"event"` in its JSON line.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "event", rename_all = "snake_case")]
pub enum SessionEvent {
    Touchdown(Touchdown),
    Classification(Classification),
    Liftoff(Liftoff),
    Error(ErrorEvent),
    End(End),
}

/// A stance began.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Touchdown {
    pub stance: u64,
    pub touchdown_frame: u64,
    /// The frame at which the stance was confirmed.
    pub frame: u64,
    /// The stance was under way when detection began: it is not sampled.
    pub partial: bool,
}

/// A terrain decision.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Classification {
    /// `single` (the k-th frame after touchdown), `fused` (several frames' posteriors averaged) or
    /// `stance` (a whole-stance model's decision on the stance's summary).
    pub kind: DecisionKind,
    pub stance: u64,
    pub label: String,
    /// The label's index in the model's classes.
    pub class: usize,
    pub confidence: f64,
    /// Every class's posterior, in the model's class order.
    pub posteriors: Posteriors,
    /// The frame classified (the last one fused or summarised).
    pub sample_frame: u64,
    /// The frame whose arrival triggered the decision.
    pub frame: u64,
    pub frames_used: u64,
    pub touchdown_frame: u64,
    /// From the triggering frame's arrival to the decision, µs (to 0.1 µs).
    pub latency_us: f64,
    /// The triggering frame's time, when the input gives frame times.
    pub timestamp_us: Option<u64>,
    /// The recommended gait (the profile's terrain-to-gait table), if it names one.
    pub gait: Option<String>,
    /// What a whole-stance decision waited for (absent for one-frame and fused decisions).
    #[serde(flatten, default, skip_serializing_if = "Option::is_none")]
    pub whole_stance: Option<WholeStance>,
    /// Why a decision asked for before lift-off (`decide_at`) was made when it was (absent without
    /// `decide_at`).
    #[serde(flatten, default, skip_serializing_if = "Option::is_none")]
    pub early: Option<EarlyDecisionEvent>,
    /// Frames missing inside the stance up to the sample frame (a step in the input's frame times
    /// well above the frame period: `session::FrameGaps`): the decision was made without them.
    /// Absent from the line when 0 (none missing, or an input without frame times).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub gap_frames: u64,
    /// The novelty score and its verdict, when the model scores novelty (absent otherwise, and with
    /// `--novelty off`); when `unknown`, `label` is `unknown` and `nearest` names the nearest class.
    #[serde(flatten, default, skip_serializing_if = "Option::is_none")]
    /// Boxed: the event stays small without a score (clippy's large_enum_variant).
    pub novelty: Option<Box<NoveltyVerdict>>,
}

/// Whether a count is 0 (left out of the line).
fn is_zero(count: &u64) -> bool {
    *count == 0
}

/// Which classifier made a decision asked for before lift-off (`decide_at`), under which rule, and why
/// at that frame: its fields are prefixed `early_` in the JSON line.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct EarlyDecisionEvent {
    /// `fixed` (`decide_at = K`) or `auto` (the first confident decision point).
    pub early_rule: EarlyRule,
    /// `fixed` (frame touchdown + K arrived), `confident` (the point's confidence passed the
    /// threshold), `deadline` (`auto`: no point's did by the deadline point, which decided),
    /// `not_confident` (`auto`: no point did before the lift-off or the model's length),
    /// `ended_first` (the stance ended or reached the model's length before the point).
    pub early_reason: EarlyReason,
    /// The decision point (frames after touchdown) whose classifier decided; `null`: the whole-stance
    /// classifier.
    pub early_point: Option<u64>,
    /// Frames after touchdown at which the decision was made (`decided_at_frame - touchdown_frame`).
    pub early_frames: u64,
    /// `auto`'s confidence threshold, learned at training.
    pub early_threshold: Option<f64>,
}

/// The rule of an early decision.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EarlyRule {
    Fixed,
    Auto,
}

impl EarlyRule {
    /// Its name in the stream protocol and the ROS 2 message.
    pub fn name(self) -> &'static str {
        match self {
            Self::Fixed => "fixed",
            Self::Auto => "auto",
        }
    }
}

/// The novelty of a decision: how far its sample lies from every trained class.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NoveltyVerdict {
    /// The sample is none of the model's classes: the decision's `label` is `unknown`.
    pub unknown: bool,
    /// The nearest class (the classifier's label, whether `unknown` or not).
    pub nearest: String,
    /// The score ([`presrs_core::novelty::Novelty::score`]): larger is more novel.
    pub novelty: f64,
    /// The score above which a sample is `unknown`.
    pub novelty_threshold: f64,
    /// The share of held-out known training samples scoring at least `novelty` (a conformal
    /// p-value), by which `confidence` is capped; absent for models that keep no held-out scores.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub credibility: Option<f64>,
}

/// What a whole-stance model's decision waited for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct WholeStance {
    pub decided_at: DecisionPoint,
    /// The lift-off frame, touchdown + K, or the frame at which the stance was known to be longer
    /// than the model's length.
    pub decided_at_frame: u64,
    /// The stance had more frames than the model's length: its first ones were used.
    pub cut: bool,
}

/// The moment a whole-stance decision was made.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DecisionPoint {
    /// At lift-off, on the whole stance.
    Liftoff,
    /// K frames after touchdown (`decide_at`), on the stance so far.
    Offset,
    /// The stance grew longer than the model's length: decided on its first `length` frames.
    Length,
}

/// A stance ended.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Liftoff {
    pub stance: u64,
    pub touchdown_frame: u64,
    /// One past the last loaded frame.
    pub end_frame: u64,
    pub len: u64,
    pub peak_frame: u64,
    pub peak_load: f64,
    pub partial: bool,
    /// Whether the stance was decided.
    pub sampled: bool,
    /// The frame at which the end was decided.
    pub frame: u64,
    /// Frames missing inside the stance (as `Classification::gap_frames`); absent when 0.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub gap_frames: u64,
}

/// A frame rejected, a classification that failed, or an input that cannot go on (`fatal`).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ErrorEvent {
    pub message: String,
    pub fatal: bool,
    /// The stance and frame of a classification that failed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stance: Option<u64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frame: Option<u64>,
}

/// The session's counters, its last event.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct End {
    pub frames: u64,
    pub stances: u64,
    pub decisions: u64,
    pub fused_decisions: u64,
    pub rejected_frames: u64,
    pub errors: u64,
    pub dropped_events: u64,
    pub warmup_frames: u64,
    /// Why no stance was decided, when the input ended during the warm-up calibration.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

/// A decision's posteriors, class by class in the model's order; a JSON object label -> posterior.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Posteriors(pub Vec<(String, f64)>);

impl Posteriors {
    /// The class names, in order.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.0.iter().map(|(name, _)| name.as_str())
    }

    /// The posteriors, in order.
    pub fn values(&self) -> impl Iterator<Item = f64> + '_ {
        self.0.iter().map(|&(_, p)| p)
    }
}

impl Serialize for Posteriors {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut map = serializer.serialize_map(Some(self.0.len()))?;
        for (name, p) in &self.0 {
            map.serialize_entry(name, p)?;
        }
        map.end()
    }
}

impl<'de> Deserialize<'de> for Posteriors {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Ordered;
        impl<'de> serde::de::Visitor<'de> for Ordered {
            type Value = Posteriors;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("an object of label -> posterior")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut map: A,
            ) -> Result<Posteriors, A::Error> {
                let mut entries = Vec::new();
                while let Some(entry) = map.next_entry::<String, f64>()? {
                    entries.push(entry);
                }
                Ok(Posteriors(entries))
            }
        }
        deserializer.deserialize_map(Ordered)
    }
}

impl SessionEvent {
    /// The protocol's JSON line (without the newline).
    pub fn to_line(&self) -> String {
        // Plain data with string keys and finite-or-null numbers: serialising cannot fail.
        serde_json::to_string(self).unwrap_or_else(|err| {
            format!(r#"{{"event":"error","message":"an event could not be written: {err}","fatal":false}}"#)
        })
    }

    /// A non-fatal or fatal error event without a stance.
    pub fn error(message: impl Into<String>, fatal: bool) -> Self {
        Self::Error(ErrorEvent {
            message: message.into(),
            fatal,
            stance: None,
            frame: None,
        })
    }

    /// The `end` event of a session's counters.
    pub fn end(summary: &ConnectionSummary) -> Self {
        let s = summary.stats;
        Self::End(End {
            frames: s.frames,
            stances: s.stances,
            decisions: s.decisions,
            fused_decisions: s.fused_decisions,
            rejected_frames: summary.rejected_frames,
            errors: summary.errors,
            dropped_events: summary.dropped_events,
            warmup_frames: summary.warmup_frames,
            note: summary.note(),
        })
    }
}

/// When an event of the classifier happened and how long the decision took.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EventTiming {
    /// From the triggering frame's arrival to the decision, µs.
    pub latency_us: f64,
    /// The triggering frame's time, when the input has frame times.
    pub timestamp_us: Option<u64>,
}

/// The events of one step of the online classifier (touchdown, classification, error, liftoff), in
/// order, with the model's class names and the profile's gait table.
pub fn step_events(
    step: &Step<'_>,
    model: &TrainedModel,
    profile: &OnlineProfile,
    timing: EventTiming,
) -> Vec<SessionEvent> {
    step.events
        .iter()
        .map(|event| match event {
            OnlineEvent::Touchdown(td) => SessionEvent::Touchdown(Touchdown {
                stance: td.stance_id,
                touchdown_frame: td.touchdown_frame as u64,
                frame: td.frame as u64,
                partial: td.partial,
            }),
            OnlineEvent::Decision(d) => {
                SessionEvent::Classification(classification(step, d, model, profile, timing))
            }
            OnlineEvent::Failed(f) => SessionEvent::Error(ErrorEvent {
                message: format!(
                    "stance {}: frame {} could not be classified ({} decision): {}",
                    f.stance_id,
                    f.sample_frame,
                    f.kind.name(),
                    step.error(f)
                        .map_or_else(|| "unknown error".to_owned(), ToString::to_string)
                ),
                fatal: false,
                stance: Some(f.stance_id),
                frame: Some(f.frame as u64),
            }),
            OnlineEvent::Liftoff(lo) => SessionEvent::Liftoff(Liftoff {
                stance: lo.stance_id,
                touchdown_frame: lo.stance.start as u64,
                end_frame: lo.stance.end() as u64,
                len: lo.stance.len as u64,
                peak_frame: lo.stance.peak_frame as u64,
                peak_load: lo.stance.peak_load,
                partial: lo.stance.partial,
                sampled: lo.sampled,
                frame: lo.frame as u64,
                // The session's `FrameGaps` fills it in.
                gap_frames: 0,
            }),
        })
        .collect()
}

fn classification(
    step: &Step<'_>,
    d: &Decision,
    model: &TrainedModel,
    profile: &OnlineProfile,
    timing: EventTiming,
) -> Classification {
    let names = model.class_names();
    let nearest = names.get(d.class).map_or("?", String::as_str).to_owned();
    let unknown = d.novelty.is_some_and(|n| n.unknown);
    let label = if unknown {
        UNKNOWN_LABEL.to_owned()
    } else {
        nearest.clone()
    };
    let posteriors = names
        .iter()
        .zip(step.posteriors(d))
        .map(|(name, &p)| (name.clone(), p))
        .collect();
    Classification {
        kind: d.kind,
        stance: d.stance_id,
        class: d.class,
        confidence: d.confidence,
        posteriors: Posteriors(posteriors),
        sample_frame: d.sample_frame as u64,
        frame: d.frame as u64,
        frames_used: d.frames_used as u64,
        touchdown_frame: d.touchdown_frame as u64,
        latency_us: (timing.latency_us * 10.0).round() / 10.0,
        timestamp_us: timing.timestamp_us,
        gait: profile.gait_table.get(&label).cloned(),
        whole_stance: d.stance.map(|how| WholeStance {
            decided_at: match how.decided_at {
                DecidedAt::Liftoff => DecisionPoint::Liftoff,
                DecidedAt::Offset(_) => DecisionPoint::Offset,
                DecidedAt::Length(_) => DecisionPoint::Length,
            },
            decided_at_frame: how.waited_for as u64,
            cut: how.cut,
        }),
        early: d.stance.and_then(|how| {
            let early = how.early?;
            Some(EarlyDecisionEvent {
                early_rule: if early.rule.is_auto() {
                    EarlyRule::Auto
                } else {
                    EarlyRule::Fixed
                },
                early_reason: early.reason,
                early_point: early.point.map(|k| k as u64),
                early_frames: how.waited_for.saturating_sub(d.touchdown_frame) as u64,
                early_threshold: early.threshold,
            })
        }),
        novelty: d.novelty.map(|n| {
            Box::new(NoveltyVerdict {
                unknown: n.unknown,
                nearest,
                novelty: n.score,
                novelty_threshold: n.threshold,
                credibility: n.credibility,
            })
        }),
        label,
        // The session's `FrameGaps` fills it in.
        gap_frames: 0,
    }
}
