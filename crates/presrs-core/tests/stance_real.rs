//! Stance segmentation on a real recording: `FrasP01L.asf` (F-Scan insole, overground walking, 31.25 Hz),
//! read in place from the shared data folder. The TekScan reader lives in presrs-io; this test carries its
//! own minimal loader of the per-frame total load so that the core crate stays free of I/O dependencies.

#![allow(clippy::unwrap_used)] // Tests: a failed unwrap is a failed test.

use presrs_core::stance::{SampleFrame, ValidSegmentParams, segment};

const FRAS: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../../shared/data/tekscan/FrasP01L.asf"
);

/// Sum of the numeric cells of each `Frame N` block (cells `B` are outside the insole and skipped).
fn total_load_per_frame(text: &str) -> Vec<f64> {
    let mut totals = Vec::new();
    let mut current: Option<f64> = None;
    for line in text.lines() {
        let line = line.trim();
        if line.starts_with("Frame") {
            if let Some(total) = current.take() {
                totals.push(total);
            }
            current = Some(0.0);
        } else if let Some(total) = current.as_mut() {
            if line.is_empty() || line == "@@" {
                totals.push(*total);
                current = None;
            } else {
                *total += line
                    .split(',')
                    .map(str::trim)
                    .filter(|cell| !cell.is_empty() && *cell != "B")
                    .map(|cell| cell.parse::<f64>().unwrap())
                    .sum::<f64>();
            }
        }
    }
    if let Some(total) = current {
        totals.push(total);
    }
    totals
}

#[test]
fn fras_walking_stances() {
    let text = std::fs::read_to_string(FRAS).unwrap();
    let load = total_load_per_frame(&text);
    assert_eq!(load.len(), 205);
    // Spot checks of the loader against totals computed independently (python).
    assert_eq!(load[0].round(), 32767.0);
    assert_eq!(load[29].round(), 3808.0);
    assert_eq!(load[204], 0.0);

    let found = segment(&load, &ValidSegmentParams::default()).unwrap();
    // Swing frames read exactly zero: baseline 0, no noise.
    assert!(found.baseline.iter().all(|&b| b.abs() < 1e-9));
    assert_eq!(found.noise, 0.0);

    let summary: Vec<(usize, usize, usize, bool)> = found
        .stances
        .iter()
        .map(|s| (s.start, s.len, s.peak_frame, s.partial))
        .collect();
    // (start, len, peak frame, partial). Boundaries are the first/last frames above 1% of the load range
    // (358 kPa-sensels): frames 135 (216) and the 90-ish blip at 16-18 stay out; 51 (384) and 157 (587) in.
    assert_eq!(
        summary,
        vec![
            (0, 15, 8, true),
            (29, 23, 46, false),
            (64, 23, 81, false),
            (100, 22, 116, false),
            (136, 22, 152, false),
            (171, 25, 187, false),
        ]
    );
    assert!((found.stances[1].peak_load - 35250.0).abs() < 1.0);
    assert_eq!(
        found.samples(SampleFrame::Mid, false).unwrap(),
        vec![40, 75, 110, 146, 183]
    );
}
