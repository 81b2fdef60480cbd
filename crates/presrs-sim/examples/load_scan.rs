//! Load robustness map: for each body mass (as a multiple of the nominal), gait and built-in terrain,
//! hops the bare dynamics (with the default touchdown-angle noise) and prints whether it fell, the mean
//! forward velocity, stance time and apex height over the last 20 hops.
//!
//! Usage: cargo run --release -p presrs-sim --example load_scan -- ['{"robot": {...}, ...}'] [factors]
//! e.g. `... load_scan -- '{}' 0.5,1,1.3,1.5`. HOPS=n sets the number of hops (default 80).
#![allow(clippy::unwrap_used, clippy::expect_used)]
use presrs_sim::SimConfig;
use presrs_sim::dataset::BUILTIN_TERRAINS;
use presrs_sim::slip::Hopper;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let cfg = args
        .get(1)
        .map(|s| SimConfig::from_json(s).unwrap())
        .unwrap_or_default();
    let factors: Vec<f64> = args
        .get(2)
        .map(|s| s.split(',').map(|x| x.parse().unwrap()).collect())
        .unwrap_or_else(|| vec![0.5, 0.75, 1.0, 1.1, 1.3, 1.5]);
    let hops: usize = std::env::var("HOPS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(80);
    let sim = presrs_sim::Simulator::new(cfg.clone(), 0, Vec::new()).unwrap();
    let mut jobs = Vec::new();
    for &f in &factors {
        for gait in &cfg.gaits {
            for t in BUILTIN_TERRAINS {
                jobs.push((f, gait.clone(), t));
            }
        }
    }
    let out: Vec<String> = jobs
        .par_iter()
        .map(|(f, gait, t)| {
            let robot = cfg.robot.with_load(cfg.robot.body_mass_kg * f);
            let ground = sim.terrain(t).unwrap().ground();
            let mut h = Hopper::new(robot, gait.clone(), ground, cfg.integrator).unwrap();
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
            let noise = Normal::new(0.0, cfg.realism.touchdown_angle_noise_rad).unwrap();
            let mut samples = Vec::new();
            let mut truths = Vec::new();
            for i in 0..hops {
                match h.hop(i, 0.01, f64::INFINITY, &mut samples, noise.sample(&mut rng)) {
                    Ok(x) => truths.push(x),
                    Err(e) => {
                        let prev = truths
                            .last()
                            .map(|x: &presrs_sim::HopTruth| {
                                format!(
                                    "prev td={:.3} lo={:.3} apex={:.3} v_lo={:.3} next_td={:.3}",
                                    x.touchdown_angle_rad,
                                    x.liftoff_angle_rad,
                                    x.apex_height_m,
                                    x.liftoff_speed_m_per_s,
                                    h.next_touchdown_angle_rad
                                )
                            })
                            .unwrap_or_default();
                        return format!(
                            "{f:.2} {} {t:<6} FELL at hop {i}: {e} [{prev}]",
                            gait.name
                        );
                    }
                }
            }
            let last = &truths[hops.saturating_sub(20)..];
            let n = last.len() as f64;
            let avg =
                |g: &dyn Fn(&presrs_sim::HopTruth) -> f64| last.iter().map(g).sum::<f64>() / n;
            format!(
                "{f:.2} {} {t:<6} v={:.3} stance={:.0}ms apex={:.3} td={:.3} lo={:.3} zg={:.1}mm",
                gait.name,
                avg(&|x| x.mean_forward_velocity_m_per_s),
                avg(&|x| x.stance_duration_s) * 1e3,
                avg(&|x| x.apex_height_m),
                avg(&|x| x.touchdown_angle_rad),
                avg(&|x| x.liftoff_angle_rad),
                avg(&|x| x.max_ground_deflection_m) * 1e3,
            )
        })
        .collect();
    for line in out {
        println!("{line}");
    }
}
