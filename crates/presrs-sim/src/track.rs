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

use std::collections::BTreeMap;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use presrs_core::Grid;

use crate::dataset::{Simulator, ankle_cop};
use crate::error::{Result, SimError, param};
use crate::slip::{ContactState, GRAVITY_M_PER_S2, Gait, Hopper};
use crate::terrain::Terrain;

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

/// SplitMix64 step.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// FNV-1a hash of a name.
fn name_hash(text: &str) -> u64 {
    text.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
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
    let cfg = &sim.config;
    if track.is_empty() {
        return Err(param("track", "the track has no segment"));
    }
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
    let mut gait = sim.gait(&params.start_gait)?;
    let robot = cfg.robot.clone();
    let mut dyn_rng = ChaCha8Rng::seed_from_u64(mix(params.seed ^ 0x7AC4_0001));
    let mut terrain_rng = ChaCha8Rng::seed_from_u64(mix(params.seed ^ 0x7AC4_0002));
    let mut sensor_rng = ChaCha8Rng::seed_from_u64(mix(params.seed ^ 0x7AC4_0003));
    let angle_noise = Normal::new(0.0, cfg.realism.touchdown_angle_noise_rad)
        .map_err(|e| param("realism.touchdown_angle_noise_rad", e.to_string()))?;
    let lat = Normal::new(0.0, cfg.realism.lateral_cop_sd_m)
        .map_err(|e| param("realism.lateral_cop_sd_m", e.to_string()))?;
    let fa = Normal::new(0.0, cfg.realism.foreaft_cop_sd_m)
        .map_err(|e| param("realism.foreaft_cop_sd_m", e.to_string()))?;
    let period = cfg.sensor.frame_period_s;
    let grid = Grid::new(cfg.foot.rows, cfg.foot.cols);
    let zeros = vec![0.0; grid.len()];

    let new_hopper = |gait: &Gait, x: f64, t: f64| -> Result<Hopper> {
        let mut h = Hopper::new(
            robot.clone(),
            gait.clone(),
            terrains[0].ground(),
            cfg.integrator,
        )?;
        h.state[0] = x;
        h.t_s = t;
        Ok(h)
    };
    let mut hopper = new_hopper(&gait, 0.0, 0.0)?;
    let mut samples: Vec<ContactState> = Vec::new();
    let mut frames: Vec<f64> = Vec::new();
    let mut counts = Vec::with_capacity(grid.len());
    let mut hops = Vec::new();
    let (mut falls, mut misclassified, mut decided, mut switches) = (0, 0, 0, 0);
    let mut gait_hops: BTreeMap<String, usize> = BTreeMap::new();
    let mut finish: Option<f64> = None;
    let mut hop = 0usize;
    loop {
        let (apex_x, apex_t) = (hopper.state[0], hopper.t_s);
        if apex_x >= length_m || apex_t >= params.max_time_s || falls > params.max_falls {
            break;
        }
        let foot_x = predicted_foot_x(&hopper);
        let seg = segment_at(&ends, foot_x);
        let terrain = &terrains[seg];
        hopper.ground = terrain.ground();
        let noise = angle_noise.sample(&mut dyn_rng);
        samples.clear();
        let outcome = hopper.hop(hop, period, 0.0, &mut samples, noise);
        *gait_hops.entry(gait.name.clone()).or_insert(0) += 1;
        let outcome = match outcome {
            Ok(_) if went_backwards(&hopper) => Err(SimError::Fell {
                hop,
                reason: "bounced back: moving backwards at the apex".to_owned(),
            }),
            other => other,
        };
        let truth = match outcome {
            Ok(truth) => truth,
            Err(SimError::Fell { .. }) => {
                falls += 1;
                hopper = new_hopper(&gait, apex_x, apex_t + params.restart_penalty_s)?;
                hops.push(TrackHop {
                    hop,
                    terrain: track[seg].terrain.clone(),
                    gait: gait.name.clone(),
                    believed: None,
                    foot_x_m: foot_x,
                    apex_x_m: apex_x,
                    apex_time_s: hopper.t_s,
                    fell: true,
                    switched: false,
                });
                hop += 1;
                continue;
            }
            Err(err) => return Err(err),
        };
        // Frames of the hop: flight frames carry no load, stance frames the rendered image.
        frames.clear();
        if params.render {
            let patch = terrain.patch(
                &sim.foot.points,
                &mut terrain_rng,
                cfg.realism.terrain_variability,
            );
            let offset = (fa.sample(&mut terrain_rng), lat.sample(&mut terrain_rng));
            let k_eff = sim.foot.effective_stiffness(&patch);
            let mut warm = None;
            for sample in &samples {
                if sample.stance_of_hop.is_some() {
                    let cop = ankle_cop(&robot, sample, offset);
                    let image = sim.foot.pressure_image(
                        &patch,
                        &k_eff,
                        sample.normal_force_n,
                        cop,
                        &mut warm,
                    )?;
                    sim.sensor.counts(&image, &mut sensor_rng, &mut counts);
                } else {
                    sim.sensor.counts(&zeros, &mut sensor_rng, &mut counts);
                }
                frames.extend_from_slice(&counts);
            }
        }
        let first_frame = samples
            .first()
            .map_or(0, |s| (s.t_s / period).round().max(0.0) as usize);
        let view = HopView {
            hop,
            grid,
            frame_period_s: period,
            first_frame,
            frames: &frames,
            gait: &gait.name,
        };
        let step = policy(&view).map_err(|reason| param("policy", reason))?;
        let hop_gait = gait.name.clone();
        if let Some(believed) = &step.terrain {
            decided += 1;
            if *believed != track[seg].terrain {
                misclassified += 1;
            }
        }
        let mut switched = false;
        if let Some(next) = step.gait.as_deref()
            && next != gait.name
        {
            gait = sim.gait(next)?;
            // The decision came during this stance: the controller applies eq. (2) at this apex with the
            // new beta_des (same actuator noise) and eq. (1) with the new omega from the next touchdown.
            let commanded = truth.liftoff_angle_rad
                + robot.touchdown_gain * (truth.touchdown_angle_rad - gait.beta_des_rad)
                + noise;
            hopper.next_touchdown_angle_rad =
                commanded.clamp(robot.min_touchdown_angle_rad, robot.max_touchdown_angle_rad);
            hopper.gait = gait.clone();
            switches += 1;
            switched = true;
        }
        let (x, t) = (hopper.state[0], hopper.t_s);
        hops.push(TrackHop {
            hop,
            terrain: track[seg].terrain.clone(),
            gait: hop_gait,
            believed: step.terrain,
            foot_x_m: foot_x,
            apex_x_m: x,
            apex_time_s: t,
            fell: false,
            switched,
        });
        hop += 1;
        if x >= length_m {
            let frac = if x > apex_x {
                (length_m - apex_x) / (x - apex_x)
            } else {
                1.0
            };
            finish = Some(apex_t + frac.clamp(0.0, 1.0) * (t - apex_t));
        }
    }
    let (finished, time_s, distance_m) = match finish {
        Some(t) => (true, t, length_m),
        None => (false, hopper.t_s, hopper.state[0].min(length_m)),
    };
    Ok(TrackRun {
        segments: track.to_vec(),
        seed: params.seed,
        length_m,
        finished,
        time_s,
        distance_m,
        mean_speed_m_per_s: if time_s > 0.0 {
            distance_m / time_s
        } else {
            0.0
        },
        hops,
        falls,
        misclassified,
        decided,
        switches,
        gait_hops,
    })
}

/// How [`gait_table`] measures.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GaitTableParams {
    /// Hops per steady run (from the initial apex, actuator noise as configured).
    pub hops: usize,
    /// Hops left out of the speed (the start transient); an exit run steps off the terrain after
    /// `settle_hops + i` hops for its `i`-th seed.
    pub settle_hops: usize,
    /// One run per seed and cell (and per seed, cell and next terrain for the exit runs).
    pub seeds: Vec<u64>,
    /// Exit runs: after `settle_hops` on the terrain, the foot steps onto each other measured terrain and
    /// hops this many hops there *in the same gait* (the robot cannot know what comes next, and the first
    /// stance on a new terrain is run before any classifier has seen it). 0: no exit runs.
    pub exit_hops: usize,
}

impl Default for GaitTableParams {
    fn default() -> Self {
        Self {
            hops: 100,
            settle_hops: 20,
            seeds: vec![1, 2, 3, 4, 5],
            exit_hops: 3,
        }
    }
}

/// One terrain and gait of the table.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GaitCell {
    pub terrain: String,
    pub gait: String,
    /// The gait's `omega` of eq. (1), rad/s, and `beta_des` of eq. (2), rad.
    pub omega_rad_per_s: f64,
    pub beta_des_rad: f64,
    /// Steady runs and those that ended in a fall.
    pub runs: usize,
    pub falls: usize,
    /// Hops completed over the steady runs.
    pub hops: usize,
    /// Mean forward speed after the settling hops, over the steady runs that did not fall, m/s (NaN if
    /// none).
    pub mean_speed_m_per_s: f64,
    /// Smallest apex clearance over the steady runs (apex height minus touchdown height), m.
    pub min_apex_clearance_m: f64,
    /// Exit runs and their falls, per next terrain.
    pub exit_runs: usize,
    pub exit_falls: BTreeMap<String, usize>,
}

impl GaitCell {
    pub fn total_exit_falls(&self) -> usize {
        self.exit_falls.values().sum()
    }

    /// No fall in any steady or exit run.
    pub fn stable(&self) -> bool {
        self.runs > 0 && self.falls == 0 && self.total_exit_falls() == 0
    }
}

/// Per terrain, the fastest stable gait, with every measured cell.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GaitTable {
    pub params: GaitTableParams,
    pub cells: Vec<GaitCell>,
    /// Terrain -> recommended gait: the fastest *robustly* stable one (no fall in steady or exit runs, nor
    /// in its nearest `beta_des` neighbours of the same `omega`, when the candidates are a sweep); else
    /// the fastest stable one; where no gait is stable, the one with the fewest falls (steady + exit),
    /// ties to the faster.
    pub best: BTreeMap<String, String>,
    /// Terrain -> whether its recommended gait is stable.
    pub best_is_stable: BTreeMap<String, bool>,
    /// Terrain -> whether its recommended gait's `beta_des` neighbours are stable too.
    #[serde(default)]
    pub best_is_robust: BTreeMap<String, bool>,
}

impl GaitTable {
    /// A text table: speed (steady falls/runs, exit falls/runs) per terrain and configured gait, the
    /// choice marked; with a `beta_des` search, per terrain and `omega` the stable `beta_des` windows and
    /// the recommended variant.
    pub fn format(&self) -> String {
        use std::fmt::Write as _;
        let is_variant = |g: &str| g.contains(Gait::VARIANT_SEPARATOR);
        let mut terrains: Vec<&str> = Vec::new();
        let mut gaits: Vec<&str> = Vec::new();
        for c in &self.cells {
            if !terrains.contains(&c.terrain.as_str()) {
                terrains.push(&c.terrain);
            }
            if !is_variant(&c.gait) && !gaits.contains(&c.gait.as_str()) {
                gaits.push(&c.gait);
            }
        }
        let searched = self.cells.iter().any(|c| is_variant(&c.gait));
        let mut out = String::new();
        let _ = writeln!(
            out,
            "Gait table: mean speed m/s (falls/runs steady {} hops, exit {} hops onto each other terrain), \
             {} seeds; * = recommended",
            self.params.hops,
            self.params.exit_hops,
            self.params.seeds.len()
        );
        let _ = write!(out, "{:<8}", "terrain");
        for g in &gaits {
            let _ = write!(out, "{g:>22}");
        }
        let _ = writeln!(out, "  best");
        for t in &terrains {
            let _ = write!(out, "{t:<8}");
            for g in &gaits {
                let cell = self.cells.iter().find(|c| c.terrain == *t && c.gait == *g);
                let text = cell.map_or_else(String::new, |c| {
                    let star = if self.best.get(*t).is_some_and(|b| b == *g) {
                        "*"
                    } else {
                        ""
                    };
                    format!(
                        "{star}{:.2} ({}/{}, {}/{})",
                        c.mean_speed_m_per_s,
                        c.falls,
                        c.runs,
                        c.total_exit_falls(),
                        c.exit_runs
                    )
                });
                let _ = write!(out, "{text:>22}");
            }
            let best = self.best.get(*t).map_or("-", String::as_str);
            let speed = self
                .cells
                .iter()
                .find(|c| c.terrain == *t && c.gait == best)
                .map_or(f64::NAN, |c| c.mean_speed_m_per_s);
            let note = if !self.best_is_stable.get(*t).copied().unwrap_or(false) {
                " (none stable: fewest falls)"
            } else if searched && !self.best_is_robust.get(*t).copied().unwrap_or(false) {
                " (stable, but a neighbour is not)"
            } else {
                ""
            };
            let _ = writeln!(out, "  {best} {speed:.2} m/s{note}");
        }
        if searched {
            let _ = writeln!(
                out,
                "Stable beta_des windows (rad; no fall in any steady or exit run) per terrain and omega:"
            );
            for t in &terrains {
                let _ = writeln!(out, "  {t:<8}{}", self.stable_windows(t));
            }
        }
        for c in self
            .cells
            .iter()
            .filter(|c| !is_variant(&c.gait) && c.total_exit_falls() > 0)
        {
            let list: Vec<String> = c
                .exit_falls
                .iter()
                .filter(|(_, n)| **n > 0)
                .map(|(t, n)| format!("{t} {n}"))
                .collect();
            let _ = writeln!(
                out,
                "  {} {} falls stepping onto: {}",
                c.terrain,
                c.gait,
                list.join(", ")
            );
        }
        out
    }

    /// `omega 7.0: 0.20-0.58, 0.62` for one terrain: runs of consecutive stable `beta_des` per `omega`.
    pub fn stable_windows(&self, terrain: &str) -> String {
        let mut omegas: Vec<f64> = self
            .cells
            .iter()
            .filter(|c| c.terrain == terrain)
            .map(|c| c.omega_rad_per_s)
            .collect();
        omegas.sort_by(f64::total_cmp);
        omegas.dedup();
        let mut parts = Vec::new();
        for omega in omegas {
            let mut cells: Vec<&GaitCell> = self
                .cells
                .iter()
                .filter(|c| c.terrain == terrain && c.omega_rad_per_s == omega)
                .collect();
            cells.sort_by(|a, b| a.beta_des_rad.total_cmp(&b.beta_des_rad));
            let mut windows: Vec<String> = Vec::new();
            let mut run: Option<(f64, f64)> = None;
            for c in &cells {
                match (c.stable(), run) {
                    (true, Some((lo, _))) => run = Some((lo, c.beta_des_rad)),
                    (true, None) => run = Some((c.beta_des_rad, c.beta_des_rad)),
                    (false, Some(r)) => {
                        windows.push(window_text(r));
                        run = None;
                    }
                    (false, None) => {}
                }
            }
            if let Some(r) = run {
                windows.push(window_text(r));
            }
            let text = if windows.is_empty() {
                "none".to_owned()
            } else {
                windows.join(", ")
            };
            parts.push(format!("omega {omega:.1}: {text}"));
        }
        parts.join("; ")
    }
}

fn window_text((lo, hi): (f64, f64)) -> String {
    if lo == hi {
        format!("{lo:.2}")
    } else {
        format!("{lo:.2}-{hi:.2}")
    }
}

/// What one measuring run found.
#[derive(Clone, Copy, Debug)]
struct RunResult {
    fell: bool,
    hops: usize,
    speed: f64,
    clearance: f64,
}

/// Whether the hop just done left the hopper in a state it cannot go on from: moving backwards at the
/// apex (it bounced back off its foot).
fn went_backwards(hopper: &Hopper) -> bool {
    hopper.state[2] <= 0.0
}

/// One measuring run on `terrain` in `gait`; with `exit`, `settle_hops` there and then `exit_hops` on
/// `exit` (same gait).
fn measure_run(
    sim: &Simulator,
    terrain: &Terrain,
    gait: &Gait,
    exit: Option<(&Terrain, usize)>,
    params: &GaitTableParams,
    seed: u64,
) -> Result<RunResult> {
    let cfg = &sim.config;
    let mut hopper = Hopper::new(
        cfg.robot.clone(),
        gait.clone(),
        terrain.ground(),
        cfg.integrator,
    )?;
    let mut rng = ChaCha8Rng::seed_from_u64(mix(seed ^ 0x6A17_7AB1));
    let noise = Normal::new(0.0, cfg.realism.touchdown_angle_noise_rad)
        .map_err(|e| param("realism.touchdown_angle_noise_rad", e.to_string()))?;
    let mut samples = Vec::new();
    let settle = params.settle_hops.min(params.hops.saturating_sub(1));
    let total = match exit {
        Some((_, switch_at)) => switch_at + params.exit_hops,
        None => params.hops,
    };
    let mut start = (hopper.state[0], hopper.t_s);
    let mut clearance = f64::INFINITY;
    for h in 0..total {
        if h == settle {
            start = (hopper.state[0], hopper.t_s);
        }
        if let Some((next, switch_at)) = exit
            && h == switch_at
        {
            hopper.ground = next.ground();
        }
        samples.clear();
        let fell = match hopper.hop(h, 1.0, f64::INFINITY, &mut samples, noise.sample(&mut rng)) {
            Ok(_) => went_backwards(&hopper),
            Err(SimError::Fell { .. }) => true,
            Err(err) => return Err(err),
        };
        if fell {
            return Ok(RunResult {
                fell: true,
                hops: h,
                speed: f64::NAN,
                clearance: clearance.min(0.0),
            });
        }
        let td = hopper.touchdown_leg_length_m() * hopper.next_touchdown_angle_rad.cos();
        clearance = clearance.min(hopper.state[1] - td);
    }
    let dt = hopper.t_s - start.1;
    let speed = if dt > 0.0 {
        (hopper.state[0] - start.0) / dt
    } else {
        f64::NAN
    };
    Ok(RunResult {
        fell: false,
        hops: total,
        speed,
        clearance,
    })
}

/// Measures every gait on every terrain (steady runs, and exit runs onto every other terrain; all in
/// parallel) and recommends, per terrain, the fastest gait that never fell (see [`GaitTable::best`]).
pub fn gait_table(
    sim: &Simulator,
    terrains: &[String],
    gaits: &[String],
    params: &GaitTableParams,
) -> Result<GaitTable> {
    gait_table_with_progress(sim, terrains, gaits, params, &|_, _| {})
}

/// [`gait_table`], calling `progress(runs done, runs in all)` as the runs finish (from worker threads).
pub fn gait_table_with_progress(
    sim: &Simulator,
    terrains: &[String],
    gaits: &[String],
    params: &GaitTableParams,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<GaitTable> {
    if params.seeds.is_empty() || params.hops == 0 {
        return Err(param("gait_table", "need at least one seed and one hop"));
    }
    let resolved: Vec<(String, Terrain)> = terrains
        .iter()
        .map(|t| Ok((t.clone(), sim.terrain(t)?)))
        .collect::<Result<_>>()?;
    // Jobs: (terrain index, gait, exit terrain index, seed).
    let mut jobs = Vec::new();
    for (ti, (t, _)) in resolved.iter().enumerate() {
        for g in gaits {
            let gait = sim.gait(g)?;
            for (si, &seed) in params.seeds.iter().enumerate() {
                // Common random numbers across gaits: the same actuator noise for every gait of a seed.
                let seed = mix(mix(seed) ^ name_hash(t));
                jobs.push((ti, gait.clone(), None, seed));
                if params.exit_hops > 0 {
                    // The terrain changes after settle_hops + seed index hops: the step off the terrain
                    // falls on every phase of a hop-to-hop oscillation, not always on the same one.
                    for ei in (0..resolved.len()).filter(|&ei| ei != ti) {
                        jobs.push((ti, gait.clone(), Some((ei, params.settle_hops + si)), seed));
                    }
                }
            }
        }
    }
    let done = std::sync::atomic::AtomicUsize::new(0);
    let results: Vec<RunResult> = jobs
        .par_iter()
        .map(|(ti, gait, exit, seed)| {
            let exit = exit.map(|(ei, at)| (&resolved[ei].1, at));
            let result = measure_run(sim, &resolved[*ti].1, gait, exit, params, *seed);
            let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress(n, jobs.len());
            result
        })
        .collect::<Result<_>>()?;
    let mut cells: Vec<GaitCell> = Vec::new();
    for ((ti, gait, exit, _), r) in jobs.iter().zip(&results) {
        let terrain = &resolved[*ti].0;
        let index = match cells
            .iter()
            .position(|c| c.terrain == *terrain && c.gait == gait.name)
        {
            Some(i) => i,
            None => {
                cells.push(GaitCell {
                    terrain: terrain.clone(),
                    gait: gait.name.clone(),
                    omega_rad_per_s: gait.omega_rad_per_s,
                    beta_des_rad: gait.beta_des_rad,
                    runs: 0,
                    falls: 0,
                    hops: 0,
                    mean_speed_m_per_s: 0.0,
                    min_apex_clearance_m: f64::INFINITY,
                    exit_runs: 0,
                    exit_falls: BTreeMap::new(),
                });
                cells.len() - 1
            }
        };
        let cell = &mut cells[index];
        match exit {
            Some((ei, _)) => {
                cell.exit_runs += 1;
                *cell.exit_falls.entry(resolved[*ei].0.clone()).or_insert(0) += usize::from(r.fell);
            }
            None => {
                cell.runs += 1;
                cell.falls += usize::from(r.fell);
                cell.hops += r.hops;
                cell.min_apex_clearance_m = cell.min_apex_clearance_m.min(r.clearance);
                if !r.fell {
                    // Running sum here, divided below.
                    cell.mean_speed_m_per_s += r.speed;
                }
            }
        }
    }
    for cell in &mut cells {
        let ok = cell.runs - cell.falls;
        cell.mean_speed_m_per_s = if ok == 0 {
            f64::NAN
        } else {
            cell.mean_speed_m_per_s / ok as f64
        };
    }
    let mut best = BTreeMap::new();
    let mut best_is_stable = BTreeMap::new();
    let mut best_is_robust = BTreeMap::new();
    for (t, _) in &resolved {
        let here: Vec<&GaitCell> = cells.iter().filter(|c| c.terrain == *t).collect();
        if let Some((c, robust)) = recommend(&here) {
            best.insert(t.clone(), c.gait.clone());
            best_is_stable.insert(t.clone(), c.stable());
            best_is_robust.insert(t.clone(), robust);
        }
    }
    Ok(GaitTable {
        params: params.clone(),
        cells,
        best,
        best_is_stable,
        best_is_robust,
    })
}

/// The recommended gait among one terrain's cells (see [`GaitTable::best`]) and whether it is robustly
/// stable.
fn recommend<'c>(here: &[&'c GaitCell]) -> Option<(&'c GaitCell, bool)> {
    let speed = |c: &GaitCell| {
        if c.mean_speed_m_per_s.is_nan() {
            f64::NEG_INFINITY
        } else {
            c.mean_speed_m_per_s
        }
    };
    let robust = |c: &GaitCell| c.stable() && neighbours_stable(here, c);
    let fastest = |keep: &dyn Fn(&GaitCell) -> bool| {
        here.iter()
            .copied()
            .filter(|c| keep(c))
            .max_by(|a, b| speed(a).total_cmp(&speed(b)))
    };
    let choice = fastest(&robust)
        .or_else(|| fastest(&GaitCell::stable))
        .or_else(|| {
            let falls = |c: &GaitCell| c.falls + c.total_exit_falls();
            here.iter()
                .copied()
                .min_by(|a, b| falls(a).cmp(&falls(b)).then(speed(b).total_cmp(&speed(a))))
        })?;
    Some((choice, robust(choice)))
}

/// Whether the cells next to `cell` in `beta_des` (same terrain and `omega`, the nearest below and
/// above, if measured) are stable: a margin against the actuator noise and model error that a finite
/// number of runs cannot rule out.
fn neighbours_stable(cells: &[&GaitCell], cell: &GaitCell) -> bool {
    let same_omega = cells
        .iter()
        .filter(|c| c.omega_rad_per_s == cell.omega_rad_per_s && c.gait != cell.gait);
    let below = same_omega
        .clone()
        .filter(|c| c.beta_des_rad < cell.beta_des_rad)
        .max_by(|a, b| a.beta_des_rad.total_cmp(&b.beta_des_rad));
    let above = same_omega
        .filter(|c| c.beta_des_rad > cell.beta_des_rad)
        .min_by(|a, b| a.beta_des_rad.total_cmp(&b.beta_des_rad));
    below.is_none_or(|c| c.stable()) && above.is_none_or(|c| c.stable())
}

/// A grid of `beta_des` values for [`gait_candidates`], rad.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BetaSweep {
    pub from_rad: f64,
    pub to_rad: f64,
    pub step_rad: f64,
}

impl Default for BetaSweep {
    /// 0.20 to 0.80 rad in steps of 0.02: past the paper's gaits (0.27-0.57) on both sides, and the
    /// finest step the variant names (two decimals) resolve.
    fn default() -> Self {
        Self {
            from_rad: 0.20,
            to_rad: 0.80,
            step_rad: 0.02,
        }
    }
}

impl BetaSweep {
    /// The grid's values, `from_rad` to `to_rad` inclusive.
    pub fn values(&self) -> Result<Vec<f64>> {
        let ok = self.from_rad.is_finite()
            && self.to_rad.is_finite()
            && self.step_rad.is_finite()
            && self.step_rad >= 0.005
            && self.from_rad <= self.to_rad;
        if !ok {
            return Err(param(
                "beta_sweep",
                format!(
                    "need from <= to and a step of at least 0.005 rad, got {} to {} step {}",
                    self.from_rad, self.to_rad, self.step_rad
                ),
            ));
        }
        let n = ((self.to_rad - self.from_rad) / self.step_rad + 1e-9).floor() as usize;
        Ok((0..=n)
            .map(|i| self.from_rad + i as f64 * self.step_rad)
            .collect())
    }
}

/// The gaits a terrain-to-gait search measures: each of `bases` (configured gaits) and, with a sweep,
/// its variants `BASE@BETA` over the sweep's `beta_des` grid (same `omega`).
pub fn gait_candidates(
    sim: &Simulator,
    bases: &[String],
    sweep: Option<&BetaSweep>,
) -> Result<Vec<String>> {
    let mut names = Vec::new();
    for base in bases {
        let gait = sim.gait(base)?;
        names.push(gait.name.clone());
        if let Some(sweep) = sweep {
            for beta in sweep.values()? {
                let name = Gait::variant_name(base, beta);
                // Resolving checks the angle limits; a variant equal to its base is not measured twice.
                if sim.gait(&name)?.beta_des_rad != gait.beta_des_rad {
                    names.push(name);
                }
            }
        }
    }
    Ok(names)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cell(
        gait: &str,
        omega: f64,
        beta: f64,
        speed: f64,
        falls: usize,
        exit_falls: usize,
    ) -> GaitCell {
        GaitCell {
            terrain: "grass".to_owned(),
            gait: gait.to_owned(),
            omega_rad_per_s: omega,
            beta_des_rad: beta,
            runs: 5,
            falls,
            hops: 500,
            mean_speed_m_per_s: speed,
            min_apex_clearance_m: 0.01,
            exit_runs: 15,
            exit_falls: BTreeMap::from([("wood".to_owned(), exit_falls)]),
        }
    }

    #[test]
    fn the_recommendation_keeps_a_margin_in_beta_des() {
        // A window 0.68-0.72 between exit falls (below) and steady falls (above).
        let cells = [
            cell("G@0.66", 6.5, 0.66, 1.58, 0, 3),
            cell("G@0.68", 6.5, 0.68, 1.62, 0, 0),
            cell("G@0.70", 6.5, 0.70, 1.66, 0, 0),
            cell("G@0.72", 6.5, 0.72, 1.70, 0, 0),
            cell("G@0.74", 6.5, 0.74, 1.74, 2, 0),
            // Another omega: fastest of all, stable, but its neighbour fell.
            cell("H@0.74", 7.0, 0.74, 1.80, 0, 0),
            cell("H@0.76", 7.0, 0.76, f64::NAN, 5, 0),
        ];
        let here: Vec<&GaitCell> = cells.iter().collect();
        let (best, robust) = recommend(&here).unwrap();
        assert_eq!(best.gait, "G@0.70");
        assert!(robust && best.stable());
        // Without the robust middle, the fastest stable cell is taken and said not to be robust.
        let here: Vec<&GaitCell> = cells.iter().filter(|c| c.gait != "G@0.70").collect();
        let (best, robust) = recommend(&here).unwrap();
        assert_eq!(best.gait, "H@0.74");
        assert!(!robust && best.stable());
        // Nothing stable: the fewest falls, ties to the faster.
        let here: Vec<&GaitCell> = [&cells[0], &cells[4], &cells[6]].into_iter().collect();
        let (best, robust) = recommend(&here).unwrap();
        assert_eq!(best.gait, "G@0.74");
        assert!(!robust && !best.stable());
        assert!(recommend(&[]).is_none());
    }

    #[test]
    fn beta_sweeps_include_both_ends_and_refuse_nonsense() {
        let sweep = BetaSweep {
            from_rad: 0.5,
            to_rad: 0.6,
            step_rad: 0.02,
        };
        let values = sweep.values().unwrap();
        assert_eq!(values.len(), 6);
        assert!((values[5] - 0.6).abs() < 1e-12);
        for (from_rad, to_rad, step_rad) in
            [(0.6, 0.5, 0.02), (0.5, 0.6, 0.0), (f64::NAN, 0.6, 0.02)]
        {
            let bad = BetaSweep {
                from_rad,
                to_rad,
                step_rad,
            };
            assert!(bad.values().is_err(), "{bad:?}");
        }
        assert_eq!(BetaSweep::default().values().unwrap().len(), 31);
    }
}
