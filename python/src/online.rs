//! `presrs.OnlineClassifier`: frames in one at a time, stance and terrain events out, with the causal
//! detector and the events of `presrs stream` (docs/stream-protocol.md).

use std::time::Instant;

use presrs::core::online::{DecideAt, OnlineClassifier as CoreOnline, OnlineProfile};
use presrs::io::model_file::ModelFile;
use presrs::session::{EventTiming, FrameGaps, SessionEvent, check_profile, step_events};
use pyo3::prelude::*;
use self_cell::self_cell;

use crate::arrays::Images;
use crate::errors::{IntoPyResult, data_error};
use crate::model::Model;

/// A model file, its online profile and a classifier running on them.
struct Running {
    file: ModelFile,
    profile: OnlineProfile,
}

self_cell!(
    struct Online {
        owner: Running,
        #[covariant]
        dependent: CoreOnline,
    }
);

/// Classifies a stream of frames as `presrs stream` does: feed frames with `push`, read the events
/// (touchdown, classification, liftoff, error) it returns, and `finish` at the end of the stream.
#[pyclass(module = "presrs", name = "OnlineClassifier", unsendable)]
pub struct OnlineClassifier {
    online: Online,
    /// Frames pushed so far.
    frames: u64,
    /// Frames missing between the pushed frames, from their times: a stance's events state them
    /// (`gap_frames`), as `presrs stream` does.
    gaps: FrameGaps,
}

impl std::fmt::Debug for OnlineClassifier {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("OnlineClassifier")
            .field("frames", &self.frames)
            .finish()
    }
}

#[pymethods]
impl OnlineClassifier {
    /// A classifier for `model`, with the model file's online profile (calibration, stance detector
    /// settings, sample frame, gait table) when it has one, else warm-up calibration on the first
    /// frames. `gait_table` adds terrain -> gait entries to the profile's. `decide_at`: a whole-stance
    /// model decides K frames after touchdown, on the stance so far, or (`"auto"`) at its first
    /// decision point confident enough (else at its deadline point), instead of at lift-off; only at a moment the model was trained
    /// for (`presrs train --decide-at`), else a `ValueError` says how to train one.
    #[new]
    #[pyo3(signature = (model, *, gait_table = None, decide_at = None, novelty = true))]
    fn new(
        model: &Bound<'_, Model>,
        gait_table: Option<std::collections::BTreeMap<String, String>>,
        decide_at: Option<&Bound<'_, PyAny>>,
        novelty: bool,
    ) -> PyResult<Self> {
        let mut file = model.get().file().clone();
        if !novelty {
            file.model = file.model.without_novelty();
        }
        let mut profile = file.online.clone().unwrap_or_default();
        profile.gait_table.extend(gait_table.unwrap_or_default());
        if let Some(decide_at) = decide_at {
            profile.params.decide_at = Some(decide_at_of(decide_at)?);
        }
        check_profile(&file.model, &profile).py_err()?;
        let online = Online::try_new(Running { file, profile }, |running| {
            CoreOnline::new(
                &running.file.model,
                &running.profile.segment,
                &running.profile.params,
                running.profile.calibration,
            )
        })
        .py_err()?;
        Ok(Self {
            online,
            frames: 0,
            gaps: FrameGaps::default(),
        })
    }

    /// Feeds one frame `(rows, cols)`; returns the events it completed, as dicts. `timestamp_us`: the
    /// frame's time in microseconds (from the recording's clock), copied into its events as
    /// `presrs stream` does with its input's times; `None` when the frame has none.
    #[pyo3(signature = (frame, *, timestamp_us = None))]
    fn push<'py>(
        &mut self,
        py: Python<'py>,
        frame: &Bound<'py, PyAny>,
        timestamp_us: Option<u64>,
    ) -> PyResult<Vec<Bound<'py, PyAny>>> {
        let images = Images::new(frame, "frame")?;
        if images.batch {
            return Err(data_error(
                "frame: push one frame (rows, cols) at a time; loop over a movie's frames",
            ));
        }
        let view = images.frame(0)?;
        let index = self.frames;
        let gaps = &mut self.gaps;
        let mut values = self.online.with_dependent_mut(|running, online| {
            let started = Instant::now();
            let step = online
                .push(&view)
                .map_err(|err| data_error(format!("frame {index}: {err}")))?;
            gaps.frame(index, timestamp_us);
            let latency_us = started.elapsed().as_secs_f64() * 1e6;
            let timing = EventTiming {
                latency_us,
                timestamp_us,
            };
            Ok::<_, PyErr>(step_events(
                &step,
                &running.file.model,
                &running.profile,
                timing,
            ))
        })?;
        self.frames += 1;
        for event in &mut values {
            self.gaps.mark(event);
        }
        to_dicts(py, &values)
    }

    /// Ends the stream: the events of a stance still open (a decision not yet made, its lift-off).
    fn finish<'py>(&mut self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyAny>>> {
        let mut values = self.online.with_dependent_mut(|running, online| {
            let step = online.finish().py_err()?;
            Ok::<_, PyErr>(step_events(
                &step,
                &running.file.model,
                &running.profile,
                EventTiming::default(),
            ))
        })?;
        for event in &mut values {
            self.gaps.mark(event);
        }
        to_dicts(py, &values)
    }

    /// Whether the detector is still calibrating on the first frames (no model-file profile).
    #[getter]
    fn warming_up(&self) -> bool {
        self.online.borrow_dependent().segmenter().warming_up()
    }

    /// Counters: frames, stances, decisions, fused decisions, rejected frames.
    #[getter]
    fn stats(&self) -> std::collections::BTreeMap<&'static str, u64> {
        let s = self.online.borrow_dependent().stats();
        [
            ("frames", s.frames),
            ("stances", s.stances),
            ("decisions", s.decisions),
            ("fused_decisions", s.fused_decisions),
            ("rejected_frames", s.rejected_frames),
        ]
        .into_iter()
        .collect()
    }
}

/// The events as the dicts of their JSON lines (`docs/stream-protocol.md`), from the typed events.
fn to_dicts<'py>(py: Python<'py>, events: &[SessionEvent]) -> PyResult<Vec<Bound<'py, PyAny>>> {
    events
        .iter()
        .map(|event| Ok(pythonize::pythonize(py, event)?))
        .collect()
}

/// `decide_at` from Python: a number of frames after touchdown, or `"auto"`.
fn decide_at_of(value: &Bound<'_, PyAny>) -> PyResult<DecideAt> {
    if let Ok(k) = value.extract::<usize>() {
        return Ok(DecideAt::Frames(k));
    }
    match value.extract::<String>() {
        Ok(text) if text.trim() == "auto" => Ok(DecideAt::AUTO),
        _ => Err(pyo3::exceptions::PyValueError::new_err(format!(
            "decide_at: expected a number of frames after touchdown or \"auto\", got {value}"
        ))),
    }
}
