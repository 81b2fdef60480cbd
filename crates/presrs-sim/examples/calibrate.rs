//! Prints steady-state hopping observables per gait and terrain ground (used to choose the defaults).
//! Usage: cargo run --release -p presrs-sim --example calibrate -- '{"robot": {...}}' 'kg,cg;kg,cg;kg,cg;kg,cg'
//! (a ground may also be a built-in terrain's default ground by name: 'wood;carpet;clay;grass').
#![allow(clippy::unwrap_used, clippy::expect_used)]
use presrs_sim::ode::IntegratorParams;
use presrs_sim::slip::{Gait, GroundParams, Hopper, RobotParams};
use presrs_sim::terrain::{CarpetParams, ClayParams, GrassParams, WoodParams};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let robot: RobotParams = args
        .get(1)
        .map(|s| serde_json::from_str(s).unwrap())
        .unwrap_or_default();
    let grounds: Vec<GroundParams> = args
        .get(2)
        .map(|s| {
            s.split(';')
                .map(|p| match p {
                    "wood" => WoodParams::default().ground,
                    "carpet" => CarpetParams::default().ground,
                    "clay" => ClayParams::default().ground,
                    "grass" => GrassParams::default().ground,
                    _ => {
                        let v: Vec<f64> = p.split(',').map(|x| x.parse().unwrap()).collect();
                        GroundParams::uniform(v[0], v[1])
                    }
                })
                .collect()
        })
        .unwrap_or_else(|| vec![GroundParams::uniform(2e6, 200.0)]);
    let paper = [
        [0.40, 0.43, 0.38, 0.81],
        [0.64, 0.63, 0.61, 1.11],
        [0.99, 0.97, 0.84, 1.49],
    ];
    for (gi, gait) in Gait::paper().into_iter().enumerate() {
        for (ti, ground) in grounds.iter().enumerate() {
            let mut h = Hopper::new(
                robot.clone(),
                gait.clone(),
                *ground,
                IntegratorParams::default(),
            )
            .unwrap();
            let mut samples = Vec::new();
            let mut hops = Vec::new();
            let mut err = None;
            let nh: usize = std::env::var("HOPS")
                .ok()
                .and_then(|s| s.parse().ok())
                .unwrap_or(60);
            for i in 0..nh {
                match h.hop(i, 0.01, 1e9, &mut samples, 0.0) {
                    Ok(t) => {
                        if std::env::var("DEBUG").is_ok() {
                            println!(
                                "  hop {i}: td={:.3} lo={:.3} v={:.3} st={:.1}ms apex={:.3} E={:.3}",
                                t.touchdown_angle_rad,
                                t.liftoff_angle_rad,
                                t.mean_forward_velocity_m_per_s,
                                t.stance_duration_s * 1e3,
                                t.apex_height_m,
                                t.apex_energy_j
                            );
                        }
                        hops.push(t)
                    }
                    Err(e) => {
                        err = Some(e);
                        break;
                    }
                }
            }
            if let Some(e) = err {
                println!("{} t{ti}: {e} after {} hops", gait.name, hops.len());
                continue;
            }
            let last = &hops[nh - 20..];
            let n = last.len() as f64;
            let v = last
                .iter()
                .map(|h| h.mean_forward_velocity_m_per_s)
                .sum::<f64>()
                / n;
            let vmin = last
                .iter()
                .map(|h| h.mean_forward_velocity_m_per_s)
                .fold(f64::MAX, f64::min);
            let vmax = last
                .iter()
                .map(|h| h.mean_forward_velocity_m_per_s)
                .fold(f64::MIN, f64::max);
            let st = last.iter().map(|h| h.stance_duration_s).sum::<f64>() / n;
            let ap = last.iter().map(|h| h.apex_height_m).sum::<f64>() / n;
            let td = last.iter().map(|h| h.touchdown_angle_rad).sum::<f64>() / n;
            let lo = last.iter().map(|h| h.liftoff_angle_rad).sum::<f64>() / n;
            let fz = last.iter().map(|h| h.peak_normal_force_n).sum::<f64>() / n;
            let zg = last.iter().map(|h| h.max_ground_deflection_m).sum::<f64>() / n;
            let zlo = last
                .iter()
                .map(|h| h.liftoff_ground_deflection_m)
                .sum::<f64>()
                / n;
            let paper_v = paper[gi].get(ti).copied().unwrap_or(f64::NAN);
            println!(
                "{} t{ti}: v={v:.3} ({vmin:.3}..{vmax:.3}) paper {paper_v:.2} ratio {:.2} stance={:.1}ms apex={ap:.3} td={td:.3} lo={lo:.3} Fpk={fz:.1} zg={:.2}mm footprint={:.2}mm",
                gait.name,
                v / paper_v,
                st * 1e3,
                zg * 1e3,
                zlo * 1e3
            );
        }
    }
}
