//! What a whole-stance model keeps online (the stance's frames, when to decide, the stance under way),
//! with its settings checked against the model; the decisions it leads to are in `whole.rs`.

use super::early;
use super::stance_buffer::StanceBuffer;
use crate::error::{CoreError, Result};
use crate::pipeline::{AutoRule, TrainedModel};
use crate::sample::SampleKind;
use crate::stance::causal::{DecideAt, OnlineParams};
use crate::stance::{BaselineMode, ValidSegmentParams};

/// What a whole-stance model keeps online: the stance's frames, when to decide, the stance under way.
#[derive(Debug)]
pub(super) struct WholeStance<'m> {
    pub(super) buffer: StanceBuffer,
    pub(super) decide_at: Option<DecideAt>,
    /// The classifiers of the model's decision points that `decide_at` uses (frames after touchdown,
    /// increasing), and `auto`'s rule.
    pub(super) points: early::PointSessions<'m>,
    pub(super) auto: Option<AutoRule>,
    /// The next point to try in the stance under way (`auto`).
    pub(super) next_point: usize,
    /// Partial stances are decided too: in the one-contact mode the stream is one partial stance.
    pub(super) decide_partial: bool,
    /// The stance under way and not yet decided: its id and touchdown frame.
    pub(super) open: Option<(u64, usize)>,
    /// Stances are reported without a decision (the end of a stream that ended in the warm-up).
    pub(super) report_only: bool,
}

impl<'m> WholeStance<'m> {
    /// The whole-stance state for `model` (`None` for a one-frame model), with `online`'s settings
    /// checked against the kind of model: fusion is for one-frame models, `decide_at` for whole
    /// stances, and only for a moment the model was trained for ([`TrainedModel::trained_for`]).
    pub(super) fn for_model(
        model: &'m TrainedModel,
        params: &ValidSegmentParams,
        online: &OnlineParams,
    ) -> Result<Option<Self>> {
        let SampleKind::Stance { summary, length } = model.sample() else {
            return match online.decide_at {
                Some(_) => Err(CoreError::Param {
                    name: "decide_at",
                    reason: "applies to whole-stance models (trained on stance samples); this \
                             model classifies one frame of each stance, chosen by the sample offset"
                        .into(),
                }),
                None => Ok(None),
            };
        };
        if !online.fusion_offsets.is_empty() {
            return Err(CoreError::Param {
                name: "fusion_offsets",
                reason: "a whole-stance model decides once per stance, on the stance's summary; \
                         fusion averages one-frame decisions: leave the fusion offsets empty"
                    .into(),
            });
        }
        let buffer = StanceBuffer::new(summary, length.unwrap_or(model.image_grid().cols))?;
        if model.crop().output_grid(buffer.sample_grid()).ok() != Some(model.image_grid()) {
            return Err(CoreError::Shape {
                what: "whole-stance model",
                expected: format!(
                    "a crop that keeps its {} stance summaries whole",
                    buffer.sample_grid()
                ),
                got: format!("crop {} giving {} images", model.crop(), model.image_grid()),
            });
        }
        let (points, auto) = early::points_for(model, online.decide_at)?;
        Ok(Some(Self {
            buffer,
            decide_at: online.decide_at,
            points,
            auto,
            next_point: 0,
            decide_partial: params.params().baseline == BaselineMode::Contact,
            open: None,
            report_only: false,
        }))
    }
}
