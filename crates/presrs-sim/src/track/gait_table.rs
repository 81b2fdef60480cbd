//! The gait table: every gait measured on every terrain (steady runs and exit runs onto the other
//! terrains), and the recommended gait per terrain.

use std::collections::BTreeMap;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::dataset::Simulator;
use crate::error::{Result, SimError, param};
use crate::slip::{Gait, Hopper};
use crate::terrain::Terrain;

use super::support::{mix, name_hash, went_backwards};

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
