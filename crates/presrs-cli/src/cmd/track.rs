//! `presrs simulate --track`: the terrain-to-gait loop on the simulator ([`presrs::gait`]); the
//! comparison is printed (and written as JSON with `--json`).

use std::io::Write;

use presrs::gait::{TrackOptions, compare_on_track};
use presrs_sim::SimConfig;

use super::common::TerminalProgress;
use super::simulate::SimulateArgs;

/// `--track`: fixed gaits and (with `--adaptive`) the adaptive policy on the same seeds.
pub fn run_track_comparison(
    args: &SimulateArgs,
    config: &SimConfig,
    spec: &str,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    // Gait names are judged with the configuration, before anything runs.
    if let Err(message) = presrs::simulation::check_gaits("--start-gait", &args.start_gait, config)
        .and_then(|()| presrs::simulation::check_gaits("--fixed-gait", &args.fixed_gait, config))
    {
        return Err(super::usage::UsageError::error("simulate", message));
    }
    let options = TrackOptions {
        seed: args.seed,
        repeats: args.repeats,
        adaptive: args.adaptive.clone(),
        gait_sweep: args.gait_sweep,
        confirm: args.confirm,
        fixed_gaits: args.fixed_gait.clone(),
        start_gait: args.start_gait.clone(),
    };
    let outcome = compare_on_track(config, spec, &options, &TerminalProgress::default())?;
    for note in &outcome.notes {
        writeln!(out, "{note}")?;
    }
    if let Some(measured) = &outcome.measured {
        write!(out, "{}", measured.format())?;
    }
    write!(out, "{}", outcome.comparison.format())?;
    if let Some(path) = &args.json {
        outcome.comparison.write_json(path)?;
        writeln!(out, "JSON: {}", path.display())?;
    }
    Ok(())
}
