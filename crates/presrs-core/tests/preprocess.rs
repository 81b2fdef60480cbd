//! Preprocessing after the crop: load normalisation and filling absent/dead sensels, in the pipeline and
//! in stored models.

#![allow(clippy::unwrap_used)] // helpers of integration tests are test code too

use presrs_core::classifier::ClassifierKind;
use presrs_core::features::{FeatureConfig, FeatureKind};
use presrs_core::pipeline::{
    LabeledImage, TrainConfig, TrainedModel, extract_features_with, train,
};
use presrs_core::preprocess::{
    FillScratch, Intensity, Preprocess, fill_from_neighbours, normalise_load,
};
use presrs_core::testing::{labeled_set, synthetic_frame};
use presrs_core::{Crop, Frame, Grid};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

const NORMALISE: Preprocess = Preprocess {
    normalise_load: true,
    ..Preprocess::NONE
};
const BOTH: Preprocess = Preprocess {
    normalise_load: true,
    fill_absent: true,
    ..Preprocess::NONE
};

fn images<'a>(set: &'a [(Frame, &'static str)]) -> Vec<LabeledImage<'a>> {
    set.iter()
        .map(|(frame, label)| LabeledImage::new(frame.view(), label))
        .collect()
}

fn scaled(frame: &Frame, factor: f64) -> Frame {
    let mut out = frame.clone();
    out.values_mut().iter_mut().for_each(|v| *v *= factor);
    out
}

fn assert_close(a: &[f64], b: &[f64], rel: f64) {
    assert_eq!(a.len(), b.len());
    let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        assert!((x - y).abs() <= rel * scale, "{i}: {x} vs {y}");
    }
}

#[test]
fn normalised_features_do_not_depend_on_the_load() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for kind in [
        FeatureKind::FFT1D,
        FeatureKind::FFT2D,
        FeatureKind::FFT2D_POLAR,
        FeatureKind::GLCM,
    ] {
        let features = kind.default_config();
        for class in 0..4 {
            let frame = synthetic_frame(class, &mut rng);
            let base =
                extract_features_with(&frame.view(), &Crop::PAPER, NORMALISE, &features).unwrap();
            for factor in [0.5, 1.3, 7.0] {
                let heavy = scaled(&frame, factor);
                let got = extract_features_with(&heavy.view(), &Crop::PAPER, NORMALISE, &features)
                    .unwrap();
                assert_close(&base, &got, 1e-9);
                // without normalisation the 1-D |FFT| scales with the load
                if kind == FeatureKind::FFT1D {
                    let raw = extract_features_with(
                        &heavy.view(),
                        &Crop::PAPER,
                        Preprocess::NONE,
                        &features,
                    )
                    .unwrap();
                    assert!((raw[0] / base[0]).is_finite());
                    let plain = extract_features_with(
                        &frame.view(),
                        &Crop::PAPER,
                        Preprocess::NONE,
                        &features,
                    )
                    .unwrap();
                    assert!((raw[0] / plain[0] - factor).abs() < 1e-9);
                }
            }
        }
    }
    // an empty image (zero total) is left as it is
    let mut zeros = vec![0.0; 12];
    assert_eq!(normalise_load(&mut zeros), 0.0);
    assert!(zeros.iter().all(|&v| v == 0.0));
}

#[test]
fn a_model_trained_with_normalisation_classifies_scaled_images_alike() {
    let train_set = labeled_set(8, 40);
    let validation_set = labeled_set(4, 41);
    for classifier in [ClassifierKind::PWE, ClassifierKind::LDA] {
        let config = TrainConfig {
            dims: 20,
            classifier: classifier.default_config(),
            preprocess: NORMALISE,
            ..TrainConfig::default()
        }
        .check()
        .unwrap();
        let model = train(&images(&train_set), &images(&validation_set), &config).unwrap();
        assert_eq!(model.preprocess(), NORMALISE);
        let mut session = model.session();
        for (frame, _) in labeled_set(3, 42) {
            let a = session.reduce(&frame.view()).unwrap().to_vec();
            let b = session
                .reduce(&scaled(&frame, 1.3).view())
                .unwrap()
                .to_vec();
            assert_close(&a, &b, 1e-9);
            let p = session.classify(&frame.view()).unwrap().class;
            let q = session.classify(&scaled(&frame, 1.3).view()).unwrap().class;
            assert_eq!(p, q);
        }
    }
}

/// A plane `a + b r + c c` on a 20 x 24 grid.
fn plane(grid: Grid) -> Vec<f64> {
    (0..grid.len())
        .map(|i| 3.5 + 0.75 * (i / grid.cols) as f64 - 1.25 * (i % grid.cols) as f64)
        .collect()
}

#[test]
fn fill_reproduces_a_plane_exactly_around_interior_holes_and_clusters() {
    let grid = Grid::new(20, 24);
    let truth = plane(grid);
    let mut present = vec![true; grid.len()];
    let mut dead = vec![false; grid.len()];
    let at = |r: usize, c: usize| r * grid.cols + c;
    // isolated absent sensels
    for (r, c) in [(2, 2), (5, 17), (18, 22)] {
        present[at(r, c)] = false;
    }
    // a 4 x 5 absent cluster and an L-shaped one
    for r in 8..12 {
        for c in 3..8 {
            present[at(r, c)] = false;
        }
    }
    for (r, c) in [(14, 12), (15, 12), (16, 12), (16, 13), (16, 14)] {
        present[at(r, c)] = false;
    }
    // dead sensels (flagged separately, the values they report are garbage), one next to a hole
    for (r, c) in [(3, 10), (3, 11), (4, 11), (5, 16)] {
        dead[at(r, c)] = true;
    }
    let mut values: Vec<f64> = truth
        .iter()
        .enumerate()
        .map(|(i, &v)| {
            if !present[i] {
                0.0
            } else if dead[i] {
                255.0
            } else {
                v
            }
        })
        .collect();
    let mut scratch = FillScratch::new(grid.len());
    fill_from_neighbours(&mut values, grid, Some(&present), Some(&dead), &mut scratch).unwrap();
    assert_close(&values, &truth, 1e-9);
    // the present sensels are untouched
    for i in 0..grid.len() {
        if present[i] && !dead[i] {
            assert_eq!(values[i], truth[i]);
        }
    }
    // the scratch is reused for another image; a constant field with a hole on the border is exact too
    let mut constant = vec![4.0; grid.len()];
    let mut border = vec![true; grid.len()];
    for c in 0..6 {
        border[at(0, c)] = false;
        border[at(1, c)] = false;
    }
    constant.iter_mut().zip(&border).for_each(|(v, &p)| {
        if !p {
            *v = 0.0;
        }
    });
    fill_from_neighbours(&mut constant, grid, Some(&border), None, &mut scratch).unwrap();
    assert_close(&constant, &[4.0; 480], 1e-12);
    // masks of the wrong size are refused
    assert!(fill_from_neighbours(&mut values, grid, Some(&[true; 3]), None, &mut scratch).is_err());
}

#[test]
fn the_pipeline_fills_masked_sensels_before_the_features() {
    // a 44 x 44 plane with masked sensels inside the paper's crop: with fill_absent its features are those
    // of the complete plane
    let grid = Grid::new(44, 44);
    let truth = plane(grid)
        .into_iter()
        .map(|v| v + 60.0)
        .collect::<Vec<_>>();
    let mut present = vec![true; grid.len()];
    for i in [
        10 * 44 + 10,
        20 * 44 + 20,
        20 * 44 + 21,
        21 * 44 + 20,
        21 * 44 + 21,
    ] {
        present[i] = false;
    }
    let masked = Frame::with_mask(grid, truth.clone(), Some(present)).unwrap();
    let full = Frame::new(grid, truth).unwrap();
    let features = FeatureConfig::default();
    let fill = Preprocess {
        fill_absent: true,
        ..Preprocess::NONE
    };
    let want = extract_features_with(&full.view(), &Crop::PAPER, fill, &features).unwrap();
    let got = extract_features_with(&masked.view(), &Crop::PAPER, fill, &features).unwrap();
    assert_close(&want, &got, 1e-9);
    let zeroed =
        extract_features_with(&masked.view(), &Crop::PAPER, Preprocess::NONE, &features).unwrap();
    assert!(zeroed.iter().zip(&want).any(|(a, b)| (a - b).abs() > 1e-6));
}

#[test]
fn models_round_trip_with_their_preprocessing_and_old_files_load() {
    let train_set = labeled_set(6, 50);
    let validation_set = labeled_set(3, 51);
    let config = TrainConfig {
        dims: 12,
        preprocess: BOTH,
        ..TrainConfig::default()
    }
    .check()
    .unwrap();
    let model = train(&images(&train_set), &images(&validation_set), &config).unwrap();
    let json = serde_json::to_string(&model).unwrap();
    assert!(json.contains("\"normalise_load\":true"));
    let loaded: TrainedModel = serde_json::from_str(&json).unwrap();
    assert_eq!(loaded.preprocess(), BOTH);
    assert_eq!(loaded.summary().config.preprocess, BOTH);
    let (mut a, mut b) = (model.session(), loaded.session());
    for (frame, _) in labeled_set(2, 52) {
        let view = frame.view();
        let scaled_frame = scaled(&frame, 2.0);
        assert_eq!(
            a.classify(&view).unwrap().posteriors,
            b.classify(&view).unwrap().posteriors
        );
        assert_eq!(
            a.classify(&view).unwrap().class,
            b.classify(&scaled_frame.view()).unwrap().class
        );
    }
    // a model without preprocessing writes no field, as files written before it existed: they load
    let plain = train(
        &images(&train_set),
        &images(&validation_set),
        &TrainConfig {
            dims: 12,
            ..TrainConfig::default()
        }
        .check()
        .unwrap(),
    )
    .unwrap();
    let json = serde_json::to_string(&plain).unwrap();
    assert!(!json.contains("preprocess"));
    let loaded: TrainedModel = serde_json::from_str(&json).unwrap();
    assert_eq!(loaded.preprocess(), Preprocess::NONE);
    // an unknown preprocessing step is refused, not ignored
    let bad = serde_json::to_string(&model).unwrap().replacen(
        "\"normalise_load\":true",
        "\"normalise_load\":true,\"denoise\":true",
        1,
    );
    assert!(serde_json::from_str::<TrainedModel>(&bad).is_err());
}

/// The pipeline's intensity transform is the transform of the image and then the plain features (the
/// oracle: the image transformed value by value beforehand), in training and classification alike; a
/// model stores it, and a model file round-trips it.
#[test]
fn intensity_transforms_run_in_the_pipeline_and_round_trip_in_models() {
    let set = labeled_set(6, 60);
    let features = FeatureConfig::default();
    for intensity in [Intensity::Sqrt, Intensity::Log1p] {
        let preprocess = Preprocess {
            intensity,
            ..Preprocess::NONE
        };
        for (frame, _) in &set[..4] {
            let mut transformed = frame.clone();
            intensity.apply(transformed.values_mut());
            let want = extract_features_with(
                &transformed.view(),
                &Crop::PAPER,
                Preprocess::NONE,
                &features,
            )
            .unwrap();
            let got =
                extract_features_with(&frame.view(), &Crop::PAPER, preprocess, &features).unwrap();
            assert_close(&want, &got, 1e-12);
        }
        let config = TrainConfig {
            dims: 12,
            preprocess,
            ..TrainConfig::default()
        }
        .check()
        .unwrap();
        let validation_set = labeled_set(3, 61);
        let model = train(&images(&set), &images(&validation_set), &config).unwrap();
        // the same model trained on images transformed beforehand, without the step, classifies the
        // transformed images as this one classifies the raw ones
        let transformed = |set: &[(Frame, &'static str)]| -> Vec<(Frame, &'static str)> {
            set.iter()
                .map(|(frame, label)| {
                    let mut frame = frame.clone();
                    intensity.apply(frame.values_mut());
                    (frame, *label)
                })
                .collect()
        };
        let oracle_config = TrainConfig {
            dims: 12,
            ..TrainConfig::default()
        }
        .check()
        .unwrap();
        let oracle = train(
            &images(&transformed(&set)),
            &images(&transformed(&validation_set)),
            &oracle_config,
        )
        .unwrap();
        let json = serde_json::to_string(&model).unwrap();
        assert!(
            json.contains(&format!("\"intensity\":\"{intensity}\"")),
            "{json}"
        );
        let loaded: TrainedModel = serde_json::from_str(&json).unwrap();
        assert_eq!(loaded.preprocess(), preprocess);
        let test = labeled_set(2, 62);
        let test_transformed = transformed(&test);
        let (mut a, mut b, mut c) = (model.session(), loaded.session(), oracle.session());
        for ((frame, _), (frame_t, _)) in test.iter().zip(&test_transformed) {
            let got = a.classify(&frame.view()).unwrap();
            assert_eq!(
                got.posteriors,
                b.classify(&frame.view()).unwrap().posteriors
            );
            let want = c.classify(&frame_t.view()).unwrap();
            assert_eq!(got.class, want.class);
            for (p, q) in got.posteriors.iter().zip(want.posteriors.iter()) {
                assert!(
                    (p - q).abs() < 1e-6,
                    "{:?} vs {:?}",
                    got.posteriors,
                    want.posteriors
                );
            }
        }
    }
}
