//! Dormand–Prince 5(4) integration with adaptive steps and exact event location.
//!
//! Events are located by root finding (Illinois variant of regula falsi) on the event function evaluated
//! at the state reached by *one* Dormand–Prince step of trial length from the start of the step in which
//! the sign change was detected, so the event state has the accuracy of the integrator itself, not of an
//! interpolant and not of the step grid.

use crate::error::{Result, SimError};

/// Tolerances and step limits.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct IntegratorParams {
    /// Relative tolerance of the local error.
    pub rel_tol: f64,
    /// Absolute tolerance of the local error (state units: m, m/s).
    pub abs_tol: f64,
    /// Largest step, s. Bounds how long an event can hide between two steps.
    pub max_step_s: f64,
    /// Smallest step before giving up, s.
    pub min_step_s: f64,
    /// Event time tolerance, s.
    pub event_tol_s: f64,
}

impl Default for IntegratorParams {
    fn default() -> Self {
        Self {
            rel_tol: 1e-9,
            abs_tol: 1e-11,
            max_step_s: 2e-3,
            min_step_s: 1e-12,
            event_tol_s: 1e-13,
        }
    }
}

// Dormand & Prince (1980) coefficients.
const C2: f64 = 1.0 / 5.0;
const C3: f64 = 3.0 / 10.0;
const C4: f64 = 4.0 / 5.0;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const B1: f64 = 35.0 / 384.0;
const B3: f64 = 500.0 / 1113.0;
const B4: f64 = 125.0 / 192.0;
const B5: f64 = -2187.0 / 6784.0;
const B6: f64 = 11.0 / 84.0;
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;

fn axpy<const N: usize>(y: &[f64; N], h: f64, terms: &[(f64, &[f64; N])]) -> [f64; N] {
    let mut out = *y;
    for (i, o) in out.iter_mut().enumerate() {
        let mut acc = 0.0;
        for (coef, k) in terms {
            acc += coef * k[i];
        }
        *o += h * acc;
    }
    out
}

/// One Dormand–Prince step of length `h`: the 5th-order solution and the local error estimate.
pub fn dopri_step<const N: usize, F>(f: &F, t: f64, y: &[f64; N], h: f64) -> ([f64; N], [f64; N])
where
    F: Fn(f64, &[f64; N]) -> [f64; N],
{
    let k1 = f(t, y);
    let k2 = f(t + C2 * h, &axpy(y, h, &[(A21, &k1)]));
    let k3 = f(t + C3 * h, &axpy(y, h, &[(A31, &k1), (A32, &k2)]));
    let k4 = f(
        t + C4 * h,
        &axpy(y, h, &[(A41, &k1), (A42, &k2), (A43, &k3)]),
    );
    let k5 = f(
        t + C5 * h,
        &axpy(y, h, &[(A51, &k1), (A52, &k2), (A53, &k3), (A54, &k4)]),
    );
    let k6 = f(
        t + h,
        &axpy(
            y,
            h,
            &[(A61, &k1), (A62, &k2), (A63, &k3), (A64, &k4), (A65, &k5)],
        ),
    );
    let y_new = axpy(
        y,
        h,
        &[(B1, &k1), (B3, &k3), (B4, &k4), (B5, &k5), (B6, &k6)],
    );
    let k7 = f(t + h, &y_new);
    let mut err = [0.0; N];
    for i in 0..N {
        err[i] = h * (E1 * k1[i] + E3 * k3[i] + E4 * k4[i] + E5 * k5[i] + E6 * k6[i] + E7 * k7[i]);
    }
    (y_new, err)
}

/// Why [`Integrator::advance`] returned.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stop {
    /// Reached the requested end time.
    Time,
    /// The event function crossed zero upwards (from negative to non-negative).
    Event,
}

/// An adaptive Dormand–Prince integrator that remembers its step size between calls.
#[derive(Clone, Debug)]
pub struct Integrator {
    pub params: IntegratorParams,
    h: f64,
    /// Accepted steps so far (for tests and diagnostics).
    pub steps: usize,
}

impl Integrator {
    pub fn new(params: IntegratorParams) -> Self {
        Self {
            h: params.max_step_s * 0.1,
            params,
            steps: 0,
        }
    }

    fn error_norm<const N: usize>(&self, y: &[f64; N], y_new: &[f64; N], err: &[f64; N]) -> f64 {
        let mut sum = 0.0;
        for i in 0..N {
            let scale = self.params.abs_tol + self.params.rel_tol * y[i].abs().max(y_new[i].abs());
            sum += (err[i] / scale).powi(2);
        }
        (sum / N as f64).sqrt()
    }

    /// Integrates `y' = f(t, y)` from `(t, y)` until `t_end` or until `event(t, y)` crosses zero upwards,
    /// whichever comes first. Updates `t` and `y` in place.
    pub fn advance<const N: usize, F, G>(
        &mut self,
        f: &F,
        event: &G,
        t: &mut f64,
        y: &mut [f64; N],
        t_end: f64,
    ) -> Result<Stop>
    where
        F: Fn(f64, &[f64; N]) -> [f64; N],
        G: Fn(f64, &[f64; N]) -> f64,
    {
        let p = self.params;
        while *t < t_end {
            let remaining = t_end - *t;
            let mut h = self.h.min(p.max_step_s);
            let last = h >= remaining;
            if last {
                h = remaining;
            }
            let (y_new, err) = dopri_step(f, *t, y, h);
            let norm = self.error_norm(y, &y_new, &err);
            if !norm.is_finite() {
                self.h = h * 0.25;
                if self.h < p.min_step_s {
                    return Err(SimError::Integrator {
                        t_s: *t,
                        reason: "non-finite state".into(),
                    });
                }
                continue;
            }
            let factor = if norm == 0.0 {
                5.0
            } else {
                (0.9 * norm.powf(-0.2)).clamp(0.2, 5.0)
            };
            if norm > 1.0 {
                self.h = h * factor.min(1.0);
                if self.h < p.min_step_s {
                    return Err(SimError::Integrator {
                        t_s: *t,
                        reason: format!("step size underflow (error norm {norm:.3e})"),
                    });
                }
                continue;
            }
            // Accepted. Only grow the remembered step if this was not a truncated final step.
            if !last {
                self.h = h * factor;
            }
            self.steps += 1;
            let g0 = event(*t, y);
            let t_new = if last { t_end } else { *t + h };
            let g1 = event(t_new, &y_new);
            if g0 < 0.0 && g1 >= 0.0 {
                let (tau, y_ev) = self.locate(f, event, *t, y, h, g0, g1);
                *t += tau;
                *y = y_ev;
                return Ok(Stop::Event);
            }
            *t = t_new;
            *y = y_new;
        }
        Ok(Stop::Time)
    }

    /// Root of `event` inside the step `(t, t + h]` by the Illinois method; each trial point is reached by
    /// a fresh Dormand–Prince step from `(t, y)`.
    #[allow(clippy::too_many_arguments)]
    fn locate<const N: usize, F, G>(
        &self,
        f: &F,
        event: &G,
        t: f64,
        y: &[f64; N],
        h: f64,
        g0: f64,
        g1: f64,
    ) -> (f64, [f64; N])
    where
        F: Fn(f64, &[f64; N]) -> [f64; N],
        G: Fn(f64, &[f64; N]) -> f64,
    {
        let (mut a, mut ga) = (0.0_f64, g0);
        let (mut b, mut gb) = (h, g1);
        let mut side = 0i8;
        let mut best = (h, dopri_step(f, t, y, h).0);
        for _ in 0..200 {
            if (b - a).abs() <= self.params.event_tol_s {
                break;
            }
            let mut c = (a * gb - b * ga) / (gb - ga);
            if !(c > a && c < b) {
                c = 0.5 * (a + b);
            }
            let yc = dopri_step(f, t, y, c).0;
            let gc = event(t + c, &yc);
            if gc >= 0.0 {
                best = (c, yc);
                b = c;
                gb = gc;
                if side == 1 {
                    ga *= 0.5;
                }
                side = 1;
            } else {
                a = c;
                ga = gc;
                if side == -1 {
                    gb *= 0.5;
                }
                side = -1;
            }
            if gc == 0.0 {
                break;
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn harmonic_oscillator_is_accurate() {
        // x'' = -x: x = cos t.
        let f = |_t: f64, y: &[f64; 2]| [y[1], -y[0]];
        let never = |_t: f64, _y: &[f64; 2]| -1.0;
        let mut integ = Integrator::new(IntegratorParams::default());
        let (mut t, mut y) = (0.0, [1.0, 0.0]);
        assert_eq!(
            integ.advance(&f, &never, &mut t, &mut y, 10.0).unwrap(),
            Stop::Time
        );
        assert!((y[0] - 10f64.cos()).abs() < 1e-8, "{}", y[0]);
        assert!((y[1] + 10f64.sin()).abs() < 1e-8);
    }

    #[test]
    fn event_is_located_exactly() {
        // x'' = -x from x = 1: first upward crossing of -x through zero at t = pi/2.
        let f = |_t: f64, y: &[f64; 2]| [y[1], -y[0]];
        let event = |_t: f64, y: &[f64; 2]| -y[0];
        let mut integ = Integrator::new(IntegratorParams::default());
        let (mut t, mut y) = (0.0, [1.0, 0.0]);
        assert_eq!(
            integ.advance(&f, &event, &mut t, &mut y, 10.0).unwrap(),
            Stop::Event
        );
        assert!((t - std::f64::consts::FRAC_PI_2).abs() < 1e-9, "{t}");
        assert!(y[0].abs() < 1e-9);
    }
}
