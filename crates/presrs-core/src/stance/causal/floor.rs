//! What the floor mode knows of the local floor: the recent totals, the current rest and the slope
//! pooled within the recent rests ([`FloorState`]).

/// Fewest frames of a rest in the floor mode online: a rest this long ends a contact (at least
/// `max_gap_frames + 1`: a shorter rest is a dropout inside one contact, as offline).
pub const MIN_REST_FRAMES: usize = 3;
/// Recent totals the floor mode keeps to look back over when a rest is found (the rest's first frames
/// are found from its last ones).
pub(super) const FLOOR_LOOKBACK: usize = 64;
/// The floor's slope counts as if a level rest of this many frames had been seen.
const SLOPE_PRIOR_FRAMES: f64 = 8.0;
/// Weight the slope evidence of earlier rests keeps each time a new rest starts.
const SLOPE_MEMORY: f64 = 0.75;

/// Least-squares sums of `(t, load)` over frames (times from `origin`, so that they stay small).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct LineSums {
    origin: usize,
    pub(super) n: f64,
    st: f64,
    sx: f64,
    stt: f64,
    stx: f64,
}

impl LineSums {
    pub(super) fn add(&mut self, t: usize, load: f64) {
        if self.n == 0.0 {
            self.origin = t;
        }
        let dt = t as f64 - self.origin as f64;
        self.n += 1.0;
        self.st += dt;
        self.sx += load;
        self.stt += dt * dt;
        self.stx += dt * load;
    }

    /// Spread of the times about their mean (the slope's denominator).
    fn sxx(&self) -> f64 {
        if self.n == 0.0 {
            0.0
        } else {
            self.stt - self.st * self.st / self.n
        }
    }

    /// Co-spread of times and loads (the slope's numerator).
    fn sxy(&self) -> f64 {
        if self.n == 0.0 {
            0.0
        } else {
            self.stx - self.st * self.sx / self.n
        }
    }
}

/// What the floor mode knows of the local floor (see [`push_floor`](crate::stance::CausalSegmenter::push_floor)).
#[derive(Clone, Debug)]
pub(super) struct FloorState {
    /// The current (or last) rest's frames.
    pub(super) rest: LineSums,
    /// Slope evidence (`sxy`, `sxx`) of the earlier rests, each weighted [`SLOPE_MEMORY`] per rest
    /// since: slopes are pooled *within* rests, so a preload that steps between rests does not tilt them.
    pool_sxy: f64,
    pool_sxx: f64,
    /// The last [`FLOOR_LOOKBACK`] totals, frame `t` at `t % FLOOR_LOOKBACK`.
    pub(super) recent: Vec<f64>,
    /// Lowest and highest total seen (the load range is their difference, as offline).
    pub(super) lowest: f64,
    pub(super) highest: f64,
    /// Frames in a row more than the off level below the floor.
    pub(super) below: usize,
}

impl FloorState {
    pub(super) fn new(seen: Option<(f64, f64)>) -> Self {
        let (lowest, highest) = seen.unwrap_or((f64::INFINITY, f64::NEG_INFINITY));
        Self {
            rest: LineSums::default(),
            pool_sxy: 0.0,
            pool_sxx: 0.0,
            recent: vec![0.0; FLOOR_LOOKBACK],
            lowest,
            highest,
            below: 0,
        }
    }

    /// The floor's slope, shrunk towards level by the spread of [`SLOPE_PRIOR_FRAMES`] flat frames (the
    /// two or three frames of a short rest alone would tilt it by their noise).
    fn slope(&self) -> f64 {
        let prior = SLOPE_PRIOR_FRAMES * (SLOPE_PRIOR_FRAMES * SLOPE_PRIOR_FRAMES - 1.0) / 12.0;
        let sxx = self.pool_sxx + self.rest.sxx() + prior;
        if sxx > 0.0 {
            (self.pool_sxy + self.rest.sxy()) / sxx
        } else {
            0.0
        }
    }

    /// The floor at frame `t`: the current rest's mean, moved along the pooled slope; `None` before any
    /// rest.
    pub(super) fn at(&self, t: usize) -> Option<f64> {
        let rest = &self.rest;
        (rest.n > 0.0).then(|| {
            let centre = rest.origin as f64 + rest.st / rest.n;
            rest.sx / rest.n + self.slope() * (t as f64 - centre)
        })
    }

    /// Ends the current rest (its slope evidence joins the pool) and starts a new one on frames
    /// `first..=last` (all within the lookback).
    pub(super) fn start_rest(&mut self, first: usize, last: usize) {
        self.close_rest();
        self.below = 0;
        for f in first..=last {
            self.rest.add(f, self.recent[f % FLOOR_LOOKBACK]);
        }
    }

    pub(super) fn close_rest(&mut self) {
        if self.rest.n >= MIN_REST_FRAMES as f64 {
            self.pool_sxy = SLOPE_MEMORY * self.pool_sxy + self.rest.sxy();
            self.pool_sxx = SLOPE_MEMORY * self.pool_sxx + self.rest.sxx();
        }
        self.rest = LineSums::default();
    }

    /// Whether the `m` frames ending at `t` lie within `off` of their mean, and that mean.
    pub(super) fn flat(&self, t: usize, m: usize, off: f64) -> Option<f64> {
        if m == 0 || m > FLOOR_LOOKBACK || t + 1 < m {
            return None;
        }
        let window = (t + 1 - m..=t).map(|f| self.recent[f % FLOOR_LOOKBACK]);
        let mean = window.clone().sum::<f64>() / m as f64;
        window
            .clone()
            .all(|v| (v - mean).abs() <= off)
            .then_some(mean)
    }
}
