//! The causal (online) stance detector against the offline segmentation on the simulated data set: fed one
//! frame at a time it must find the same stances, and on stances of typical length its sample frame (the
//! k-th after touchdown, k learned from training recordings) must be the offline mid-stance frame.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use presrs_core::online::{CausalSegmenter, OnlineParams, OnlineProfile, SegEvent};
use presrs_core::stance::{Segmentation, Stance, ValidSegmentParams, segment};
use presrs_sim::{DatasetSpec, SimConfig, Simulator, TrialOutput};

fn trials(seed: u64, hops: usize, terrains: &[&str]) -> Vec<TrialOutput> {
    let mut spec = DatasetSpec::paper(seed);
    spec.hops_per_gait = Some(hops);
    spec.terrains = terrains.iter().map(|t| (*t).to_owned()).collect();
    let sim = Simulator::new(SimConfig::default(), seed, Vec::new()).unwrap();
    sim.for_each_trial(&spec, Ok::<_, presrs_sim::SimError>)
        .unwrap()
}

fn offline(trial: &TrialOutput) -> Segmentation {
    segment(
        &trial.recording.total_per_frame(),
        &ValidSegmentParams::default(),
    )
    .unwrap()
}

/// Stances and sample requests of the causal detector, frame by frame.
fn online(
    trial: &TrialOutput,
    params: &OnlineParams,
    profile: &OnlineProfile,
    calibrated: bool,
) -> (Vec<Stance>, Vec<(usize, usize)>) {
    let mut seg = CausalSegmenter::new(
        &ValidSegmentParams::default(),
        params,
        if calibrated {
            profile.calibration
        } else {
            None
        },
    )
    .unwrap();
    let (mut stances, mut samples) = (Vec::new(), Vec::new());
    let mut record = |events: presrs_core::online::SegEvents| {
        for event in events.iter() {
            match event {
                SegEvent::Liftoff(l) => stances.push(l.stance),
                SegEvent::ClassifySample {
                    touchdown_frame,
                    frame,
                    ..
                } => samples.push((touchdown_frame, frame)),
                _ => {}
            }
        }
    };
    for total in trial.recording.total_per_frame() {
        record(seg.push(total).unwrap());
    }
    record(seg.finish().unwrap());
    (stances, samples)
}

#[test]
fn causal_detector_agrees_with_offline_segmentation_on_simulated_data() {
    // Train on one seed, test on another (as a deployed robot would).
    let all = ["wood", "carpet", "clay", "grass"];
    let training = trials(11, 10, &all);
    let segs: Vec<Segmentation> = training.iter().map(offline).collect();
    let profile = OnlineProfile::learn(&segs);
    let typical = profile.typical_stance_frames.unwrap();
    assert!((12..=17).contains(&typical), "typical stance {typical}");
    assert_eq!(profile.params.sample_offset, (typical - 1) / 2);

    let test = trials(12, 20, &all);
    let (mut total, mut same_stance, mut typical_count, mut same_sample) = (0, 0, 0, 0);
    let mut mismatches = Vec::new();
    for trial in &test {
        let off = offline(trial);
        let (on, samples) = online(trial, &profile.params, &profile, true);
        for stance in off.stances.iter().filter(|s| !s.partial) {
            total += 1;
            let found = on
                .iter()
                .find(|o| o.start == stance.start && o.len == stance.len);
            match found {
                Some(o) => {
                    same_stance += 1;
                    assert_eq!(o.peak_frame, stance.peak_frame);
                    assert_eq!(o.peak_load, stance.peak_load);
                }
                None => mismatches.push((trial.plan.name(), *stance)),
            }
            if (stance.len - 1) / 2 == profile.params.sample_offset {
                typical_count += 1;
                if samples.contains(&(stance.start, stance.mid_frame())) {
                    same_sample += 1;
                }
            }
        }
        // Nothing the offline method does not find (partial ones aside).
        for o in on.iter().filter(|o| !o.partial) {
            if !off
                .stances
                .iter()
                .any(|s| s.start == o.start && s.len == o.len)
            {
                let tot = trial.recording.total_per_frame();
                let near: Vec<_> = off
                    .stances
                    .iter()
                    .filter(|s| s.start.abs_diff(o.start) < 20)
                    .collect();
                panic!(
                    "{}: online stance {o:?} not found offline; near {near:?}; off {} on {} noise {} range {} base {}; totals {:?}",
                    trial.plan.name(),
                    off.off_level,
                    off.on_level,
                    off.noise,
                    off.load_range,
                    off.baseline[o.start],
                    &tot[o.start.saturating_sub(3)..(o.start + o.len + 4).min(tot.len())]
                );
            }
        }
    }
    eprintln!(
        "{same_stance}/{total} stances identical; {same_sample}/{typical_count} typical stances sampled at the offline mid frame"
    );
    assert!(total > 200);
    assert_eq!(same_stance, total, "{mismatches:?}");
    assert!(typical_count * 3 > total, "typical stances are common");
    assert_eq!(same_sample, typical_count);
}

#[test]
fn warm_up_calibration_finds_the_same_stances_after_the_warm_up() {
    let test = trials(13, 20, &["wood", "grass"]);
    let params = OnlineParams::default();
    let profile = OnlineProfile::default();
    let mut compared = 0;
    for trial in test.iter().take(6) {
        let off = offline(trial);
        let (on, _) = online(trial, &params, &profile, false);
        for stance in off
            .stances
            .iter()
            .filter(|s| !s.partial && s.start > params.warmup_frames)
        {
            compared += 1;
            assert!(
                on.iter()
                    .any(|o| o.start == stance.start && o.len == stance.len),
                "{}: {stance:?} missed after warm-up",
                trial.plan.name()
            );
        }
    }
    assert!(compared > 20);
}
