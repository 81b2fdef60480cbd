//! The session's typed events pin the stream protocol: each event's JSON line, exactly, and every key
//! of it named in its bullet of `docs/stream-protocol.md` ("Server -> client").

#![allow(clippy::unwrap_used, clippy::expect_used)]

use presrs::core::online::{DecisionKind, EarlyReason};
use presrs::session::{
    Classification, DecisionPoint, EarlyDecisionEvent, EarlyRule, End, ErrorEvent, Liftoff,
    NoveltyVerdict, Posteriors, SessionEvent, Touchdown, WholeStance,
};

fn decision(whole_stance: Option<WholeStance>) -> Classification {
    Classification {
        kind: if whole_stance.is_some() {
            DecisionKind::Stance
        } else {
            DecisionKind::Single
        },
        stance: 3,
        label: "sand".to_owned(),
        class: 1,
        confidence: 0.75,
        posteriors: Posteriors(vec![("grass".to_owned(), 0.25), ("sand".to_owned(), 0.75)]),
        sample_frame: 26,
        frame: 27,
        frames_used: 1,
        touchdown_frame: 20,
        latency_us: 12.5,
        timestamp_us: None,
        gait: Some("G1".to_owned()),
        whole_stance,
        early: None,
        gap_frames: 0,
        novelty: None,
    }
}

/// A decision of a model that scores novelty, its sample none of the classes.
fn unknown_decision() -> Classification {
    Classification {
        label: "unknown".to_owned(),
        // The posterior 0.75 capped by the credibility.
        confidence: 0.0625,
        gait: None,
        novelty: Some(Box::new(NoveltyVerdict {
            unknown: true,
            nearest: "sand".to_owned(),
            novelty: 3.5,
            novelty_threshold: 2.25,
            credibility: Some(0.0625),
        })),
        ..decision(None)
    }
}

/// One event of each kind (and of each optional part), with its line as the protocol has it.
fn golden() -> Vec<(SessionEvent, &'static str)> {
    vec![
        (
            SessionEvent::Touchdown(Touchdown {
                stance: 3,
                touchdown_frame: 20,
                frame: 22,
                partial: false,
            }),
            r#"{"event":"touchdown","stance":3,"touchdown_frame":20,"frame":22,"partial":false}"#,
        ),
        (
            SessionEvent::Classification(decision(None)),
            r#"{"event":"classification","kind":"single","stance":3,"label":"sand","class":1,"confidence":0.75,"posteriors":{"grass":0.25,"sand":0.75},"sample_frame":26,"frame":27,"frames_used":1,"touchdown_frame":20,"latency_us":12.5,"timestamp_us":null,"gait":"G1"}"#,
        ),
        (
            SessionEvent::Classification(decision(Some(WholeStance {
                decided_at: DecisionPoint::Offset,
                decided_at_frame: 32,
                cut: false,
            }))),
            r#"{"event":"classification","kind":"stance","stance":3,"label":"sand","class":1,"confidence":0.75,"posteriors":{"grass":0.25,"sand":0.75},"sample_frame":26,"frame":27,"frames_used":1,"touchdown_frame":20,"latency_us":12.5,"timestamp_us":null,"gait":"G1","decided_at":"offset","decided_at_frame":32,"cut":false}"#,
        ),
        (
            SessionEvent::Classification(Classification {
                early: Some(EarlyDecisionEvent {
                    early_rule: EarlyRule::Auto,
                    early_reason: EarlyReason::Confident,
                    early_point: Some(12),
                    early_frames: 12,
                    early_threshold: Some(0.875),
                }),
                ..decision(Some(WholeStance {
                    decided_at: DecisionPoint::Offset,
                    decided_at_frame: 32,
                    cut: false,
                }))
            }),
            r#"{"event":"classification","kind":"stance","stance":3,"label":"sand","class":1,"confidence":0.75,"posteriors":{"grass":0.25,"sand":0.75},"sample_frame":26,"frame":27,"frames_used":1,"touchdown_frame":20,"latency_us":12.5,"timestamp_us":null,"gait":"G1","decided_at":"offset","decided_at_frame":32,"cut":false,"early_rule":"auto","early_reason":"confident","early_point":12,"early_frames":12,"early_threshold":0.875}"#,
        ),
        (
            SessionEvent::Classification(Classification {
                early: Some(EarlyDecisionEvent {
                    early_rule: EarlyRule::Fixed,
                    early_reason: EarlyReason::EndedFirst,
                    early_point: None,
                    early_frames: 9,
                    early_threshold: None,
                }),
                ..decision(Some(WholeStance {
                    decided_at: DecisionPoint::Liftoff,
                    decided_at_frame: 29,
                    cut: false,
                }))
            }),
            r#"{"event":"classification","kind":"stance","stance":3,"label":"sand","class":1,"confidence":0.75,"posteriors":{"grass":0.25,"sand":0.75},"sample_frame":26,"frame":27,"frames_used":1,"touchdown_frame":20,"latency_us":12.5,"timestamp_us":null,"gait":"G1","decided_at":"liftoff","decided_at_frame":29,"cut":false,"early_rule":"fixed","early_reason":"ended_first","early_point":null,"early_frames":9,"early_threshold":null}"#,
        ),
        (
            SessionEvent::Classification(unknown_decision()),
            r#"{"event":"classification","kind":"single","stance":3,"label":"unknown","class":1,"confidence":0.0625,"posteriors":{"grass":0.25,"sand":0.75},"sample_frame":26,"frame":27,"frames_used":1,"touchdown_frame":20,"latency_us":12.5,"timestamp_us":null,"gait":null,"unknown":true,"nearest":"sand","novelty":3.5,"novelty_threshold":2.25,"credibility":0.0625}"#,
        ),
        (
            SessionEvent::Liftoff(Liftoff {
                stance: 3,
                touchdown_frame: 20,
                end_frame: 34,
                len: 14,
                peak_frame: 27,
                peak_load: 1234.5,
                partial: false,
                sampled: true,
                frame: 36,
                gap_frames: 0,
            }),
            r#"{"event":"liftoff","stance":3,"touchdown_frame":20,"end_frame":34,"len":14,"peak_frame":27,"peak_load":1234.5,"partial":false,"sampled":true,"frame":36}"#,
        ),
        // Frames missing inside the stance (a gap in the input's frame times): said, never hidden.
        (
            SessionEvent::Classification(Classification {
                gap_frames: 4,
                ..decision(None)
            }),
            r#"{"event":"classification","kind":"single","stance":3,"label":"sand","class":1,"confidence":0.75,"posteriors":{"grass":0.25,"sand":0.75},"sample_frame":26,"frame":27,"frames_used":1,"touchdown_frame":20,"latency_us":12.5,"timestamp_us":null,"gait":"G1","gap_frames":4}"#,
        ),
        (
            SessionEvent::Liftoff(Liftoff {
                stance: 3,
                touchdown_frame: 20,
                end_frame: 30,
                len: 10,
                peak_frame: 27,
                peak_load: 1234.5,
                partial: false,
                sampled: true,
                frame: 32,
                gap_frames: 4,
            }),
            r#"{"event":"liftoff","stance":3,"touchdown_frame":20,"end_frame":30,"len":10,"peak_frame":27,"peak_load":1234.5,"partial":false,"sampled":true,"frame":32,"gap_frames":4}"#,
        ),
        (
            SessionEvent::error("input frame 5 rejected: 2 values are not finite", false),
            r#"{"event":"error","message":"input frame 5 rejected: 2 values are not finite","fatal":false}"#,
        ),
        (
            SessionEvent::Error(ErrorEvent {
                message: "stance 2: frame 40 could not be classified".to_owned(),
                fatal: false,
                stance: Some(2),
                frame: Some(41),
            }),
            r#"{"event":"error","message":"stance 2: frame 40 could not be classified","fatal":false,"stance":2,"frame":41}"#,
        ),
        (
            SessionEvent::End(End {
                frames: 300,
                stances: 8,
                decisions: 8,
                fused_decisions: 0,
                rejected_frames: 1,
                errors: 1,
                dropped_events: 0,
                warmup_frames: 0,
                note: None,
            }),
            r#"{"event":"end","frames":300,"stances":8,"decisions":8,"fused_decisions":0,"rejected_frames":1,"errors":1,"dropped_events":0,"warmup_frames":0}"#,
        ),
        (
            SessionEvent::End(End {
                frames: 50,
                stances: 0,
                decisions: 0,
                fused_decisions: 0,
                rejected_frames: 0,
                errors: 0,
                dropped_events: 0,
                warmup_frames: 50,
                note: Some("the stream ended during the warm-up calibration".to_owned()),
            }),
            r#"{"event":"end","frames":50,"stances":0,"decisions":0,"fused_decisions":0,"rejected_frames":0,"errors":0,"dropped_events":0,"warmup_frames":50,"note":"the stream ended during the warm-up calibration"}"#,
        ),
    ]
}

#[test]
fn each_event_is_exactly_its_protocol_line_and_reads_back_as_itself() {
    for (event, line) in golden() {
        assert_eq!(event.to_line(), line);
        let back: SessionEvent = serde_json::from_str(line).unwrap();
        assert_eq!(back, event, "{line}");
    }
}

/// The bullet of `docs/stream-protocol.md` that describes event `name` (up to the next bullet).
fn protocol_bullet(doc: &str, name: &str) -> String {
    let start = doc
        .find(&format!("- `{name}`:"))
        .unwrap_or_else(|| panic!("docs/stream-protocol.md has no bullet for `{name}`"));
    let rest = &doc[start + 2..];
    let end = rest.find("\n- ").unwrap_or(rest.len());
    rest[..end].to_owned()
}

#[test]
fn every_key_of_every_event_is_documented_in_the_protocol() {
    let doc = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/stream-protocol.md"),
    )
    .unwrap();
    for (event, line) in golden() {
        let value: serde_json::Value = serde_json::from_str(line).unwrap();
        let name = value["event"].as_str().unwrap();
        let bullet = protocol_bullet(&doc, name);
        for key in value.as_object().unwrap().keys().filter(|k| *k != "event") {
            assert!(
                bullet.contains(&format!("`{key}`")),
                "{event:?}: key `{key}` is not in the protocol's `{name}` bullet"
            );
        }
    }
}

/// The events of a session over a synthetic walk (8 stances of 14 frames, 20 frames between them,
/// frame `i` stamped `10 i` ms), with the frames `missing` (original indices) never sent.
fn events_without(missing: std::ops::Range<usize>) -> Vec<SessionEvent> {
    use presrs::core::online::{Calibration, OnlineProfile};
    use presrs::core::testing::{bench_fixture, synthetic_stream};
    use presrs::session::{Input, SessionObserver, run_frames};
    use rand::SeedableRng;

    #[derive(Default)]
    struct Kept(Vec<SessionEvent>);
    impl SessionObserver for Kept {
        fn event(&mut self, event: &SessionEvent) -> bool {
            self.0.push(event.clone());
            true
        }
    }

    let (model, _) = bench_fixture(3, 0).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
    let frames = synthetic_stream(8, &mut rng);
    let load_range = frames
        .iter()
        .map(|f| f.values().iter().sum::<f64>())
        .fold(0.0, f64::max);
    let profile = OnlineProfile {
        calibration: Some(Calibration {
            baseline: 0.0,
            noise: 1.0,
            load_range,
        }),
        ..OnlineProfile::default()
    };
    let mut sent = frames
        .iter()
        .enumerate()
        .filter(|(i, _)| !missing.contains(i));
    let next = |values: &mut Vec<f64>, _: &mut Vec<bool>| match sent.next() {
        Some((i, frame)) => {
            values.clear();
            values.extend_from_slice(frame.values());
            Input::Frame {
                grid: frame.grid(),
                has_mask: false,
                timestamp_us: Some(i as u64 * 10_000),
                arrival: std::time::Instant::now(),
            }
        }
        None => Input::End,
    };
    let mut kept = Kept::default();
    run_frames(&model, &profile, next, &mut kept, &|_| {}).unwrap();
    kept.0
}

#[test]
fn a_stance_with_frames_missing_is_decided_with_the_gap_stated() {
    // Stance 3 (frames 122-135 as sent) loses 3 frames right after its touchdown, as when its
    // publisher restarts during the step.
    let whole = events_without(0..0);
    let touchdown = whole
        .iter()
        .find_map(|e| match e {
            SessionEvent::Touchdown(td) if td.touchdown_frame >= 120 => Some(td.touchdown_frame),
            _ => None,
        })
        .unwrap();
    let first_missing = touchdown as usize + 2;
    let events = events_without(first_missing..first_missing + 3);
    let (mut decided, mut ended) = (0, 0);
    for event in &events {
        match event {
            SessionEvent::Classification(d) => {
                let holed = d.touchdown_frame == touchdown && d.sample_frame >= touchdown + 2;
                assert_eq!(d.gap_frames, if holed { 3 } else { 0 }, "{d:?}");
                decided += u64::from(holed);
                let line: serde_json::Value = serde_json::from_str(&event.to_line()).unwrap();
                assert_eq!(line.get("gap_frames").is_some(), holed);
            }
            SessionEvent::Liftoff(lo) => {
                let holed = lo.touchdown_frame == touchdown;
                assert_eq!(lo.gap_frames, if holed { 3 } else { 0 }, "{lo:?}");
                ended += u64::from(holed);
            }
            _ => {}
        }
    }
    assert_eq!((decided, ended), (1, 1), "{events:?}");
    // Without a gap nothing says one.
    assert!(whole.iter().all(|e| match e {
        SessionEvent::Classification(d) => d.gap_frames == 0,
        SessionEvent::Liftoff(lo) => lo.gap_frames == 0,
        _ => true,
    }));
}
