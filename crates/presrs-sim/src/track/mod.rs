//! Closing the terrain-to-gait loop: the hopper runs a *track* of terrain segments, a policy sees every
//! hop's pressure frames and may switch the gait, and [`gait_table`] measures which gait is fastest and
//! stable on each terrain.
//!
//! **Track.** A track is a sequence of segments, `wood:3,grass:3` (terrain, metres). Before each hop the
//! runner predicts, exactly (the flight from the apex is ballistic), where the foot will touch down, and
//! puts that segment's ground compliance under the foot for the whole stance; the stance's pressure
//! images are rendered with a fresh random patch of the same terrain. So the terrain changes at a stance,
//! never inside one.
//!
//! **Policy.** After every hop (apex to apex) the policy receives the hop's frames (flight and stance,
//! raw counts at the sensor's frame period, on the same clock as a continuous recording) and answers with
//! a [`PolicyStep`]: optionally the terrain it believes it stood on (scored against the truth) and the
//! gait to use from now on. The sim crate does not know any classifier: the policy is a closure.
//! An online classifier decides at the `k`-th frame after touchdown, i.e. during stance, before the next
//! apex, which is when the controller acts: a gait switch sets `omega` of eq. (1) for the next stance and
//! `beta_des` of eq. (2) for the next touchdown angle (recomputed at this apex with the new `beta_des`
//! and the same actuator noise). Nothing changes during a stance.
//!
//! **Falls** are counted, not hidden: when a hop fails ([`SimError::Fell`]) the robot is put back at the
//! last apex, restarted from the initial apex of its current gait, and the clock is charged
//! [`TrackParams::restart_penalty_s`]. A run that has not finished by [`TrackParams::max_time_s`] (or
//! falls more than [`TrackParams::max_falls`] times) is reported unfinished.
//!
//! **Randomness.** Actuator noise, terrain patches and sensor noise come from three ChaCha8 generators
//! seeded from [`TrackParams::seed`]; the actuator noise of hop `n` is the same whatever the policy does
//! (common random numbers), so policies are compared on the same disturbances.

mod gait_table;
mod support;

use std::collections::BTreeMap;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use serde::{Deserialize, Serialize};

use presrs_core::Grid;

use crate::config::SimConfig;
use crate::dataset::{Simulator, ankle_cop};
use crate::error::{Result, SimError, param};
use crate::slip::{ContactState, GRAVITY_M_PER_S2, Gait, HopTruth, Hopper};
use crate::terrain::Terrain;

pub use gait_table::{
    BetaSweep, GaitCell, GaitTable, GaitTableParams, gait_candidates, gait_table,
    gait_table_with_progress,
};
use support::{mix, went_backwards};

/// One stretch of a track: `length_m` metres of one terrain.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Segment {
    pub terrain: String,
    pub length_m: f64,
}

/// Parses `wood:3,grass:3,clay:3,carpet:3` (terrain:metres, comma separated).
pub fn parse_track(spec: &str) -> Result<Vec<Segment>> {
    let mut segments = Vec::new();
    for part in spec.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let (terrain, length) = part.split_once(':').ok_or_else(|| {
            param(
                "track",
                format!("expected TERRAIN:METRES, got {part:?} (e.g. wood:3,grass:3)"),
            )
        })?;
        let length_m: f64 = length.trim().parse().map_err(|_| {
            param(
                "track",
                format!("{part:?}: the length {length:?} is not a number of metres"),
            )
        })?;
        if !(length_m.is_finite() && length_m > 0.0) {
            return Err(param(
                "track",
                format!("{part:?}: the length must be positive"),
            ));
        }
        let terrain = terrain.trim();
        if terrain.is_empty() {
            return Err(param("track", format!("{part:?}: empty terrain name")));
        }
        segments.push(Segment {
            terrain: terrain.to_owned(),
            length_m,
        });
    }
    if segments.is_empty() {
        return Err(param("track", "the track has no segment"));
    }
    Ok(segments)
}

/// Settings of a track run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrackParams {
    /// Seed of every random choice of the run.
    pub seed: u64,
    /// Gait at the start line.
    pub start_gait: String,
    /// Render the pressure frames handed to the policy (a fixed-gait run does not need them).
    pub render: bool,
    /// Time charged for picking the robot up after a fall, s.
    pub restart_penalty_s: f64,
    /// Give up (unfinished) after this much track time, s.
    pub max_time_s: f64,
    /// Give up (unfinished) after this many falls.
    pub max_falls: usize,
}

impl TrackParams {
    pub fn new(seed: u64, start_gait: &str) -> Self {
        Self {
            seed,
            start_gait: start_gait.to_owned(),
            render: true,
            restart_penalty_s: 2.0,
            max_time_s: 120.0,
            max_falls: 20,
        }
    }
}

/// What the policy sees after a hop.
#[derive(Clone, Copy, Debug)]
pub struct HopView<'a> {
    /// Index of the hop on the track (0-based, falls included).
    pub hop: usize,
    /// Sensor grid of every frame.
    pub grid: Grid,
    pub frame_period_s: f64,
    /// Index (on the run's frame clock, `t = index * frame_period_s`) of the first frame in `frames`.
    pub first_frame: usize,
    /// The hop's frames, raw counts, `frame_count() * grid.len()` values (empty without rendering).
    pub frames: &'a [f64],
    /// The gait the hop was run with.
    pub gait: &'a str,
}

impl HopView<'_> {
    pub fn frame_count(&self) -> usize {
        self.frames.len() / self.grid.len().max(1)
    }

    /// Frame `i` of the hop (raw counts).
    pub fn frame(&self, i: usize) -> Option<&[f64]> {
        let n = self.grid.len();
        self.frames.get(i * n..(i + 1) * n)
    }
}

/// A policy's answer after a hop.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PolicyStep {
    /// The terrain the policy believes this hop stood on (`None`: no decision this hop).
    pub terrain: Option<String>,
    /// The gait to run from the next hop on (`None`: keep the current one).
    pub gait: Option<String>,
}

/// One hop of a track run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrackHop {
    pub hop: usize,
    /// The terrain under the foot (truth).
    pub terrain: String,
    pub gait: String,
    /// What the policy believed (`None`: no decision or no policy).
    pub believed: Option<String>,
    /// Where the foot touched down, m along the track.
    pub foot_x_m: f64,
    /// Body position and time at the apex ending the hop (after a fall: where the robot restarts).
    pub apex_x_m: f64,
    pub apex_time_s: f64,
    pub fell: bool,
    /// Gait switched after this hop (to the gait of the next hop).
    pub switched: bool,
}

/// The result of a track run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrackRun {
    pub segments: Vec<Segment>,
    pub seed: u64,
    pub length_m: f64,
    pub finished: bool,
    /// Time at which the body crossed the finish line (interpolated between apexes), s; the elapsed time
    /// when the run was given up otherwise.
    pub time_s: f64,
    /// Distance covered, m (the track length when finished).
    pub distance_m: f64,
    /// `distance_m / time_s`.
    pub mean_speed_m_per_s: f64,
    pub hops: Vec<TrackHop>,
    pub falls: usize,
    /// Hops whose believed terrain differs from the truth.
    pub misclassified: usize,
    /// Hops with a decision.
    pub decided: usize,
    pub switches: usize,
    /// Hops per gait.
    pub gait_hops: BTreeMap<String, usize>,
}

/// Index of the segment containing position `x` (the last one beyond the end, the first before 0).
fn segment_at(ends: &[f64], x: f64) -> usize {
    ends.iter()
        .position(|&end| x < end)
        .unwrap_or(ends.len().saturating_sub(1))
}

/// Where the foot will touch down if the hopper flies ballistically from its current apex.
fn predicted_foot_x(hopper: &Hopper) -> f64 {
    let [x, y, vx, vy, _] = hopper.state;
    let leg = hopper.touchdown_leg_length_m();
    let beta = hopper.next_touchdown_angle_rad;
    let drop = (y - leg * beta.cos()).max(0.0);
    // y(t) = y + vy t - g t^2 / 2 reaches the touchdown height at the positive root.
    let g = GRAVITY_M_PER_S2;
    let t = (vy + (vy * vy + 2.0 * g * drop).sqrt()) / g;
    x + vx * t + leg * beta.sin()
}

/// Runs the hopper over `track`, handing each hop's frames to `policy` (see the module docs).
pub fn run_track<P>(
    sim: &Simulator,
    track: &[Segment],
    params: &TrackParams,
    mut policy: P,
) -> Result<TrackRun>
where
    P: FnMut(&HopView<'_>) -> std::result::Result<PolicyStep, String>,
{
    if track.is_empty() {
        return Err(param("track", "the track has no segment"));
    }
    let layout = TrackLayout::new(sim, track)?;
    let gait = sim.gait(&params.start_gait)?;
    let noise = TrackNoise::new(&sim.config, params.seed)?;
    let mut runner = TrackRunner::new(sim, track, params, layout, noise, gait)?;
    while !runner.given_up_or_done() {
        runner.run_hop(&mut policy)?;
    }
    Ok(runner.into_run())
}

/// The terrains of a track's segments and where each segment ends, m.
struct TrackLayout {
    terrains: Vec<Terrain>,
    ends: Vec<f64>,
    length_m: f64,
}

impl TrackLayout {
    fn new(sim: &Simulator, track: &[Segment]) -> Result<Self> {
        let terrains: Vec<Terrain> = track
            .iter()
            .map(|s| sim.terrain(&s.terrain))
            .collect::<Result<_>>()?;
        let ends: Vec<f64> = track
            .iter()
            .scan(0.0, |acc, s| {
                *acc += s.length_m;
                Some(*acc)
            })
            .collect();
        let length_m = ends.last().copied().unwrap_or(0.0);
        Ok(Self {
            terrains,
            ends,
            length_m,
        })
    }
}

/// The run's three random streams (actuator, terrain patches, sensor) and its noise distributions.
struct TrackNoise {
    dynamics_rng: ChaCha8Rng,
    terrain_rng: ChaCha8Rng,
    sensor_rng: ChaCha8Rng,
    touchdown_angle: Normal<f64>,
    lateral_cop: Normal<f64>,
    foreaft_cop: Normal<f64>,
}

impl TrackNoise {
    fn new(cfg: &SimConfig, seed: u64) -> Result<Self> {
        let dynamics_rng = ChaCha8Rng::seed_from_u64(mix(seed ^ 0x7AC4_0001));
        let terrain_rng = ChaCha8Rng::seed_from_u64(mix(seed ^ 0x7AC4_0002));
        let sensor_rng = ChaCha8Rng::seed_from_u64(mix(seed ^ 0x7AC4_0003));
        let touchdown_angle = Normal::new(0.0, cfg.realism.touchdown_angle_noise_rad)
            .map_err(|e| param("realism.touchdown_angle_noise_rad", e.to_string()))?;
        let lateral_cop = Normal::new(0.0, cfg.realism.lateral_cop_sd_m)
            .map_err(|e| param("realism.lateral_cop_sd_m", e.to_string()))?;
        let foreaft_cop = Normal::new(0.0, cfg.realism.foreaft_cop_sd_m)
            .map_err(|e| param("realism.foreaft_cop_sd_m", e.to_string()))?;
        Ok(Self {
            dynamics_rng,
            terrain_rng,
            sensor_rng,
            touchdown_angle,
            lateral_cop,
            foreaft_cop,
        })
    }
}

/// What a run counts as it goes.
#[derive(Default)]
struct TrackTally {
    hops: Vec<TrackHop>,
    falls: usize,
    misclassified: usize,
    decided: usize,
    switches: usize,
    gait_hops: BTreeMap<String, usize>,
}

/// Where a hop started: the apex it left from and the foot's touchdown on segment `segment`.
#[derive(Clone, Copy)]
struct HopStart {
    apex_x: f64,
    apex_t: f64,
    foot_x: f64,
    segment: usize,
}

/// One track run in progress: the hopper, its gait, the buffers reused hop to hop, and the tally.
struct TrackRunner<'a> {
    sim: &'a Simulator,
    track: &'a [Segment],
    params: &'a TrackParams,
    layout: TrackLayout,
    noise: TrackNoise,
    gait: Gait,
    grid: Grid,
    hopper: Hopper,
    samples: Vec<ContactState>,
    frames: Vec<f64>,
    counts: Vec<f64>,
    zeros: Vec<f64>,
    hop: usize,
    finish: Option<f64>,
    tally: TrackTally,
}

impl<'a> TrackRunner<'a> {
    fn new(
        sim: &'a Simulator,
        track: &'a [Segment],
        params: &'a TrackParams,
        layout: TrackLayout,
        noise: TrackNoise,
        gait: Gait,
    ) -> Result<Self> {
        let cfg = &sim.config;
        let grid = Grid::new(cfg.foot.rows, cfg.foot.cols);
        let hopper = new_track_hopper(sim, &layout, &gait, 0.0, 0.0)?;
        Ok(Self {
            sim,
            track,
            params,
            layout,
            noise,
            gait,
            grid,
            hopper,
            samples: Vec::new(),
            frames: Vec::new(),
            counts: Vec::with_capacity(grid.len()),
            zeros: vec![0.0; grid.len()],
            hop: 0,
            finish: None,
            tally: TrackTally::default(),
        })
    }

    /// The hopper's apex is past the finish line, or the run has used up its time or its falls.
    fn given_up_or_done(&self) -> bool {
        let (apex_x, apex_t) = (self.hopper.state[0], self.hopper.t_s);
        apex_x >= self.layout.length_m
            || apex_t >= self.params.max_time_s
            || self.tally.falls > self.params.max_falls
    }

    /// One hop, apex to apex: the dynamics on the predicted segment, the frames, the policy's answer.
    fn run_hop<P>(&mut self, policy: &mut P) -> Result<()>
    where
        P: FnMut(&HopView<'_>) -> std::result::Result<PolicyStep, String>,
    {
        let period = self.sim.config.sensor.frame_period_s;
        let foot_x = predicted_foot_x(&self.hopper);
        let start = HopStart {
            apex_x: self.hopper.state[0],
            apex_t: self.hopper.t_s,
            foot_x,
            segment: segment_at(&self.layout.ends, foot_x),
        };
        self.hopper.ground = self.layout.terrains[start.segment].ground();
        let noise = self
            .noise
            .touchdown_angle
            .sample(&mut self.noise.dynamics_rng);
        self.samples.clear();
        let outcome = self
            .hopper
            .hop(self.hop, period, 0.0, &mut self.samples, noise);
        *self
            .tally
            .gait_hops
            .entry(self.gait.name.clone())
            .or_insert(0) += 1;
        let outcome = match outcome {
            Ok(_) if went_backwards(&self.hopper) => Err(SimError::Fell {
                hop: self.hop,
                reason: "bounced back: moving backwards at the apex".to_owned(),
            }),
            other => other,
        };
        let truth = match outcome {
            Ok(truth) => truth,
            Err(SimError::Fell { .. }) => return self.restart_after_fall(start),
            Err(err) => return Err(err),
        };
        self.render_frames(start.segment)?;
        let step = self.ask_policy(policy)?;
        let hop_gait = self.gait.name.clone();
        if let Some(believed) = &step.terrain {
            self.tally.decided += 1;
            if *believed != self.track[start.segment].terrain {
                self.tally.misclassified += 1;
            }
        }
        let switched = self.switch_gait(step.gait.as_deref(), &truth, noise)?;
        self.record_hop(start, hop_gait, step.terrain, switched);
        Ok(())
    }

    /// A fall: the robot restarts at the apex it fell from, in its current gait, after the penalty.
    fn restart_after_fall(&mut self, start: HopStart) -> Result<()> {
        self.tally.falls += 1;
        self.hopper = new_track_hopper(
            self.sim,
            &self.layout,
            &self.gait,
            start.apex_x,
            start.apex_t + self.params.restart_penalty_s,
        )?;
        self.tally.hops.push(TrackHop {
            hop: self.hop,
            terrain: self.track[start.segment].terrain.clone(),
            gait: self.gait.name.clone(),
            believed: None,
            foot_x_m: start.foot_x,
            apex_x_m: start.apex_x,
            apex_time_s: self.hopper.t_s,
            fell: true,
            switched: false,
        });
        self.hop += 1;
        Ok(())
    }

    /// The hop's frames: flight frames carry no load, stance frames the rendered image (none without
    /// rendering).
    fn render_frames(&mut self, segment: usize) -> Result<()> {
        self.frames.clear();
        if !self.params.render {
            return Ok(());
        }
        let (sim, noise) = (self.sim, &mut self.noise);
        let patch = self.layout.terrains[segment].patch(
            &sim.foot.points,
            &mut noise.terrain_rng,
            sim.config.realism.terrain_variability,
        );
        let offset = (
            noise.foreaft_cop.sample(&mut noise.terrain_rng),
            noise.lateral_cop.sample(&mut noise.terrain_rng),
        );
        let k_eff = sim.foot.effective_stiffness(&patch);
        let mut warm = None;
        for sample in &self.samples {
            if sample.stance_of_hop.is_some() {
                let cop = ankle_cop(&sim.config.robot, sample, offset);
                let image = sim.foot.pressure_image(
                    &patch,
                    &k_eff,
                    sample.normal_force_n,
                    cop,
                    &mut warm,
                )?;
                sim.sensor
                    .counts(&image, &mut noise.sensor_rng, &mut self.counts);
            } else {
                sim.sensor
                    .counts(&self.zeros, &mut noise.sensor_rng, &mut self.counts);
            }
            self.frames.extend_from_slice(&self.counts);
        }
        Ok(())
    }

    /// Hands the hop's frames to the policy; its refusal is an error naming the policy.
    fn ask_policy<P>(&self, policy: &mut P) -> Result<PolicyStep>
    where
        P: FnMut(&HopView<'_>) -> std::result::Result<PolicyStep, String>,
    {
        let period = self.sim.config.sensor.frame_period_s;
        let first_frame = self
            .samples
            .first()
            .map_or(0, |s| (s.t_s / period).round().max(0.0) as usize);
        let view = HopView {
            hop: self.hop,
            grid: self.grid,
            frame_period_s: period,
            first_frame,
            frames: &self.frames,
            gait: &self.gait.name,
        };
        policy(&view).map_err(|reason| param("policy", reason))
    }

    /// Switches to gait `next` if it differs from the current one; true when it did.
    fn switch_gait(&mut self, next: Option<&str>, truth: &HopTruth, noise: f64) -> Result<bool> {
        let Some(next) = next else {
            return Ok(false);
        };
        if next == self.gait.name {
            return Ok(false);
        }
        self.gait = self.sim.gait(next)?;
        let robot = &self.sim.config.robot;
        // The decision came during this stance: the controller applies eq. (2) at this apex with the
        // new beta_des (same actuator noise) and eq. (1) with the new omega from the next touchdown.
        let commanded = truth.liftoff_angle_rad
            + robot.touchdown_gain * (truth.touchdown_angle_rad - self.gait.beta_des_rad)
            + noise;
        self.hopper.next_touchdown_angle_rad =
            commanded.clamp(robot.min_touchdown_angle_rad, robot.max_touchdown_angle_rad);
        self.hopper.gait = self.gait.clone();
        self.tally.switches += 1;
        Ok(true)
    }

    /// Records a hop that did not fall, and the finish time (interpolated between the apexes) when
    /// it crossed the line.
    fn record_hop(
        &mut self,
        start: HopStart,
        hop_gait: String,
        believed: Option<String>,
        switched: bool,
    ) {
        let (x, t) = (self.hopper.state[0], self.hopper.t_s);
        self.tally.hops.push(TrackHop {
            hop: self.hop,
            terrain: self.track[start.segment].terrain.clone(),
            gait: hop_gait,
            believed,
            foot_x_m: start.foot_x,
            apex_x_m: x,
            apex_time_s: t,
            fell: false,
            switched,
        });
        self.hop += 1;
        let (length_m, apex_x, apex_t) = (self.layout.length_m, start.apex_x, start.apex_t);
        if x >= length_m {
            let frac = if x > apex_x {
                (length_m - apex_x) / (x - apex_x)
            } else {
                1.0
            };
            self.finish = Some(apex_t + frac.clamp(0.0, 1.0) * (t - apex_t));
        }
    }

    fn into_run(self) -> TrackRun {
        let length_m = self.layout.length_m;
        let (finished, time_s, distance_m) = match self.finish {
            Some(t) => (true, t, length_m),
            None => (false, self.hopper.t_s, self.hopper.state[0].min(length_m)),
        };
        let tally = self.tally;
        TrackRun {
            segments: self.track.to_vec(),
            seed: self.params.seed,
            length_m,
            finished,
            time_s,
            distance_m,
            mean_speed_m_per_s: if time_s > 0.0 {
                distance_m / time_s
            } else {
                0.0
            },
            hops: tally.hops,
            falls: tally.falls,
            misclassified: tally.misclassified,
            decided: tally.decided,
            switches: tally.switches,
            gait_hops: tally.gait_hops,
        }
    }
}

/// A hopper at `x` m and `t` s in `gait`, on the first segment's ground (the next hop sets its own).
fn new_track_hopper(
    sim: &Simulator,
    layout: &TrackLayout,
    gait: &Gait,
    x: f64,
    t: f64,
) -> Result<Hopper> {
    let cfg = &sim.config;
    let mut h = Hopper::new(
        cfg.robot.clone(),
        gait.clone(),
        layout.terrains[0].ground(),
        cfg.integrator,
    )?;
    h.state[0] = x;
    h.t_s = t;
    Ok(h)
}
