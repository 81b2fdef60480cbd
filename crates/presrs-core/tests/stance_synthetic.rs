//! Stance segmentation on synthetic total-load series: half-sine stances on a noisy, drifting baseline.

#![allow(clippy::unwrap_used)] // Tests: a failed unwrap is a failed test.

use std::f64::consts::PI;

use presrs_core::stance::{
    BaselineMode, SampleFrame, SegmentParams, Segmentation, Stance, ValidSegmentParams,
    sample_frames, segment,
};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A synthetic movie's total load: stances given as `(start, len)`, each a half sine of height `amplitude`
/// (frame `i` of `len` at `sin(pi (i + 0.5) / len)`), on a baseline going linearly from `offset` to
/// `offset + drift`, plus Gaussian noise of standard deviation `sigma`.
struct Synth {
    frames: usize,
    stances: Vec<(usize, usize)>,
    amplitude: f64,
    offset: f64,
    drift: f64,
    sigma: f64,
    seed: u64,
}

impl Synth {
    fn baseline(&self, t: usize) -> f64 {
        self.offset + self.drift * t as f64 / self.frames.max(2).saturating_sub(1) as f64
    }

    fn series(&self) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let mut load: Vec<f64> = (0..self.frames)
            .map(|t| self.baseline(t) + self.sigma * gaussian(&mut rng))
            .collect();
        for &(start, len) in &self.stances {
            for i in 0..len {
                if let Some(value) = load.get_mut(start + i) {
                    *value += self.amplitude * (PI * (i as f64 + 0.5) / len as f64).sin();
                }
            }
        }
        load
    }
}

fn gaussian(rng: &mut impl Rng) -> f64 {
    // Box-Muller; 1 - u keeps the logarithm finite.
    let u: f64 = 1.0 - rng.random::<f64>();
    let v: f64 = rng.random();
    (-2.0 * u.ln()).sqrt() * (2.0 * PI * v).cos()
}

/// The paper's hopper: stances of 14 frames at 100 Hz, flights of ~20 frames (17..=23).
fn hopper_layout(hops: usize, seed: u64) -> (Vec<(usize, usize)>, usize) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut t = 12;
    let mut stances = Vec::new();
    for _ in 0..hops {
        stances.push((t, 14));
        t += 14 + rng.random_range(17..=23);
    }
    (stances, t)
}

fn run(series: &[f64]) -> Segmentation {
    segment(series, &ValidSegmentParams::default()).unwrap()
}

fn assert_recovered(found: &Segmentation, truth: &[(usize, usize)], tolerance: usize) {
    let got: Vec<(usize, usize)> = found.stances.iter().map(|s| (s.start, s.len)).collect();
    assert_eq!(
        found.stances.len(),
        truth.len(),
        "found {got:?}, expected {truth:?}"
    );
    for (stance, &(start, len)) in found.stances.iter().zip(truth) {
        assert!(
            stance.start.abs_diff(start) <= tolerance
                && stance.end().abs_diff(start + len) <= tolerance,
            "stance {stance:?} vs truth {start}..{} (found {got:?})",
            start + len
        );
    }
}

#[test]
fn hopper_with_offset_noise_and_drift() {
    let (stances, frames) = hopper_layout(40, 1);
    let synth = Synth {
        frames,
        stances: stances.clone(),
        amplitude: 1000.0,
        offset: 200.0,
        drift: 400.0, // the baseline drifts by 40% of the stance load over the recording
        sigma: 12.0,
        seed: 2,
    };
    let series = synth.series();
    let found = run(&series);
    assert_recovered(&found, &stances, 1);
    // 14-frame half sines clear the off level on their first and last frames: exact boundaries.
    for stance in &found.stances {
        assert_eq!(stance.len, 14, "{stance:?}");
        assert!(!stance.partial);
        assert_eq!(
            stance.mid_frame(),
            stance.start + 6,
            "the paper's 7th frame"
        );
        assert_eq!(
            sample_frames(stance, SampleFrame::Mid).unwrap(),
            vec![stance.start + (stance.len - 1) / 2]
        );
        // The peak of a 14-frame half sine is frame 6 or 7; noise picks one of them.
        assert!((6..=7).contains(&(stance.peak_frame - stance.start)));
        assert!((stance.peak_load - synth.baseline(stance.peak_frame) - 1000.0).abs() < 60.0);
    }
    // The baseline follows the drift, and the noise estimate is close to the truth.
    for (t, &base) in found.baseline.iter().enumerate() {
        assert!(
            (base - synth.baseline(t)).abs() < 2.0 * synth.sigma,
            "frame {t}: baseline {base} vs {}",
            synth.baseline(t)
        );
    }
    assert!(
        (found.noise / synth.sigma - 1.0).abs() < 0.25,
        "noise {}",
        found.noise
    );
    assert_eq!(
        found.samples(SampleFrame::Mid, false).unwrap(),
        stances.iter().map(|&(s, _)| s + 6).collect::<Vec<_>>()
    );
}

#[test]
fn walking_like_stances_at_31_hz() {
    // ~23-frame stances, ~12-frame swings: a 66% duty factor.
    let stances: Vec<(usize, usize)> = (0..8).map(|k| (10 + 35 * k, 22 + k % 3)).collect();
    let synth = Synth {
        frames: 10 + 35 * 8,
        stances: stances.clone(),
        amplitude: 30_000.0,
        offset: 0.0,
        drift: 0.0,
        sigma: 0.0,
        seed: 0,
    };
    let found = run(&synth.series());
    assert_recovered(&found, &stances, 0);
    assert_eq!(found.noise, 0.0);
}

#[test]
fn a_drift_larger_than_the_stance_load_is_followed() {
    let (stances, frames) = hopper_layout(60, 3);
    let synth = Synth {
        frames,
        stances: stances.clone(),
        amplitude: 500.0,
        offset: -300.0,
        drift: 2000.0, // four stance heights over the recording
        sigma: 5.0,
        seed: 4,
    };
    assert_recovered(&run(&synth.series()), &stances, 1);
}

#[test]
fn stances_cut_by_the_recording_are_partial() {
    let synth = Synth {
        frames: 100,
        stances: vec![(0, 8), (30, 14), (90, 14)],
        amplitude: 1000.0,
        offset: 50.0,
        drift: 0.0,
        sigma: 5.0,
        seed: 5,
    };
    let found = run(&synth.series());
    let summary: Vec<(usize, usize, bool)> = found
        .stances
        .iter()
        .map(|s| (s.start, s.len, s.partial))
        .collect();
    // The first half sine is cut after 8 of its frames... as built it is a full 8-frame sine starting at 0,
    // which is exactly the ambiguity: we cannot tell, so it is partial.
    assert_eq!(summary, vec![(0, 8, true), (30, 14, false), (90, 10, true)]);
    assert_eq!(found.complete().count(), 1);
    assert_eq!(found.samples(SampleFrame::Mid, false).unwrap(), vec![36]);
    assert_eq!(
        found.samples(SampleFrame::Mid, true).unwrap(),
        vec![3, 36, 94]
    );
}

#[test]
fn spikes_are_not_stances() {
    let truth = vec![(20, 14), (70, 14)];
    let synth = Synth {
        frames: 110,
        stances: truth.clone(),
        amplitude: 1000.0,
        offset: 100.0,
        drift: 0.0,
        sigma: 5.0,
        seed: 6,
    };
    let mut series = synth.series();
    series[50] += 1500.0; // one frame, higher than any stance
    series[95] += 800.0; // two frames
    series[96] += 800.0;
    assert_recovered(&run(&series), &truth, 0);
    // Without the minimum length, both would count: the test can fail.
    let lenient = SegmentParams {
        min_stance_frames: 1,
        ..SegmentParams::default()
    }
    .check()
    .unwrap();
    assert_eq!(segment(&series, &lenient).unwrap().stances.len(), 4);
}

#[test]
fn short_dropouts_inside_a_stance_are_merged() {
    let truth = vec![(20, 14), (60, 14), (100, 14)];
    let synth = Synth {
        frames: 140,
        stances: truth.clone(),
        amplitude: 1000.0,
        offset: 100.0,
        drift: 0.0,
        sigma: 5.0,
        seed: 7,
    };
    let mut series = synth.series();
    series[25] = 100.0; // one-frame dropout
    series[65] = 100.0; // two-frame dropout
    series[66] = 100.0;
    let found = run(&series);
    assert_recovered(&found, &truth, 0);
    // A four-frame dropout splits the stance in two.
    series[104..108].fill(100.0);
    let split = run(&series);
    let starts: Vec<usize> = split.stances.iter().map(|s| s.start).collect();
    assert_eq!(starts, vec![20, 60, 100, 108]);
    // And with merging disabled, the short dropouts split too.
    let strict = SegmentParams {
        max_gap_frames: 0,
        ..SegmentParams::default()
    }
    .check()
    .unwrap();
    assert_eq!(segment(&series, &strict).unwrap().stances.len(), 6);
}

#[test]
fn no_contact_gives_no_stances() {
    let quiet = Synth {
        frames: 2000,
        stances: Vec::new(),
        amplitude: 0.0,
        offset: 300.0,
        drift: 100.0,
        sigma: 10.0,
        seed: 8,
    };
    let found = run(&quiet.series());
    assert!(found.stances.is_empty(), "{:?}", found.stances);
    assert!((found.noise / 10.0 - 1.0).abs() < 0.2, "{}", found.noise);

    for series in [vec![0.0; 500], vec![42.0; 3], vec![7.0], Vec::new()] {
        let found = run(&series);
        assert!(found.stances.is_empty());
        assert_eq!(found.baseline.len(), series.len());
        assert_eq!(found.load_range, 0.0);
    }
}

#[test]
fn non_finite_loads_are_rejected() {
    let params = ValidSegmentParams::default();
    let err = segment(&[0.0, 1.0, f64::NAN, 0.0], &params).unwrap_err();
    assert!(err.to_string().contains("frame 2"), "{err}");
    assert!(segment(&[f64::INFINITY], &params).is_err());
}

#[test]
fn params_are_checked() {
    let default = SegmentParams::default();
    assert!(default.check().is_ok());
    let bad = [
        SegmentParams {
            on_fraction: 0.0,
            ..default.clone()
        },
        SegmentParams {
            off_fraction: 0.2,
            ..default.clone()
        },
        SegmentParams {
            off_noise: 9.0,
            ..default.clone()
        },
        SegmentParams {
            on_noise: f64::NAN,
            ..default.clone()
        },
        SegmentParams {
            min_stance_frames: 0,
            ..default.clone()
        },
        SegmentParams {
            baseline_window_frames: 3,
            ..default.clone()
        },
        SegmentParams {
            baseline_quantile: 0.7,
            ..default.clone()
        },
    ];
    for params in bad {
        assert!(params.check().is_err(), "{params:?}");
    }
    // Deserializing checks; missing fields take their defaults.
    let valid: ValidSegmentParams = serde_json::from_str(r#"{"min_stance_frames": 5}"#).unwrap();
    assert_eq!(valid.params().min_stance_frames, 5);
    assert_eq!(valid.params().on_fraction, 0.10);
    assert!(serde_json::from_str::<ValidSegmentParams>(r#"{"min_stance_frames": 0}"#).is_err());
}

#[test]
fn sample_frame_choices() {
    let stance = Stance {
        start: 10,
        len: 14,
        peak_load: 5.0,
        peak_frame: 18,
        partial: false,
    };
    let pick = |text: &str| sample_frames(&stance, text.parse().unwrap());
    assert_eq!(pick("mid").unwrap(), vec![16]);
    assert_eq!(pick("Peak").unwrap(), vec![18]);
    assert_eq!(pick("0").unwrap(), vec![10]);
    assert_eq!(pick("6").unwrap(), vec![16]);
    assert_eq!(pick("13").unwrap(), vec![23]);
    assert!(
        pick("14")
            .unwrap_err()
            .to_string()
            .contains("past the stance")
    );
    assert_eq!(pick("all").unwrap(), (10..24).collect::<Vec<_>>());
    for bad in ["", "-1", "middle", "1.5"] {
        assert!(bad.parse::<SampleFrame>().is_err(), "{bad}");
    }
    assert_eq!(SampleFrame::default(), SampleFrame::Mid);
    for sample in [
        SampleFrame::Mid,
        SampleFrame::Peak,
        SampleFrame::All,
        SampleFrame::Offset(6),
    ] {
        let json = serde_json::to_string(&sample).unwrap();
        assert_eq!(
            serde_json::from_str::<SampleFrame>(&json).unwrap(),
            sample,
            "{json}"
        );
    }
    assert_eq!(
        serde_json::to_string(&SampleFrame::Offset(6)).unwrap(),
        r#""6""#
    );
    // An even-length stance: the earlier of the two middle frames, as the paper's 7th of 14.
    let odd = Stance { len: 15, ..stance };
    assert_eq!(odd.mid_frame(), 17);
}

#[test]
fn output_serializes() {
    let synth = Synth {
        frames: 60,
        stances: vec![(20, 14)],
        amplitude: 100.0,
        offset: 0.0,
        drift: 0.0,
        sigma: 0.0,
        seed: 0,
    };
    let json = serde_json::to_value(run(&synth.series())).unwrap();
    assert_eq!(json["stances"][0]["start"], 20);
    assert_eq!(json["stances"][0]["len"], 14);
    assert_eq!(json["stances"][0]["partial"], false);
    assert_eq!(json["baseline"].as_array().unwrap().len(), 60);
}

/// 96 cases by default; `STANCE_PROPTEST_CASES` asks for more.
fn cases() -> u32 {
    std::env::var("STANCE_PROPTEST_CASES")
        .ok()
        .and_then(|text| text.parse().ok())
        .unwrap_or(96)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(), failure_persistence: None, ..ProptestConfig::default() })]

    /// Random layouts of stances (6-30 frames) and flights (8-40 frames), with offset, noise (up to 1% of
    /// the stance load) and a drift of up to 0.01% of the stance load per frame (1.3% per baseline window;
    /// real sensor drift is slower still; the fast drifts of long recordings are tested above): every
    /// stance is found, within one frame.
    #[test]
    fn random_layouts_are_recovered(
        lead in 3usize..30,
        layout in prop::collection::vec((6usize..=30, 8usize..=40), 1..12),
        offset in -500.0f64..500.0,
        drift_per_frame in -0.1f64..0.1,
        noise_fraction in 0.0f64..0.01,
        seed in any::<u64>(),
    ) {
        let mut t = lead;
        let mut stances = Vec::new();
        for &(len, flight) in &layout {
            stances.push((t, len));
            t += len + flight;
        }
        let amplitude = 1000.0;
        let synth = Synth {
            frames: t,
            stances: stances.clone(),
            amplitude,
            offset,
            drift: drift_per_frame * t as f64,
            sigma: noise_fraction * amplitude,
            seed,
        };
        let found = run(&synth.series());
        let got: Vec<(usize, usize)> = found.stances.iter().map(|s| (s.start, s.len)).collect();
        prop_assert_eq!(found.stances.len(), stances.len(), "found {:?}, expected {:?}", got, stances);
        for (stance, &(start, len)) in found.stances.iter().zip(&stances) {
            prop_assert!(stance.start.abs_diff(start) <= 1 && stance.end().abs_diff(start + len) <= 1,
                "found {:?}, expected {:?}", got, stances);
            prop_assert!(!stance.partial);
        }
    }
}

/// Presses (half sines) on a standing preload that starts with the first press and never unloads, after
/// a lead of unloaded frames: the load between presses stays at the preload (which drifts).
struct Preload {
    lead: usize,
    /// (press length, frames at the preload after it)
    presses: Vec<(usize, usize)>,
    preload: f64,
    drift_per_frame: f64,
    amplitude: f64,
    sigma: f64,
    seed: u64,
}

impl Preload {
    /// The series and the presses `(start, len)`.
    fn build(&self) -> (Vec<f64>, Vec<(usize, usize)>) {
        let mut truth = Vec::new();
        let mut t = self.lead;
        for &(len, rest) in &self.presses {
            truth.push((t, len));
            t += len + rest;
        }
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let mut load: Vec<f64> = (0..t)
            .map(|f| {
                let preload = if f >= self.lead {
                    self.preload + self.drift_per_frame * (f - self.lead) as f64
                } else {
                    0.0
                };
                preload + self.sigma * gaussian(&mut rng)
            })
            .collect();
        for &(start, len) in &truth {
            for i in 0..len {
                load[start + i] += self.amplitude * (PI * (i as f64 + 0.5) / len as f64).sin();
            }
        }
        (load, truth)
    }
}

#[test]
fn presses_on_a_preload_are_found_from_the_local_floor() {
    let preload = Preload {
        lead: 10,
        // Long presses, short rests: the rests are too few for a low quantile of the load to find the
        // preload.
        presses: (0..12).map(|k| (24 + k % 5, 3 + k % 3)).collect(),
        preload: 400.0,
        drift_per_frame: 1.5,
        amplitude: 3000.0,
        sigma: 5.0,
        seed: 9,
    };
    let (series, truth) = preload.build();
    // The drifting baseline takes the first presses for one stance (the bug of issue 22): its first
    // window holds the only unloaded frames.
    let drifting = SegmentParams {
        baseline: BaselineMode::Drifting,
        ..SegmentParams::default()
    }
    .check()
    .unwrap();
    let stuck = segment(&series, &drifting).unwrap();
    assert!(
        stuck.stances[0].len > 100 && stuck.stances.len() < truth.len(),
        "{:?}",
        stuck.stances
    );
    let found = run(&series);
    assert_eq!(found.mode, BaselineMode::Floor, "{:?}", found.mode_reason);
    assert!(found.mode_reason.as_deref().unwrap().contains("presses"));
    assert_recovered_but_last(&found, &truth);
    // The floor follows the preload between presses.
    let (start, len) = truth[5];
    let between = start + len + 1;
    assert!((found.baseline[between] - series[between]).abs() < 40.0);
}

/// Like [`assert_recovered`] within one frame, the last stance allowed to be partial (it may end at
/// the last frame).
fn assert_recovered_but_last(found: &Segmentation, truth: &[(usize, usize)]) {
    let got: Vec<(usize, usize)> = found.stances.iter().map(|s| (s.start, s.len)).collect();
    assert_eq!(got.len(), truth.len(), "found {got:?}, expected {truth:?}");
    for (stance, &(start, len)) in found.stances.iter().zip(truth) {
        assert!(
            stance.start.abs_diff(start) <= 1 && stance.end().abs_diff(start + len) <= 1,
            "found {got:?}, expected {truth:?}"
        );
    }
}

#[test]
fn a_recording_that_is_one_contact_is_one_stance_partial_at_both_ends() {
    // A heel-and-toe double hump from the first frame to the last, never unloading.
    let n = 60;
    let series: Vec<f64> = (0..n)
        .map(|t| {
            let x = t as f64 / (n - 1) as f64;
            300.0 + 12_000.0 * (PI * x).sin() * (0.6 + 0.4 * (3.0 * PI * x).cos().abs())
        })
        .collect();
    let found = run(&series);
    assert_eq!(found.mode, BaselineMode::Contact);
    let summary: Vec<(usize, usize, bool)> = found
        .stances
        .iter()
        .map(|s| (s.start, s.len, s.partial))
        .collect();
    assert_eq!(summary, vec![(0, n, true)]);
    assert!(found.samples(SampleFrame::Mid, false).unwrap().is_empty());
    assert_eq!(found.samples(SampleFrame::Mid, true).unwrap(), vec![29]);
    // Asked for explicitly, even a recording with swing is one contact.
    let contact = SegmentParams {
        baseline: BaselineMode::Contact,
        ..SegmentParams::default()
    }
    .check()
    .unwrap();
    let walking = Synth {
        frames: 100,
        stances: vec![(10, 14), (50, 14)],
        amplitude: 1000.0,
        offset: 0.0,
        drift: 0.0,
        sigma: 0.0,
        seed: 0,
    };
    assert_eq!(
        segment(&walking.series(), &contact).unwrap().stances.len(),
        1
    );
    // A hopper movie with one stance and a flight is not one contact.
    let one = Synth {
        frames: 53,
        stances: vec![(15, 11)],
        amplitude: 1000.0,
        offset: 0.0,
        drift: 0.0,
        sigma: 5.0,
        seed: 3,
    };
    let found = run(&one.series());
    assert_eq!(found.mode, BaselineMode::Drifting);
    assert_recovered(&found, &[(15, 11)], 1);
}

#[test]
fn very_short_recordings() {
    // Shorter than a stance could be: nothing, and no panic.
    for series in [vec![0.0, 500.0], vec![5.0, 900.0, 4.0]] {
        let found = run(&series);
        assert!(found.complete().next().is_none(), "{series:?}");
    }
    // Five loaded frames, the foot on the sensor throughout: one contact.
    let found = run(&[400.0, 900.0, 1200.0, 800.0, 350.0]);
    assert_eq!(found.stances.len(), 1);
    assert!(found.stances[0].partial);
    // A short stance with unloaded frames around it is a complete stance.
    let found = run(&[
        0.0, 0.0, 0.0, 300.0, 900.0, 1000.0, 600.0, 0.0, 0.0, 0.0, 0.0,
    ]);
    let summary: Vec<(usize, usize, bool)> = found
        .stances
        .iter()
        .map(|s| (s.start, s.len, s.partial))
        .collect();
    assert_eq!(summary, vec![(3, 4, false)]);
}

#[test]
fn the_longest_stance_is_a_parameter() {
    let synth = Synth {
        frames: 120,
        stances: vec![(10, 14), (40, 40)],
        amplitude: 1000.0,
        offset: 0.0,
        drift: 0.0,
        sigma: 2.0,
        seed: 1,
    };
    let capped = SegmentParams {
        baseline: BaselineMode::Drifting,
        max_stance_frames: Some(30),
        ..SegmentParams::default()
    }
    .check()
    .unwrap();
    let found = segment(&synth.series(), &capped).unwrap();
    assert_eq!(found.stances.len(), 1);
    assert_eq!(found.stances[0].start, 10);
    let bad = SegmentParams {
        min_stance_frames: 5,
        max_stance_frames: Some(4),
        ..SegmentParams::default()
    };
    assert!(bad.check().is_err());
    assert_eq!(
        "floor".parse::<BaselineMode>().unwrap(),
        BaselineMode::Floor
    );
    assert!("flor".parse::<BaselineMode>().is_err());
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(), failure_persistence: None, ..ProptestConfig::default() })]

    /// Random trains of presses (8-30 frames, 3-20 frames apart at the preload: rests of at most
    /// `max_gap_frames` are bridged as dropouts by design) on a random preload
    /// (10-40% of the press load) that drifts (up to +-0.1% of the press load per frame) under noise (up
    /// to 0.5%): every press is found within one frame, none invented.
    #[test]
    fn random_presses_on_a_preload_are_recovered(
        lead in 5usize..30,
        presses in prop::collection::vec((8usize..=30, 3usize..=20), 3..12),
        preload_fraction in 0.1f64..0.4,
        drift in -1.0f64..1.0,
        noise_fraction in 0.0f64..0.005,
        seed in any::<u64>(),
    ) {
        let amplitude = 1000.0;
        let preload = Preload {
            lead,
            presses,
            preload: preload_fraction * amplitude,
            drift_per_frame: drift,
            amplitude,
            sigma: noise_fraction * amplitude,
            seed,
        };
        let (series, truth) = preload.build();
        // Chosen automatically, and asked for.
        let floor = SegmentParams { baseline: BaselineMode::Floor, ..SegmentParams::default() }
            .check()
            .unwrap();
        for found in [run(&series), segment(&series, &floor).unwrap()] {
            let got: Vec<(usize, usize)> = found.stances.iter().map(|s| (s.start, s.len)).collect();
            prop_assert_eq!(got.len(), truth.len(), "found {:?}, expected {:?}", got, truth);
            for (stance, &(start, len)) in found.stances.iter().zip(&truth) {
                prop_assert!(stance.start.abs_diff(start) <= 1 && stance.end().abs_diff(start + len) <= 1,
                    "found {:?}, expected {:?} ({})", got, truth, found.mode);
            }
        }
    }
}

/// Walking with a heel and a toe peak per stance, on a swing baseline that drifts (up or down, up to
/// half a count per frame, 0.05% of the stance load) under noise: the floor splits each stance at its heel-toe valley,
/// and a drifting swing level rises above the recording's lowest, but the valleys do not chain (the foot
/// unloads in every swing): the automatic choice stays with the drifting baseline and finds the stances.
#[test]
fn walking_with_heel_and_toe_on_a_drifting_baseline_stays_drifting() {
    walking_trials(11, 40);
}

/// The automatic choice over many walks (30 seeds of 40 trials): it never takes walking whose drifting
/// baseline finds every stance for presses on a preload. It used to on 12 of the 30 seeds (about 1 trial
/// in 40): a swing lost a frame to the drifting baseline's stance on each side, and `preload` counted
/// those two frames as a rest found loaded (now a rest's first and last frames do not count). No trial
/// is skipped: the 4 of 1200 where a strong drift made the drifting baseline miss are found since
/// every block starts with its own lowest frames
/// (`a_strong_downward_drift_does_not_merge_the_last_stances`).
#[test]
fn walking_over_many_seeds_stays_drifting() {
    for seed in 0..30 {
        walking_trials(seed, 40);
    }
}

/// The walks where a strong downward drift (0.43-0.49 a frame, noise below 0.7) put the drifting
/// baseline's last block below all its swings (30 counts low at its centre): the block got none of the
/// lowest frames the unloaded set starts from, kept the other blocks' correction, and its last 3-4
/// stances merged into one (seed 13 trial 32: found 268..406 for four stances; also seed 18 trial 5,
/// seed 19 trial 4, seed 20 trial 27). They were skipped by `walking_over_many_seeds_stays_drifting`.
#[test]
fn a_strong_downward_drift_does_not_merge_the_last_stances() {
    for (seed, trial) in [(13, 32), (18, 5), (19, 4), (20, 27)] {
        let (series, truth) = walking_trial(seed, trial);
        let drifting = SegmentParams {
            baseline: BaselineMode::Drifting,
            ..SegmentParams::default()
        }
        .check()
        .unwrap();
        assert_recovered(&segment(&series, &drifting).unwrap(), &truth, 1);
        let found = run(&series);
        assert_eq!(
            found.mode,
            BaselineMode::Drifting,
            "{:?}",
            found.mode_reason
        );
        assert_recovered(&found, &truth, 1);
    }
}

/// A walk where the automatic choice took the floor (seed 76 trial 3 of `walking_trials`, found over
/// 300 seeds; old and new code alike): the floor's contact ended a frame early (307) and the drifting
/// stance a frame late (309), so the swing's second frame lay in a drifting stance and `preload` took
/// that swing for a rest found loaded beside one found unloaded at the same level (a preload). A rest
/// is now loaded only by a frame past its first two and last two; the floor split three stances.
#[test]
fn edges_a_frame_off_each_way_do_not_make_walking_a_preload() {
    let (series, truth) = walking_trial(76, 3);
    let found = run(&series);
    assert_eq!(
        found.mode,
        BaselineMode::Drifting,
        "{:?}",
        found.mode_reason
    );
    assert_recovered(&found, &truth, 1);
}

/// Trial `trial` (0-based) of [`walking_trials`]`(seed, ..)`: its series and stances.
fn walking_trial(seed: u64, trial: usize) -> (Vec<f64>, Vec<(usize, usize)>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut walk = walk_from(&mut rng);
    for _ in 0..trial {
        walk = walk_from(&mut rng);
    }
    walk
}

/// `trials` walks from `seed`: the automatic choice stays drifting and finds every stance within a frame.
fn walking_trials(seed: u64, trials: usize) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for trial in 0..trials {
        let (series, truth) = walk_from(&mut rng);
        let found = run(&series);
        assert_eq!(
            found.mode,
            BaselineMode::Drifting,
            "trial {trial}: {:?}",
            found.mode_reason
        );
        assert_recovered(&found, &truth, 1);
    }
}

/// One walk of ~400 frames drawn from `rng`: heel-and-toe stances of 20-28 frames, swings of 10-16, on
/// a swing level of 200 drifting by up to half a count a frame, under noise of up to 8.
fn walk_from(rng: &mut ChaCha8Rng) -> (Vec<f64>, Vec<(usize, usize)>) {
    let mut truth = Vec::new();
    let mut t = rng.random_range(5..15);
    while t < 400 {
        let len = rng.random_range(20..=28);
        truth.push((t, len));
        t += len + rng.random_range(10..=16);
    }
    let n = t;
    // Up to half a count per frame: 6% of the stance load per baseline window.
    let drift = rng.random_range(-0.5..0.5) * n as f64;
    let sigma = rng.random_range(0.0..8.0);
    let mut series: Vec<f64> = (0..n)
        .map(|f| 200.0 + drift * f as f64 / n as f64 + sigma * gaussian(rng))
        .collect();
    for &(start, len) in &truth {
        let dip = rng.random_range(0.3..0.7);
        for i in 0..len {
            let x = (i as f64 + 0.5) / len as f64;
            // Heel and toe humps with a valley between them (dip x the peak at mid-stance).
            let shape = (PI * x).sin() * (1.0 - (1.0 - dip) * (PI * x).sin().powi(8));
            series[start + i] += 1000.0 * shape;
        }
    }
    (series, truth)
}

/// The rare failure of `random_layouts_are_recovered` (`PROPTEST_RNG_SEED=5`, 20000 cases): one
/// 23-frame stance in a 50-frame movie, noise 8.2. By chance 9 of its 27 unloaded frames lie within 1.5
/// of each other at the bottom; the growth of the unloaded set stalled on that cluster (its MAD said a
/// noise of 1.5, and the frames below it were left out as glitches), so noise frames after the stance
/// joined it (found 14..48). A layout the issue's definition recovers: a detector fault, fixed.
#[test]
fn a_chance_cluster_of_low_frames_does_not_set_the_noise() {
    let synth = Synth {
        frames: 50,
        stances: vec![(14, 23)],
        amplitude: 1000.0,
        offset: 0.0,
        drift: 0.0,
        sigma: 0.008_174_716_376_350_35 * 1000.0,
        seed: 4_058_022_688_811_925_243,
    };
    let found = run(&synth.series());
    assert_recovered(&found, &[(14, 23)], 1);
    assert!(found.noise > 0.5 * synth.sigma, "noise {}", found.noise);
}

/// A failure of `random_presses_on_a_preload_are_recovered` (`PROPTEST_RNG_SEED=1`, 20000 cases): eight
/// presses after a 15-frame unloaded lead, on a preload of 229 that drifts down by 0.88 a frame to
/// about 7 at the end. The drifting baseline (two blocks, one line) sat between the lead and the
/// preload, 230 above the lead and ~15 below the rests, so no rest chained as loaded and the automatic
/// choice stayed drifting; there the last press ran 5 frames into the rest after it (found 227..256).
/// The drifting baseline lying above a rest of the floor (the lead) by more than its off level now
/// tells that it took the preload for its baseline.
#[test]
fn presses_on_a_preload_that_drifts_down_to_zero_are_found_from_the_floor() {
    let preload = Preload {
        lead: 15,
        presses: vec![
            (24, 9),
            (23, 16),
            (13, 3),
            (19, 3),
            (29, 10),
            (9, 12),
            (28, 14),
            (24, 17),
        ],
        preload: 0.229_084_059_532_145_25 * 1000.0,
        drift_per_frame: -0.879_050_019_749_021,
        amplitude: 1000.0,
        sigma: 0.003_926_552_230_711_038 * 1000.0,
        seed: 10_463_593_274_048_121_643,
    };
    let (series, truth) = preload.build();
    let found = run(&series);
    assert_eq!(found.mode, BaselineMode::Floor, "{:?}", found.mode_reason);
    assert!(
        found.mode_reason.as_deref().unwrap().contains("lies above"),
        "{:?}",
        found.mode_reason
    );
    assert_recovered(&found, &truth, 1);
}

/// A failure of `random_presses_on_a_preload_are_recovered` (`PROPTEST_RNG_SEED=13`, 20000 cases): six
/// presses after a 6-frame lead at zero, on a preload rising from 100 to 270. The drifting baseline (a
/// line through lead and rests) put the lead 100 below it and mixed the two levels into a noise of 51
/// (true 4.9): every press came out a frame short at each end (2 frames from the truth), but within a
/// frame of the floor's, so `preload` saw no press missed. As above, the drifting baseline lying above
/// the lead now chooses the floor.
#[test]
fn presses_on_a_rising_preload_after_an_unloaded_lead_are_not_shortened() {
    let preload = Preload {
        lead: 6,
        presses: vec![(19, 10), (30, 9), (11, 8), (29, 3), (14, 9), (16, 20)],
        preload: 100.0,
        drift_per_frame: 0.945_803_534_865_380_8,
        amplitude: 1000.0,
        sigma: 0.004_887_533_314_826_409 * 1000.0,
        seed: 8_778_558_774_864_676_333,
    };
    let (series, truth) = preload.build();
    let found = run(&series);
    assert_eq!(found.mode, BaselineMode::Floor, "{:?}", found.mode_reason);
    assert_recovered(&found, &truth, 1);
}

/// Failures of `random_layouts_are_recovered` (20000 cases; `PROPTEST_RNG_SEED` 9, 11 and 12, the
/// last twice: before and after a first fix): one stance in a movie of 41 to 46 frames with 13 to 28
/// unloaded frames and noise of 0.8-0.9% of the stance load. The growth of the unloaded set started
/// from the 10 lowest frames, most of which lay by chance within a few counts of each other (MAD
/// noise 1.6 for a true 8-9); it stalled there, the noise came out at 1-3, and noise frames beside the
/// stance joined it (found up to 4 frames long). A small set's RMS spread (at most three MADs) now
/// lets the growth reach the other unloaded frames. A layout the issue's definition recovers: a
/// detector fault, fixed.
#[test]
fn a_short_movie_whose_lowest_frames_cluster_by_chance_keeps_its_edges() {
    // (lead, stance length, flight, drift per frame, noise, seed)
    let cases = [
        (
            3,
            27,
            11,
            0.046_326_477_675_569_945,
            9.435_836_252_758_982,
            4_305_224_834_500_459_808,
        ),
        (
            5,
            29,
            8,
            0.0,
            8.580_187_653_577_22,
            9_201_017_802_457_212_005,
        ),
        (
            18,
            17,
            8,
            0.0,
            8.208_846_869_827_842,
            15_291_367_076_092_581_150,
        ),
        (
            18,
            18,
            10,
            0.0,
            8.208_846_869_827_842,
            15_291_367_076_092_581_150,
        ),
    ];
    for (lead, len, flight, drift_per_frame, sigma, seed) in cases {
        let frames = lead + len + flight;
        let synth = Synth {
            frames,
            stances: vec![(lead, len)],
            amplitude: 1000.0,
            offset: 0.0,
            drift: drift_per_frame * frames as f64,
            sigma,
            seed,
        };
        let found = run(&synth.series());
        assert_eq!(found.mode, BaselineMode::Drifting);
        assert_recovered(&found, &[(lead, len)], 1);
        assert!(!found.stances[0].partial);
        assert!(
            found.noise > 0.5 * sigma,
            "noise {} for {sigma}",
            found.noise
        );
    }
}
