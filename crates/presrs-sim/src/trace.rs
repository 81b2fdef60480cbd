//! A finely sampled trace of a few hops: body position and ground force over time, for figures.
//!
//! [`trace_hops`] reruns a short trial of one terrain and gait (after the usual warm-up hops, without the
//! actuator noise of the data set) with the hopper's frame clock set to `step_s`. The hopper reports the
//! ground force at every sample; the body position between apexes is the integral of that force
//! (trapezoidal rule), pinned to the hopper's exact apex states by spreading the small integration error
//! linearly over each hop. It is a picture of the motion, not a replacement for the data set's truth.

use serde::{Deserialize, Serialize};

use crate::config::SimConfig;
use crate::dataset::Simulator;
use crate::error::{Result, param};
use crate::slip::{ContactState, GRAVITY_M_PER_S2, HopTruth, Hopper};

/// One sample of a [`HopTrace`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TracePoint {
    /// Time since the first traced apex, s.
    pub t_s: f64,
    /// Body position: forward distance since the first traced apex and height above the ground, m.
    pub x_m: f64,
    pub y_m: f64,
    /// Ground reaction force on the foot: normal (vertical) and tangential (forward), N; 0 in flight.
    pub normal_force_n: f64,
    pub tangential_force_n: f64,
    /// Whether the foot is on the ground.
    pub stance: bool,
}

/// A few hops of one terrain and gait, sampled every `step_s`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HopTrace {
    pub terrain: String,
    pub gait: String,
    pub step_s: f64,
    pub points: Vec<TracePoint>,
    /// The hops' truth (times relative to the first traced apex).
    pub hops: Vec<HopTruth>,
}

/// Traces `hops` hops of `gait` on `terrain` (built-in terrain names) every `step_s` seconds.
pub fn trace_hops(
    config: &SimConfig,
    terrain: &str,
    gait: &str,
    hops: usize,
    step_s: f64,
) -> Result<HopTrace> {
    if !(step_s.is_finite() && step_s > 0.0) {
        return Err(param("trace step", "must be a positive number of seconds"));
    }
    if hops == 0 {
        return Err(param("trace hops", "at least one hop is needed"));
    }
    let simulator = Simulator::new(config.clone(), 0, Vec::new())?;
    let ground = simulator.terrain(terrain)?.ground();
    let gait_params = simulator.gait(gait)?;
    let mut hopper = Hopper::new(config.robot.clone(), gait_params, ground, config.integrator)?;
    let mut samples: Vec<ContactState> = Vec::new();
    for i in 0..config.robot.warmup_hops {
        hopper.hop(i, step_s, f64::INFINITY, &mut samples, 0.0)?;
    }
    samples.clear();
    let mass = config.robot.body_mass_kg;
    let t0 = hopper.t_s;
    let x0 = hopper.state[0];
    let mut points = Vec::new();
    let mut truths = Vec::with_capacity(hops);
    for h in 0..hops {
        let (t_start, start) = (hopper.t_s, hopper.state);
        samples.clear();
        let mut truth = hopper.hop(h, step_s, t0, &mut samples, 0.0)?;
        truth.touchdown_time_s -= t0;
        truth.liftoff_time_s -= t0;
        truths.push(truth);
        let (t_end, end) = (hopper.t_s, hopper.state);
        // Integrate the body's motion from the apex through the samples to the next apex.
        let accel = |s: &ContactState| {
            (
                s.tangential_force_n / mass,
                s.normal_force_n / mass - GRAVITY_M_PER_S2,
            )
        };
        let (mut t, mut x, mut y, mut vx, mut vy) =
            (t_start, start[0], start[1], start[2], start[3]);
        let mut a = (0.0, -GRAVITY_M_PER_S2);
        let mut hop_points = Vec::with_capacity(samples.len() + 2);
        hop_points.push((t, x, y, None::<ContactState>));
        let flight_end = ContactState {
            t_s: t_end,
            stance_of_hop: None,
            normal_force_n: 0.0,
            tangential_force_n: 0.0,
            leg_angle_rad: 0.0,
        };
        for s in samples.iter().chain(std::iter::once(&flight_end)) {
            let dt = s.t_s - t;
            if dt <= 0.0 {
                continue;
            }
            let a1 = accel(s);
            let (vx1, vy1) = (vx + 0.5 * (a.0 + a1.0) * dt, vy + 0.5 * (a.1 + a1.1) * dt);
            x += 0.5 * (vx + vx1) * dt;
            y += 0.5 * (vy + vy1) * dt;
            (t, vx, vy, a) = (s.t_s, vx1, vy1, a1);
            hop_points.push((t, x, y, Some(*s)));
        }
        // Pin the end to the exact apex: spread the error linearly in time.
        let span = (t_end - t_start).max(f64::EPSILON);
        let (ex, ey) = (end[0] - x, end[1] - y);
        for (i, (tp, xp, yp, sample)) in hop_points.into_iter().enumerate() {
            // The hop's first point is the previous hop's last (except for the first hop).
            if i == 0 && h > 0 {
                continue;
            }
            let w = (tp - t_start) / span;
            let sample = sample.filter(|s| s.stance_of_hop.is_some());
            points.push(TracePoint {
                t_s: tp - t0,
                x_m: xp + w * ex - x0,
                y_m: yp + w * ey,
                normal_force_n: sample.map_or(0.0, |s| s.normal_force_n),
                tangential_force_n: sample.map_or(0.0, |s| s.tangential_force_n),
                stance: sample.is_some(),
            });
        }
    }
    Ok(HopTrace {
        terrain: terrain.to_owned(),
        gait: gait.to_owned(),
        step_s,
        points,
        hops: truths,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trace_moves_forward_and_carries_the_weight() {
        let config = SimConfig::default();
        let trace = trace_hops(&config, "wood", "G2", 3, 1e-3).unwrap();
        assert_eq!(trace.hops.len(), 3);
        let last = trace.points.last().unwrap();
        assert!(last.x_m > 0.3, "forward distance {}", last.x_m);
        assert!(trace.points.iter().all(|p| p.y_m > 0.0));
        assert!(trace.points.windows(2).all(|w| w[1].t_s > w[0].t_s));
        // Over whole hops the mean normal force balances the weight.
        let mean_force =
            trace.points.iter().map(|p| p.normal_force_n).sum::<f64>() / trace.points.len() as f64;
        let weight = config.robot.body_mass_kg * GRAVITY_M_PER_S2;
        assert!(
            (mean_force / weight - 1.0).abs() < 0.1,
            "{mean_force} vs {weight}"
        );
        assert!(trace.points.iter().any(|p| p.stance));
    }
}
