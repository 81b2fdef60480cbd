//! The TekScan #5051 sensor and its acquisition: pressure -> 8-bit raw counts (paper, section II).

use rand::Rng;
use rand_distr::{Distribution, Normal};
use serde::{Deserialize, Serialize};

use crate::error::{Result, param};

/// Fixed properties of the sensor (datasheet values quoted by the paper).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SensorParams {
    /// TekScan model written in the movie header.
    pub model: String,
    /// Pressure at full scale, Pa (0-138 kPa).
    pub full_scale_pa: f64,
    /// Raw count at full scale (8-bit: 255).
    pub max_count: f64,
    /// Frame period, s (100 Hz).
    pub frame_period_s: f64,
}

impl Default for SensorParams {
    fn default() -> Self {
        Self {
            model: "5051".into(),
            full_scale_pa: 138e3,
            max_count: 255.0,
            frame_period_s: 0.01,
        }
    }
}

/// Imperfections of the acquisition (realism knobs; see [`crate::config::RealismParams`]).
#[derive(Clone, Debug, PartialEq)]
pub struct SensorFaults {
    pub noise_counts: f64,
    pub threshold_counts: f64,
}

/// One physical sensor: its per-sensel gains and dead sensels are drawn once (the same sensor is used in
/// every trial).
#[derive(Clone, Debug)]
pub struct SensorInstance {
    pub params: SensorParams,
    pub gain: Vec<f64>,
    pub dead: Vec<bool>,
    pub faults: SensorFaults,
}

impl SensorInstance {
    pub fn new<R: Rng + ?Sized>(
        params: SensorParams,
        sensels: usize,
        gain_spread: f64,
        dead_fraction: f64,
        faults: SensorFaults,
        rng: &mut R,
    ) -> Result<Self> {
        if !(params.full_scale_pa > 0.0 && params.max_count > 0.0 && params.frame_period_s > 0.0) {
            return Err(param(
                "sensor",
                "full scale, max count and frame period must be positive",
            ));
        }
        if !(0.0..=1.0).contains(&dead_fraction) {
            return Err(param("realism.dead_sensel_fraction", "must be in [0, 1]"));
        }
        if !(gain_spread >= 0.0 && faults.noise_counts >= 0.0 && faults.threshold_counts >= 0.0) {
            return Err(param(
                "realism",
                "gain spread, noise and threshold must be >= 0",
            ));
        }
        let normal = Normal::new(0.0, gain_spread.max(0.0))
            .map_err(|e| param("realism.gain_spread", e.to_string()))?;
        let gain = (0..sensels)
            .map(|_| (1.0 + normal.sample(rng)).max(0.0))
            .collect();
        let dead = (0..sensels)
            .map(|_| dead_fraction > 0.0 && rng.random::<f64>() < dead_fraction)
            .collect();
        Ok(Self {
            params,
            gain,
            dead,
            faults,
        })
    }

    /// Converts a pressure image (Pa) into raw counts: gain, additive noise, noise threshold (readings at
    /// or below it become 0), saturation at full scale, rounding, dead sensels.
    pub fn counts<R: Rng + ?Sized>(&self, pressure_pa: &[f64], rng: &mut R, out: &mut Vec<f64>) {
        let scale = self.params.max_count / self.params.full_scale_pa;
        let noise = Normal::new(0.0, self.faults.noise_counts).ok();
        out.clear();
        for (i, &p) in pressure_pa.iter().enumerate() {
            let mut c = p * scale * self.gain[i];
            if let Some(n) = &noise
                && self.faults.noise_counts > 0.0
            {
                c += n.sample(rng);
            }
            let c = c.clamp(0.0, self.params.max_count).round();
            let c = if self.dead[i] || c <= self.faults.threshold_counts {
                0.0
            } else {
                c
            };
            out.push(c);
        }
    }
}
