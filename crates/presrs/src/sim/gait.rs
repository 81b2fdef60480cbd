//! The terrain-to-gait loop on the simulator: the hopper runs a track of terrain segments
//! ([`presrs_sim::track`]) in each fixed gait and, with a model, adaptively: classifying every stance
//! online and switching to the gait the model's terrain-to-gait table recommends
//! ([`compare_on_track`]).
//!
//! Also here: measuring that table with the simulator ([`measure_gait_table`], for training a model's
//! online profile and for an adaptive run whose model has none), over the configured gaits and their
//! `beta_des` variants ([`GaitSweep`]).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use presrs_core::novelty::UNKNOWN_LABEL;
use presrs_core::online::{OnlineClassifier, OnlineEvent, OnlineProfile};
use presrs_core::{FrameView, Grid};
use presrs_io::model_file::load_model;
use presrs_sim::track::{
    BetaSweep, GaitTable, GaitTableParams, HopView, PolicyStep, TrackParams, TrackRun,
    gait_candidates, gait_table_with_progress, parse_track, run_track,
};
use presrs_sim::{SimConfig, Simulator};

use crate::error::{Context, Error, Result};
use crate::progress::Progress;

/// `--gait-sweep`: the `beta_des` grid searched around each configured gait, or none.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaitSweep(pub Option<BetaSweep>);

impl GaitSweep {
    /// The default of `--gait-sweep` (that of [`BetaSweep::default`]).
    pub const DEFAULT_TEXT: &'static str = "0.20:0.80:0.02";
}

impl std::str::FromStr for GaitSweep {
    type Err = String;

    /// `none` or `FROM:TO:STEP` (radians).
    fn from_str(text: &str) -> std::result::Result<Self, String> {
        parse_gait_sweep(text)
    }
}

/// Parses `none` or `FROM:TO:STEP` (radians).
pub fn parse_gait_sweep(text: &str) -> std::result::Result<GaitSweep, String> {
    let text = text.trim();
    if text.eq_ignore_ascii_case("none") {
        return Ok(GaitSweep(None));
    }
    let parts: Vec<f64> = text
        .split(':')
        .map(|p| p.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| {
            format!("expected none or FROM:TO:STEP in radians (e.g. 0.20:0.80:0.02), got {text:?}")
        })?;
    let [from_rad, to_rad, step_rad] = parts[..] else {
        return Err(format!(
            "expected none or FROM:TO:STEP in radians (e.g. 0.20:0.80:0.02), got {text:?}"
        ));
    };
    let sweep = BetaSweep {
        from_rad,
        to_rad,
        step_rad,
    };
    sweep.values().map_err(|e| e.to_string())?;
    Ok(GaitSweep(Some(sweep)))
}

/// A terrain-to-gait table measured with the simulator.
#[derive(Clone, Debug)]
pub struct MeasuredGaitTable {
    pub table: GaitTable,
    /// Terrains of the model the simulator does not know (no gait recommended for them).
    pub unknown: Vec<String>,
}

impl MeasuredGaitTable {
    /// The table as text, after a line naming the unknown terrains if any.
    pub fn format(&self) -> String {
        let mut text = String::new();
        if !self.unknown.is_empty() {
            text.push_str(&format!(
                "gait table: the simulator does not know {} (no gait recommended for them)\n",
                self.unknown.join(", ")
            ));
        }
        text.push_str(&self.table.format());
        text
    }
}

/// Measures the terrain-to-gait table with the simulator on every terrain of `class_names` it knows:
/// the configured gaits and, with a sweep, their `beta_des` variants.
pub fn measure_gait_table(
    config: &SimConfig,
    seed: u64,
    class_names: &[String],
    sweep: GaitSweep,
    progress: &dyn Progress,
) -> Result<MeasuredGaitTable> {
    let sim = Simulator::new(config.clone(), seed, Vec::new())?;
    let (terrains, unknown): (Vec<String>, Vec<String>) = class_names
        .iter()
        .cloned()
        .partition(|t| sim.terrain(t).is_ok());
    let bases: Vec<String> = config.gaits.iter().map(|g| g.name.clone()).collect();
    let candidates = gait_candidates(&sim, &bases, sweep.0.as_ref())?;
    let started = std::sync::Once::new();
    let advance = |done: usize, total: usize| {
        started.call_once(|| progress.start("gait table runs", Some(total as u64)));
        if done > 0 {
            progress.advance(1);
        }
    };
    let table = gait_table_with_progress(
        &sim,
        &terrains,
        &candidates,
        &GaitTableParams::default(),
        &advance,
    );
    progress.finish();
    Ok(MeasuredGaitTable {
        table: table?,
        unknown,
    })
}

/// One policy's runs on the track.
#[derive(Debug, serde::Serialize)]
pub struct PolicyRuns {
    /// `adaptive` or `fixed G1`, ...
    pub policy: String,
    pub runs: Vec<TrackRun>,
}

impl PolicyRuns {
    fn finished(&self) -> usize {
        self.runs.iter().filter(|r| r.finished).count()
    }

    fn mean(&self, f: impl Fn(&TrackRun) -> f64) -> f64 {
        if self.runs.is_empty() {
            f64::NAN
        } else {
            self.runs.iter().map(f).sum::<f64>() / self.runs.len() as f64
        }
    }

    fn total(&self, f: impl Fn(&TrackRun) -> usize) -> usize {
        self.runs.iter().map(f).sum()
    }
}

/// The whole comparison (what `--json` writes).
#[derive(Debug, serde::Serialize)]
pub struct TrackComparison {
    pub track: String,
    pub length_m: f64,
    pub seeds: Vec<u64>,
    /// The terrain-to-gait table the adaptive runs used, and where it came from.
    pub gait_table: BTreeMap<String, String>,
    pub gait_table_source: Option<String>,
    /// The measured table, when it was measured here.
    pub measured_table: Option<GaitTable>,
    pub policies: Vec<PolicyRuns>,
}

impl TrackComparison {
    /// The comparison table as text.
    pub fn format(&self) -> String {
        use std::fmt::Write as _;
        let mut out = String::new();
        let _ = writeln!(
            out,
            "Track {} ({:.1} m), {} run(s) per policy (seeds {}); means over runs, counts summed",
            self.track,
            self.length_m,
            self.seeds.len(),
            self.seeds
                .iter()
                .map(u64::to_string)
                .collect::<Vec<_>>()
                .join(",")
        );
        // The policy column fits the longest name (`fixed G3@0.62`) and a space.
        let width = self
            .policies
            .iter()
            .map(|p| p.policy.chars().count() + 1)
            .max()
            .unwrap_or(0)
            .max(12);
        let _ = writeln!(
            out,
            "{:<width$}{:>10}{:>10}{:>11}{:>7}{:>22}{:>10}",
            "policy", "finished", "time s", "speed m/s", "falls", "misclassified", "switches"
        );
        for p in &self.policies {
            let decided = p.total(|r| r.decided);
            let mis = if p.policy == "adaptive" {
                format!(
                    "{}/{} ({:.1} %)",
                    p.total(|r| r.misclassified),
                    decided,
                    100.0 * p.total(|r| r.misclassified) as f64 / decided.max(1) as f64
                )
            } else {
                "-".to_owned()
            };
            let _ = writeln!(
                out,
                "{:<width$}{:>10}{:>10.2}{:>11.3}{:>7}{:>22}{:>10}",
                p.policy,
                format!("{}/{}", p.finished(), p.runs.len()),
                p.mean(|r| r.time_s),
                p.mean(|r| r.mean_speed_m_per_s),
                p.total(|r| r.falls),
                mis,
                p.total(|r| r.switches)
            );
        }
        if let Some(source) = &self.gait_table_source {
            let table: Vec<String> = self
                .gait_table
                .iter()
                .map(|(t, g)| format!("{t}={g}"))
                .collect();
            let _ = writeln!(out, "gait table ({source}): {}", table.join(","));
        }
        let _ = writeln!(out, "{}", self.verdict());
        out
    }

    /// Whether the adaptive policy beat every fixed gait, said plainly. Policies rank by runs finished,
    /// then falls (a fall is a robot on the ground: no time saved pays for it), then time; the fastest
    /// fixed gait is named too when it is not the best.
    pub fn verdict(&self) -> String {
        let Some(adaptive) = self.policies.iter().find(|p| p.policy == "adaptive") else {
            return "no adaptive run (give --adaptive MODEL)".to_owned();
        };
        let fixed = || self.policies.iter().filter(|p| p.policy != "adaptive");
        let rank = |a: &PolicyRuns, b: &PolicyRuns| {
            b.finished()
                .cmp(&a.finished())
                .then(a.total(|r| r.falls).cmp(&b.total(|r| r.falls)))
                .then(a.mean(|r| r.time_s).total_cmp(&b.mean(|r| r.time_s)))
        };
        let Some(best) = fixed().min_by(|a, b| rank(a, b)) else {
            return "no fixed gait to compare with".to_owned();
        };
        let describe = |p: &PolicyRuns| {
            format!(
                "{}, {:.2} s ({} falls)",
                p.policy,
                p.mean(|r| r.time_s),
                p.total(|r| r.falls)
            )
        };
        let change =
            |p: &PolicyRuns| 100.0 * (adaptive.mean(|r| r.time_s) / p.mean(|r| r.time_s) - 1.0);
        let helps = rank(adaptive, best) == std::cmp::Ordering::Less;
        let mut text = format!(
            "adaptation {}: adaptive {:.2} s ({} falls) vs the best fixed gait (finished, then falls, then \
             time), {}: {:+.1} % time",
            if helps { "helps" } else { "does NOT help" },
            adaptive.mean(|r| r.time_s),
            adaptive.total(|r| r.falls),
            describe(best),
            change(best)
        );
        if let Some(fastest) = fixed()
            .filter(|p| p.finished() == best.finished())
            .min_by(|a, b| a.mean(|r| r.time_s).total_cmp(&b.mean(|r| r.time_s)))
            && fastest.policy != best.policy
        {
            text.push_str(&format!(
                "; the fastest fixed gait, {}: {:+.1} % time",
                describe(fastest),
                change(fastest)
            ));
        }
        text
    }
}

/// The adaptive policy: the online classifier, the terrain-to-gait table, and a switching rule.
struct AdaptivePolicy<'m, 'a> {
    classifier: OnlineClassifier<'m>,
    class_names: &'a [String],
    table: &'a BTreeMap<String, String>,
    /// Switch only after this many consecutive decisions for the same terrain (1: on every decision).
    confirm: usize,
    /// The last decided terrain and how many decisions in a row named it.
    streak: Option<(usize, usize)>,
}

impl AdaptivePolicy<'_, '_> {
    /// Feeds a hop's frames to the classifier; the hop's decision (if any) names the terrain, and the
    /// gait switches once `confirm` decisions in a row agree.
    fn step(&mut self, view: &HopView<'_>) -> std::result::Result<PolicyStep, String> {
        let mut step = PolicyStep::default();
        let grid: Grid = view.grid;
        for i in 0..view.frame_count() {
            let Some(values) = view.frame(i) else {
                break;
            };
            let frame = FrameView::new(grid, values, None).map_err(|e| e.to_string())?;
            let events = self.classifier.push(&frame).map_err(|e| e.to_string())?;
            for event in events.events {
                // A terrain never seen: keep the current gait, unless the table names a cautious one
                // for `unknown`; it breaks any streak.
                if let OnlineEvent::Decision(decision) = event
                    && decision.novelty.is_some_and(|novelty| novelty.unknown)
                {
                    self.streak = None;
                    step.terrain = Some(UNKNOWN_LABEL.to_owned());
                    step.gait = self.table.get(UNKNOWN_LABEL).cloned();
                    continue;
                }
                if let OnlineEvent::Decision(decision) = event
                    && let Some(label) = self.class_names.get(decision.class)
                {
                    let run = match self.streak {
                        Some((class, n)) if class == decision.class => n + 1,
                        _ => 1,
                    };
                    self.streak = Some((decision.class, run));
                    step.terrain = Some(label.clone());
                    step.gait = if run >= self.confirm {
                        self.table.get(label).cloned()
                    } else {
                        None
                    };
                }
            }
        }
        Ok(step)
    }
}

/// How a track is run.
#[derive(Clone, Debug, PartialEq)]
pub struct TrackOptions {
    /// Seed of the first run; run `i` has seed `seed + i`.
    pub seed: u64,
    /// Runs per policy.
    pub repeats: usize,
    /// The model of the adaptive run (none: fixed gaits only).
    pub adaptive: Option<PathBuf>,
    /// With a model without a terrain-to-gait table: the `beta_des` grid measured.
    pub gait_sweep: GaitSweep,
    /// Decisions in a row for the same terrain before the adaptive run switches gait.
    pub confirm: usize,
    /// The fixed gaits run (empty: every configured gait and every gait the table recommends).
    pub fixed_gaits: Vec<String>,
    /// The adaptive run's gait at the start line (default: the second configured gait).
    pub start_gait: Option<String>,
    /// A whole-stance model decides K frames after touchdown, or at its first confident decision point
    /// (`auto`), instead of at lift-off (an error with a one-frame model, and for a moment the model
    /// was not trained for, as in `stream`).
    pub decide_at: Option<presrs_core::online::DecideAt>,
    /// Whether a model that scores novelty may decide `unknown` (false: `--novelty off`).
    pub novelty: bool,
}

/// What [`compare_on_track`] found.
#[derive(Debug)]
pub struct TrackOutcome {
    pub comparison: TrackComparison,
    /// Said before the comparison (a model without an online profile).
    pub notes: Vec<String>,
    /// The table measured for a model that had none.
    pub measured: Option<MeasuredGaitTable>,
}

/// Fixed gaits and (with a model) the adaptive policy on the same seeds along the track `spec`
/// (`TERRAIN:METRES,...`).
pub fn compare_on_track(
    config: &SimConfig,
    spec: &str,
    options: &TrackOptions,
    progress: &dyn Progress,
) -> Result<TrackOutcome> {
    let track = parse_track(spec)?;
    let sim = Simulator::new(config.clone(), options.seed, Vec::new())?;
    let seeds: Vec<u64> = (0..options.repeats as u64)
        .map(|i| options.seed.wrapping_add(i))
        .collect();
    let mut policies = Vec::new();
    let mut notes = Vec::new();
    let (mut gait_table_map, mut source, mut measured): (BTreeMap<String, String>, _, _) =
        (BTreeMap::new(), None, None);
    if let Some(path) = &options.adaptive {
        let mut file = load_model(path)
            .with_context(|| format!("cannot read the model {}", path.display()))?;
        if !options.novelty {
            file.model = file.model.without_novelty();
        }
        let model = &file.model;
        let class_names = model.class_names().to_vec();
        let mut profile = file.online.clone().unwrap_or_else(|| {
            notes.push(format!(
                "note: {} has no online profile; warm-up calibration, k = 6 (train with --online-profile)",
                path.display()
            ));
            OnlineProfile::default()
        });
        if options.decide_at.is_some() {
            profile.params.decide_at = options.decide_at;
        }
        crate::session::check_profile(model, &profile)
            .with_context(|| format!("cannot run {} adaptively", path.display()))?;
        if profile.gait_table.is_empty() {
            let table = measure_gait_table(
                config,
                options.seed,
                &class_names,
                options.gait_sweep,
                progress,
            )?;
            gait_table_map = table.table.best.clone();
            source = Some("measured now: the model has none".to_owned());
            measured = Some(table);
        } else {
            gait_table_map = profile.gait_table.clone();
            source = Some(format!("from {}", path.display()));
        }
        let start = match &options.start_gait {
            Some(g) => g.trim().to_owned(),
            None => config
                .gaits
                .get(1)
                .or(config.gaits.first())
                .map(|g| g.name.clone())
                .ok_or_else(|| Error::invalid("the configuration has no gait"))?,
        };
        let mut runs = Vec::new();
        for &seed in &seeds {
            let mut policy = AdaptivePolicy {
                classifier: OnlineClassifier::new(
                    model,
                    &profile.segment,
                    &profile.params,
                    profile.calibration,
                )?,
                class_names: &class_names,
                table: &gait_table_map,
                confirm: options.confirm,
                streak: None,
            };
            let params = TrackParams::new(seed, &start);
            let run = run_track(&sim, &track, &params, |view| policy.step(view))?;
            runs.push(run);
        }
        policies.push(PolicyRuns {
            policy: "adaptive".to_owned(),
            runs,
        });
    }
    // The honest baseline: every configured gait and every gait the table recommends, each run fixed.
    let fixed: Vec<String> = if options.fixed_gaits.is_empty() {
        let mut fixed: Vec<String> = config.gaits.iter().map(|g| g.name.clone()).collect();
        for gait in gait_table_map.values() {
            if !fixed.contains(gait) {
                fixed.push(gait.clone());
            }
        }
        fixed
    } else {
        options
            .fixed_gaits
            .iter()
            .map(|g| g.trim().to_owned())
            .collect()
    };
    for gait in &fixed {
        let runs = seeds
            .iter()
            .map(|&seed| {
                let mut params = TrackParams::new(seed, gait);
                params.render = false;
                run_track(&sim, &track, &params, |_| Ok(PolicyStep::default()))
            })
            .collect::<std::result::Result<Vec<_>, _>>()?;
        policies.push(PolicyRuns {
            policy: format!("fixed {gait}"),
            runs,
        });
    }
    let comparison = TrackComparison {
        track: spec.to_owned(),
        length_m: track.iter().map(|s| s.length_m).sum(),
        seeds,
        gait_table: gait_table_map,
        gait_table_source: source,
        measured_table: measured.as_ref().map(|m| m.table.clone()),
        policies,
    };
    Ok(TrackOutcome {
        comparison,
        notes,
        measured,
    })
}

impl TrackComparison {
    /// Writes the comparison as JSON to `path` (atomically).
    pub fn write_json(&self, path: &Path) -> Result<()> {
        presrs_io::write_atomic(path, |w| {
            serde_json::to_writer_pretty(&mut *w, self).map_err(std::io::Error::from)?;
            writeln!(w)
        })
        .with_context(|| format!("cannot write {}", path.display()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gait_sweeps_parse_and_bad_ones_are_refused() {
        assert_eq!(parse_gait_sweep("none").unwrap(), GaitSweep(None));
        let sweep = parse_gait_sweep(GaitSweep::DEFAULT_TEXT)
            .unwrap()
            .0
            .unwrap();
        assert_eq!(sweep, BetaSweep::default());
        for bad in [
            "",
            "0.2:0.8",
            "0.2:0.8:0.02:1",
            "a:b:c",
            "0.8:0.2:0.02",
            "0.2:0.8:0",
        ] {
            assert!(parse_gait_sweep(bad).is_err(), "{bad:?} accepted");
        }
    }

    fn policy(name: &str, times_s: &[f64], falls: usize) -> PolicyRuns {
        let runs = times_s
            .iter()
            .map(|&t| {
                serde_json::from_value(serde_json::json!({
                    "segments": [], "seed": 1, "length_m": 12.0, "finished": true, "time_s": t,
                    "distance_m": 12.0, "mean_speed_m_per_s": 12.0 / t, "hops": [], "falls": falls,
                    "misclassified": 0, "decided": 0, "switches": 0, "gait_hops": {}
                }))
                .unwrap()
            })
            .collect();
        PolicyRuns {
            policy: name.to_owned(),
            runs,
        }
    }

    fn comparison(policies: Vec<PolicyRuns>) -> TrackComparison {
        TrackComparison {
            track: "wood:6,grass:6".to_owned(),
            length_m: 12.0,
            seeds: vec![1],
            gait_table: BTreeMap::new(),
            gait_table_source: None,
            measured_table: None,
            policies,
        }
    }

    #[test]
    fn the_policy_column_fits_the_longest_name() {
        let cmp = comparison(vec![
            policy("adaptive", &[11.0], 0),
            policy("fixed G1", &[12.0], 0),
            policy("fixed G3@0.62", &[10.0], 0),
        ]);
        let text = cmp.format();
        let lines: Vec<&str> = text.lines().skip(1).take(4).collect();
        // Every row's "finished" column ends where the header's does.
        let end = lines[0].find("finished").unwrap() + "finished".len();
        for line in &lines[1..] {
            assert_eq!(&line[end - 3..end], "1/1", "{text}");
        }
        assert!(text.contains("fixed G3@0.62 "), "{text}");
    }

    #[test]
    fn the_verdict_ranks_falls_before_time_and_names_the_fastest_fixed_gait() {
        // Slower than a gait that falls, faster than every gait that does not: it helps.
        let cmp = comparison(vec![
            policy("adaptive", &[11.0], 0),
            policy("fixed A", &[10.0], 1),
            policy("fixed B", &[12.0], 0),
        ]);
        let verdict = cmp.verdict();
        assert!(verdict.starts_with("adaptation helps"), "{verdict}");
        assert!(
            verdict.contains("fixed B, 12.00 s (0 falls): -8.3 % time"),
            "{verdict}"
        );
        assert!(verdict.contains("the fastest fixed gait, fixed A, 10.00 s (1 falls): +10.0 %"));
        // Slower than a gait that never falls either: it does not.
        let cmp = comparison(vec![
            policy("adaptive", &[11.0], 0),
            policy("fixed B", &[10.5], 0),
        ]);
        assert!(
            cmp.verdict().starts_with("adaptation does NOT help"),
            "{}",
            cmp.verdict()
        );
        // Falling is worse than being slow.
        let cmp = comparison(vec![
            policy("adaptive", &[9.0], 2),
            policy("fixed B", &[12.0], 1),
        ]);
        assert!(cmp.verdict().starts_with("adaptation does NOT help"));
    }
}
