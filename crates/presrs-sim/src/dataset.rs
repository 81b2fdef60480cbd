//! The data set: trials (one TekScan movie each) over terrains x gaits, simulated in parallel.
//!
//! Every random choice comes from a ChaCha8 generator seeded from the master seed and the trial's
//! identity (terrain name, gait name, trial index), so the result does not depend on thread scheduling:
//! the same seed gives the same recordings, byte for byte once written.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use presrs_core::{Grid, PressureUnit, Recording, SensorMeta};

use crate::config::SimConfig;
use crate::error::{Result, SimError, param};
use crate::sensor::{SensorFaults, SensorInstance};
use crate::skin::Foot;
use crate::slip::{ContactState, Gait, HopTruth, Hopper};
use crate::terrain::{HeightMap, Terrain};

/// The paper's Table I: average forward velocity (m/s) per gait (rows G1-G3) and terrain
/// (wood, carpet, clay, grass).
pub const PAPER_TABLE1: [[f64; 4]; 3] = [
    [0.40, 0.43, 0.38, 0.81],
    [0.64, 0.63, 0.61, 1.11],
    [0.99, 0.97, 0.84, 1.49],
];

/// The four built-in terrains, in the paper's order.
pub const BUILTIN_TERRAINS: [&str; 4] = ["wood", "carpet", "clay", "grass"];

/// What to simulate.
#[derive(Clone, Debug, PartialEq)]
pub struct DatasetSpec {
    pub seed: u64,
    /// Terrain names: built-ins or names of `image_terrains`.
    pub terrains: Vec<String>,
    /// Gait names (from the configuration's gaits).
    pub gaits: Vec<String>,
    /// Recorded hops per terrain and gait (`None`: the configuration's `experiment.hops_per_gait`).
    pub hops_per_gait: Option<usize>,
    /// Body mass including payload, kg (`None`: the configuration's `robot.body_mass_kg`).
    pub load_kg: Option<f64>,
    /// Terrains given as height-map images, by name.
    pub image_terrains: Vec<(String, HeightMap)>,
}

impl DatasetSpec {
    /// The paper's experiment: 4 terrains x 3 gaits.
    pub fn paper(seed: u64) -> Self {
        Self {
            seed,
            terrains: BUILTIN_TERRAINS.iter().map(|s| (*s).to_owned()).collect(),
            gaits: vec!["G1".into(), "G2".into(), "G3".into()],
            hops_per_gait: None,
            load_kg: None,
            image_terrains: Vec::new(),
        }
    }
}

/// One trial to run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrialPlan {
    pub terrain: String,
    pub gait: Gait,
    /// Index of this trial among the trials of its terrain and gait.
    pub index: usize,
    /// Recorded hops.
    pub hops: usize,
    pub seed: u64,
    pub load_kg: f64,
}

impl TrialPlan {
    /// `wood_G1_000`: the trial's group name and file stem.
    pub fn name(&self) -> String {
        format!("{}_{}_{:03}", self.terrain, self.gait.name, self.index)
    }
}

/// Ground truth of a recorded hop, with its frames in the movie.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HopRecord {
    /// Dynamics (times relative to the first frame of the movie, which is at t = 0).
    #[serde(flatten)]
    pub truth: HopTruth,
    /// First and last frame (0-based, inclusive) sampled during stance; `None` if the stance fell
    /// between two frames.
    pub first_stance_frame: Option<usize>,
    pub last_stance_frame: Option<usize>,
    /// The paper's sample: the middle stance frame (the 7th of 13 or 14).
    pub mid_stance_frame: Option<usize>,
    /// Normal force of the dynamics at each stance frame, N.
    pub frame_normal_force_n: Vec<f64>,
    /// Tangential force at each stance frame, N.
    pub frame_tangential_force_n: Vec<f64>,
    /// Force recovered from the unquantised pressure image at each stance frame, N.
    pub frame_image_force_n: Vec<f64>,
    /// Centre of pressure asked of the contact model at each stance frame (forward, left), m.
    pub frame_cop_m: Vec<(f64, f64)>,
}

/// A simulated trial: one continuous movie through flight and stance, and its truth.
#[derive(Clone, Debug)]
pub struct TrialOutput {
    pub plan: TrialPlan,
    pub recording: Recording,
    pub hops: Vec<HopRecord>,
    /// Attempts it took (the hopper may fall on an unlucky seed; the trial is then rerun).
    pub attempts: usize,
}

impl TrialOutput {
    /// Mean forward velocity over the recorded hops, m/s.
    pub fn mean_velocity_m_per_s(&self) -> f64 {
        mean(
            self.hops
                .iter()
                .map(|h| h.truth.mean_forward_velocity_m_per_s),
        )
    }
}

fn mean(values: impl Iterator<Item = f64>) -> f64 {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    if n == 0 { f64::NAN } else { sum / n as f64 }
}

/// SplitMix64 step: a well-mixed 64-bit value from a 64-bit input.
fn splitmix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// FNV-1a hash of a name (stable across platforms and versions).
fn fnv(text: &str) -> u64 {
    text.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// The seed of one trial attempt, from the master seed and the trial's identity.
pub fn trial_seed(master: u64, terrain: &str, gait: &str, index: usize, attempt: usize) -> u64 {
    let mut z = splitmix(master);
    z = splitmix(z ^ fnv(terrain));
    z = splitmix(z ^ fnv(gait).rotate_left(17));
    z = splitmix(z ^ (index as u64).wrapping_mul(0xA24B_AED4_963E_E407));
    splitmix(z ^ (attempt as u64).wrapping_mul(0x9FB2_1C65_1E98_DF25))
}

/// Everything shared by the trials of a data set.
#[derive(Debug)]
pub struct Simulator {
    pub config: SimConfig,
    pub foot: Foot,
    pub sensor: SensorInstance,
    images: Vec<(String, HeightMap)>,
}

impl Simulator {
    /// Builds the foot and draws the sensor (gains, dead sensels) from the master seed.
    ///
    /// Every image terrain needs a name of its own: not empty, not a built-in terrain's (the built-in
    /// would always be the one simulated), not another image's.
    pub fn new(config: SimConfig, seed: u64, images: Vec<(String, HeightMap)>) -> Result<Self> {
        config.validate()?;
        for (i, (name, _)) in images.iter().enumerate() {
            if name.trim().is_empty() {
                return Err(param("image_terrains", "a height-map terrain has no name"));
            }
            if BUILTIN_TERRAINS.contains(&name.as_str()) {
                return Err(param(
                    "image_terrains",
                    format!(
                        "the height-map terrain {name:?} has the name of a built-in terrain; give it \
                         another name"
                    ),
                ));
            }
            if images[..i].iter().any(|(other, _)| other == name) {
                return Err(param(
                    "image_terrains",
                    format!("two height-map terrains are called {name:?}"),
                ));
            }
        }
        let foot = Foot::new(config.foot.clone(), &config.skin)?;
        let mut rng = ChaCha8Rng::seed_from_u64(splitmix(seed ^ 0x5E45_0B5E_0000_0001));
        let r = &config.realism;
        let sensor = SensorInstance::new(
            config.sensor.clone(),
            config.foot.rows * config.foot.cols,
            r.gain_spread,
            r.dead_sensel_fraction,
            SensorFaults {
                noise_counts: r.sensor_noise_counts,
                threshold_counts: r.noise_threshold_counts,
            },
            &mut rng,
        )?;
        Ok(Self {
            config,
            foot,
            sensor,
            images,
        })
    }

    /// The terrain called `name`.
    pub fn terrain(&self, name: &str) -> Result<Terrain> {
        let t = &self.config.terrains;
        let terrain = match name {
            "wood" => Terrain::Wood(t.wood.clone()),
            "carpet" => Terrain::Carpet(t.carpet.clone()),
            "clay" => Terrain::Clay(t.clay.clone()),
            "grass" => Terrain::Grass(t.grass.clone()),
            other => match self.images.iter().find(|(n, _)| n == other) {
                Some((_, map)) => Terrain::Image {
                    map: map.clone(),
                    params: t.image.clone(),
                },
                None => {
                    return Err(param(
                        "terrains",
                        format!(
                            "unknown terrain {other:?}; built-in terrains are wood, carpet, clay, grass \
                             (others must be given as height-map images)"
                        ),
                    ));
                }
            },
        };
        terrain.validate(name)?;
        Ok(terrain)
    }

    /// A configured gait by name, or a variant `BASE@BETA` (the configured gait BASE with `beta_des`
    /// = BETA rad, within the robot's touchdown-angle limits).
    pub fn gait(&self, name: &str) -> Result<Gait> {
        if let Some(gait) = self.config.gaits.iter().find(|g| g.name == name) {
            return Ok(gait.clone());
        }
        let known = || {
            let names: Vec<&str> = self.config.gaits.iter().map(|g| g.name.as_str()).collect();
            names.join(", ")
        };
        let Some((base, beta)) = name.split_once(Gait::VARIANT_SEPARATOR) else {
            return Err(param(
                "gaits",
                format!(
                    "unknown gait {name:?}; known: {} (or a variant such as G3@0.62: G3 with beta_des \
                     0.62 rad)",
                    known()
                ),
            ));
        };
        let base_gait = self
            .config
            .gaits
            .iter()
            .find(|g| g.name == base)
            .ok_or_else(|| {
                param(
                    "gaits",
                    format!("{name:?}: unknown base gait {base:?}; known: {}", known()),
                )
            })?;
        let robot = &self.config.robot;
        let beta_des_rad: f64 = beta
            .trim()
            .parse()
            .ok()
            .filter(|b: &f64| {
                b.is_finite()
                    && *b >= robot.min_touchdown_angle_rad
                    && *b <= robot.max_touchdown_angle_rad
            })
            .ok_or_else(|| {
                param(
                    "gaits",
                    format!(
                        "{name:?}: beta_des {beta:?} must be a number of radians in [{}, {}]",
                        robot.min_touchdown_angle_rad, robot.max_touchdown_angle_rad
                    ),
                )
            })?;
        Ok(Gait::new(name, base_gait.omega_rad_per_s, beta_des_rad))
    }

    /// The trials of a data set, in a fixed order (terrain, gait, index).
    ///
    /// A data set has at least one terrain, gait and hop per terrain and gait, and names each terrain and
    /// gait once: a repeated one would give two trials of the same name (one movie overwriting the other)
    /// and the same images twice in the manifest, where they could be both trained on and tested.
    pub fn plan(&self, spec: &DatasetSpec) -> Result<Vec<TrialPlan>> {
        let hops = spec
            .hops_per_gait
            .unwrap_or(self.config.experiment.hops_per_gait);
        if hops == 0 {
            return Err(param(
                "hops_per_gait",
                "must be at least 1 (a data set without hops has no images)",
            ));
        }
        for (what, names) in [("terrains", &spec.terrains), ("gaits", &spec.gaits)] {
            if names.is_empty() {
                return Err(param(what, "none given"));
            }
            if let Some(twice) = first_repeated(names) {
                return Err(param(
                    what,
                    format!("{twice:?} is listed twice; each can be simulated once"),
                ));
            }
        }
        let per_trial = self.config.experiment.hops_per_trial.max(1);
        let load = spec.load_kg.unwrap_or(self.config.robot.body_mass_kg);
        if !(load.is_finite() && load > 0.0) {
            return Err(param(
                "load",
                format!("must be a positive mass in kg, got {load}"),
            ));
        }
        let mut plans = Vec::new();
        for terrain in &spec.terrains {
            self.terrain(terrain)?;
            for gait_name in &spec.gaits {
                let gait = self.gait(gait_name)?;
                let mut left = hops;
                let mut index = 0;
                while left > 0 {
                    let n = left.min(per_trial);
                    plans.push(TrialPlan {
                        terrain: terrain.clone(),
                        gait: gait.clone(),
                        index,
                        hops: n,
                        seed: trial_seed(spec.seed, terrain, &gait.name, index, 0),
                        load_kg: load,
                    });
                    left -= n;
                    index += 1;
                }
            }
        }
        Ok(plans)
    }

    /// Simulates one trial, rerunning it with a new seed if the hopper falls.
    pub fn run_trial(&self, plan: &TrialPlan, master_seed: u64) -> Result<TrialOutput> {
        let attempts = self.config.experiment.max_attempts.max(1);
        let mut last_err = None;
        for attempt in 0..attempts {
            let seed = if attempt == 0 {
                plan.seed
            } else {
                trial_seed(
                    master_seed,
                    &plan.terrain,
                    &plan.gait.name,
                    plan.index,
                    attempt,
                )
            };
            match self.run_trial_once(plan, seed) {
                Ok(mut out) => {
                    out.attempts = attempt + 1;
                    return Ok(out);
                }
                Err(err @ SimError::Fell { .. }) => last_err = Some(err),
                Err(err) => return Err(err),
            }
        }
        Err(last_err.unwrap_or_else(|| param("experiment.max_attempts", "must be at least 1")))
    }

    fn run_trial_once(&self, plan: &TrialPlan, seed: u64) -> Result<TrialOutput> {
        let cfg = &self.config;
        let terrain = self.terrain(&plan.terrain)?;
        let robot = cfg.robot.with_load(plan.load_kg);
        let mut dyn_rng = ChaCha8Rng::seed_from_u64(seed);
        let mut terrain_rng = ChaCha8Rng::seed_from_u64(splitmix(seed ^ 0x7E44_A100));
        let mut sensor_rng = ChaCha8Rng::seed_from_u64(splitmix(seed ^ 0x5E45_0A00));
        let mut hopper = Hopper::new(robot, plan.gait.clone(), terrain.ground(), cfg.integrator)?;
        let angle_noise = Normal::new(0.0, cfg.realism.touchdown_angle_noise_rad)
            .map_err(|e| param("realism.touchdown_angle_noise_rad", e.to_string()))?;
        let period = cfg.sensor.frame_period_s;
        let mut samples: Vec<ContactState> = Vec::new();
        for i in 0..cfg.robot.warmup_hops {
            hopper.hop(
                i,
                period,
                f64::INFINITY,
                &mut samples,
                angle_noise.sample(&mut dyn_rng),
            )?;
        }
        samples.clear();
        let t0 = hopper.t_s;
        let mut truths = Vec::with_capacity(plan.hops);
        for h in 0..plan.hops {
            truths.push(hopper.hop(
                h,
                period,
                t0,
                &mut samples,
                angle_noise.sample(&mut dyn_rng),
            )?);
        }
        // Frames.
        let grid = Grid::new(cfg.foot.rows, cfg.foot.cols);
        let mut data = Vec::with_capacity(samples.len() * grid.len());
        let mut records: Vec<HopRecord> = truths
            .into_iter()
            .map(|mut truth| {
                truth.touchdown_time_s -= t0;
                truth.liftoff_time_s -= t0;
                HopRecord {
                    truth,
                    first_stance_frame: None,
                    last_stance_frame: None,
                    mid_stance_frame: None,
                    frame_normal_force_n: Vec::new(),
                    frame_tangential_force_n: Vec::new(),
                    frame_image_force_n: Vec::new(),
                    frame_cop_m: Vec::new(),
                }
            })
            .collect();
        let zeros = vec![0.0; grid.len()];
        let mut counts = Vec::with_capacity(grid.len());
        let mut current: Option<CurrentHop> = None;
        let mut warm = None;
        let lat = Normal::new(0.0, cfg.realism.lateral_cop_sd_m)
            .map_err(|e| param("realism.lateral_cop_sd_m", e.to_string()))?;
        let fa = Normal::new(0.0, cfg.realism.foreaft_cop_sd_m)
            .map_err(|e| param("realism.foreaft_cop_sd_m", e.to_string()))?;
        // Every hop gets its patch and CoP offsets drawn in order, whether or not a frame hits its stance.
        let mut patches = Vec::with_capacity(plan.hops);
        for _ in 0..plan.hops {
            let patch = terrain.patch(
                &self.foot.points,
                &mut terrain_rng,
                cfg.realism.terrain_variability,
            );
            let offset = (fa.sample(&mut terrain_rng), lat.sample(&mut terrain_rng));
            patches.push(Some((patch, offset)));
        }
        for (frame, sample) in samples.iter().enumerate() {
            match sample.stance_of_hop {
                None => self.sensor.counts(&zeros, &mut sensor_rng, &mut counts),
                Some(h) => {
                    if current.as_ref().is_none_or(|c| c.0 != h) {
                        let (patch, offset) = patches
                            .get_mut(h)
                            .and_then(Option::take)
                            .ok_or_else(|| param("hop", "stance samples out of order"))?;
                        let k_eff = self.foot.effective_stiffness(&patch);
                        current = Some((h, patch, k_eff, offset));
                        warm = None;
                    }
                    let Some((_, patch, k_eff, offset)) = current.as_ref() else {
                        return Err(param("hop", "no patch"));
                    };
                    let n = sample.normal_force_n;
                    let cop = ankle_cop(&cfg.robot, sample, *offset);
                    let image = self.foot.pressure_image(patch, k_eff, n, cop, &mut warm)?;
                    let image_force: f64 = image.iter().sum::<f64>() * self.foot.sensel_area_m2();
                    let rec = &mut records[h];
                    rec.first_stance_frame.get_or_insert(frame);
                    rec.last_stance_frame = Some(frame);
                    rec.frame_normal_force_n.push(n);
                    rec.frame_tangential_force_n.push(sample.tangential_force_n);
                    rec.frame_image_force_n.push(image_force);
                    rec.frame_cop_m.push(cop);
                    self.sensor.counts(&image, &mut sensor_rng, &mut counts);
                }
            }
            data.extend_from_slice(&counts);
        }
        for rec in &mut records {
            if let (Some(first), Some(last)) = (rec.first_stance_frame, rec.last_stance_frame) {
                rec.mid_stance_frame = Some(first + (last - first) / 2);
            }
        }
        let meta = SensorMeta {
            sensor: Some(cfg.sensor.model.clone()),
            row_pitch_mm: Some(cfg.foot.pitch_m * 1e3),
            col_pitch_mm: Some(cfg.foot.pitch_m * 1e3),
            units: Some(PressureUnit::Raw),
            full_scale: Some(cfg.sensor.max_count),
            noise_threshold: Some(cfg.realism.noise_threshold_counts),
            extra: Vec::new(),
        };
        let recording = Recording::new(grid, Some(period), data, None, meta)?;
        Ok(TrialOutput {
            plan: plan.clone(),
            recording,
            hops: records,
            attempts: 1,
        })
    }

    /// Runs every trial in parallel and hands each result to `consume` (on a worker thread) as soon as
    /// it is ready; returns what `consume` returned, in plan order.
    pub fn for_each_trial<T, E, F>(
        &self,
        spec: &DatasetSpec,
        consume: F,
    ) -> std::result::Result<Vec<T>, E>
    where
        T: Send,
        E: From<SimError> + Send,
        F: Fn(TrialOutput) -> std::result::Result<T, E> + Sync + Send,
    {
        let plans = self.plan(spec)?;
        plans
            .par_iter()
            .map(|plan| consume(self.run_trial(plan, spec.seed)?))
            .collect()
    }
}

/// The first item that `items` holds twice (at its second place).
pub fn first_repeated<T: PartialEq>(items: &[T]) -> Option<&T> {
    items
        .iter()
        .enumerate()
        .find(|(i, item)| items[..*i].contains(item))
        .map(|(_, item)| item)
}

/// Centre of pressure (forward, left), m, from the ankle's moment balance: the massless foot carries the
/// ground reaction `(T, N)` at the CoP, the leg's push `(-T, -N)` at the ankle (height `h_a`), and the
/// ankle spring's torque `k_a * beta`: `x_cop = -(h_a T + k_a beta) / N`; plus the hop's random offset.
pub fn ankle_cop(
    robot: &crate::slip::RobotParams,
    sample: &ContactState,
    offset: (f64, f64),
) -> (f64, f64) {
    let n = sample.normal_force_n.max(1e-9);
    let x = -(robot.ankle_height_m * sample.tangential_force_n
        + robot.ankle_stiffness_n_m_per_rad * sample.leg_angle_rad)
        / n;
    (x + offset.0, offset.1)
}

/// The hop whose stance is being imaged: index, patch, effective stiffness, CoP offset.
type CurrentHop = (usize, crate::terrain::SurfacePatch, Vec<f64>, (f64, f64));

/// A simulated data set held in memory.
#[derive(Clone, Debug)]
pub struct SimulatedDataset {
    pub trials: Vec<TrialOutput>,
}

impl SimulatedDataset {
    /// Table I of the simulation: mean forward velocity per gait and terrain.
    pub fn velocity_table(&self) -> VelocityTable {
        VelocityTable::from_trials(self.trials.iter().map(|t| {
            (
                t.plan.gait.name.clone(),
                t.plan.terrain.clone(),
                t.hops
                    .iter()
                    .map(|h| h.truth.mean_forward_velocity_m_per_s)
                    .collect(),
            )
        }))
    }
}

/// Simulates a data set in memory (all trials in parallel).
pub fn simulate_dataset(config: &SimConfig, spec: &DatasetSpec) -> Result<SimulatedDataset> {
    let sim = Simulator::new(config.clone(), spec.seed, spec.image_terrains.clone())?;
    let trials = sim.for_each_trial(spec, Ok::<_, SimError>)?;
    Ok(SimulatedDataset { trials })
}

/// Mean forward velocity per gait (rows) and terrain (columns), m/s.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VelocityTable {
    pub gaits: Vec<String>,
    pub terrains: Vec<String>,
    /// `velocity[g][t]`, NaN where there is no trial.
    pub velocity_m_per_s: Vec<Vec<f64>>,
    /// Number of hops behind each cell.
    pub hops: Vec<Vec<usize>>,
}

impl VelocityTable {
    /// From `(gait, terrain, per-hop velocities)` triples (several per cell are pooled).
    pub fn from_trials(items: impl Iterator<Item = (String, String, Vec<f64>)>) -> Self {
        let mut gaits: Vec<String> = Vec::new();
        let mut terrains: Vec<String> = Vec::new();
        let mut cells: Vec<(usize, usize, Vec<f64>)> = Vec::new();
        for (g, t, v) in items {
            let gi = gaits.iter().position(|x| *x == g).unwrap_or_else(|| {
                gaits.push(g.clone());
                gaits.len() - 1
            });
            let ti = terrains.iter().position(|x| *x == t).unwrap_or_else(|| {
                terrains.push(t.clone());
                terrains.len() - 1
            });
            cells.push((gi, ti, v));
        }
        let mut sum = vec![vec![0.0; terrains.len()]; gaits.len()];
        let mut hops = vec![vec![0usize; terrains.len()]; gaits.len()];
        for (g, t, v) in cells {
            sum[g][t] += v.iter().sum::<f64>();
            hops[g][t] += v.len();
        }
        let velocity_m_per_s = sum
            .iter()
            .zip(&hops)
            .map(|(row, n)| {
                row.iter()
                    .zip(n)
                    .map(|(s, &n)| if n == 0 { f64::NAN } else { s / n as f64 })
                    .collect()
            })
            .collect();
        Self {
            gaits,
            terrains,
            velocity_m_per_s,
            hops,
        }
    }

    /// The paper's value for a cell, if it is one of Table I's.
    pub fn paper_value(gait: &str, terrain: &str) -> Option<f64> {
        let g = ["G1", "G2", "G3"].iter().position(|x| *x == gait)?;
        let t = BUILTIN_TERRAINS.iter().position(|x| *x == terrain)?;
        Some(PAPER_TABLE1[g][t])
    }

    /// A text table: simulated velocity, the paper's value and the ratio, per cell.
    pub fn format_with_paper(&self) -> String {
        use std::fmt::Write as _;
        let mut out = String::new();
        let _ = writeln!(
            out,
            "Forward velocity [m/s]: simulated (paper, sim/paper) — the paper's Table I"
        );
        let _ = write!(out, "{:<6}", "Gait");
        for t in &self.terrains {
            let _ = write!(out, "{t:>24}");
        }
        out.push('\n');
        for (g, row) in self.gaits.iter().zip(&self.velocity_m_per_s) {
            let _ = write!(out, "{g:<6}");
            for (t, v) in self.terrains.iter().zip(row) {
                let cell = match Self::paper_value(g, t) {
                    Some(p) => {
                        format!("{v:.2} ({p:.2}, {})", signed_percent((v / p - 1.0) * 100.0))
                    }
                    None => format!("{v:.2}"),
                };
                let _ = write!(out, "{cell:>24}");
            }
            out.push('\n');
        }
        out
    }
}

/// A signed whole percentage, `+19 %`, `-6 %`, and `0 %` for anything that rounds to zero (not `-0 %`).
fn signed_percent(percent: f64) -> String {
    let rounded = percent.round();
    if rounded == 0.0 {
        "0 %".to_owned()
    } else {
        format!("{rounded:+.0} %")
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    fn map() -> HeightMap {
        HeightMap::new(2, 2, vec![0.0, 1.0, 0.5, 0.25]).unwrap()
    }

    #[test]
    fn image_terrains_need_names_of_their_own() {
        let config = SimConfig::default();
        let image = |name: &str| (name.to_owned(), map());
        let err = Simulator::new(config.clone(), 1, vec![image("wood")]).unwrap_err();
        assert!(
            err.to_string().contains("name of a built-in terrain"),
            "{err}"
        );
        let err = Simulator::new(config.clone(), 1, vec![image("a"), image("a")]).unwrap_err();
        assert!(
            err.to_string()
                .contains("two height-map terrains are called \"a\""),
            "{err}"
        );
        assert!(Simulator::new(config.clone(), 1, vec![image(" ")]).is_err());
        Simulator::new(config, 1, vec![image("a"), image("b")]).unwrap();
    }

    #[test]
    fn a_plan_refuses_repeated_names_and_zero_hops() {
        let sim = Simulator::new(SimConfig::default(), 1, Vec::new()).unwrap();
        let mut spec = DatasetSpec::paper(1);
        spec.hops_per_gait = Some(1);
        assert_eq!(sim.plan(&spec).unwrap().len(), 12);
        let mut twice = spec.clone();
        twice.terrains = vec!["wood".into(), "clay".into(), "wood".into()];
        let err = sim.plan(&twice).unwrap_err().to_string();
        assert!(err.contains("terrains: \"wood\" is listed twice"), "{err}");
        let mut twice = spec.clone();
        twice.gaits = vec!["G2".into(), "G2".into()];
        let err = sim.plan(&twice).unwrap_err().to_string();
        assert!(err.contains("gaits: \"G2\" is listed twice"), "{err}");
        let mut none = spec.clone();
        none.hops_per_gait = Some(0);
        let err = sim.plan(&none).unwrap_err().to_string();
        assert!(err.contains("hops_per_gait: must be at least 1"), "{err}");
        let mut none = spec.clone();
        none.terrains.clear();
        assert!(sim.plan(&none).is_err());
    }

    #[test]
    fn the_table_prints_no_negative_zero() {
        assert_eq!(signed_percent(-0.3), "0 %");
        assert_eq!(signed_percent(-0.0), "0 %");
        assert_eq!(signed_percent(0.4), "0 %");
        assert_eq!(signed_percent(19.2), "+19 %");
        assert_eq!(signed_percent(-5.6), "-6 %");
        let table = VelocityTable {
            gaits: vec!["G1".into()],
            terrains: vec!["carpet".into()],
            velocity_m_per_s: vec![vec![0.43 * 0.999]],
            hops: vec![vec![1]],
        };
        let text = table.format_with_paper();
        assert!(text.contains("0.43 (0.43, 0 %)"), "{text}");
    }
}
