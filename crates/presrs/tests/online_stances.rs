//! A whole-stance model online on real movies (`real/jiku-walk`, plantar pressure, one foot contact a
//! movie, read in place from the shared data folder): every movie streamed frame by frame through the
//! online classifier, each decision checked against the offline path (`classify`, and the stance cut
//! at `decide_at`), and the stream's JSON lines of a whole-stance decision.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use std::path::{Path, PathBuf};

use presrs::classify::{Classified, ClassifyOptions, classify_recording};
use presrs::core::Recording;
use presrs::core::classifier::ClassifierKind;
use presrs::core::online::{
    DecideAt, DecidedAt, Decision, DecisionKind, OnlineClassifier, OnlineEvent, OnlineParams,
    OnlineProfile,
};
use presrs::core::pipeline::{Session, TrainedModel};
use presrs::core::sample::SampleKind;
use presrs::core::stance::summary::{SummaryConfig, pad_to, summarise};
use presrs::session::{EventTiming, Input, JsonLines, run_frames, step_events};
use presrs::{Dataset, Quiet, SampleOptions};

fn shared(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data")
        .join(path)
}

fn options() -> SampleOptions {
    SampleOptions {
        one_sample_per_file: true,
        kind: SampleKind::Stance {
            summary: SummaryConfig::default(),
            length: None,
        },
        ..SampleOptions::default()
    }
}

/// A small whole-stance model (168 MiniRocket features, linear discriminant) on every movie, and the
/// movies, read as `classify` reads them.
fn setup() -> (TrainedModel, Vec<(PathBuf, Recording)>) {
    setup_with(ClassifierKind::LDA)
}

/// [`setup`] with another classifier (ridge: no PCA step, the classifier takes the 168 features).
fn setup_with(classifier: ClassifierKind) -> (TrainedModel, Vec<(PathBuf, Recording)>) {
    let options = options();
    let dataset = Dataset::load(&shared("real/jiku-walk/manifest.csv"), &options, &Quiet).unwrap();
    let model = common::small_rocket_model(&dataset, classifier, 20, options.kind);
    let movies = dataset
        .samples
        .iter()
        .map(|s| {
            let path = shared("real/jiku-walk").join(&s.source);
            let read = presrs::dataset::read_corrected(
                &path,
                &options.read,
                options.dead_sensels.as_ref(),
            )
            .unwrap();
            (path, read.0.recording)
        })
        .collect();
    (model, movies)
}

/// The decisions of one movie streamed frame by frame, with their posteriors and JSON lines.
fn stream(
    model: &TrainedModel,
    recording: &Recording,
    decide_at: Option<DecideAt>,
) -> Vec<(Decision, Vec<f64>, serde_json::Value)> {
    let profile = OnlineProfile {
        params: OnlineParams {
            decide_at,
            ..OnlineParams::default()
        },
        segment: options().segment_params(),
        ..OnlineProfile::default()
    };
    let mut online = OnlineClassifier::new(model, &profile.segment, &profile.params, None).unwrap();
    let mut out = Vec::new();
    let mut keep = |step: presrs::core::online::Step<'_>| {
        let events = step_events(&step, model, &profile, EventTiming::default());
        let lines = events
            .iter()
            .map(|event| serde_json::to_value(event).unwrap());
        for (event, line) in step.events.iter().zip(lines) {
            assert!(!matches!(event, OnlineEvent::Failed(_)), "{line}");
            if let OnlineEvent::Decision(d) = event {
                out.push((*d, step.posteriors(d).to_vec(), line));
            }
        }
    };
    for index in 0..recording.frame_count() {
        keep(online.push(&recording.frame(index).unwrap()).unwrap());
    }
    keep(online.finish().unwrap());
    out
}

/// One movie, whose one stance is classified offline (`classify_recording`) and decided once online
/// (`stream`, at lift-off): the offline result, and the decision with its posteriors and JSON line.
fn offline_and_online(
    model: &TrainedModel,
    session: &mut Session<'_>,
    recording: &Recording,
    name: &str,
) -> (Classified, (Decision, Vec<f64>, serde_json::Value)) {
    let classify = ClassifyOptions {
        frame: None,
        samples: options(),
    };
    let offline = classify_recording(model, session, recording, name, &classify).unwrap();
    let [offline] = <[Classified; 1]>::try_from(offline.frames).unwrap_or_else(|frames| {
        panic!("{name}: one stance a movie offline, got {}", frames.len())
    });
    let online = stream(model, recording, None);
    let [online] = <[_; 1]>::try_from(online)
        .unwrap_or_else(|online| panic!("{name}: one decision a movie online, got {online:?}"));
    (offline, online)
}

/// The online decision's class and posteriors are the offline classification's, to 1e-9.
fn assert_same_classification(
    model: &TrainedModel,
    (decision, posteriors): (&Decision, &[f64]),
    offline: &Classified,
    name: &str,
) {
    assert_eq!(model.class_names()[decision.class], offline.label, "{name}");
    for (class, p) in model.class_names().iter().zip(posteriors) {
        assert!(
            (p - offline.posteriors[class]).abs() < 1e-9,
            "{name}: {class}"
        );
    }
}

#[test]
fn every_liftoff_decision_is_the_offline_classification_of_the_stance() {
    let (model, movies) = setup();
    assert_eq!(movies.len(), 120);
    let mut session = model.session();
    let mut compared = 0;
    for (path, recording) in &movies {
        let name = path.display().to_string();
        let (offline, (decision, posteriors, line)) =
            offline_and_online(&model, &mut session, recording, &name);
        // The same stance: the whole movie, touchdown at frame 0, decided as the stream ends.
        assert_eq!(decision.kind, DecisionKind::Stance);
        assert_eq!(decision.touchdown_frame, offline.frame, "{name}");
        assert_eq!(decision.frames_used, recording.frame_count(), "{name}");
        let how = decision.stance.unwrap();
        assert_eq!(how.decided_at, DecidedAt::Liftoff);
        assert_eq!(how.waited_for, recording.frame_count() - 1);
        assert!(!how.cut);
        // The same classification.
        assert_same_classification(&model, (&decision, &posteriors), &offline, &name);
        assert!(
            (decision.confidence - offline.confidence).abs() < 1e-9,
            "{name}"
        );
        // Its JSON line says what it waited for.
        assert_eq!(line["kind"], "stance");
        assert_eq!(line["decided_at"], "liftoff");
        assert_eq!(line["decided_at_frame"], recording.frame_count() - 1);
        assert_eq!(line["cut"], false);
        assert_eq!(line["label"], offline.label.as_str());
        compared += 1;
    }
    assert_eq!(compared, 120, "every movie, online as offline");
}

#[test]
fn a_ridge_model_without_a_pca_decides_online_as_offline() {
    let (model, movies) = setup_with(ClassifierKind::RIDGE);
    assert!(model.pca().is_none());
    let mut session = model.session();
    for (path, recording) in movies.iter().step_by(5) {
        let name = path.display().to_string();
        let (offline, (decision, posteriors, _)) =
            offline_and_online(&model, &mut session, recording, &name);
        assert_same_classification(&model, (&decision, &posteriors), &offline, &name);
    }
}

#[test]
fn decide_at_k_is_the_offline_classification_of_the_stance_cut_at_k() {
    let k = 12;
    let (_, movies) = setup();
    let options = SampleOptions {
        decision_points: vec![k],
        ..options()
    };
    let dataset = Dataset::load(&shared("real/jiku-walk/manifest.csv"), &options, &Quiet).unwrap();
    let whole = common::small_rocket_model(&dataset, ClassifierKind::LDA, 20, options.kind);
    let model = common::with_points(whole, &dataset);
    let SampleKind::Stance { summary, .. } = model.sample() else {
        panic!("a whole-stance model");
    };
    // The classifier trained on the stances cut at K decides there, on samples of K + 1 frames.
    let length = k + 1;
    let mut session = model.early().unwrap().point(k).unwrap().session();
    for (path, recording) in movies.iter().step_by(7) {
        let name = path.display().to_string();
        assert!(recording.frame_count() > k + 1, "{name}");
        let online = stream(&model, recording, Some(DecideAt::Frames(k)));
        let [(decision, posteriors, line)] = online.as_slice() else {
            panic!("{name}: one decision, got {online:?}");
        };
        let how = decision.stance.unwrap();
        assert_eq!(how.decided_at, DecidedAt::Offset(k));
        assert_eq!(
            (how.waited_for, decision.frame),
            (k, k),
            "decided as frame K arrives"
        );
        assert_eq!(decision.frames_used, k + 1);
        assert_eq!(line["decided_at"], "offset");
        assert_eq!(line["decided_at_frame"], k);
        assert_eq!(
            (
                &line["early_rule"],
                &line["early_reason"],
                &line["early_point"]
            ),
            (&"fixed".into(), &"fixed".into(), &k.into())
        );
        let frames: Vec<_> = (0..=k).map(|i| recording.frame(i).unwrap()).collect();
        let cut = summarise(&frames, &summary).unwrap();
        let (padded, _) = pad_to(&cut.view(), length).unwrap();
        let prediction = session.classify(&padded.view()).unwrap();
        assert_eq!(decision.class, prediction.class, "{name}");
        assert!((decision.confidence - prediction.confidence).abs() < 1e-9);
        for (a, b) in posteriors.iter().zip(prediction.posteriors) {
            assert!((a - b).abs() < 1e-9, "{name}");
        }
    }
}

#[test]
fn the_stream_session_takes_a_movies_frames_and_decides_as_the_online_classifier() {
    // The frames are the sensor's (63 x 33), not the model's images (its summaries): the session
    // must not ask them to match the model's image grid, as it does for a one-frame model.
    let (model, movies) = setup();
    let profile = OnlineProfile {
        segment: options().segment_params(),
        ..OnlineProfile::default()
    };
    for (path, recording) in movies.iter().step_by(20) {
        let name = path.display().to_string();
        let mut index = 0;
        let next = |values: &mut Vec<f64>, _: &mut Vec<bool>| {
            let Some(frame) = recording.frame(index) else {
                return Input::End;
            };
            index += 1;
            values.clear();
            values.extend_from_slice(frame.values());
            Input::Frame {
                grid: recording.grid(),
                has_mask: false,
                timestamp_us: Some(index as u64 * 10_000),
                arrival: std::time::Instant::now(),
            }
        };
        let mut output = Vec::new();
        let summary = run_frames(
            &model,
            &profile,
            next,
            &mut JsonLines::new(&mut output),
            &|_| {},
        )
        .unwrap();
        assert_eq!((summary.rejected_frames, summary.errors), (0, 0), "{name}");
        let lines: Vec<serde_json::Value> = String::from_utf8(output)
            .unwrap()
            .lines()
            .map(|line| serde_json::from_str(line).unwrap())
            .filter(|line: &serde_json::Value| line["event"] == "classification")
            .collect();
        let direct = stream(&model, recording, None);
        assert_eq!(lines.len(), direct.len(), "{name}");
        for (line, (_, _, expected)) in lines.iter().zip(&direct) {
            for key in ["label", "decided_at", "decided_at_frame", "frame", "cut"] {
                assert_eq!(line[key], expected[key], "{name}: {key}");
            }
            let confidence = line["confidence"].as_f64().unwrap();
            assert!((confidence - expected["confidence"].as_f64().unwrap()).abs() < 1e-9);
        }
    }
}
