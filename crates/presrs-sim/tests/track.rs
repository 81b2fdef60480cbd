#![allow(clippy::unwrap_used, clippy::expect_used)]
//! The track runner and the gait table (module `presrs_sim::track`).

use presrs_sim::track::{
    GaitTableParams, PolicyStep, TrackParams, gait_table, parse_track, run_track,
};
use presrs_sim::{Gait, SimConfig, Simulator};

fn sim_with(extra: &[Gait]) -> Simulator {
    let mut cfg = SimConfig::default();
    cfg.gaits.extend(extra.iter().cloned());
    Simulator::new(cfg, 1, Vec::new()).unwrap()
}

fn names(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| (*s).to_owned()).collect()
}

fn fixed(_: &presrs_sim::track::HopView<'_>) -> Result<PolicyStep, String> {
    Ok(PolicyStep::default())
}

#[test]
fn tracks_parse_and_bad_ones_are_refused() {
    let t = parse_track("wood:3, grass:2.5").unwrap();
    assert_eq!(t.len(), 2);
    assert_eq!(t[1].terrain, "grass");
    assert!((t[1].length_m - 2.5).abs() < 1e-12);
    for bad in ["", "wood", "wood:x", "wood:-1", ":3", "wood:0"] {
        assert!(parse_track(bad).is_err(), "{bad:?} accepted");
    }
}

#[test]
fn a_fixed_gait_run_is_deterministic_and_puts_each_foot_on_its_segment() {
    let sim = sim_with(&[]);
    let track = parse_track("wood:1.5,carpet:1.5").unwrap();
    let mut params = TrackParams::new(3, "G2");
    params.render = false;
    let a = run_track(&sim, &track, &params, fixed).unwrap();
    let b = run_track(&sim, &track, &params, fixed).unwrap();
    assert_eq!(a, b, "same seed, same run");
    assert!(a.finished && a.falls == 0, "{a:?}");
    assert!((a.distance_m - 3.0).abs() < 1e-12);
    assert!((a.mean_speed_m_per_s - 3.0 / a.time_s).abs() < 1e-12);
    // G2 runs at about 0.7 m/s on wood and carpet (start transient included).
    assert!(
        (0.5..0.85).contains(&a.mean_speed_m_per_s),
        "{}",
        a.mean_speed_m_per_s
    );
    for h in &a.hops {
        let expected = if h.foot_x_m < 1.5 { "wood" } else { "carpet" };
        assert_eq!(h.terrain, expected, "hop {} foot at {}", h.hop, h.foot_x_m);
        assert_eq!(h.gait, "G2");
    }
    assert!(a.hops.iter().any(|h| h.terrain == "carpet"));
    // The last apex is past the line, the one before is not, and the finish time lies between them.
    let n = a.hops.len();
    assert!(a.hops[n - 1].apex_x_m >= 3.0 && a.hops[n - 2].apex_x_m < 3.0);
    assert!(a.time_s <= a.hops[n - 1].apex_time_s && a.time_s >= a.hops[n - 2].apex_time_s);
    // Another seed, other disturbances.
    params.seed = 4;
    let c = run_track(&sim, &track, &params, fixed).unwrap();
    assert_ne!(a.time_s, c.time_s);
}

#[test]
fn the_policy_sees_each_stance_and_its_gait_switch_applies_from_the_next_hop() {
    let sim = sim_with(&[]);
    let track = parse_track("wood:1,clay:1").unwrap();
    let params = TrackParams::new(5, "G1");
    let mut seen = Vec::new();
    let run = run_track(&sim, &track, &params, |view| {
        let loaded = (0..view.frame_count())
            .filter(|&i| view.frame(i).unwrap().iter().sum::<f64>() > 500.0)
            .count();
        seen.push((view.hop, view.frame_count(), loaded, view.first_frame));
        // Believe wood always; ask for G3 after the second hop.
        Ok(PolicyStep {
            terrain: Some("wood".to_owned()),
            gait: (view.hop >= 1).then(|| "G3".to_owned()),
        })
    })
    .unwrap();
    assert!(run.finished, "{run:?}");
    assert_eq!(run.switches, 1);
    assert_eq!(run.hops[0].gait, "G1");
    assert_eq!(run.hops[1].gait, "G1");
    assert!(run.hops[1].switched);
    assert!(run.hops[2..].iter().all(|h| h.gait == "G3" && !h.switched));
    // Every hop has its frames (~0.3-0.45 s at 100 Hz) with a stance of 10-20 loaded frames in them,
    // on one continuous clock.
    for w in seen.windows(2) {
        assert_eq!(
            w[1].3,
            w[0].3 + w[0].1,
            "frames continue across hops: {w:?}"
        );
    }
    for &(hop, frames, loaded, _) in &seen {
        assert!((20..60).contains(&frames), "hop {hop}: {frames} frames");
        assert!(
            (8..22).contains(&loaded),
            "hop {hop}: {loaded} loaded frames"
        );
    }
    // Misclassifications: every stance on clay was called wood.
    let on_clay = run.hops.iter().filter(|h| h.terrain == "clay").count();
    assert!(on_clay > 0);
    assert_eq!(run.misclassified, on_clay);
    assert_eq!(run.decided, run.hops.len());
}

#[test]
fn falls_are_counted_and_a_hopeless_run_is_unfinished() {
    // G5 (7.75 rad/s, 0.8 rad) does not hop on wood (it is stable on grass only).
    let sim = sim_with(&[Gait::new("G5", 7.75, 0.8)]);
    let track = parse_track("wood:3").unwrap();
    let mut params = TrackParams::new(1, "G5");
    params.render = false;
    params.max_falls = 3;
    let run = run_track(&sim, &track, &params, fixed).unwrap();
    assert!(!run.finished);
    assert_eq!(run.falls, 4);
    assert!(run.hops.iter().filter(|h| h.fell).count() == 4);
    // Each fall costs the restart penalty.
    assert!(run.time_s >= 4.0 * params.restart_penalty_s);
}

#[test]
fn the_gait_table_recommends_the_fastest_gait_that_never_fell() {
    let sim = sim_with(&[Gait::new("G5", 7.75, 0.8)]);
    let params = GaitTableParams {
        hops: 40,
        settle_hops: 10,
        seeds: vec![1, 2],
        exit_hops: 2,
    };
    let table = gait_table(
        &sim,
        &names(&["wood", "clay"]),
        &names(&["G1", "G2", "G3", "G5"]),
        &params,
    )
    .unwrap();
    assert_eq!(table.cells.len(), 8);
    for t in ["wood", "clay"] {
        let cells: Vec<_> = table.cells.iter().filter(|c| c.terrain == t).collect();
        // Speeds rise G1 -> G3 (the paper's Table I); G5 falls on both.
        assert!(cells[0].mean_speed_m_per_s < cells[1].mean_speed_m_per_s);
        assert!(cells[1].mean_speed_m_per_s < cells[2].mean_speed_m_per_s);
        assert_eq!(cells[3].falls, 2, "{:?}", cells[3]);
        assert!(cells[..3].iter().all(|c| c.stable()), "{cells:?}");
        assert_eq!(cells[0].exit_runs, 2);
        assert_eq!(table.best[t], "G3");
        assert!(table.best_is_stable[t]);
    }
    assert!(table.format().contains("*"));
}
