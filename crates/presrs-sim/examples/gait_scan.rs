//! The terrain-to-gait search on the built-in terrains: every configured gait and its `beta_des`
//! variants (default sweep 0.20-0.80 rad, step 0.02), steady and exit runs, the table and the stable
//! windows. Prints every cell with `--cells`.
//!
//! Usage: cargo run --release -p presrs-sim --example gait_scan -- [--cells] [SEEDS]
#![allow(clippy::unwrap_used, clippy::expect_used)]
use presrs_sim::SimConfig;
use presrs_sim::track::{BetaSweep, GaitTableParams, gait_candidates, gait_table};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let cells = args.iter().any(|a| a == "--cells");
    let seeds: u64 = args
        .iter()
        .find_map(|a| a.parse().ok())
        .unwrap_or(GaitTableParams::default().seeds.len() as u64);
    let cfg = SimConfig::default();
    let sim = presrs_sim::Simulator::new(cfg.clone(), 0, Vec::new()).unwrap();
    let bases: Vec<String> = cfg.gaits.iter().map(|g| g.name.clone()).collect();
    let names = gait_candidates(&sim, &bases, Some(&BetaSweep::default())).unwrap();
    let terrains: Vec<String> = presrs_sim::dataset::BUILTIN_TERRAINS
        .iter()
        .map(|s| s.to_string())
        .collect();
    let params = GaitTableParams {
        seeds: (1..=seeds).collect(),
        ..GaitTableParams::default()
    };
    let t = std::time::Instant::now();
    let table = gait_table(&sim, &terrains, &names, &params).unwrap();
    eprintln!(
        "{} candidates x {} terrains in {:.1} s",
        names.len(),
        terrains.len(),
        t.elapsed().as_secs_f64()
    );
    if cells {
        for c in &table.cells {
            let exits: Vec<String> = c
                .exit_falls
                .iter()
                .map(|(t, n)| format!("{t}:{n}"))
                .collect();
            println!(
                "{} {} speed {:.3} falls {}/{} exit {} clearance {:.3}",
                c.terrain,
                c.gait,
                c.mean_speed_m_per_s,
                c.falls,
                c.runs,
                exits.join(" "),
                c.min_apex_clearance_m
            );
        }
    }
    print!("{}", table.format());
}
