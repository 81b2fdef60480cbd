//! A feature family added through the registration alone: a toy family that learns from the training
//! images (the mean image, subtracted before each row's roughness is taken), defined here, registered at run time,
//! then trained, stored, loaded and combined through the pipeline like a built-in one. Also: the
//! built-in families' names and stored forms.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use presrs_core::classifier::ClassifierKind;
use presrs_core::error::{CoreError, Result};
use presrs_core::features::{
    FeatureConfig, FeatureFamily, FeatureKind, Fft1dConfig, Fft1dFamily, Fft2dConfig, Fft2dFamily,
    FitImages, GlcmConfig, GlcmFamily, register,
};
use presrs_core::pipeline::{LabeledImage, TrainConfig, TrainedModel, extract_features, train};
use presrs_core::testing::labeled_set;
use presrs_core::{Crop, Frame, Grid};
use serde::{Deserialize, Serialize};

/// The roughness of each row (the sum of absolute steps along it) of the image less the training
/// images' mean, times `scale`.
#[derive(Debug)]
struct RowRoughness;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RowRoughnessConfig {
    scale: f64,
    /// The mean training image, once fitted.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    mean: Option<Vec<f64>>,
}

impl Default for RowRoughnessConfig {
    fn default() -> Self {
        Self {
            scale: 1.0,
            mean: None,
        }
    }
}

#[derive(Clone, Debug)]
struct RowRoughnessExtractor {
    grid: Grid,
    scale: f64,
    mean: Vec<f64>,
}

impl FeatureFamily for RowRoughness {
    const NAME: &'static str = "row_roughness";
    const PRESETS: &'static [&'static str] = &["row_roughness", "row_roughness_halved"];
    const LEARNS: bool = true;
    type Config = RowRoughnessConfig;
    type Extractor = RowRoughnessExtractor;

    fn preset(index: usize) -> RowRoughnessConfig {
        RowRoughnessConfig {
            scale: if index == 1 { 0.5 } else { 1.0 },
            mean: None,
        }
    }

    fn preset_of(config: &RowRoughnessConfig) -> usize {
        usize::from(config.scale == 0.5)
    }

    fn check(config: &RowRoughnessConfig) -> Result<()> {
        if config.scale.is_finite() && config.scale > 0.0 {
            return Ok(());
        }
        Err(CoreError::Param {
            name: "scale",
            reason: "must be positive".into(),
        })
    }

    fn fit(config: &RowRoughnessConfig, images: FitImages<'_>) -> Result<RowRoughnessConfig> {
        let mut mean = vec![0.0; images.grid.len()];
        for index in 0..images.len() {
            for (m, v) in mean.iter_mut().zip(images.image(index)) {
                *m += v / images.len() as f64;
            }
        }
        Ok(RowRoughnessConfig {
            mean: Some(mean),
            ..config.clone()
        })
    }

    fn output_len(_config: &RowRoughnessConfig, grid: Grid) -> Result<usize> {
        Ok(grid.rows)
    }

    fn feature_names(_config: &RowRoughnessConfig, grid: Grid) -> Result<Vec<String>> {
        Ok((0..grid.rows)
            .map(|r| format!("row_roughness_{r}"))
            .collect())
    }

    fn extractor(config: &RowRoughnessConfig, grid: Grid) -> Result<RowRoughnessExtractor> {
        let mean = config.mean.clone().ok_or_else(|| CoreError::Param {
            name: "row_roughness",
            reason: "not fitted".into(),
        })?;
        presrs_core::error::check_len("row_roughness mean", grid.len(), mean.len())?;
        Ok(RowRoughnessExtractor {
            grid,
            scale: config.scale,
            mean,
        })
    }

    fn grid(extractor: &RowRoughnessExtractor) -> Grid {
        extractor.grid
    }

    fn len(extractor: &RowRoughnessExtractor) -> usize {
        extractor.grid.rows
    }

    fn extract_into(
        extractor: &mut RowRoughnessExtractor,
        image: &[f64],
        out: &mut [f64],
    ) -> Result<()> {
        let cols = extractor.grid.cols;
        for ((dst, row), mean) in out
            .iter_mut()
            .zip(image.chunks_exact(cols))
            .zip(extractor.mean.chunks_exact(cols))
        {
            let centred = |c: usize| row[c] - mean[c];
            *dst = extractor.scale
                * (1..cols)
                    .map(|c| (centred(c) - centred(c - 1)).abs())
                    .sum::<f64>();
        }
        Ok(())
    }
}

/// Another family that claims a built-in name.
#[derive(Debug)]
struct FakeFft1d;

impl FeatureFamily for FakeFft1d {
    const NAME: &'static str = "fake";
    const PRESETS: &'static [&'static str] = &["fake", "fft1d"];
    type Config = Fft1dConfig;
    type Extractor = RowRoughnessExtractor;

    fn preset(_index: usize) -> Fft1dConfig {
        Fft1dConfig::PAPER
    }

    fn check(_config: &Fft1dConfig) -> Result<()> {
        Ok(())
    }

    fn output_len(_config: &Fft1dConfig, grid: Grid) -> Result<usize> {
        Ok(grid.rows)
    }

    fn feature_names(_config: &Fft1dConfig, _grid: Grid) -> Result<Vec<String>> {
        Ok(Vec::new())
    }

    fn extractor(_config: &Fft1dConfig, grid: Grid) -> Result<RowRoughnessExtractor> {
        Ok(RowRoughnessExtractor {
            grid,
            scale: 1.0,
            mean: vec![0.0; grid.len()],
        })
    }

    fn grid(extractor: &RowRoughnessExtractor) -> Grid {
        extractor.grid
    }

    fn len(extractor: &RowRoughnessExtractor) -> usize {
        extractor.grid.rows
    }

    fn extract_into(_: &mut RowRoughnessExtractor, _: &[f64], _: &mut [f64]) -> Result<()> {
        Ok(())
    }
}

fn images<'a>(set: &'a [(Frame, &'static str)]) -> Vec<LabeledImage<'a>> {
    set.iter()
        .map(|(frame, label)| LabeledImage::new(frame.view(), label))
        .collect()
}

fn config_with(features: FeatureConfig) -> TrainConfig {
    TrainConfig {
        crop: Crop::PAPER,
        dims: 8,
        features,
        classifier: ClassifierKind::LDA.default_config(),
        ..TrainConfig::default()
    }
}

#[test]
fn a_registered_learning_family_trains_round_trips_and_combines() {
    let kind = register::<RowRoughness>().unwrap();
    assert_eq!(
        register::<RowRoughness>().unwrap(),
        kind,
        "registering twice"
    );
    assert!(register::<FakeFft1d>().is_err(), "a taken preset name");
    assert_eq!(FeatureKind::parse(" Row_Roughness ").unwrap(), kind);
    let halved = FeatureKind::parse("row_roughness_halved").unwrap();
    assert_eq!(halved.family_name(), "row_roughness");
    assert_eq!(halved.default_config().kind(), Some(halved));
    assert!(FeatureKind::names().contains(&"row_roughness_halved"));
    assert_eq!(
        FeatureKind::parse_list("fft1d+row_roughness").unwrap(),
        [FeatureKind::FFT1D, kind]
    );
    let bad = FeatureConfig::of::<RowRoughness>(RowRoughnessConfig {
        scale: -1.0,
        mean: None,
    });
    assert!(config_with(bad).check().is_err());

    // Fitted on the prepared (cropped) training images, and stored so.
    let (train_set, validation_set, test_set) =
        (labeled_set(10, 1), labeled_set(5, 2), labeled_set(10, 3));
    let config = config_with(kind.default_config()).check().unwrap();
    let model = train(&images(&train_set), &images(&validation_set), &config).unwrap();
    let fitted = model.features().params::<RowRoughness>().unwrap();
    let image_grid = Crop::PAPER.output_grid(train_set[0].0.grid()).unwrap();
    let mean = fitted.mean.as_ref().unwrap();
    assert_eq!(mean.len(), image_grid.len());
    let (row0, col0, _) = Crop::PAPER.window(train_set[0].0.grid()).unwrap();
    let cols = train_set[0].0.grid().cols;
    let by_hand: f64 = train_set
        .iter()
        .map(|(frame, _)| frame.values()[row0 * cols + col0] / train_set.len() as f64)
        .sum();
    assert!((mean[0] - by_hand).abs() < 1e-9, "{} vs {by_hand}", mean[0]);

    let mut session = model.session();
    let right = test_set
        .iter()
        .filter(|(frame, label)| session.classify(&frame.view()).unwrap().label == *label)
        .count();
    assert!(
        right * 10 >= test_set.len() * 8,
        "{right} of {}",
        test_set.len()
    );

    let json = serde_json::to_string(&model).unwrap();
    assert!(json.contains(r#""features":{"kind":"row_roughness","scale":1.0,"mean":["#));
    let back: TrainedModel = serde_json::from_str(&json).unwrap();
    assert_eq!(serde_json::to_string(&back).unwrap(), json);
    let frames: Vec<_> = test_set.iter().map(|(frame, _)| frame.view()).collect();
    for (a, b) in model
        .classify_batch(&frames)
        .into_iter()
        .zip(back.classify_batch(&frames))
    {
        assert_eq!(a.unwrap(), b.unwrap());
    }

    // Side by side with the paper's family: fitted as a part, named by its preset.
    let combined = FeatureConfig::combined(&[FeatureKind::FFT1D, halved]);
    assert_eq!(combined.name(), "fft1d+row_roughness_halved");
    let config = config_with(combined).check().unwrap();
    let model = train(&images(&train_set), &images(&validation_set), &config).unwrap();
    let parts = model.features().parts();
    assert_eq!(parts.len(), 2);
    assert!(parts[1].params::<RowRoughness>().unwrap().mean.is_some());
    let back: TrainedModel = serde_json::from_str(&serde_json::to_string(&model).unwrap()).unwrap();
    assert_eq!(back.features(), model.features());

    // Not fitted, it cannot extract: a clear error, not a panic.
    let frame = train_set[0].0.view();
    let err = extract_features(&frame, &Crop::PAPER, &kind.default_config()).unwrap_err();
    assert!(err.to_string().contains("not fitted"), "{err}");
}

#[test]
fn built_in_families_keep_their_names_and_stored_forms() {
    let names: Vec<&str> = [
        FeatureKind::FFT1D,
        FeatureKind::FFT2D,
        FeatureKind::FFT2D_POLAR,
        FeatureKind::GLCM,
    ]
    .map(FeatureKind::as_str)
    .to_vec();
    assert_eq!(names, ["fft1d", "fft2d", "fft2d_polar", "glcm"]);
    assert_eq!(&FeatureKind::names()[..4], names);
    assert!(FeatureKind::GLCM.costly() && !FeatureKind::FFT2D_POLAR.costly());

    // What `#[serde(tag = "kind")]` on the enum of the families wrote.
    let stored = [
        (
            FeatureConfig::of::<Fft1dFamily>(Fft1dConfig::PAPER),
            r#"{"kind":"fft1d","fft_len":null}"#.to_owned(),
        ),
        (
            FeatureKind::FFT2D_POLAR.default_config(),
            format!(
                r#"{{"kind":"fft2d",{}"#,
                &serde_json::to_string(&Fft2dConfig::POLAR).unwrap()[1..]
            ),
        ),
        (
            FeatureConfig::of::<GlcmFamily>(GlcmConfig::default()),
            format!(
                r#"{{"kind":"glcm",{}"#,
                &serde_json::to_string(&GlcmConfig::default()).unwrap()[1..]
            ),
        ),
    ];
    for (config, json) in stored {
        assert_eq!(serde_json::to_string(&config).unwrap(), json);
        assert_eq!(
            serde_json::from_str::<FeatureConfig>(&json).unwrap(),
            config
        );
    }
    let combined = FeatureConfig::combined(&[FeatureKind::FFT1D, FeatureKind::GLCM]);
    let json = serde_json::to_string(&combined).unwrap();
    assert!(
        json.starts_with(r#"{"kind":"combined","parts":[{"kind":"fft1d","#),
        "{json}"
    );
    assert_eq!(
        serde_json::from_str::<FeatureConfig>(&json).unwrap(),
        combined
    );
    assert_eq!(
        FeatureKind::FFT2D_POLAR
            .default_config()
            .params::<Fft2dFamily>(),
        Some(&Fft2dConfig::POLAR)
    );

    // Refused: an unknown kind (the known ones listed), a field of another family, a bad combination.
    for (json, wanted) in [
        (r#"{"kind":"wavelet"}"#, "fft1d, fft2d, glcm"),
        (r#"{"kind":"fft1d","levels":4}"#, "levels"),
        (r#"{"kind":"combined","parts":[],"extra":1}"#, "extra"),
        (r#"{"fft_len":4}"#, "kind"),
    ] {
        let err = serde_json::from_str::<FeatureConfig>(json).unwrap_err();
        assert!(err.to_string().contains(wanted), "{json}: {err}");
    }
    assert!(FeatureConfig::of_parts(Vec::new()).check().is_err());
}
