//! Simulates a data set and writes the mid-stance frames as text matrices to look at.
//! Usage: cargo run --release -p presrs-sim --example preview -- OUT_DIR [HOPS_PER_GAIT] [SEED]
#![allow(clippy::unwrap_used, clippy::expect_used)]
use std::io::Write;

use presrs_sim::{DatasetSpec, SimConfig, simulate_dataset};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let out = std::path::PathBuf::from(args.get(1).cloned().unwrap_or("/tmp/preview".into()));
    let hops: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(4);
    let seed: u64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(1);
    std::fs::create_dir_all(&out).unwrap();
    let mut spec = DatasetSpec::paper(seed);
    spec.hops_per_gait = Some(hops);
    let cfg = SimConfig::default();
    let start = std::time::Instant::now();
    let ds = simulate_dataset(&cfg, &spec).unwrap();
    println!(
        "simulated {} trials in {:.2} s",
        ds.trials.len(),
        start.elapsed().as_secs_f64()
    );
    print!("{}", ds.velocity_table().format_with_paper());
    let mut worst: f64 = 0.0;
    let mut stance = Vec::new();
    for t in &ds.trials {
        for (i, h) in t.hops.iter().enumerate() {
            stance.push(h.truth.stance_duration_s);
            for (a, b) in h.frame_normal_force_n.iter().zip(&h.frame_image_force_n) {
                if *a > 1.0 {
                    worst = worst.max((a - b).abs() / a);
                }
            }
            if i >= 3 {
                continue;
            }
            if let Some(mid) = h.mid_stance_frame {
                let f = t.recording.frame(mid).unwrap();
                let path = out.join(format!("{}_h{i}.txt", t.plan.name()));
                let mut file = std::fs::File::create(path).unwrap();
                for r in 0..44 {
                    let row: Vec<String> = (0..44).map(|c| format!("{}", f.get(r, c))).collect();
                    writeln!(file, "{}", row.join(" ")).unwrap();
                }
            }
        }
        let frames_in_stance: Vec<usize> = t
            .hops
            .iter()
            .map(|h| h.frame_normal_force_n.len())
            .collect();
        println!(
            "{} attempts={} stance frames {:?} attempts",
            t.plan.name(),
            t.attempts,
            frames_in_stance
        );
    }
    let n = stance.len() as f64;
    println!(
        "mean stance {:.1} ms, worst image force error {:.2e}",
        stance.iter().sum::<f64>() / n * 1e3,
        worst
    );
}
