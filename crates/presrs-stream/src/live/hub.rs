//! What the viewers are shown: the latest frame, the recent total loads and JSON lines, kept by
//! [`LiveTap`] (on the session's thread) and read by the viewers' threads.

use std::collections::VecDeque;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};

use presrs_core::Grid;

use presrs::session::{Classification, SessionEvent, SessionObserver};

/// Total loads kept for a viewer that connects late or falls behind (the trace it can draw).
pub const LOAD_HISTORY: usize = 2048;
/// JSON lines kept (the decision log a new viewer starts with).
pub const LINE_HISTORY: usize = 256;

/// The state shared by the session(s) and the viewers; cheap to clone (one `Arc`).
#[derive(Clone, Debug)]
pub struct LiveHub {
    shared: Arc<Shared>,
}

#[derive(Debug)]
struct Shared {
    state: Mutex<State>,
    /// Viewers connected now.
    viewers: AtomicUsize,
}

/// What the page is told once, when it connects.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LiveInfo {
    /// What is being shown (`stdin`, a file name, a client's address).
    pub source: String,
    /// The unit of the frame values (`kPa`, `raw`, ...), for the colour scale.
    pub units: String,
    /// The model's classes (empty without a model).
    pub classes: Vec<String>,
}

#[derive(Debug, Default)]
struct State {
    info: LiveInfo,
    /// Sessions seen (a frame with index 0 starts one): the page clears its trace on a new one.
    session: u64,
    /// Frames seen in all, and the latest one (copied only while a viewer is connected).
    frame_seq: u64,
    frame: LatestFrame,
    /// The largest value seen: the top of the colour scale (it only grows, so colours stay comparable).
    scale_max: f64,
    /// (frame_seq, session, index, load).
    loads: VecDeque<(u64, u64, u64, f64)>,
    /// (line_seq, line).
    lines: VecDeque<(u64, String)>,
    line_seq: u64,
    /// The latest classification, as the session made it.
    last_decision: Option<Classification>,
    /// The exclusive tap being shown (0: none), and the last id given out.
    owner: u64,
    last_tap: u64,
}

impl State {
    /// Whether tap `id` is shown now: a shared tap (0) always; an exclusive one when no other is, and
    /// then until it is dropped.
    fn admit(&mut self, id: u64, source: &str) -> bool {
        if id == 0 || self.owner == id {
            return true;
        }
        if self.owner == 0 {
            self.owner = id;
            source.clone_into(&mut self.info.source);
            return true;
        }
        false
    }
}

/// The latest frame.
#[derive(Clone, Debug, PartialEq)]
pub struct LatestFrame {
    pub session: u64,
    /// Input frame index in its session.
    pub index: u64,
    pub grid: Grid,
    pub values: Vec<f64>,
    /// Empty when every sensel is present.
    pub present: Vec<bool>,
    /// The top of the colour scale.
    pub scale_max: f64,
}

impl Default for LatestFrame {
    fn default() -> Self {
        Self {
            session: 0,
            index: 0,
            grid: Grid::new(0, 0),
            values: Vec::new(),
            present: Vec::new(),
            scale_max: 0.0,
        }
    }
}

/// Where a viewer is: what it has already been sent.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Cursor {
    frame_seq: u64,
    load_seq: u64,
    line_seq: u64,
}

/// What is new for a viewer since its cursor.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Update {
    /// The latest frame, when a new one came (the ones in between are skipped).
    pub frame: Option<LatestFrame>,
    /// (session, index, load) of every frame since, at most [`LOAD_HISTORY`] (older ones are lost).
    pub loads: Vec<(u64, u64, f64)>,
    /// JSON lines since, at most [`LINE_HISTORY`].
    pub lines: Vec<String>,
}

impl Update {
    pub fn is_empty(&self) -> bool {
        self.frame.is_none() && self.loads.is_empty() && self.lines.is_empty()
    }
}

impl LiveHub {
    pub fn new(info: LiveInfo) -> Self {
        let state = State {
            info,
            ..State::default()
        };
        Self {
            shared: Arc::new(Shared {
                state: Mutex::new(state),
                viewers: AtomicUsize::new(0),
            }),
        }
    }

    fn lock(&self) -> MutexGuard<'_, State> {
        self.shared
            .state
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// A tap for one session that feeds this hub.
    pub fn tap(&self) -> LiveTap {
        LiveTap {
            hub: self.clone(),
            id: 0,
            source: String::new(),
        }
    }

    /// A tap for one of several sessions at once (the clients of a server): the hub shows one session
    /// at a time, the first that sends something while none is shown, until its tap is dropped; the
    /// others' frames and lines are ignored. `source` names it on the page.
    pub fn exclusive_tap(&self, source: &str) -> LiveTap {
        let mut state = self.lock();
        state.last_tap += 1;
        LiveTap {
            hub: self.clone(),
            id: state.last_tap,
            source: source.to_owned(),
        }
    }

    pub fn info(&self) -> LiveInfo {
        self.lock().info.clone()
    }

    /// Frames seen so far.
    pub fn frames_seen(&self) -> u64 {
        self.lock().frame_seq
    }

    /// Viewers connected now.
    pub fn viewers(&self) -> usize {
        self.shared.viewers.load(Ordering::SeqCst)
    }

    /// Counts a viewer in while the guard lives.
    pub(super) fn viewer(&self) -> ViewerGuard {
        self.shared.viewers.fetch_add(1, Ordering::SeqCst);
        ViewerGuard { hub: self.clone() }
    }

    /// The latest classification shown.
    pub fn last_decision(&self) -> Option<Classification> {
        self.lock().last_decision.clone()
    }

    /// The lines kept (oldest first).
    pub fn recent_lines(&self) -> Vec<String> {
        self.lock().lines.iter().map(|(_, l)| l.clone()).collect()
    }

    /// What is new since `cursor` (a new viewer starts from `Cursor::default()` and gets what is kept);
    /// moves the cursor on.
    pub fn update(&self, cursor: &mut Cursor) -> Update {
        let state = self.lock();
        let mut update = Update::default();
        if state.frame_seq != cursor.frame_seq && !state.frame.values.is_empty() {
            update.frame = Some(state.frame.clone());
        }
        cursor.frame_seq = state.frame_seq;
        update.loads = state
            .loads
            .iter()
            .filter(|(seq, ..)| *seq > cursor.load_seq)
            .map(|&(_, session, index, load)| (session, index, load))
            .collect();
        cursor.load_seq = state.frame_seq;
        update.lines = state
            .lines
            .iter()
            .filter(|(seq, _)| *seq > cursor.line_seq)
            .map(|(_, line)| line.clone())
            .collect();
        cursor.line_seq = state.line_seq;
        update
    }
}

/// Counts a viewer while it lives.
#[derive(Debug)]
pub(super) struct ViewerGuard {
    hub: LiveHub,
}

impl Drop for ViewerGuard {
    fn drop(&mut self) {
        self.hub.shared.viewers.fetch_sub(1, Ordering::SeqCst);
    }
}

/// The [`SessionObserver`] of a live view: it never waits for a viewer. Each frame costs its total load and
/// a copy into the hub's one frame slot (the viewers take the latest
/// frame, skipping those in between); lines go to a bounded history.
#[derive(Debug)]
pub struct LiveTap {
    hub: LiveHub,
    /// 0: shown always; else shown while it owns the hub (see [`LiveHub::exclusive_tap`]).
    id: u64,
    source: String,
}

impl Drop for LiveTap {
    fn drop(&mut self) {
        let mut state = self.hub.lock();
        if self.id != 0 && state.owner == self.id {
            state.owner = 0;
        }
    }
}

impl SessionObserver for LiveTap {
    fn frame(
        &mut self,
        index: u64,
        grid: Grid,
        values: &[f64],
        present: Option<&[bool]>,
        _timestamp_us: Option<u64>,
    ) {
        let mut load = 0.0;
        let mut peak = 0.0f64;
        match present {
            Some(mask) => {
                for (&v, _) in values.iter().zip(mask).filter(|(_, p)| **p) {
                    load += v;
                    peak = peak.max(v);
                }
            }
            None => {
                for &v in values {
                    load += v;
                    peak = peak.max(v);
                }
            }
        }
        let mut state = self.hub.lock();
        if !state.admit(self.id, &self.source) {
            return;
        }
        if index == 0 {
            state.session += 1;
        }
        state.frame_seq += 1;
        if peak.is_finite() && peak > state.scale_max {
            state.scale_max = peak;
        }
        let (seq, session, scale_max) = (state.frame_seq, state.session, state.scale_max);
        if state.loads.len() == LOAD_HISTORY {
            state.loads.pop_front();
        }
        state.loads.push_back((seq, session, index, load));
        // Copied even with no viewer: one who comes while the stream pauses must see its last frame.
        let frame = &mut state.frame;
        frame.session = session;
        frame.index = index;
        frame.grid = grid;
        frame.scale_max = scale_max;
        frame.values.clear();
        frame.values.extend_from_slice(values);
        frame.present.clear();
        if let Some(mask) = present {
            frame.present.extend_from_slice(mask);
        }
    }

    /// Kept as its JSON line for the page's log, and a classification as the typed last decision.
    fn event(&mut self, event: &SessionEvent) -> bool {
        let line = event.to_line();
        let mut state = self.hub.lock();
        if !state.admit(self.id, &self.source) {
            return true;
        }
        if let SessionEvent::Classification(decision) = event {
            state.last_decision = Some(decision.clone());
        }
        state.line_seq += 1;
        let seq = state.line_seq;
        if state.lines.len() == LINE_HISTORY {
            state.lines.pop_front();
        }
        state.lines.push_back((seq, line));
        true
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn a_cursor_sees_each_load_and_line_once_and_only_the_latest_frame() {
        let hub = LiveHub::new(LiveInfo::default());
        let _viewer = hub.viewer();
        let mut tap = hub.tap();
        let grid = Grid::new(2, 2);
        let mut cursor = Cursor::default();
        assert!(hub.update(&mut cursor).is_empty());
        for i in 0..5 {
            tap.frame(i, grid, &[i as f64, 1.0, 2.0, 3.0], None, None);
        }
        tap.event(&SessionEvent::error("a line", false));
        let update = hub.update(&mut cursor);
        let frame = update.frame.unwrap();
        assert_eq!(
            (frame.index, frame.values[0], frame.scale_max),
            (4, 4.0, 4.0)
        );
        let loads: Vec<f64> = update.loads.iter().map(|l| l.2).collect();
        assert_eq!(loads, [6.0, 7.0, 8.0, 9.0, 10.0]);
        assert_eq!(update.lines.len(), 1);
        assert!(hub.update(&mut cursor).is_empty());
        // Absent sensels count for nothing.
        tap.frame(
            5,
            grid,
            &[100.0, 1.0, 1.0, 1.0],
            Some(&[false, true, true, true]),
            None,
        );
        let update = hub.update(&mut cursor);
        assert_eq!(update.loads, [(1, 5, 3.0)]);
        assert_eq!(update.frame.unwrap().present, [false, true, true, true]);
    }

    #[test]
    fn history_is_bounded_and_a_late_cursor_skips_what_was_dropped() {
        let hub = LiveHub::new(LiveInfo::default());
        let mut tap = hub.tap();
        let grid = Grid::new(1, 1);
        for i in 0..(3 * LOAD_HISTORY as u64) {
            tap.frame(i, grid, &[1.0], None, None);
            tap.event(&SessionEvent::error("a line", false));
        }
        let mut cursor = Cursor::default();
        let update = hub.update(&mut cursor);
        assert_eq!(update.loads.len(), LOAD_HISTORY);
        assert_eq!(update.lines.len(), LINE_HISTORY);
        assert_eq!(update.loads[0].1, 2 * LOAD_HISTORY as u64);
        assert_eq!(update.frame.unwrap().index, 3 * LOAD_HISTORY as u64 - 1);
    }

    #[test]
    fn a_frame_with_index_0_starts_a_new_session() {
        let hub = LiveHub::new(LiveInfo::default());
        let mut tap = hub.tap();
        let grid = Grid::new(1, 1);
        tap.frame(0, grid, &[1.0], None, None);
        tap.frame(1, grid, &[1.0], None, None);
        tap.frame(0, grid, &[1.0], None, None);
        let sessions: Vec<u64> = hub
            .update(&mut Cursor::default())
            .loads
            .iter()
            .map(|l| l.0)
            .collect();
        assert_eq!(sessions, [1, 1, 2]);
    }

    #[test]
    fn exclusive_taps_are_shown_one_at_a_time() {
        let hub = LiveHub::new(LiveInfo::default());
        let grid = Grid::new(1, 1);
        let mut first = hub.exclusive_tap("a");
        let mut second = hub.exclusive_tap("b");
        first.frame(0, grid, &[1.0], None, None);
        second.frame(0, grid, &[2.0], None, None);
        second.event(&SessionEvent::error("a line", false));
        assert_eq!(hub.info().source, "a");
        drop(first);
        second.frame(1, grid, &[3.0], None, None);
        assert_eq!(hub.info().source, "b");
        let loads: Vec<f64> = hub
            .update(&mut Cursor::default())
            .loads
            .iter()
            .map(|l| l.2)
            .collect();
        assert_eq!(loads, [1.0, 3.0]);
        assert!(hub.recent_lines().is_empty());
    }
}
