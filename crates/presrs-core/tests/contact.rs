//! The contact-geometry family against numpy (`fixtures/make_contact_fixture.py`), closed forms, and its
//! learned standardisation.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use presrs_core::features::contact::raw_measures_into;
use presrs_core::features::{
    ContactConfig, ContactExtractor, ContactFamily, FeatureFamily, FitImages,
};
use presrs_core::frame::Grid;
use serde::Deserialize;

#[derive(Deserialize)]
struct Fixture {
    rows: usize,
    cols: usize,
    images: Vec<Vec<f64>>,
    raw: Vec<Vec<f64>>,
    mean: Vec<f64>,
    spread: Vec<f64>,
    standardised: Vec<Vec<f64>>,
}

fn fixture() -> Fixture {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/contact_numpy.json"
    ))
    .unwrap();
    serde_json::from_str(&text).unwrap()
}

fn assert_close(got: &[f64], expected: &[f64], what: &str) {
    assert_eq!(got.len(), expected.len(), "{what}");
    for (i, (g, e)) in got.iter().zip(expected).enumerate() {
        assert!(
            (g - e).abs() <= 1e-10 * (1.0 + e.abs()),
            "{what}, measure {i}: {g} against numpy's {e}"
        );
    }
}

fn raw(config: &ContactConfig, grid: Grid, image: &[f64]) -> Vec<f64> {
    let mut out = vec![f64::NAN; config.measures()];
    raw_measures_into(config, grid, image, &mut out).unwrap();
    out
}

#[test]
fn measures_and_their_standardisation_match_numpy() {
    let fixture = fixture();
    let grid = Grid::new(fixture.rows, fixture.cols);
    let config = ContactConfig::default();
    for (k, (image, expected)) in fixture.images.iter().zip(&fixture.raw).enumerate() {
        assert_close(&raw(&config, grid, image), expected, &format!("image {k}"));
    }
    let values: Vec<f64> = fixture.images.concat();
    let fitted = ContactFamily::fit(
        &config,
        FitImages {
            grid,
            values: &values,
        },
    )
    .unwrap();
    let scale = fitted.fitted.as_ref().unwrap();
    assert_close(&scale.mean, &fixture.mean, "means");
    assert_close(&scale.spread, &fixture.spread, "spreads");
    let mut extractor = ContactFamily::extractor(&fitted, grid).unwrap();
    let mut out = vec![0.0; ContactFamily::len(&extractor)];
    for (k, (image, expected)) in fixture.images.iter().zip(&fixture.standardised).enumerate() {
        ContactFamily::extract_into(&mut extractor, image, &mut out).unwrap();
        assert_close(&out, expected, &format!("standardised image {k}"));
    }
}

#[test]
fn closed_forms_of_a_point_and_a_bar() {
    let config = ContactConfig::default();
    let grid = Grid::new(5, 8);
    let mut point = vec![0.0; grid.len()];
    point[2 * 8 + 3] = 9.0;
    let m = raw(&config, grid, &point);
    // every area is the one sensel; no extent; all the load within every radius
    assert!(m[..7].iter().all(|&a| a == 1.0 / 40.0));
    assert_eq!(&m[7..10], &[0.0, 0.0, 0.0]);
    assert!((m[10] - (9.0f64 / 40.0).ln_1p()).abs() < 1e-15);
    assert!((m[11] - 10.0f64.ln()).abs() < 1e-15);
    assert!(m[12..].iter().all(|&p| p == 1.0));
    // a bar of 6 equal sensels along a row: variance (6² - 1) / 12 along it, none across
    let mut bar = vec![0.0; grid.len()];
    bar[8 + 1..8 + 7].fill(2.0);
    let m = raw(&config, grid, &bar);
    let major = (35.0f64 / 12.0).sqrt() / 40.0f64.sqrt();
    assert!((m[7] - major).abs() < 1e-12, "{} against {major}", m[7]);
    assert_eq!((m[8], m[9]), (0.0, 0.0));
    // no load: zeros (and negative readings carry none)
    assert!(
        raw(&config, grid, &vec![-1.0; grid.len()])
            .iter()
            .all(|&v| v == 0.0)
    );
    // a buffer or an image of the wrong size is an error, not a panic
    assert!(raw_measures_into(&config, grid, &bar, &mut [0.0; 3]).is_err());
    assert!(raw_measures_into(&config, grid, &bar[1..], &mut [0.0; 20]).is_err());
}

#[test]
fn the_measures_do_not_depend_on_the_contact_orientation() {
    let config = ContactConfig::default();
    let grid = Grid::new(9, 9);
    let image: Vec<f64> = (0..81)
        .map(|i| {
            let (r, c) = ((i / 9) as f64 - 3.5, (i % 9) as f64 - 4.2);
            (10.0 - r * r - 0.3 * c * c).max(0.0)
        })
        .collect();
    let transposed: Vec<f64> = (0..81).map(|i| image[(i % 9) * 9 + i / 9]).collect();
    assert_close(
        &raw(&config, grid, &transposed),
        &raw(&config, grid, &image),
        "transposed",
    );
}

#[test]
fn the_family_is_learned_and_checks_its_parameters() {
    let grid = Grid::new(4, 4);
    let err = ContactExtractor::new(grid, &ContactConfig::default()).unwrap_err();
    assert!(err.to_string().contains("train a model"), "{err}");
    let bad = ContactConfig {
        area_shares: vec![0.5, 1.0],
        ..ContactConfig::default()
    };
    assert!(bad.check().unwrap_err().to_string().contains("(0, 1)"));
    let many = ContactConfig {
        profile_radii: vec![0.5; 65],
        ..ContactConfig::default()
    };
    assert!(many.check().unwrap_err().to_string().contains("at most 64"));
    let (grid, image) = (Grid::new(2, 2), [1.0; 4]);
    let err = raw_measures_into(&many, grid, &image, &mut vec![0.0; many.measures()]).unwrap_err();
    assert!(err.to_string().contains("at most 64"), "{err}");
    // a stored scale of the wrong length or with a zero spread is refused (model files are checked)
    let values = vec![1.0; 3 * grid.len()];
    let mut fitted = ContactFamily::fit(
        &ContactConfig::default(),
        FitImages {
            grid,
            values: &values,
        },
    )
    .unwrap();
    // three equal images: every measure constant, every spread taken as 1
    assert!(
        fitted
            .fitted
            .as_ref()
            .unwrap()
            .spread
            .iter()
            .all(|&s| s == 1.0)
    );
    fitted.fitted.as_mut().unwrap().spread[0] = 0.0;
    assert!(fitted.check().is_err());
    fitted.fitted.as_mut().unwrap().spread.pop();
    assert!(fitted.check().is_err());
}

/// A model with the contact family stores its learned scale, loads back and classifies alike; a
/// stored scale of the wrong length is refused on loading.
#[test]
fn a_model_keeps_its_contact_scale() {
    use presrs_core::features::{FeatureConfig, FeatureKind};
    use presrs_core::pipeline::{LabeledImage, TrainConfig, TrainedModel, train};
    use presrs_core::testing::labeled_set;

    let set = labeled_set(10, 5);
    let images: Vec<LabeledImage<'_>> = set
        .iter()
        .map(|(frame, label)| LabeledImage::new(frame.view(), label))
        .collect();
    let config = TrainConfig {
        features: FeatureConfig::combined(&[FeatureKind::FFT2D_POLAR, FeatureKind::CONTACT]),
        dims: 4,
        classifier: presrs_core::classifier::ClassifierKind::LDA.default_config(),
        ..TrainConfig::default()
    }
    .check()
    .unwrap();
    let model = train(&images[..32], &[], &config).unwrap();
    let json = serde_json::to_value(&model).unwrap();
    assert!(
        json.to_string().contains("\"spread\""),
        "the scale is stored"
    );
    let loaded: TrainedModel = serde_json::from_value(json.clone()).unwrap();
    let (mut a, mut b) = (model.session(), loaded.session());
    let mut right = 0;
    for (frame, label) in &set[32..] {
        let (x, y) = (
            a.classify(&frame.view()).unwrap(),
            b.classify(&frame.view()).unwrap(),
        );
        assert_eq!(x.posteriors, y.posteriors);
        right += usize::from(x.label == *label);
    }
    assert!(right >= 6, "{right} of 8 held-out synthetic frames");
    let cut = json
        .to_string()
        .replacen("\"spread\":[", "\"spread\":[1.0,", 1);
    let err = serde_json::from_str::<TrainedModel>(&cut).unwrap_err();
    assert!(err.to_string().contains("contact spreads"), "{err}");
}
