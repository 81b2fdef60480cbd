//! Every parameter of the simulator, with defaults, overridable from a JSON file (partial documents are
//! fine: missing fields keep their defaults).

use serde::{Deserialize, Serialize};

use crate::error::{Result, param};
use crate::ode::IntegratorParams;
use crate::sensor::SensorParams;
use crate::skin::{FootParams, SkinParams};
use crate::slip::{Gait, RobotParams};
use crate::terrain::{CarpetParams, ClayParams, GrassParams, ImageTerrainParams, WoodParams};

/// The four terrains of the paper and the defaults for image terrains.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, Default)]
#[serde(default, deny_unknown_fields)]
pub struct TerrainSet {
    pub wood: WoodParams,
    pub carpet: CarpetParams,
    pub clay: ClayParams,
    pub grass: GrassParams,
    pub image: ImageTerrainParams,
}

/// The knobs that decide how hard the data set is. The experiment calibrates them; defaults are modest.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RealismParams {
    /// Additive Gaussian noise of each reading, raw counts (standard deviation).
    pub sensor_noise_counts: f64,
    /// Readings at or below this many counts are reported as 0 (TekScan's noise threshold).
    pub noise_threshold_counts: f64,
    /// Relative standard deviation of the per-sensel gain (calibration spread of the array).
    pub gain_spread: f64,
    /// Fraction of sensels that read 0 whatever the pressure.
    pub dead_sensel_fraction: f64,
    /// Scales the hop-to-hop variation of each terrain's dimensions (0: none, 1: default).
    pub terrain_variability: f64,
    /// Standard deviation of the touchdown-angle actuation error, rad (varies load and CoP per hop).
    pub touchdown_angle_noise_rad: f64,
    /// Standard deviation of the lateral centre of pressure per hop, m (boom roll, foot camber).
    pub lateral_cop_sd_m: f64,
    /// Standard deviation of a fore-aft offset of the centre of pressure per hop, m (ankle preload).
    pub foreaft_cop_sd_m: f64,
}

impl Default for RealismParams {
    fn default() -> Self {
        Self {
            sensor_noise_counts: 1.0,
            noise_threshold_counts: 3.0,
            gain_spread: 0.05,
            dead_sensel_fraction: 0.0,
            terrain_variability: 1.0,
            touchdown_angle_noise_rad: 0.005,
            // Calibrated so that the paper's protocol gives the paper's Table II (docs/reproducing.md,
            // "Calibration of the simulator"): a few millimetres of hop-to-hop foot placement on the
            // 48 x 52 mm foot.
            lateral_cop_sd_m: 3.0e-3,
            foreaft_cop_sd_m: 2.2e-3,
        }
    }
}

/// The experiment: which trials to run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ExperimentParams {
    /// Recorded hops (stance images) per terrain for each gait. The paper has over 300 images per gait
    /// over four terrains (961 in all): 80 per terrain and gait gives 320 per gait, 960 in all.
    pub hops_per_gait: usize,
    /// Recorded hops per trial (one TekScan movie per trial).
    pub hops_per_trial: usize,
    /// Diameter of the circular track, m (paper: 2.8 m). Reported with the distance each trial covers.
    pub track_diameter_m: f64,
    /// Attempts at a trial whose hopper falls before giving up (each with a new seed).
    pub max_attempts: usize,
}

impl Default for ExperimentParams {
    fn default() -> Self {
        Self {
            hops_per_gait: 80,
            hops_per_trial: 20,
            track_diameter_m: 2.8,
            max_attempts: 8,
        }
    }
}

/// The complete configuration of the simulator.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimConfig {
    pub robot: RobotParams,
    /// The gaits `G(omega, beta_des)`; `phi` and `c` are in `robot`.
    pub gaits: Vec<Gait>,
    pub terrains: TerrainSet,
    pub foot: FootParams,
    pub skin: SkinParams,
    pub sensor: SensorParams,
    pub realism: RealismParams,
    pub experiment: ExperimentParams,
    pub integrator: IntegratorParams,
}

impl Default for SimConfig {
    fn default() -> Self {
        Self {
            robot: RobotParams::default(),
            gaits: Gait::paper(),
            terrains: TerrainSet::default(),
            foot: FootParams::default(),
            skin: SkinParams::default(),
            sensor: SensorParams::default(),
            realism: RealismParams::default(),
            experiment: ExperimentParams::default(),
            integrator: IntegratorParams::default(),
        }
    }
}

impl SimConfig {
    /// Parses a (partial) JSON document of overrides on top of the defaults.
    pub fn from_json(text: &str) -> Result<Self> {
        let cfg: Self = serde_json::from_str(text).map_err(|e| param("config", e.to_string()))?;
        cfg.validate()?;
        Ok(cfg)
    }

    pub fn to_json_pretty(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    pub fn validate(&self) -> Result<()> {
        self.robot.validate()?;
        self.skin.validate()?;
        if self.gaits.is_empty() {
            return Err(param("gaits", "need at least one gait"));
        }
        let r = &self.realism;
        for (name, v) in [
            ("realism.sensor_noise_counts", r.sensor_noise_counts),
            ("realism.noise_threshold_counts", r.noise_threshold_counts),
            ("realism.gain_spread", r.gain_spread),
            ("realism.terrain_variability", r.terrain_variability),
            (
                "realism.touchdown_angle_noise_rad",
                r.touchdown_angle_noise_rad,
            ),
            ("realism.lateral_cop_sd_m", r.lateral_cop_sd_m),
            ("realism.foreaft_cop_sd_m", r.foreaft_cop_sd_m),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(param(name, format!("must be >= 0, got {v}")));
            }
        }
        if self.experiment.hops_per_trial == 0 {
            return Err(param("experiment.hops_per_trial", "must be at least 1"));
        }
        Ok(())
    }
}
