//! The sample settings judged in the library, so that every face says the same (issue 45): a stance
//! length far beyond the longest stance refused before a sample is laid out, in the face's words, and
//! the settings that do nothing with the sample kind chosen refused or warned of.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::PathBuf;

use presrs::core::sample::SampleChoice;
use presrs::core::stance::SampleFrame;
use presrs::core::stance::summary::SummaryConfig;
use presrs::core::{Frame, Grid};
use presrs::dataset::{GivenSampleSettings, check_sample_settings};
use presrs::{Dataset, Face, Sample, SampleKind};

/// Six stance summaries (12 channels) of 14 to 20 frames, two classes.
fn stance_samples() -> Vec<Sample> {
    (0..6)
        .map(|i| {
            let frames = 14 + i;
            let values = (0..12 * frames)
                .map(|v| (v % 7) as f64 + i as f64)
                .collect();
            let frame = Frame::new(Grid::new(12, frames), values).unwrap();
            let label = if i % 2 == 0 { "a" } else { "b" };
            Sample::new(frame, label, PathBuf::from("movies"), i)
        })
        .collect()
}

fn stance(length: Option<usize>) -> SampleKind {
    SampleKind::Stance {
        summary: SummaryConfig::default(),
        length,
    }
}

#[test]
fn a_stance_length_far_beyond_the_longest_stance_is_refused_in_each_face_s_words() {
    let err = Dataset::from_samples_of("movies", stance_samples(), stance(Some(100_000_000)))
        .unwrap_err();
    let cli = err.render(Face::Cli);
    assert!(
        cli.contains(
            "--stance-length 100000000 is far longer than the longest stance found (19 frames)"
        ) && cli.contains("give at most 76 frames")
            && cli.contains("leave --stance-length out"),
        "{cli}"
    );
    let python = err.render(Face::Python);
    assert!(
        python.contains("stance_length=100000000 is far longer") && !python.contains("--"),
        "{python}"
    );
    // Up to four times the longest is laid out, zeros after lift-off.
    let dataset = Dataset::from_samples_of("movies", stance_samples(), stance(Some(76))).unwrap();
    assert!(
        dataset
            .samples
            .iter()
            .all(|s| s.frame.grid() == Grid::new(12, 76))
    );
}

#[test]
fn settings_of_another_sample_kind_are_refused_or_warned_of() {
    let length = GivenSampleSettings {
        stance_length: Some(50),
        ..GivenSampleSettings::default()
    };
    let frame = SampleChoice::Kind(SampleKind::Frame);
    let err = check_sample_settings(frame, &length).unwrap_err();
    assert_eq!(
        err.render(Face::Python),
        "stance_length=50 applies to whole-stance samples, not to the frame sample chosen; leave \
         it out, or choose sample=\"stance\""
    );
    let axis = GivenSampleSettings {
        series_axis: Some("rows"),
        ..GivenSampleSettings::default()
    };
    let err = check_sample_settings(SampleChoice::Kind(stance(None)), &axis).unwrap_err();
    assert!(
        err.to_string()
            .starts_with("--series-axis rows applies to series samples, not to the stance"),
        "{err}"
    );

    let peak = GivenSampleSettings {
        stance_frame: Some(SampleFrame::Peak),
        ..GivenSampleSettings::default()
    };
    let warnings = check_sample_settings(SampleChoice::Kind(stance(None)), &peak).unwrap();
    assert_eq!(warnings.len(), 1);
    assert!(
        warnings[0]
            .to_string()
            .starts_with("--stance-frame peak picks one frame of each stance"),
        "{}",
        warnings[0]
    );
    assert!(check_sample_settings(frame, &peak).unwrap().is_empty());
    assert!(check_sample_settings(SampleChoice::Kind(stance(Some(50))), &length).is_ok());

    // `auto` races both kinds: each kind's settings apply to one of them.
    let all = GivenSampleSettings {
        stance_length: Some(50),
        stance_frame: Some(SampleFrame::Peak),
        series_axis: Some("rows"),
    };
    assert!(
        check_sample_settings(SampleChoice::Auto, &all)
            .unwrap()
            .is_empty()
    );
}
