//! The session's typed events pin the stream protocol: each event's JSON line, exactly, and every key
//! of it named in its bullet of `docs/stream-protocol.md` ("Server -> client").

#![allow(clippy::unwrap_used, clippy::expect_used)]

use presrs::core::online::DecisionKind;
use presrs::session::{
    Classification, DecisionPoint, End, ErrorEvent, Liftoff, NoveltyVerdict, Posteriors,
    SessionEvent, Touchdown, WholeStance,
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
        novelty: None,
    }
}

/// A decision of a model that scores novelty, its sample none of the classes.
fn unknown_decision() -> Classification {
    Classification {
        label: "unknown".to_owned(),
        gait: None,
        novelty: Some(NoveltyVerdict {
            unknown: true,
            nearest: "sand".to_owned(),
            novelty: 3.5,
            novelty_threshold: 2.25,
        }),
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
            SessionEvent::Classification(unknown_decision()),
            r#"{"event":"classification","kind":"single","stance":3,"label":"unknown","class":1,"confidence":0.75,"posteriors":{"grass":0.25,"sand":0.75},"sample_frame":26,"frame":27,"frames_used":1,"touchdown_frame":20,"latency_us":12.5,"timestamp_us":null,"gait":null,"unknown":true,"nearest":"sand","novelty":3.5,"novelty_threshold":2.25}"#,
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
            }),
            r#"{"event":"liftoff","stance":3,"touchdown_frame":20,"end_frame":34,"len":14,"peak_frame":27,"peak_load":1234.5,"partial":false,"sampled":true,"frame":36}"#,
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
