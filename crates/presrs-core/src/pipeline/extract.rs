//! From frames to feature vectors: the crop, the preprocessing steps and the feature extractor of one
//! image grid ([`Preprocessor`]), for one image, many, or a table the automatic choice reuses.

use rayon::prelude::*;

use crate::crop::Crop;
use crate::error::{CoreError, Result, check_len};
use crate::features::{FeatureConfig, FeatureExtractor, FitImages, Precision};
use crate::frame::{FrameView, Grid};
use crate::pipeline::config::TrainConfig;
use crate::pipeline::model::check_sizes;
use crate::preprocess::{FillScratch, Preprocess, fill_from_neighbours, normalise_load};

/// A labelled image as the algorithms see it (a borrowed view of a data set's sample): its class name
/// and, for evaluation, the operating condition it was recorded in and its value of the held-out
/// column.
#[derive(Clone, Copy, Debug)]
pub struct LabeledImage<'a> {
    pub frame: FrameView<'a>,
    pub label: &'a str,
    /// The operating condition (e.g. gait) the image was recorded in.
    pub condition: Option<&'a str>,
    /// The image's group (e.g. a person or a trial; with a leave-one-out protocol, the held-out column's
    /// value): the automatic choice validates by leaving one out.
    pub group: Option<&'a str>,
}

impl<'a> LabeledImage<'a> {
    /// An image with its class name (no condition, no group).
    pub fn new(frame: FrameView<'a>, label: &'a str) -> Self {
        Self {
            frame,
            label,
            condition: None,
            group: None,
        }
    }
}

/// `config` with its features fitted on the prepared `images` ([`FeatureConfig::fit`]); a clone when no
/// family learns. The labels are not used.
pub(crate) fn fitted_config(
    config: &TrainConfig,
    images: &[LabeledImage<'_>],
) -> Result<TrainConfig> {
    let mut fitted = config.clone();
    if !config.features.learns() {
        return Ok(fitted);
    }
    let first = images
        .first()
        .ok_or_else(|| CoreError::NotEnoughData("no images to fit the features on".into()))?;
    let image_grid = config.crop.output_grid(first.frame.grid())?;
    check_sizes(&config.features, image_grid)?;
    let mut preparation = Preparation::new(config.crop, config.preprocess, image_grid);
    let mut values = Vec::with_capacity(images.len() * image_grid.len());
    for image in images {
        values.extend_from_slice(preparation.prepare(&image.frame)?);
    }
    fitted.features = config.features.fit(FitImages {
        grid: image_grid,
        values: &values,
    })?;
    Ok(fitted)
}

/// The crop, preprocessing and feature extractor of `config` for images of `frame_grid`, with the size
/// limits loading applies checked first (so that every trained model can be read back).
pub(crate) fn preprocessor_for(config: &TrainConfig, frame_grid: Grid) -> Result<Preprocessor> {
    let image_grid = config.crop.output_grid(frame_grid)?;
    check_sizes(&config.features, image_grid)?;
    Ok(Preprocessor::new(
        config.crop,
        config.preprocess,
        image_grid,
        config.features.extractor(image_grid)?,
    ))
}

/// The features of many images under one configuration: exact (as training computes them) and, when
/// classification computes them otherwise (the 1-D |FFT| in single precision), as classification
/// does. What the automatic choice computes once and reuses over its folds and classifiers.
pub(crate) struct FeatureTable {
    pub n_features: usize,
    /// Row-major `n x n_features`.
    pub exact: Vec<f64>,
    /// As a session computes them, when that differs from `exact`.
    pub fast: Option<Vec<f64>>,
}

impl FeatureTable {
    /// The features of `images` (all of one grid) under `config`'s crop, preprocessing and features.
    pub fn of(images: &[LabeledImage<'_>], config: &TrainConfig) -> Result<Self> {
        let first = images
            .first()
            .ok_or_else(|| CoreError::NotEnoughData("no images".into()))?;
        // Families that learn are fitted on the whole table (unsupervised: no label is read).
        let config = &fitted_config(config, images)?;
        let preprocessor = preprocessor_for(config, first.frame.grid())?;
        let exact = features_of(images, &preprocessor, Precision::Exact)?;
        let fast = if config.features.has_fast_path() {
            Some(features_of(images, &preprocessor, Precision::Fast)?)
        } else {
            None
        };
        Ok(Self {
            n_features: preprocessor.extractor.output_len(),
            exact,
            fast,
        })
    }

    /// Image `index`'s features as training computes them.
    pub fn exact_row(&self, index: usize) -> &[f64] {
        &self.exact[index * self.n_features..(index + 1) * self.n_features]
    }

    /// Image `index`'s features as a classification session computes them.
    pub fn fast_row(&self, index: usize) -> &[f64] {
        let table = self.fast.as_ref().unwrap_or(&self.exact);
        &table[index * self.n_features..(index + 1) * self.n_features]
    }

    /// The exact rows of `indices`, in order.
    pub fn exact_rows(&self, indices: &[usize]) -> Vec<f64> {
        let mut rows = Vec::with_capacity(indices.len() * self.n_features);
        for &index in indices {
            rows.extend_from_slice(self.exact_row(index));
        }
        rows
    }
}

/// Features of many images (`n x n_features`, row-major), in parallel.
pub(crate) fn features_of<T: FeatureValue>(
    images: &[LabeledImage<'_>],
    preprocessor: &Preprocessor,
    precision: Precision,
) -> Result<Vec<T>> {
    let n_features = preprocessor.extractor.output_len();
    let mut features = vec![T::ZERO; images.len() * n_features];
    features
        .par_chunks_mut(n_features)
        .zip(images.par_iter())
        .enumerate()
        .try_for_each_init(
            || (preprocessor.clone(), vec![0.0; n_features]),
            |(preprocessor, row), (index, (out, image))| {
                preprocessor
                    .features_into(&image.frame, row, precision)
                    .map_err(|err| match err {
                        CoreError::Shape {
                            what,
                            expected,
                            got,
                        } => CoreError::Shape {
                            what,
                            expected,
                            got: format!("{got} (image {index}, label {:?})", image.label),
                        },
                        other => other,
                    })?;
                out.iter_mut()
                    .zip(row.iter())
                    .for_each(|(o, &v)| *o = T::from_f64(v));
                Ok(())
            },
        )?;
    Ok(features)
}

/// A feature table's element: `f64`, or `f32` for a classifier that reads single precision (a value
/// rounded to the nearest `f32`).
pub(crate) trait FeatureValue: Copy + Send + Sync {
    const ZERO: Self;
    fn from_f64(value: f64) -> Self;
}

impl FeatureValue for f64 {
    const ZERO: Self = 0.0;
    fn from_f64(value: f64) -> Self {
        value
    }
}

impl FeatureValue for f32 {
    const ZERO: Self = 0.0;
    #[allow(clippy::cast_possible_truncation)]
    fn from_f64(value: f64) -> Self {
        value as f32
    }
}

/// Crop + preprocessing for one image grid, with its buffers: a frame made ready for the features.
#[derive(Clone, Debug)]
pub(crate) struct Preparation {
    pub(crate) crop: Crop,
    pub(crate) preprocess: Preprocess,
    pub(crate) image_grid: Grid,
    cropped: Vec<f64>,
    /// The crop of the frame's mask (used when filling absent sensels).
    cropped_present: Vec<bool>,
    fill: FillScratch,
}

impl Preparation {
    pub(crate) fn new(crop: Crop, preprocess: Preprocess, image_grid: Grid) -> Self {
        let len = image_grid.len();
        let fill = preprocess.fill_absent;
        Self {
            crop,
            preprocess,
            image_grid,
            cropped: vec![0.0; len],
            cropped_present: if fill { vec![true; len] } else { Vec::new() },
            fill: if fill {
                FillScratch::new(len)
            } else {
                FillScratch::default()
            },
        }
    }

    /// Crops `frame` (absent sensels read as 0, or filled from their neighbours), applies the intensity
    /// transform and normalises its load when asked; the image is valid until the next call. Does not
    /// allocate.
    pub(crate) fn prepare(&mut self, frame: &FrameView<'_>) -> Result<&[f64]> {
        crop_masked_into(&self.crop, self.image_grid, frame, &mut self.cropped)?;
        if self.preprocess.fill_absent
            && let Some(mask) = frame.present()
        {
            let (row0, col0, grid) = self.crop.window(frame.grid())?;
            let in_cols = frame.grid().cols;
            for (r, dst) in self.cropped_present.chunks_exact_mut(grid.cols).enumerate() {
                let start = (row0 + r) * in_cols + col0;
                dst.copy_from_slice(&mask[start..start + grid.cols]);
            }
            fill_from_neighbours(
                &mut self.cropped,
                self.image_grid,
                Some(&self.cropped_present),
                None,
                &mut self.fill,
            )?;
        }
        self.preprocess.intensity.apply(&mut self.cropped);
        if self.preprocess.normalise_load {
            normalise_load(&mut self.cropped);
        }
        Ok(&self.cropped)
    }
}

/// Crop + preprocessing + features for one image grid, with its buffers.
#[derive(Clone, Debug)]
pub(crate) struct Preprocessor {
    pub(crate) preparation: Preparation,
    pub(crate) extractor: FeatureExtractor,
}

impl Preprocessor {
    pub(crate) fn new(
        crop: Crop,
        preprocess: Preprocess,
        image_grid: Grid,
        extractor: FeatureExtractor,
    ) -> Self {
        Self {
            preparation: Preparation::new(crop, preprocess, image_grid),
            extractor,
        }
    }

    /// The grid of the images the features are taken of (after the crop).
    pub(crate) fn image_grid(&self) -> Grid {
        self.preparation.image_grid
    }

    /// Prepares `frame` ([`Preparation::prepare`]) and writes its features into `out`. Does not
    /// allocate.
    pub(crate) fn features_into(
        &mut self,
        frame: &FrameView<'_>,
        out: &mut [f64],
        precision: Precision,
    ) -> Result<()> {
        if precision == Precision::Fast
            && let Some(features) = self.fast_f32_features(frame)?
        {
            check_len("feature buffer", features.len(), out.len())?;
            for (dst, &value) in out.iter_mut().zip(features) {
                *dst = f64::from(value);
            }
            return Ok(());
        }
        let image = self.preparation.prepare(frame)?;
        match precision {
            Precision::Exact => self.extractor.extract_into(image, out),
            Precision::Fast => self.extractor.extract_fast_into(image, out),
        }
    }

    /// The common case of classification: a family with a windowed fast path (the 1-D |FFT|) reads the
    /// crop straight from the frame (no absent sensels, no load normalisation, no intensity transform)
    /// and gives its features in f32, as the fixed-point PCA reads them. `None` when the case does not
    /// apply.
    pub(crate) fn fast_f32_features(&mut self, frame: &FrameView<'_>) -> Result<Option<&[f32]>> {
        let Preparation {
            crop,
            preprocess,
            image_grid,
            ..
        } = &self.preparation;
        if frame.present().is_some() || preprocess.normalise_load || !preprocess.intensity.is_none()
        {
            return Ok(None);
        }
        let start = crop_start(crop, *image_grid, frame)?;
        self.extractor
            .extract_fast_window(frame.values(), start, frame.grid().cols)
            .transpose()
    }
}

/// Where the crop of `frame` starts in its row-major values; the crop must give `expected`.
fn crop_start(crop: &Crop, expected: Grid, frame: &FrameView<'_>) -> Result<usize> {
    let (row0, col0, grid) = crop.window(frame.grid())?;
    if grid != expected {
        return Err(CoreError::Shape {
            what: "image",
            expected: format!("{expected} sensels after the crop {crop}"),
            got: format!("{grid} (from a {} image)", frame.grid()),
        });
    }
    Ok(row0 * frame.grid().cols + col0)
}

/// Copies the crop of `frame` into `out`, zeroing absent sensels; the crop must give `expected`.
fn crop_masked_into(
    crop: &Crop,
    expected: Grid,
    frame: &FrameView<'_>,
    out: &mut [f64],
) -> Result<()> {
    let start = crop_start(crop, expected, frame)?;
    let in_cols = frame.grid().cols;
    let grid = expected;
    let values = frame.values();
    let mask = frame.present();
    for (r, dst) in out.chunks_exact_mut(grid.cols).enumerate() {
        let start = start + r * in_cols;
        let src = &values[start..start + grid.cols];
        match mask {
            None => dst.copy_from_slice(src),
            Some(mask) => {
                for ((d, &s), &here) in dst.iter_mut().zip(src).zip(&mask[start..start + grid.cols])
                {
                    *d = if here { s } else { 0.0 };
                }
            }
        }
    }
    Ok(())
}

/// The features of one image as the pipeline computes them (crop, absent sensels as 0, then `features`).
pub fn extract_features(
    frame: &FrameView<'_>,
    crop: &Crop,
    features: &FeatureConfig,
) -> Result<Vec<f64>> {
    extract_features_with(frame, crop, Preprocess::NONE, features)
}

/// [`extract_features`] with the preprocessing steps `preprocess` after the crop.
pub fn extract_features_with(
    frame: &FrameView<'_>,
    crop: &Crop,
    preprocess: Preprocess,
    features: &FeatureConfig,
) -> Result<Vec<f64>> {
    Ok(extract_features_many(std::slice::from_ref(frame), crop, preprocess, features)?.0)
}

/// [`extract_features_with`] for many images of one grid, row-major `frames.len() x n_features` (the
/// transforms planned once). Equal, image for image, to what `extract_features_with` gives.
pub fn extract_features_many(
    frames: &[FrameView<'_>],
    crop: &Crop,
    preprocess: Preprocess,
    features: &FeatureConfig,
) -> Result<(Vec<f64>, usize)> {
    features.check()?;
    let Some(first) = frames.first() else {
        return Ok((Vec::new(), 0));
    };
    let image_grid = crop.output_grid(first.grid())?;
    let mut preprocessor = Preprocessor::new(
        *crop,
        preprocess,
        image_grid,
        features.extractor(image_grid)?,
    );
    let width = preprocessor.extractor.output_len();
    let mut out = vec![0.0; frames.len() * width];
    for (frame, row) in frames.iter().zip(out.chunks_exact_mut(width)) {
        preprocessor.features_into(frame, row, Precision::Exact)?;
    }
    Ok((out, width))
}
