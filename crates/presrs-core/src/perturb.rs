//! Fault injection on test images: sensor faults (dead, stuck, gain drift, noise) and changed conditions
//! (a shifted or rotated foot placement, a different load), to measure how accuracy degrades.
//!
//! A [`Perturbation`] is written `KIND=LEVEL` (as `presrs eval --perturb` takes it):
//!
//! | kind | level | effect |
//! |---|---|---|
//! | `dead` | fraction 0..1 | that fraction of the present sensels read 0 (the same sensels in every image) |
//! | `stuck` | fraction 0..1 | that fraction read the image's largest value (saturated; same sensels) |
//! | `gain` | s.d. >= 0 | every sensel's gain is multiplied by `1 + N(0, sd)` (fixed per sensel), floored at 0 |
//! | `noise` | s.d. >= 0, counts | independent `N(0, sd)` added to every sensel of every image, floored at 0 |
//! | `shift` | `ROWS` or `ROWS,COLS` | the image moves by whole sensels (vacated sensels read 0) |
//! | `rotate` | degrees | the image turns about its centre of pressure (bilinear resampling) |
//! | `load` | factor > 0, or `+50%` / `-50%` | every value is multiplied by the factor |
//!
//! Every random choice comes from the seed: sensor faults (`dead`, `stuck`, `gain`) depend on the seed
//! and the grid only, as a faulty sensor would affect every image alike; `noise` also depends on the
//! image's index. Absent sensels (outside the sensor's outline) read 0 to every perturbation (whatever a
//! borrowed view holds there) and stay absent and 0. Values stay finite: a result beyond the range of
//! `f64` (e.g. `load=1e308`) saturates at `±f64::MAX`; an image that large may still be beyond what a
//! model's features can represent, which an evaluation counts as a wrong answer
//! ([`crate::evaluation::EvalReport::unclassified`]).

use std::fmt;
use std::str::FromStr;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::error::{CoreError, Result};
use crate::frame::{Frame, FrameView, Grid};

/// One fault or condition change; see the module documentation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Perturbation {
    Dead(f64),
    Stuck(f64),
    Gain(f64),
    Noise(f64),
    Shift(i64, i64),
    Rotate(f64),
    Load(f64),
}

impl Perturbation {
    /// The kind's name (`dead`, `stuck`, ...).
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Dead(_) => "dead",
            Self::Stuck(_) => "stuck",
            Self::Gain(_) => "gain",
            Self::Noise(_) => "noise",
            Self::Shift(..) => "shift",
            Self::Rotate(_) => "rotate",
            Self::Load(_) => "load",
        }
    }

    /// The kinds, in the order reports show them.
    pub const KINDS: [&'static str; 7] =
        ["dead", "stuck", "gain", "noise", "shift", "rotate", "load"];

    /// The fault's size as one number, for plotting accuracy against it: the fraction (`dead`,
    /// `stuck`), the s.d. (`gain`, `noise`), the distance in sensels (`shift`), the angle (`rotate`) or
    /// the factor (`load`).
    pub fn level(&self) -> f64 {
        match *self {
            Self::Dead(v) | Self::Stuck(v) | Self::Gain(v) | Self::Noise(v) | Self::Rotate(v) => v,
            Self::Shift(r, c) => (r as f64).hypot(c as f64),
            Self::Load(f) => f,
        }
    }

    /// The [`level`](Self::level) of this kind that changes nothing (0; 1 for `load`).
    pub fn clean_level(&self) -> f64 {
        match self {
            Self::Load(_) => 1.0,
            _ => 0.0,
        }
    }

    /// What [`level`](Self::level) measures, for an axis label.
    pub fn level_name(&self) -> &'static str {
        match self {
            Self::Dead(_) => "fraction of sensels dead",
            Self::Stuck(_) => "fraction of sensels stuck at the maximum",
            Self::Gain(_) => "s.d. of the per-sensel gain",
            Self::Noise(_) => "noise s.d. (counts)",
            Self::Shift(..) => "shift (sensels)",
            Self::Rotate(_) => "rotation (degrees)",
            Self::Load(_) => "load factor",
        }
    }

    /// A sweep of a few levels of every kind (three each, mild to severe), for reports.
    pub fn default_sweep() -> Vec<Self> {
        vec![
            Self::Dead(0.02),
            Self::Dead(0.05),
            Self::Dead(0.1),
            Self::Stuck(0.005),
            Self::Stuck(0.01),
            Self::Stuck(0.02),
            Self::Gain(0.1),
            Self::Gain(0.2),
            Self::Gain(0.4),
            Self::Noise(2.0),
            Self::Noise(5.0),
            Self::Noise(10.0),
            Self::Shift(1, 0),
            Self::Shift(2, 0),
            Self::Shift(4, 0),
            Self::Rotate(5.0),
            Self::Rotate(10.0),
            Self::Rotate(20.0),
            Self::Load(0.7),
            Self::Load(1.3),
            Self::Load(1.6),
        ]
    }

    /// This perturbation as an evaluation test transform ([`crate::evaluation::TestTransform`]): the
    /// test image's number varies the noise from image to image.
    pub fn transform(&self) -> impl Fn(usize, FrameView<'_>, u64) -> Result<Frame> + Sync + '_ {
        move |index, frame, seed| Ok(self.apply(frame, seed, index as u64))
    }

    /// A perturbed copy of `frame`. `seed` fixes the sensor faults; `index` (the image's number) varies
    /// the noise from image to image. Finite values stay finite (saturated at `±f64::MAX`).
    pub fn apply(&self, frame: FrameView<'_>, seed: u64, index: u64) -> Frame {
        let grid = frame.grid();
        // A view may hold anything at its absent sensels: every perturbation reads them as 0 (the centre
        // of pressure of `rotate`, the maximum of `stuck`, the sensels `shift` moves).
        let zeroed = absent_as_zero(frame);
        let frame = zeroed.as_ref().map_or(frame, Frame::view);
        let present = |i: usize| frame.present().is_none_or(|p| p[i]);
        let mut values = frame.values().to_vec();
        // Sensor faults: a stream that depends on the seed and the grid only.
        let mut sensor_rng = ChaCha8Rng::seed_from_u64(
            seed ^ (grid.rows as u64).wrapping_mul(0x9e37_79b9) ^ ((grid.cols as u64) << 32),
        );
        match *self {
            Self::Dead(fraction) | Self::Stuck(fraction) => {
                let cells = random_sensels(fraction, values.len(), &present, &mut sensor_rng);
                let value = match self {
                    Self::Dead(_) => 0.0,
                    _ => values.iter().copied().fold(0.0, f64::max),
                };
                for &i in &cells {
                    values[i] = value;
                }
            }
            Self::Gain(sd) => {
                for (i, v) in values.iter_mut().enumerate() {
                    let gain = 1.0 + sd * normal(&mut sensor_rng);
                    if present(i) {
                        *v = (*v * gain).max(0.0);
                    }
                }
            }
            Self::Noise(sd) => {
                let mut rng = ChaCha8Rng::seed_from_u64(seed);
                rng.set_stream(index);
                for (i, v) in values.iter_mut().enumerate() {
                    let noise = sd * normal(&mut rng);
                    if present(i) {
                        *v = (*v + noise).max(0.0);
                    }
                }
            }
            Self::Shift(dr, dc) => shift(frame, dr, dc, &mut values),
            Self::Rotate(degrees) => rotate(frame, degrees, &mut values),
            Self::Load(factor) => values.iter_mut().for_each(|v| *v *= factor),
        }
        // Absent sensels stay absent and read 0; an overflow saturates instead of becoming infinite.
        let mask = frame.present();
        for (i, v) in values.iter_mut().enumerate() {
            if mask.is_some_and(|mask| !mask[i]) {
                *v = 0.0;
            } else {
                *v = v.clamp(-f64::MAX, f64::MAX);
            }
        }
        // The grid and mask are the input's: this cannot fail.
        Frame::with_mask(grid, values, mask.map(<[bool]>::to_vec))
            .unwrap_or_else(|_| Frame::zeros(grid))
    }
}

/// `frame` with its absent sensels read as 0 (`None` without a mask: it is used as it is).
fn absent_as_zero(frame: FrameView<'_>) -> Option<Frame> {
    let grid = frame.grid();
    frame.present().map(|mask| {
        let values = frame.values().iter().zip(mask);
        let values = values
            .map(|(&v, &here)| if here { v } else { 0.0 })
            .collect();
        Frame::with_mask(grid, values, Some(mask.to_vec())).unwrap_or_else(|_| Frame::zeros(grid))
    })
}

/// `fraction` of the `len` sensels for which `present` holds, drawn without repeats from `rng`.
fn random_sensels(
    fraction: f64,
    len: usize,
    present: &dyn Fn(usize) -> bool,
    rng: &mut ChaCha8Rng,
) -> Vec<usize> {
    let mut cells: Vec<usize> = (0..len).filter(|&i| present(i)).collect();
    let count = ((fraction.clamp(0.0, 1.0) * cells.len() as f64).round() as usize).min(cells.len());
    // A partial Fisher-Yates shuffle picks `count` distinct sensels.
    for k in 0..count {
        let j = rng.random_range(k..cells.len());
        cells.swap(k, j);
    }
    cells.truncate(count);
    cells
}

/// Writes `frame` moved by `dr` rows and `dc` columns into `values` (0 where nothing moved in).
fn shift(frame: FrameView<'_>, dr: i64, dc: i64, values: &mut [f64]) {
    let grid = frame.grid();
    values.iter_mut().for_each(|v| *v = 0.0);
    for r in 0..grid.rows {
        for c in 0..grid.cols {
            let (sr, sc) = (r as i64 - dr, c as i64 - dc);
            if (0..grid.rows as i64).contains(&sr) && (0..grid.cols as i64).contains(&sc) {
                values[r * grid.cols + c] = frame.get(sr as usize, sc as usize);
            }
        }
    }
}

/// A standard normal deviate (Box-Muller).
fn normal(rng: &mut ChaCha8Rng) -> f64 {
    let u1: f64 = 1.0 - rng.random::<f64>(); // (0, 1]
    let u2: f64 = rng.random();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// Rotates the image by `degrees` (counter-clockwise with rows growing downwards) about its centre of
/// pressure (the grid's centre for an empty image, or one whose moments overflow), by bilinear
/// interpolation of the source at each output sensel.
fn rotate(frame: FrameView<'_>, degrees: f64, out: &mut [f64]) {
    let Grid { rows, cols } = frame.grid();
    let total = frame.total();
    let (mut cr, mut cc) = ((rows as f64 - 1.0) / 2.0, (cols as f64 - 1.0) / 2.0);
    if total > 0.0 {
        let (mut sr, mut sc) = (0.0, 0.0);
        for r in 0..rows {
            for c in 0..cols {
                let v = frame.get(r, c);
                sr += v * r as f64;
                sc += v * c as f64;
            }
        }
        let (r, c) = (sr / total, sc / total);
        if r.is_finite() && c.is_finite() {
            (cr, cc) = (r, c);
        }
    }
    let (sin, cos) = degrees.to_radians().sin_cos();
    let sample = |r: f64, c: f64| -> f64 {
        if r < 0.0 || c < 0.0 || r > (rows - 1) as f64 || c > (cols - 1) as f64 {
            return 0.0;
        }
        let (r0, c0) = (r.floor() as usize, c.floor() as usize);
        let (r1, c1) = ((r0 + 1).min(rows - 1), (c0 + 1).min(cols - 1));
        let (fr, fc) = (r - r0 as f64, c - c0 as f64);
        let top = frame.get(r0, c0) * (1.0 - fc) + frame.get(r0, c1) * fc;
        let bottom = frame.get(r1, c0) * (1.0 - fc) + frame.get(r1, c1) * fc;
        top * (1.0 - fr) + bottom * fr
    };
    for r in 0..rows {
        for c in 0..cols {
            // The inverse rotation finds where this output sensel comes from.
            let (dr, dc) = (r as f64 - cr, c as f64 - cc);
            let sr = cr + cos * dr - sin * dc;
            let sc = cc + sin * dr + cos * dc;
            out[r * cols + c] = sample(sr, sc);
        }
    }
}

/// A level as a user would write it: plain decimals (`0.5`, `1`), but exponent form where the plain one
/// would run to dozens of digits (`1e308`, not 309 digits). Parses back to the same value either way.
struct Level(f64);

impl fmt::Display for Level {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let magnitude = self.0.abs();
        if magnitude != 0.0 && !(1e-6..1e16).contains(&magnitude) {
            write!(f, "{:e}", self.0)
        } else {
            write!(f, "{}", self.0)
        }
    }
}

impl fmt::Display for Perturbation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Dead(x) | Self::Stuck(x) | Self::Gain(x) | Self::Noise(x) | Self::Rotate(x) => {
                write!(f, "{}={}", self.kind(), Level(x))
            }
            Self::Shift(r, c) => write!(f, "shift={r},{c}"),
            Self::Load(x) => write!(f, "load={}", Level(x)),
        }
    }
}

impl FromStr for Perturbation {
    type Err = CoreError;

    fn from_str(text: &str) -> Result<Self> {
        let bad = |reason: String| CoreError::Param {
            name: "perturbation",
            reason,
        };
        let (kind, level) = text.split_once('=').ok_or_else(|| {
            bad(format!(
                "`{text}`: expected KIND=LEVEL with KIND one of dead, stuck, gain, noise, shift, rotate, load"
            ))
        })?;
        let (kind, level) = (kind.trim().to_ascii_lowercase(), level.trim());
        let number = |s: &str| -> Result<f64> {
            s.trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| bad(format!("`{text}`: `{s}` is not a finite number")))
        };
        let fraction = |s: &str| -> Result<f64> {
            let v = match s.strip_suffix('%') {
                Some(p) => number(p)? / 100.0,
                None => number(s)?,
            };
            if (0.0..=1.0).contains(&v) {
                Ok(v)
            } else {
                Err(bad(format!(
                    "`{text}`: the fraction must be between 0 and 1 (or 0% and 100%)"
                )))
            }
        };
        let non_negative = |s: &str| -> Result<f64> {
            let v = number(s)?;
            if v >= 0.0 {
                Ok(v)
            } else {
                Err(bad(format!(
                    "`{text}`: the standard deviation must not be negative"
                )))
            }
        };
        let whole = |s: &str| -> Result<i64> {
            s.trim()
                .parse::<i64>()
                .ok()
                .filter(|v| v.abs() <= 10_000)
                .ok_or_else(|| bad(format!("`{text}`: `{s}` is not a whole number of sensels")))
        };
        Ok(match kind.as_str() {
            "dead" => Self::Dead(fraction(level)?),
            "stuck" => Self::Stuck(fraction(level)?),
            "gain" => Self::Gain(non_negative(level)?),
            "noise" => Self::Noise(non_negative(level)?),
            "shift" => match level.split_once(',') {
                Some((r, c)) => Self::Shift(whole(r)?, whole(c)?),
                None => Self::Shift(whole(level)?, 0),
            },
            "rotate" => Self::Rotate(number(level)?),
            "load" => {
                let factor = match level.strip_suffix('%') {
                    Some(p) => 1.0 + number(p)? / 100.0,
                    None => number(level)?,
                };
                if factor <= 0.0 {
                    return Err(bad(format!("`{text}`: the load factor must be positive")));
                }
                Self::Load(factor)
            }
            other => {
                return Err(bad(format!(
                    "`{text}`: unknown kind `{other}`; expected dead, stuck, gain, noise, shift, rotate or load"
                )));
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp(grid: Grid) -> Frame {
        Frame::new(
            grid,
            (0..grid.len()).map(|i| (i % 13) as f64 + 1.0).collect(),
        )
        .unwrap()
    }

    #[test]
    fn random_sensels_are_distinct_present_and_the_fraction() {
        let present = |i: usize| i % 3 != 0;
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let cells = random_sensels(0.25, 120, &present, &mut rng);
        assert_eq!(cells.len(), 20, "a quarter of the 80 present sensels");
        let mut distinct = cells.clone();
        distinct.sort_unstable();
        distinct.dedup();
        assert_eq!(distinct.len(), cells.len());
        assert!(cells.iter().all(|&i| present(i)));
        assert_eq!(random_sensels(2.0, 120, &present, &mut rng).len(), 80);
        assert!(random_sensels(0.0, 120, &present, &mut rng).is_empty());
    }

    #[test]
    fn shift_moves_the_image_and_fills_with_zero() {
        let grid = Grid::new(3, 4);
        let frame = ramp(grid);
        let mut values = vec![9.0; grid.len()];
        shift(frame.view(), 1, -1, &mut values);
        for r in 0..3 {
            for c in 0..4 {
                let expected = if r >= 1 && c + 1 < 4 {
                    frame.view().get(r - 1, c + 1)
                } else {
                    0.0
                };
                assert_eq!(values[r * 4 + c], expected, "({r}, {c})");
            }
        }
    }

    #[test]
    fn parses_every_kind_and_rejects_nonsense() {
        let p = |t: &str| t.parse::<Perturbation>();
        assert_eq!(p("dead=0.05").unwrap(), Perturbation::Dead(0.05));
        assert_eq!(p("dead=5%").unwrap(), Perturbation::Dead(0.05));
        assert_eq!(p("Stuck=0.01").unwrap(), Perturbation::Stuck(0.01));
        assert_eq!(p("gain=0.2").unwrap(), Perturbation::Gain(0.2));
        assert_eq!(p("noise=3").unwrap(), Perturbation::Noise(3.0));
        assert_eq!(p("shift=2,-1").unwrap(), Perturbation::Shift(2, -1));
        assert_eq!(p("shift=3").unwrap(), Perturbation::Shift(3, 0));
        assert_eq!(p("rotate=-15").unwrap(), Perturbation::Rotate(-15.0));
        assert_eq!(p("load=1.5").unwrap(), Perturbation::Load(1.5));
        assert_eq!(p("load=-50%").unwrap(), Perturbation::Load(0.5));
        assert_eq!(p("load=+50%").unwrap(), Perturbation::Load(1.5));
        for bad in [
            "dead",
            "dead=2",
            "dead=-0.1",
            "noise=-1",
            "noise=nan",
            "load=0",
            "load=-200%",
            "shift=1.5",
            "rotate=inf",
            "warp=3",
            "=",
        ] {
            let err = p(bad).unwrap_err().to_string();
            assert!(err.contains("perturbation"), "{bad}: {err}");
        }
        for text in [
            "dead=0.05",
            "shift=2,-1",
            "load=0.5",
            "rotate=10",
            "load=1e308",
            "noise=1e-7",
        ] {
            assert_eq!(p(text).unwrap().to_string(), text);
        }
    }

    #[test]
    fn dead_and_stuck_hit_the_same_sensels_in_every_image() {
        let grid = Grid::new(10, 8);
        let frame = ramp(grid);
        let dead = Perturbation::Dead(0.1);
        let a = dead.apply(frame.view(), 7, 0);
        let b = dead.apply(frame.view(), 7, 99);
        assert_eq!(a, b);
        let zeros: Vec<usize> = (0..grid.len()).filter(|&i| a.values()[i] == 0.0).collect();
        assert_eq!(zeros.len(), 8); // 10 % of 80
        let c = dead.apply(frame.view(), 8, 0);
        assert_ne!(a, c, "another seed picks other sensels");
        let stuck = Perturbation::Stuck(0.05).apply(frame.view(), 7, 0);
        let high = stuck.values().iter().filter(|&&v| v == 13.0).count();
        let before = frame.values().iter().filter(|&&v| v == 13.0).count();
        assert!(high > before && high <= before + 4, "{high} vs {before}");
    }

    #[test]
    fn level_zero_is_the_identity() {
        let frame = ramp(Grid::new(6, 5));
        for p in [
            Perturbation::Dead(0.0),
            Perturbation::Stuck(0.0),
            Perturbation::Gain(0.0),
            Perturbation::Noise(0.0),
            Perturbation::Shift(0, 0),
            Perturbation::Rotate(0.0),
            Perturbation::Load(1.0),
        ] {
            let out = p.apply(frame.view(), 3, 1);
            for (x, y) in out.values().iter().zip(frame.values()) {
                assert!((x - y).abs() < 1e-9, "{p}: {x} vs {y}");
            }
        }
    }

    #[test]
    fn noise_varies_per_image_and_is_reproducible() {
        let frame = ramp(Grid::new(20, 20));
        let noise = Perturbation::Noise(2.0);
        let a = noise.apply(frame.view(), 1, 0);
        assert_eq!(a, noise.apply(frame.view(), 1, 0));
        assert_ne!(a, noise.apply(frame.view(), 1, 1));
        let diffs: Vec<f64> = a
            .values()
            .iter()
            .zip(frame.values())
            .map(|(x, y)| x - y)
            .collect();
        let sd = (diffs.iter().map(|d| d * d).sum::<f64>() / diffs.len() as f64).sqrt();
        assert!((1.6..2.4).contains(&sd), "noise sd {sd}");
        assert!(a.values().iter().all(|&v| v >= 0.0));
    }

    #[test]
    fn shift_rotate_and_load_move_and_scale_the_print() {
        let grid = Grid::new(9, 9);
        let mut values = vec![0.0; 81];
        values[4 * 9 + 4] = 10.0; // the centre
        values[2 * 9 + 4] = 5.0; // two rows above it
        let frame = Frame::new(grid, values).unwrap();
        let shifted = Perturbation::Shift(1, -2).apply(frame.view(), 0, 0);
        assert_eq!(shifted.view().get(5, 2), 10.0);
        assert_eq!(shifted.view().get(3, 2), 5.0);
        assert_eq!(shifted.view().total(), 15.0);
        // A quarter turn about the centre of pressure (row 4 - 10/15*... = 3.33, col 4).
        let turned = Perturbation::Rotate(90.0).apply(frame.view(), 0, 0);
        let t = turned.view();
        let (mut best, mut at) = (0.0, (0, 0));
        for r in 0..9 {
            for c in 0..9 {
                if t.get(r, c) > best {
                    (best, at) = (t.get(r, c), (r, c));
                }
            }
        }
        // The heaviest point stays on the centre row band but moves off the centre column.
        assert!(at.1 != 4 && at.0.abs_diff(3) <= 1, "{at:?}");
        assert!((t.total() - 15.0).abs() < 5.0, "{}", t.total());
        let heavier = Perturbation::Load(1.5).apply(frame.view(), 0, 0);
        assert_eq!(heavier.view().total(), 22.5);
    }

    #[test]
    fn values_stay_finite() {
        let frame = ramp(Grid::new(6, 5));
        for p in [
            Perturbation::Load(1e308),
            Perturbation::Gain(1e308),
            Perturbation::Noise(1e308),
        ] {
            let out = p.apply(frame.view(), 3, 1);
            assert!(out.values().iter().all(|v| v.is_finite()), "{p}: {out:?}");
        }
        let out = Perturbation::Load(1e308).apply(frame.view(), 0, 0);
        for (&v, &x) in out.values().iter().zip(frame.values()) {
            // 1 x 1e308 fits; 2 x 1e308 and more saturate.
            assert_eq!(v, if x < 1.5 { 1e308 } else { f64::MAX });
        }
        let big = Frame::new(Grid::new(3, 3), vec![f64::MAX; 9]).unwrap();
        for p in [Perturbation::Rotate(30.0), Perturbation::Stuck(0.5)] {
            let out = p.apply(big.view(), 0, 0);
            assert!(out.values().iter().all(|v| v.is_finite()), "{p}: {out:?}");
        }
    }

    #[test]
    fn what_a_view_holds_at_absent_sensels_is_read_as_zero() {
        let grid = Grid::new(5, 5);
        let mask: Vec<bool> = (0..25).map(|i| i % 5 != 4).collect();
        let clean: Vec<f64> = (0..25)
            .map(|i| if i % 5 == 4 { 0.0 } else { (i % 7) as f64 })
            .collect();
        let mut dirty = clean.clone();
        for i in (4..25).step_by(5) {
            dirty[i] = 1000.0;
        }
        let clean = FrameView::new(grid, &clean, Some(&mask)).unwrap();
        let dirty = FrameView::new(grid, &dirty, Some(&mask)).unwrap();
        for p in [
            Perturbation::Rotate(20.0),
            Perturbation::Stuck(0.2),
            Perturbation::Shift(0, -1),
        ] {
            assert_eq!(p.apply(dirty, 1, 0), p.apply(clean, 1, 0), "{p}");
        }
    }

    #[test]
    fn absent_sensels_stay_absent() {
        let grid = Grid::new(3, 3);
        let mask = vec![true, true, false, true, true, true, false, true, true];
        let frame = Frame::with_mask(grid, vec![1.0; 9], Some(mask.clone())).unwrap();
        for p in [
            Perturbation::Noise(5.0),
            Perturbation::Stuck(1.0),
            Perturbation::Shift(1, 1),
        ] {
            let out = p.apply(frame.view(), 2, 0);
            assert_eq!(out.present(), Some(&mask[..]));
            assert_eq!(out.values()[2], 0.0);
            assert_eq!(out.values()[6], 0.0);
        }
    }
}
