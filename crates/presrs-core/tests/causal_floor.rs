//! The causal (online) detector in the floor mode (contacts on a standing preload) against the offline
//! floor segmentation of the same synthetic movies: presses (half sines) and steps (trapezoids) on a
//! constant and on a drifting preload, with noise, seeded. Every contact the offline method finds is
//! found online with the same touchdown (within a frame) and end (within two), its lift-off reported at
//! most `max_gap_frames` + a few frames after its end, and none is invented.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::f64::consts::PI;

use presrs_core::online::{Calibration, CausalSegmenter, OnlineParams, SegEvent};
use presrs_core::stance::{BaselineMode, SegmentParams, Stance, ValidSegmentParams, segment};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn gaussian(rng: &mut impl Rng) -> f64 {
    let u: f64 = 1.0 - rng.random::<f64>();
    let v: f64 = rng.random();
    (-2.0 * u.ln()).sqrt() * (2.0 * PI * v).cos()
}

/// The shape of a contact: a press (half sine) or a step (ramps of `ramp` frames around a plateau).
#[derive(Clone, Copy, Debug)]
enum Shape {
    Press,
    Step { ramp: usize },
}

impl Shape {
    fn at(self, i: usize, len: usize) -> f64 {
        match self {
            Shape::Press => (PI * (i as f64 + 0.5) / len as f64).sin(),
            Shape::Step { ramp } => {
                let edge = (i + 1).min(len - i) as f64;
                (edge / (ramp + 1) as f64).min(1.0)
            }
        }
    }
}

/// A preload movie: unloaded lead, then contacts on a preload (which drifts) with rests between them.
struct Movie {
    lead: usize,
    contacts: Vec<(usize, usize)>,
    shape: Shape,
    preload: f64,
    drift_per_frame: f64,
    amplitude: f64,
    sigma: f64,
    seed: u64,
}

impl Movie {
    fn random(seed: u64, shape: Shape, drift: bool) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let count = rng.random_range(12..30);
        let contacts = (0..count)
            .map(|_| (rng.random_range(10..=30), rng.random_range(4..=20)))
            .collect();
        Self {
            lead: rng.random_range(5..30),
            contacts,
            shape,
            preload: rng.random_range(100.0..400.0),
            drift_per_frame: if drift {
                rng.random_range(-0.5..0.5)
            } else {
                0.0
            },
            amplitude: 1000.0,
            sigma: rng.random_range(0.0..5.0),
            seed,
        }
    }

    fn build(&self) -> (Vec<f64>, Vec<(usize, usize)>) {
        let mut truth = Vec::new();
        let mut t = self.lead;
        for &(len, rest) in &self.contacts {
            truth.push((t, len));
            t += len + rest;
        }
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed ^ 0x5eed);
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
                load[start + i] += self.amplitude * self.shape.at(i, len);
            }
        }
        (load, truth)
    }
}

fn floor_params() -> ValidSegmentParams {
    SegmentParams {
        baseline: BaselineMode::Floor,
        ..SegmentParams::default()
    }
    .check()
    .unwrap()
}

/// Each lift-off's stance and the frame it was reported at, `finish` included.
fn run_online(seg: &mut CausalSegmenter, totals: &[f64]) -> Vec<(Stance, usize, usize)> {
    let mut touchdowns = std::collections::BTreeMap::new();
    let mut out = Vec::new();
    let mut events = Vec::new();
    for &total in totals {
        events.extend(seg.push(total).unwrap().iter());
    }
    events.extend(seg.finish().unwrap().iter());
    for event in events {
        match event {
            SegEvent::Touchdown(td) => {
                touchdowns.insert(td.stance_id, td.frame);
            }
            SegEvent::Liftoff(l) => out.push((l.stance, touchdowns[&l.stance_id], l.frame)),
            _ => {}
        }
    }
    out
}

#[derive(Default, Debug)]
struct Agreement {
    offline: usize,
    matched: usize,
    invented: usize,
    worst_start: usize,
    worst_end: usize,
    worst_liftoff_delay: usize,
    worst_touchdown_delay: usize,
}

fn compare(
    offline: &[Stance],
    online: &[(Stance, usize, usize)],
    from: usize,
    agreement: &mut Agreement,
) -> Vec<String> {
    let mut problems = Vec::new();
    let offline: Vec<&Stance> = offline
        .iter()
        .filter(|s| !s.partial && s.start > from)
        .collect();
    let online: Vec<&(Stance, usize, usize)> = online
        .iter()
        .filter(|(s, _, _)| !s.partial && s.start > from)
        .collect();
    agreement.offline += offline.len();
    for off in &offline {
        match online
            .iter()
            .find(|(s, _, _)| s.start.abs_diff(off.start) <= 2)
        {
            Some((s, td, lo)) => {
                agreement.matched += 1;
                agreement.worst_start = agreement.worst_start.max(s.start.abs_diff(off.start));
                agreement.worst_end = agreement.worst_end.max(s.end().abs_diff(off.end()));
                agreement.worst_liftoff_delay = agreement.worst_liftoff_delay.max(lo + 1 - s.end());
                agreement.worst_touchdown_delay = agreement.worst_touchdown_delay.max(td - s.start);
                if s.start.abs_diff(off.start) > 1 || s.end().abs_diff(off.end()) > 2 {
                    problems.push(format!("offline {off:?} online {s:?}"));
                }
            }
            None => problems.push(format!("offline {off:?} not found online")),
        }
    }
    for (s, _, _) in &online {
        if !offline.iter().any(|off| off.start.abs_diff(s.start) <= 2) {
            agreement.invented += 1;
            problems.push(format!("online {s:?} invented"));
        }
    }
    problems
}

#[test]
fn online_floor_agrees_with_offline_on_preload_movies() {
    let params = floor_params();
    let auto = ValidSegmentParams::default();
    let mut agreement = Agreement::default();
    // Movies whose first 128 frames alone do not make the automatic choice pick the floor.
    let mut warmup_chose_other = 0;
    let mut failures = Vec::new();
    for seed in 0..40u64 {
        for shape in [Shape::Press, Shape::Step { ramp: 3 }] {
            for drift in [false, true] {
                let movie = Movie::random(seed, shape, drift);
                let (series, _truth) = movie.build();
                let offline = segment(&series, &params).unwrap();
                // With a calibration from another movie of the kind (detection from frame 0), and from a
                // warm-up (detection after it).
                // (Another layout, the same sensor: the same noise.)
                let training = Movie {
                    sigma: movie.sigma,
                    ..Movie::random(seed + 1000, shape, drift)
                }
                .build()
                .0;
                let cal = Calibration::from_segmentations([&segment(&training, &params).unwrap()]);
                let mut calibrated =
                    CausalSegmenter::new(&params, &OnlineParams::default(), cal).unwrap();
                let online = run_online(&mut calibrated, &series);
                for p in compare(&offline.stances, &online, 0, &mut agreement) {
                    failures.push(format!(
                        "seed {seed} {shape:?} drift {drift} calibrated: {p}"
                    ));
                }
                // From a warm-up, asked for the floor or left to choose (the warm-up's offline
                // segmentation chooses the floor).
                let warmup_choice = segment(&series[..128], &auto).unwrap().mode;
                if warmup_choice != BaselineMode::Floor {
                    warmup_chose_other += 1;
                }
                let choices: &[&ValidSegmentParams] = if warmup_choice == BaselineMode::Floor {
                    &[&params, &auto]
                } else {
                    &[&params]
                };
                for &online_params in choices {
                    let mut warm =
                        CausalSegmenter::new(online_params, &OnlineParams::default(), None)
                            .unwrap();
                    let online = run_online(&mut warm, &series);
                    for p in compare(&offline.stances, &online, 128, &mut agreement) {
                        failures.push(format!(
                            "seed {seed} {shape:?} drift {drift} warm-up {}: {p}",
                            online_params.params().baseline
                        ));
                    }
                }
            }
        }
    }
    eprintln!("{agreement:?}; warm-up chose another mode on {warmup_chose_other} of 160 movies");
    assert!(warmup_chose_other < 40, "{warmup_chose_other}");
    assert!(
        failures.is_empty(),
        "{} problems:\n{}",
        failures.len(),
        failures.join("\n")
    );
    assert!(agreement.offline > 5000, "{agreement:?}");
    assert_eq!(
        (agreement.matched, agreement.invented),
        (agreement.offline, 0)
    );
    // Touchdown within a frame of the offline one, confirmed `min_stance_frames - 1` frames after it;
    // the end within two frames, the lift-off reported `max_gap_frames` frames after the end (at the
    // third frame of the rest), looking back over a rest's first frames if they are flat.
    assert!(
        agreement.worst_start <= 1 && agreement.worst_end <= 2,
        "{agreement:?}"
    );
    assert!(agreement.worst_touchdown_delay <= 2, "{agreement:?}");
    assert!(agreement.worst_liftoff_delay <= 4, "{agreement:?}");
}
