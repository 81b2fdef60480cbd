//! The hopper: a spring-loaded inverted pendulum (SLIP) with the paper's Active Energy Removal (AER) stance
//! law (eq. 1), the touchdown-angle law (eq. 2), and terrain compliance in series with the leg.
//!
//! Coordinates: `x` forward along the track, `y` up, origin on the undeformed ground surface. Leg angles
//! are measured from the vertical: the touchdown angle `beta_td > 0` puts the foot ahead of the body and
//! the lift-off angle `beta_lo > 0` has the foot behind it, so a symmetric stance has `beta_lo = beta_td`
//! and eq. (2) places the next foot at the mirror image of the last lift-off (the neutral point) plus a
//! correction towards the desired angle.
//!
//! State (5 numbers): `[x, y, vx, vy, z_g]`, where `z_g >= 0` is how far the ground under the foot is
//! pushed down (terrain compliance, a Kelvin–Voigt spring/damper in series with the leg; the foot is
//! massless and does not slide). During flight `z_g` is not used.

use serde::{Deserialize, Serialize};

use crate::error::{Result, SimError, param};
use crate::ode::{Integrator, IntegratorParams, Stop};

/// Interval at which the stance force is scanned for its peak, s.
const PEAK_SCAN_S: f64 = 1e-3;

/// Standard gravity, m/s^2.
pub const GRAVITY_M_PER_S2: f64 = 9.806_65;

/// Mechanical parameters of the robot and its controller.
///
/// The FAMU-FSU Hopper's own values are not given in the paper; the defaults are assumptions chosen so that
/// the simulated hopper reproduces the paper's observables: a stance of about 140 ms (section IV) and the
/// forward velocities of Table I (see `cargo run --release -p presrs-cli -- simulate` and the crate README).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RobotParams {
    /// Body (point) mass, kg. Assumption; the `--load` option replaces it.
    pub body_mass_kg: f64,
    /// Leg spring stiffness, N/m. Assumption, set with the mass for a ~140 ms stance (paper, section IV).
    pub leg_stiffness_n_per_m: f64,
    /// Viscous damping of the leg's sliding joint, in parallel with the leg spring, N s/m. Assumption: the
    /// dissipation that, with the terrain's, balances the energy the AER law injects.
    pub leg_damping_n_s_per_m: f64,
    /// `zeta_o` of eq. (1): nominal leg rest length, m. Assumption.
    pub leg_rest_length_m: f64,
    /// `zeta_dev` of eq. (1): amplitude of the leg-length recirculation, m. Assumption.
    pub aer_amplitude_m: f64,
    /// `phi` of eq. (1), rad: the phase of the recirculation at touchdown (t in eq. 1 is the time since
    /// touchdown). A stabilising factor held fixed across gaits (paper, section IV); see the README.
    pub aer_phase_rad: f64,
    /// `c` of eq. (2): weight of the touchdown-angle error. A stabilising factor held fixed across gaits.
    pub touchdown_gain: f64,
    /// Smallest and largest touchdown angle the leg can be placed at, rad (mechanical limits; assumption).
    pub min_touchdown_angle_rad: f64,
    pub max_touchdown_angle_rad: f64,
    /// Height of the ball-joint ankle above the foot's base, m (Fig. 3; assumption).
    pub ankle_height_m: f64,
    /// Rotational stiffness of the compliant ankle (compression spring of Fig. 3), N m/rad (assumption).
    pub ankle_stiffness_n_m_per_rad: f64,
    /// Apex height of the body at the start of a trial, m (initial condition).
    pub initial_apex_height_m: f64,
    /// Forward speed at the start of a trial, m/s (initial condition). `null`: the speed of a symmetric
    /// stance at the desired touchdown angle, `2 zeta_o sin(beta_des) / (pi sqrt(m / k))`.
    pub initial_speed_m_per_s: Option<f64>,
    /// Hops simulated before recording starts, so that the gait has settled.
    pub warmup_hops: usize,
    /// When a trial's body mass differs from `body_mass_kg` (a payload, `--load`), scale the leg spring and
    /// damper with the mass (k ∝ m, c ∝ m), as an engineer re-tunes a hopper's leg for its payload. The
    /// leg's natural frequency and damping ratio, and so the stance time and the gaits G1-G3, stay those
    /// the controller was tuned for, while every force scales with the load. Without it the AER energy input
    /// outgrows the leg damping and the hopper is unstable beyond about 1.0x the nominal mass (see the
    /// README, "Load robustness").
    pub retune_leg_for_load: bool,
}

impl RobotParams {
    /// The robot carrying a total body mass of `load_kg` instead of `body_mass_kg`: the mass is replaced
    /// and, with [`retune_leg_for_load`](Self::retune_leg_for_load), the leg spring and damper scale with it.
    pub fn with_load(&self, load_kg: f64) -> Self {
        let mut robot = self.clone();
        let ratio = load_kg / self.body_mass_kg;
        robot.body_mass_kg = load_kg;
        if self.retune_leg_for_load {
            robot.leg_stiffness_n_per_m *= ratio;
            robot.leg_damping_n_s_per_m *= ratio;
        }
        robot
    }
}

impl Default for RobotParams {
    fn default() -> Self {
        Self {
            body_mass_kg: 2.5,
            leg_stiffness_n_per_m: 1700.0,
            leg_damping_n_s_per_m: 4.0,
            leg_rest_length_m: 0.16,
            aer_amplitude_m: 0.02,
            aer_phase_rad: 1.6,
            touchdown_gain: 0.1,
            min_touchdown_angle_rad: 0.0,
            max_touchdown_angle_rad: 1.2,
            ankle_height_m: 0.03,
            ankle_stiffness_n_m_per_rad: 0.5,
            initial_apex_height_m: 0.2,
            initial_speed_m_per_s: None,
            warmup_hops: 40,
            retune_leg_for_load: true,
        }
    }
}

impl RobotParams {
    pub fn validate(&self) -> Result<()> {
        let positive = [
            ("robot.body_mass_kg", self.body_mass_kg),
            ("robot.leg_stiffness_n_per_m", self.leg_stiffness_n_per_m),
            ("robot.leg_rest_length_m", self.leg_rest_length_m),
            ("robot.initial_apex_height_m", self.initial_apex_height_m),
        ];
        for (name, value) in positive {
            if !(value.is_finite() && value > 0.0) {
                return Err(param(name, format!("must be positive, got {value}")));
            }
        }
        let non_negative = [
            ("robot.leg_damping_n_s_per_m", self.leg_damping_n_s_per_m),
            ("robot.aer_amplitude_m", self.aer_amplitude_m),
            ("robot.ankle_height_m", self.ankle_height_m),
            (
                "robot.ankle_stiffness_n_m_per_rad",
                self.ankle_stiffness_n_m_per_rad,
            ),
        ];
        for (name, value) in non_negative {
            if !(value.is_finite() && value >= 0.0) {
                return Err(param(name, format!("must be >= 0, got {value}")));
            }
        }
        if self.aer_amplitude_m >= self.leg_rest_length_m {
            return Err(param(
                "robot.aer_amplitude_m",
                "must be smaller than the leg rest length",
            ));
        }
        if !(self.min_touchdown_angle_rad < self.max_touchdown_angle_rad
            && self.max_touchdown_angle_rad < std::f64::consts::FRAC_PI_2)
        {
            return Err(param(
                "robot.max_touchdown_angle_rad",
                "need min < max < pi/2",
            ));
        }
        Ok(())
    }
}

/// A leg gait `G(omega, phi, c, beta_des)`; `phi` and `c` are the robot's fixed stabilising factors.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Gait {
    pub name: String,
    /// `omega` of eq. (1), rad/s.
    pub omega_rad_per_s: f64,
    /// `beta_des^TD` of eq. (2), rad.
    pub beta_des_rad: f64,
}

impl Gait {
    /// Separates a gait variant's base gait from its `beta_des`: `G3@0.74` is G3's `omega` with
    /// `beta_des` = 0.74 rad (what [`crate::track::gait_candidates`] searches and
    /// [`crate::Simulator::gait`] resolves).
    pub const VARIANT_SEPARATOR: char = '@';

    pub fn new(name: &str, omega_rad_per_s: f64, beta_des_rad: f64) -> Self {
        Self {
            name: name.to_owned(),
            omega_rad_per_s,
            beta_des_rad,
        }
    }

    /// The name of the variant of `base` with `beta_des_rad` (two decimals, the resolution of a search).
    pub fn variant_name(base: &str, beta_des_rad: f64) -> String {
        format!("{base}{}{beta_des_rad:.2}", Self::VARIANT_SEPARATOR)
    }

    /// The configured gait a variant derives from (the name itself for a configured gait).
    pub fn base_name(&self) -> &str {
        self.name
            .split_once(Self::VARIANT_SEPARATOR)
            .map_or(self.name.as_str(), |(base, _)| base)
    }

    /// The paper's three gaits (section IV).
    pub fn paper() -> Vec<Self> {
        vec![
            Self::new("G1", 6.0, 0.27),
            Self::new("G2", 6.5, 0.42),
            Self::new("G3", 7.0, 0.57),
        ]
    }
}

/// Macroscopic normal compliance of a terrain under the foot: a spring and a damper in parallel
/// (Kelvin–Voigt), in series with the leg. `None` stiffness means rigid ground.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GroundParams {
    /// Normal stiffness, N/m; `null` for rigid ground.
    pub stiffness_n_per_m: Option<f64>,
    /// Normal damping, N s/m (must be > 0 for compliant ground: the foot is massless).
    pub damping_n_s_per_m: f64,
    /// Depth of a soft top layer (thick grass over soil), m: deeper than this the firm layer below adds
    /// `base_stiffness_n_per_m`. `null`: one uniform layer.
    pub layer_depth_m: Option<f64>,
    /// Stiffness the layer below adds once the top layer is compressed through, N/m.
    pub base_stiffness_n_per_m: f64,
    /// Exponent `n` of a stiffening top layer (a fibrous mat such as a grass canopy): with a layer depth
    /// `d`, the top layer's force is `k z (z / d)^(n - 1)` (secant stiffness `k` at `z = d`, tangent
    /// stiffness `n k z^(n-1) / d^(n-1)`, vanishing at the surface). 1: linear (Kelvin-Voigt).
    pub stiffening_exponent: f64,
}

impl Default for GroundParams {
    fn default() -> Self {
        Self::RIGID
    }
}

impl GroundParams {
    pub const RIGID: Self = Self {
        stiffness_n_per_m: None,
        damping_n_s_per_m: 0.0,
        layer_depth_m: None,
        base_stiffness_n_per_m: 0.0,
        stiffening_exponent: 1.0,
    };

    /// A uniform Kelvin-Voigt ground.
    pub const fn uniform(stiffness_n_per_m: f64, damping_n_s_per_m: f64) -> Self {
        Self {
            stiffness_n_per_m: Some(stiffness_n_per_m),
            damping_n_s_per_m,
            layer_depth_m: None,
            base_stiffness_n_per_m: 0.0,
            stiffening_exponent: 1.0,
        }
    }

    /// Elastic force of the ground at deflection `zg`, N (the top layer, plus the base once reached).
    pub fn spring_force_n(&self, zg: f64) -> f64 {
        let Some(k) = self.stiffness_n_per_m else {
            return 0.0;
        };
        let (top, base) = match self.layer_depth_m {
            Some(depth) => {
                let z = zg.max(0.0);
                let top = if self.stiffening_exponent == 1.0 {
                    k * zg
                } else {
                    k * z * (z / depth).powf(self.stiffening_exponent - 1.0)
                };
                let base = if zg > depth {
                    self.base_stiffness_n_per_m * (zg - depth)
                } else {
                    0.0
                };
                (top, base)
            }
            None => (k * zg, 0.0),
        };
        top + base
    }

    pub fn validate(&self, name: &str) -> Result<()> {
        if let Some(k) = self.stiffness_n_per_m {
            if !(k.is_finite() && k > 0.0) {
                return Err(param(
                    &format!("{name}.stiffness_n_per_m"),
                    format!("must be positive, got {k}"),
                ));
            }
            if let Some(depth) = self.layer_depth_m
                && !(depth.is_finite()
                    && depth > 0.0
                    && self.base_stiffness_n_per_m.is_finite()
                    && self.base_stiffness_n_per_m >= 0.0)
            {
                return Err(param(
                    &format!("{name}.layer_depth_m"),
                    format!(
                        "a layer depth must be positive with a non-negative base stiffness, got {depth} m"
                    ),
                ));
            }
            if !(self.stiffening_exponent.is_finite()
                && (1.0..=4.0).contains(&self.stiffening_exponent))
            {
                return Err(param(
                    &format!("{name}.stiffening_exponent"),
                    format!("must be in [1, 4], got {}", self.stiffening_exponent),
                ));
            }
            if self.stiffening_exponent != 1.0 && self.layer_depth_m.is_none() {
                return Err(param(
                    &format!("{name}.stiffening_exponent"),
                    "a stiffening top layer needs its depth (layer_depth_m)",
                ));
            }
            if !(self.damping_n_s_per_m.is_finite() && self.damping_n_s_per_m > 0.0) {
                return Err(param(
                    &format!("{name}.damping_n_s_per_m"),
                    "compliant ground needs positive damping (the foot is massless)",
                ));
            }
        }
        Ok(())
    }
}

/// The contact between foot and ground at one instant (between two simulation steps): what the skin
/// model needs at a frame time. (Not a data-set sample: that is `presrs::Sample`.)
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContactState {
    /// Time since the start of the trial, s.
    pub t_s: f64,
    /// Index of the hop whose stance this sample is in (`None` in flight).
    pub stance_of_hop: Option<usize>,
    /// Normal (vertical) ground reaction force, N (0 in flight).
    pub normal_force_n: f64,
    /// Tangential (forward) ground reaction force on the foot, N (negative = braking).
    pub tangential_force_n: f64,
    /// Leg angle from the vertical, rad, positive with the foot ahead of the body.
    pub leg_angle_rad: f64,
}

/// Ground truth of one hop (apex to apex, with its stance phase in the middle).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HopTruth {
    /// 0-based index of the hop in the trial (counting recorded hops only).
    pub hop: usize,
    pub touchdown_time_s: f64,
    pub liftoff_time_s: f64,
    pub stance_duration_s: f64,
    /// Touchdown angle (foot ahead), rad.
    pub touchdown_angle_rad: f64,
    /// Lift-off angle (foot behind), rad.
    pub liftoff_angle_rad: f64,
    /// Forward speed at touchdown and lift-off, m/s.
    pub touchdown_speed_m_per_s: f64,
    pub liftoff_speed_m_per_s: f64,
    /// Mean forward velocity from the previous apex to the next apex, m/s.
    pub mean_forward_velocity_m_per_s: f64,
    /// Apex height after this hop, m.
    pub apex_height_m: f64,
    /// Peak normal and tangential ground force over stance (scanned every millisecond), N.
    pub peak_normal_force_n: f64,
    pub peak_tangential_force_n: f64,
    /// Largest ground deflection under the foot, m.
    pub max_ground_deflection_m: f64,
    /// Ground deflection under the foot at lift-off, m: the footprint the foot leaves (a stiffening grass
    /// canopy is still pressed down when the foot comes off it).
    pub liftoff_ground_deflection_m: f64,
    /// Mechanical energy at the apex after the hop, J (kinetic + potential, ground level 0).
    pub apex_energy_j: f64,
}

/// The frame sample times of a hop: every `period_s`, from `record_from_s` on.
#[derive(Clone, Copy, Debug)]
struct SampleClock {
    record_from_s: f64,
    period_s: f64,
}

impl SampleClock {
    /// The first sample time at or after `t`.
    fn next_at_or_after(self, t: f64) -> f64 {
        let k = ((t - self.record_from_s) / self.period_s).ceil().max(0.0);
        let mut ts = self.record_from_s + k * self.period_s;
        if ts < t - 1e-12 {
            ts += self.period_s;
        }
        ts
    }
}

/// The continuous-time SLIP with its controller.
#[derive(Clone, Debug)]
pub struct Hopper {
    pub robot: RobotParams,
    pub gait: Gait,
    pub ground: GroundParams,
    integ: Integrator,
    /// Time since trial start, s.
    pub t_s: f64,
    /// `[x, y, vx, vy, z_g]`.
    pub state: [f64; 5],
    /// Touchdown angle that will be used at the next touchdown (commanded + noise), rad.
    pub next_touchdown_angle_rad: f64,
    hops_done: usize,
}

/// The leg rest length of eq. (1) and its rate, at time `tau` since touchdown.
fn rest_length(robot: &RobotParams, gait: &Gait, tau: f64) -> (f64, f64) {
    let arg = gait.omega_rad_per_s * tau + robot.aer_phase_rad;
    (
        robot.leg_rest_length_m - robot.aer_amplitude_m * arg.sin(),
        -robot.aer_amplitude_m * gait.omega_rad_per_s * arg.cos(),
    )
}

/// Forces in stance: (leg compression force along the leg, N; ground deflection rate, m/s).
fn stance_forces(
    robot: &RobotParams,
    gait: &Gait,
    ground: &GroundParams,
    foot_x: f64,
    tau: f64,
    s: &[f64; 5],
) -> (f64, f64, f64, f64) {
    let [x, y, vx, vy, zg] = *s;
    let rx = x - foot_x;
    let ry = y + zg;
    let l = (rx * rx + ry * ry).sqrt();
    let (ux, uy) = (rx / l, ry / l);
    let (zeta, zeta_dot) = rest_length(robot, gait, tau);
    let k = robot.leg_stiffness_n_per_m;
    let b = robot.leg_damping_n_s_per_m;
    // Leg force without the ground-rate term of the damper.
    let f0 = k * (zeta - l) + b * (zeta_dot - ux * vx - uy * vy);
    let zg_dot = match ground.stiffness_n_per_m {
        None => 0.0,
        Some(_) => (f0 * uy - ground.spring_force_n(zg)) / (ground.damping_n_s_per_m + b * uy * uy),
    };
    let force = f0 - b * uy * zg_dot;
    (force, zg_dot, ux, uy)
}

impl Hopper {
    /// A hopper at its initial apex, leg set to the gait's desired touchdown angle.
    pub fn new(
        robot: RobotParams,
        gait: Gait,
        ground: GroundParams,
        integrator: IntegratorParams,
    ) -> Result<Self> {
        robot.validate()?;
        ground.validate("ground")?;
        if !(gait.omega_rad_per_s.is_finite() && gait.beta_des_rad.is_finite()) {
            return Err(param("gait", "omega and beta_des must be finite"));
        }
        let beta = gait
            .beta_des_rad
            .clamp(robot.min_touchdown_angle_rad, robot.max_touchdown_angle_rad);
        let speed = robot.initial_speed_m_per_s.unwrap_or_else(|| {
            let stance_s =
                std::f64::consts::PI * (robot.body_mass_kg / robot.leg_stiffness_n_per_m).sqrt();
            2.0 * robot.leg_rest_length_m * beta.sin() / stance_s
        });
        let state = [0.0, robot.initial_apex_height_m, speed, 0.0, 0.0];
        Ok(Self {
            robot,
            gait,
            ground,
            integ: Integrator::new(integrator),
            t_s: 0.0,
            state,
            next_touchdown_angle_rad: beta,
            hops_done: 0,
        })
    }

    /// Leg length at touchdown, `zeta(0)` of eq. (1), m.
    pub fn touchdown_leg_length_m(&self) -> f64 {
        rest_length(&self.robot, &self.gait, 0.0).0
    }

    /// Total mechanical energy in flight (J): kinetic + gravitational (ground at y = 0).
    pub fn flight_energy_j(&self) -> f64 {
        let [_, y, vx, vy, _] = self.state;
        let m = self.robot.body_mass_kg;
        0.5 * m * (vx * vx + vy * vy) + m * GRAVITY_M_PER_S2 * y
    }

    /// Accepted integrator steps so far.
    pub fn integrator_steps(&self) -> usize {
        self.integ.steps
    }

    /// Ballistic flight until `event` crosses zero, pushing a flight sample (no ground force, the leg held
    /// at `leg_angle_rad`) onto `samples` at every time of `clock` on the way. With `limit = (start_s,
    /// max_s, reason)`, a flight that lasts more than `max_s` after `start_s` is a fall for `reason`.
    fn fly(
        &mut self,
        event: &impl Fn(f64, &[f64; 5]) -> f64,
        clock: SampleClock,
        leg_angle_rad: f64,
        samples: &mut Vec<ContactState>,
        limit: Option<(f64, f64, &str)>,
    ) -> Result<()> {
        let g = GRAVITY_M_PER_S2;
        let flight = |_t: f64, s: &[f64; 5]| [s[2], s[3], 0.0, -g, 0.0];
        let mut sample_t = clock.next_at_or_after(self.t_s);
        loop {
            let stop =
                self.integ
                    .advance(&flight, event, &mut self.t_s, &mut self.state, sample_t)?;
            if stop == Stop::Event {
                return Ok(());
            }
            if self.t_s >= clock.record_from_s - 1e-12 {
                samples.push(ContactState {
                    t_s: self.t_s,
                    stance_of_hop: None,
                    normal_force_n: 0.0,
                    tangential_force_n: 0.0,
                    leg_angle_rad,
                });
            }
            sample_t += clock.period_s;
            if let Some((start_s, max_s, reason)) = limit
                && self.t_s - start_s > max_s
            {
                return Err(SimError::Fell {
                    hop: self.hops_done,
                    reason: reason.to_owned(),
                });
            }
        }
    }

    /// Simulates one hop from the current apex to the next apex. Frame samples at times `k * period`
    /// (`k` integer, times after `record_from_s`) are pushed onto `samples`. `angle_noise_rad` is added
    /// to the commanded touchdown angle of the *next* hop (actuator error).
    pub fn hop(
        &mut self,
        hop_index: usize,
        sample_period_s: f64,
        record_from_s: f64,
        samples: &mut Vec<ContactState>,
        angle_noise_rad: f64,
    ) -> Result<HopTruth> {
        let g = GRAVITY_M_PER_S2;
        let m = self.robot.body_mass_kg;
        let beta_td = self.next_touchdown_angle_rad;
        let leg_td = self.touchdown_leg_length_m();
        let apex_x = self.state[0];
        let apex_t = self.t_s;
        let hop_number = self.hops_done;
        let fell = |reason: &str| SimError::Fell {
            hop: hop_number,
            reason: reason.to_owned(),
        };
        if self.state[1] <= leg_td * beta_td.cos() {
            return Err(fell("apex below the touchdown height of the leg"));
        }

        // ---- Flight (descent): ballistic until the foot reaches the ground.
        let td_height = leg_td * beta_td.cos();
        let touchdown_event = |_t: f64, s: &[f64; 5]| td_height - s[1];
        let clock = SampleClock {
            record_from_s,
            period_s: sample_period_s,
        };
        self.fly(
            &touchdown_event,
            clock,
            beta_td,
            samples,
            Some((apex_t, 10.0, "no touchdown within 10 s")),
        )?;
        let t_td = self.t_s;
        let v_td = self.state[2];
        let foot_x = self.state[0] + leg_td * beta_td.sin();
        self.state[4] = 0.0;

        // ---- Stance.
        let (robot, gait, ground) = (self.robot.clone(), self.gait.clone(), self.ground);
        let stance = |t: f64, s: &[f64; 5]| {
            let (force, zg_dot, ux, uy) =
                stance_forces(&robot, &gait, &ground, foot_x, t - t_td, s);
            [s[2], s[3], force * ux / m, force * uy / m - g, zg_dot]
        };
        let liftoff_event = |t: f64, s: &[f64; 5]| {
            let (force, ..) = stance_forces(&robot, &gait, &ground, foot_x, t - t_td, s);
            -force
        };
        let mut peak_n = 0.0_f64;
        let mut peak_t = 0.0_f64;
        let mut max_zg = 0.0_f64;
        let mut sample_t = clock.next_at_or_after(self.t_s);
        loop {
            // Stop at every frame sample, and at least every PEAK_SCAN_S to track force peaks.
            let target = sample_t.min(self.t_s + PEAK_SCAN_S);
            let stop = self.integ.advance(
                &stance,
                &liftoff_event,
                &mut self.t_s,
                &mut self.state,
                target,
            )?;
            max_zg = max_zg.max(self.state[4]);
            if stop == Stop::Event {
                break;
            }
            let (force, _, ux, uy) =
                stance_forces(&robot, &gait, &ground, foot_x, self.t_s - t_td, &self.state);
            let force = force.max(0.0);
            let normal = force * uy;
            // Ground reaction on the foot: the leg pushes the foot along -u, the ground pushes back along +u.
            let tangential = force * ux;
            peak_n = peak_n.max(normal);
            if tangential.abs() > peak_t.abs() {
                peak_t = tangential;
            }
            if self.state[1] <= 0.0 {
                return Err(fell("body reached the ground"));
            }
            if self.t_s - t_td > 5.0 {
                return Err(fell("stance longer than 5 s"));
            }
            if self.t_s < sample_t {
                continue;
            }
            if self.t_s >= record_from_s - 1e-12 {
                samples.push(ContactState {
                    t_s: self.t_s,
                    stance_of_hop: Some(hop_index),
                    normal_force_n: normal,
                    tangential_force_n: tangential,
                    leg_angle_rad: (foot_x - self.state[0]).atan2(self.state[1] + self.state[4]),
                });
            }
            sample_t += sample_period_s;
        }
        let t_lo = self.t_s;
        let beta_lo = (self.state[0] - foot_x).atan2(self.state[1] + self.state[4]);
        let v_lo = self.state[2];
        let liftoff_zg = self.state[4];
        // The foot leaves the ground; the body is at height y (the ground relaxes behind it).
        self.state[4] = 0.0;
        if self.state[3] <= 0.0 {
            return Err(fell("lift-off with downward velocity (no flight phase)"));
        }

        // ---- Flight (ascent) to the apex: the apex event is vy crossing zero downwards.
        let apex_event = |_t: f64, s: &[f64; 5]| -s[3];
        self.fly(&apex_event, clock, -beta_lo, samples, None)?;

        // ---- Eq. (2): the next touchdown angle.
        let commanded = beta_lo
            + self.robot.touchdown_gain * (beta_td - self.gait.beta_des_rad)
            + angle_noise_rad;
        self.next_touchdown_angle_rad = commanded.clamp(
            self.robot.min_touchdown_angle_rad,
            self.robot.max_touchdown_angle_rad,
        );
        self.hops_done += 1;
        Ok(HopTruth {
            hop: hop_index,
            touchdown_time_s: t_td,
            liftoff_time_s: t_lo,
            stance_duration_s: t_lo - t_td,
            touchdown_angle_rad: beta_td,
            liftoff_angle_rad: beta_lo,
            touchdown_speed_m_per_s: v_td,
            liftoff_speed_m_per_s: v_lo,
            mean_forward_velocity_m_per_s: (self.state[0] - apex_x) / (self.t_s - apex_t),
            apex_height_m: self.state[1],
            peak_normal_force_n: peak_n,
            peak_tangential_force_n: peak_t,
            max_ground_deflection_m: max_zg,
            liftoff_ground_deflection_m: liftoff_zg,
            apex_energy_j: self.flight_energy_j(),
        })
    }
}
