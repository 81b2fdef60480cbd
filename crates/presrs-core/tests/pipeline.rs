//! The trained pipeline end to end on synthetic paper-sized images.

#![allow(clippy::unwrap_used)] // helpers of integration tests are test code too

use presrs_core::classifier::{ClassifierConfig, ParzenConfig, PweFamily, SigmaChoice};
use presrs_core::features::{FeatureConfig, Fft1dConfig, Fft1dExtractor};
use presrs_core::pipeline::{
    BATCH_BLOCK, LabeledImage, TrainConfig, TrainedModel, extract_features, train,
};
use presrs_core::testing::{SYNTHETIC_CLASSES, bench_fixture, labeled_set};
use presrs_core::{CoreError, Crop, Frame, FrameView, Grid};

fn images<'a>(set: &'a [(Frame, &'static str)]) -> Vec<LabeledImage<'a>> {
    set.iter()
        .map(|(frame, label)| LabeledImage::new(frame.view(), label))
        .collect()
}

#[test]
fn bench_fixture_has_the_paper_shapes_and_learns() {
    let (model, frames) = bench_fixture(11, 200).unwrap();
    assert_eq!(model.image_grid(), Grid::new(38, 41));
    assert_eq!(model.pca().unwrap().n_features(), 1025);
    assert_eq!(model.pca().unwrap().n_components(), 51);
    assert_eq!(model.class_names(), SYNTHETIC_CLASSES);
    assert_eq!(model.summary().train_per_class, vec![13; 4]);
    assert_eq!(model.summary().validation_per_class, vec![7; 4]);
    let parzen = model.classifier().get::<PweFamily>().unwrap();
    assert_eq!(parzen.n_stored(), 80);
    assert!(model.sigma().unwrap() > 0.0);
    assert_eq!(model.validation_curve().len(), 41);

    // the test frames cycle through the classes in SYNTHETIC_CLASSES order
    let mut session = model.session();
    let mut correct = 0;
    for (i, frame) in frames.iter().enumerate() {
        let prediction = session.classify(&frame.view()).unwrap();
        assert_eq!(prediction.label, SYNTHETIC_CLASSES[prediction.class]);
        assert!((prediction.posteriors.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        let top = prediction.posteriors.iter().cloned().fold(0.0, f64::max);
        assert_eq!(prediction.confidence, top);
        correct += usize::from(prediction.class == i % 4);
    }
    let accuracy = correct as f64 / frames.len() as f64;
    assert!(accuracy >= 0.95, "held-out accuracy {accuracy}");
}

#[test]
fn training_is_deterministic() {
    let (a, _) = bench_fixture(5, 0).unwrap();
    let (b, _) = bench_fixture(5, 0).unwrap();
    assert_eq!(
        serde_json::to_string(&a).unwrap(),
        serde_json::to_string(&b).unwrap()
    );
}

#[test]
fn saved_and_loaded_model_classifies_identically() {
    let (model, frames) = bench_fixture(12, 40).unwrap();
    let json = serde_json::to_string(&model).unwrap();
    let loaded: TrainedModel = serde_json::from_str(&json).unwrap();
    assert_eq!(serde_json::to_string(&loaded).unwrap(), json);
    let (mut before, mut after) = (model.session(), loaded.session());
    for frame in &frames {
        let p = before.classify(&frame.view()).unwrap();
        let q = after.classify(&frame.view()).unwrap();
        assert_eq!(p, q, "bit-identical after a JSON round trip");
    }
}

#[test]
fn loading_checks_that_the_parts_fit() {
    let (model, _) = bench_fixture(13, 0).unwrap();
    let json = serde_json::to_string(&model).unwrap();
    let tamper = |edit: &dyn Fn(&mut serde_json::Value)| {
        let mut value: serde_json::Value = serde_json::from_str(&json).unwrap();
        edit(&mut value);
        serde_json::from_value::<TrainedModel>(value)
    };
    assert!(tamper(&|_| {}).is_ok());
    assert!(tamper(&|v| v["class_names"] = serde_json::json!(["a", "b"])).is_err());
    // 64 x 64 images give 2049 features, not the 1025 the PCA takes
    assert!(tamper(&|v| v["image_grid"] = serde_json::json!({"rows": 64, "cols": 64})).is_err());
    assert!(tamper(&|v| v["format_version"] = serde_json::json!(99)).is_err());
    assert!(
        tamper(&|v| v["features"] = serde_json::json!({"kind": "fft1d", "fft_len": 4096})).is_err()
    );
}

#[test]
fn batch_matches_one_at_a_time() {
    // Three blocks of BATCH_BLOCK frames (the last one partial), with bad frames in two of them.
    let (model, mut frames) = bench_fixture(14, 2 * BATCH_BLOCK + 20).unwrap();
    frames[BATCH_BLOCK + 3].values_mut()[100] = f64::NAN;
    let mut views: Vec<FrameView<'_>> = frames.iter().map(Frame::view).collect();
    let odd = Frame::zeros(Grid::new(20, 20));
    views.insert(5, odd.view());
    // A frame with absent sensels takes the f64 feature path (the others the f32 one) in both.
    let source = &frames[7];
    let mut present = vec![true; source.grid().len()];
    present[source.grid().cols * 20 + 20] = false;
    let masked = Frame::with_mask(source.grid(), source.values().to_vec(), Some(present)).unwrap();
    views.insert(9, masked.view());
    let batch = model.classify_batch(&views);
    assert!(batch[BATCH_BLOCK + 5].is_err(), "the NaN frame is refused");
    assert!(
        batch[9].is_ok(),
        "the frame with an absent sensel is classified"
    );
    assert_eq!(batch.len(), views.len());
    let mut session = model.session();
    for (view, result) in views.iter().zip(&batch) {
        match (session.classify(view), result) {
            (Ok(single), Ok(batched)) => assert_eq!(&single.to_classification(), batched),
            (Err(_), Err(_)) => {}
            (single, batched) => panic!("{single:?} vs {batched:?}"),
        }
    }
    assert!(batch[5].is_err(), "the 20 x 20 frame does not fit the crop");
}

#[test]
fn frames_that_do_not_fit_the_crop_are_clear_errors() {
    let (model, _) = bench_fixture(15, 0).unwrap();
    let mut session = model.session();
    // 40 x 40 crops to 34 x 37: the crop fits, but not the model's 38 x 41
    let smaller = Frame::zeros(Grid::new(40, 40));
    let err = session.classify(&smaller.view()).unwrap_err();
    assert!(matches!(err, CoreError::Shape { .. }), "{err}");
    assert!(err.to_string().contains("38x41"), "{err}");
    // transposed 41 x 38 region of the same length is still refused
    let window = Crop::Window {
        row0: 0,
        col0: 0,
        rows: 41,
        cols: 38,
    };
    assert!(
        extract_features(
            &Frame::zeros(Grid::new(44, 44)).view(),
            &window,
            &FeatureConfig::default()
        )
        .is_ok()
    );
    let tall = Frame::zeros(Grid::new(47, 41));
    assert!(session.classify(&tall.view()).is_err());
    // too small for the crop at all
    let tiny = Frame::zeros(Grid::new(5, 2));
    assert!(session.classify(&tiny.view()).is_err());
    // non-finite values
    let mut nan = Frame::zeros(Grid::new(44, 44));
    nan.values_mut()[100] = f64::NAN;
    assert!(session.classify(&nan.view()).is_err());
}

#[test]
fn absent_sensels_count_as_zero() {
    let (model, frames) = bench_fixture(16, 1).unwrap();
    let frame = &frames[0];
    let grid = frame.grid();
    // mark every third sensel absent but leave garbage in its value
    let present: Vec<bool> = (0..grid.len()).map(|i| i % 3 != 0).collect();
    let garbage: Vec<f64> = frame
        .values()
        .iter()
        .zip(&present)
        .map(|(&v, &here)| if here { v } else { 1e6 })
        .collect();
    let masked = FrameView::new(grid, &garbage, Some(&present)).unwrap();
    let zeroed = Frame::with_mask(grid, frame.values().to_vec(), Some(present.clone())).unwrap();
    let mut session = model.session();
    let a = session.features(&masked).unwrap().to_vec();
    let b = session.features(&zeroed.view()).unwrap().to_vec();
    assert_eq!(a, b);
    let p = session.classify(&masked).unwrap().to_classification();
    let q = session
        .classify(&zeroed.view())
        .unwrap()
        .to_classification();
    assert_eq!(p, q);
}

#[test]
fn session_features_are_the_paper_features_of_the_cropped_image() {
    let (model, frames) = bench_fixture(17, 1).unwrap();
    let view = frames[0].view();
    let cropped = Crop::PAPER.apply(&view).unwrap();
    let direct = Fft1dExtractor::new(Grid::new(38, 41), &Fft1dConfig::PAPER)
        .unwrap()
        .extract(cropped.values())
        .unwrap();
    let mut session = model.session();
    assert_eq!(session.features(&view).unwrap(), direct.as_slice());
    assert_eq!(
        extract_features(&view, &Crop::PAPER, &FeatureConfig::default()).unwrap(),
        direct
    );
    // To classify, the session takes the single-precision |FFT| and the PCA's fixed-point projection,
    // bit for bit.
    let reduced = session.reduce(&view).unwrap().to_vec();
    let mut single = vec![0.0; direct.len()];
    Fft1dExtractor::new(Grid::new(38, 41), &Fft1dConfig::PAPER)
        .unwrap()
        .extract_fast_into(cropped.values(), &mut single)
        .unwrap();
    assert_eq!(session.fast_features(&view).unwrap(), single.as_slice());
    let pca = model.pca().unwrap();
    let mut fast = vec![0.0; pca.n_components()];
    pca.project_fast_into(&single, &mut pca.scratch(), &mut fast)
        .unwrap();
    assert_eq!(reduced, fast);
    // ... which is the exact projection of the exact features within about 1e-5 of the largest value
    // (the fixed-point roundings; `Pca::project_fast_into`).
    let exact = pca.project(&direct).unwrap();
    let scale = exact.iter().map(|v| v.abs()).fold(0.0, f64::max);
    for (a, b) in reduced.iter().zip(&exact) {
        assert!((a - b).abs() <= 3e-5 * scale, "{a} vs {b}");
    }
}

#[test]
fn training_input_errors() {
    let train_set = labeled_set(6, 20);
    let validation_set = labeled_set(2, 21);
    let config = TrainConfig::default().check().unwrap();
    assert!(train(&images(&train_set), &images(&validation_set), &config).is_ok());
    // no data, one class
    assert!(train(&[], &images(&validation_set), &config).is_err());
    let one_class: Vec<_> = train_set
        .iter()
        .filter(|(_, l)| *l == "wood")
        .cloned()
        .collect();
    assert!(train(&images(&one_class), &[], &config).is_err());
    // a validation label that is not a training class
    let mut unknown = images(&validation_set);
    unknown[0].label = "ice";
    let err = train(&images(&train_set), &unknown, &config).unwrap_err();
    assert!(err.to_string().contains("ice"), "{err}");
    // mixed grids
    let other = Frame::zeros(Grid::new(40, 44));
    let mut mixed = images(&train_set);
    mixed.push(LabeledImage::new(other.view(), "wood"));
    assert!(train(&mixed, &images(&validation_set), &config).is_err());
    // bad parameters are caught before any data is seen
    assert!(
        TrainConfig {
            dims: 0,
            ..TrainConfig::default()
        }
        .check()
        .is_err()
    );
    let bad_sigma = TrainConfig {
        classifier: ClassifierConfig::of::<PweFamily>(ParzenConfig {
            sigma: SigmaChoice::Fixed { sigma: -1.0 },
        }),
        ..TrainConfig::default()
    };
    assert!(bad_sigma.check().is_err());
    let short_fft = TrainConfig {
        features: FeatureConfig::of::<presrs_core::features::Fft1dFamily>(Fft1dConfig {
            fft_len: Some(1000),
        }),
        ..TrainConfig::default()
    };
    let checked = short_fft.check().unwrap(); // the image size is only known with the data
    assert!(train(&images(&train_set), &images(&validation_set), &checked).is_err());
}

#[test]
fn dims_are_capped_by_the_training_set_and_other_settings_work() {
    let train_set = labeled_set(3, 30); // 12 training images: at most 11 components
    let validation_set = labeled_set(2, 31);
    let config = TrainConfig {
        crop: Crop::NONE,
        features: FeatureConfig::of::<presrs_core::features::Fft1dFamily>(Fft1dConfig {
            fft_len: Some(2000),
        }),
        dims: 51,
        classifier: ClassifierConfig::of::<PweFamily>(ParzenConfig {
            sigma: SigmaChoice::Fixed { sigma: 100.0 },
        }),
        ..TrainConfig::default()
    }
    .check()
    .unwrap();
    let model = train(&images(&train_set), &images(&validation_set), &config).unwrap();
    assert_eq!(model.image_grid(), Grid::new(44, 44));
    assert_eq!(model.pca().unwrap().n_features(), 1001);
    assert_eq!(model.pca().unwrap().n_components(), 11);
    assert_eq!(model.sigma(), Some(100.0));
    assert!(model.validation_curve().is_empty());
    assert!(model.session().classify(&train_set[0].0.view()).is_ok());
}

#[test]
fn train_config_serde_round_trip() {
    let config = TrainConfig::default();
    let json = serde_json::to_string(&config).unwrap();
    let back: TrainConfig = serde_json::from_str(&json).unwrap();
    assert_eq!(back, config);
    assert!(
        json.contains(r#""kind":"pwe""#) && json.contains(r#""kind":"fft1d""#),
        "{json}"
    );
}
