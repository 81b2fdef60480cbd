//! What a feature family is: the one trait a feature file implements to be trained on, stored, chosen by
//! the automatic search and named by every face (as the classifiers' [`ClassifierFamily`]).
//!
//! A family is a unit type (`Fft1dFamily`, `GlcmFamily`, ...) naming its parameters
//! ([`FeatureFamily::Config`], stored in model files under `{"kind": NAME, ...}`) and its extractor
//! ([`FeatureFamily::Extractor`], bound to one image grid, owning its plans and buffers so that extracting
//! does not allocate). Adding one is one new file with its `impl FeatureFamily` and one registration line:
//! a line in the built-in list (`features/registry.rs`) or, for an extension or a test,
//! [`register`](super::register). A family may offer several named presets of one stored kind (the 2-D
//! |FFT|'s `fft2d` and `fft2d_polar`), and may learn from the training images before extracting
//! ([`FeatureFamily::fit`]; the fitted parameters are stored in the model).
//!
//! [`ClassifierFamily`]: crate::classifier::ClassifierFamily

use std::fmt::Debug;

use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::error::Result;
use crate::frame::Grid;

/// The most points the feature transforms of one model may hold together: `fft_len` of the 1-D |FFT|,
/// `pad_rows x pad_cols` of the 2-D one, summed over the parts of combined features (also the limit on
/// the polar form's `radial_bins` and `angular_bins`). 4 Mi points are a few hundred MB of plans and
/// buffers; the paper's setting needs 2048.
pub const MAX_TRANSFORM_LEN: usize = 1 << 22;

/// Training images as a feature family's [`fit`](FeatureFamily::fit) sees them: cropped and
/// preprocessed, each `grid.len()` long, row-major.
#[derive(Clone, Copy, Debug)]
pub struct FitImages<'a> {
    pub grid: Grid,
    /// `n x grid.len()`, row-major.
    pub values: &'a [f64],
}

impl<'a> FitImages<'a> {
    /// Number of images.
    pub fn len(&self) -> usize {
        self.values.len().checked_div(self.grid.len()).unwrap_or(0)
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Image `index`.
    pub fn image(&self, index: usize) -> &'a [f64] {
        let len = self.grid.len();
        &self.values[index * len..(index + 1) * len]
    }
}

/// A feature family: its names, parameters and extraction.
pub trait FeatureFamily: Send + Sync + 'static {
    /// The name files know it by (`{"kind": NAME}`): lower-case.
    const NAME: &'static str;
    /// The names users may give it by (`--features NAME`), each a preset of its parameters
    /// ([`preset`](Self::preset)); the first is `NAME` with the default parameters.
    const PRESETS: &'static [&'static str];
    /// Whether the family is costly to compute (the automatic choice scores such families last, and in
    /// its default search only where time allows).
    const COSTLY: bool = false;
    /// Whether [`fit`](Self::fit) learns from the training images (then training prepares them for it).
    const LEARNS: bool = false;

    /// Parameters; `Default` is the first preset's.
    type Config: Clone + Debug + Default + PartialEq + Serialize + DeserializeOwned + Send + Sync;
    /// An extractor bound to one image grid; owns its buffers.
    type Extractor: Clone + Debug + Send + Sync + 'static;

    /// The parameters of preset `index` (`index < PRESETS.len()`).
    fn preset(index: usize) -> Self::Config;

    /// Which preset `config` shows as (its name in reports and file names).
    fn preset_of(config: &Self::Config) -> usize {
        let _ = config;
        0
    }

    /// Checks the parameters on their own (the image grid is checked by
    /// [`output_len`](Self::output_len)).
    fn check(config: &Self::Config) -> Result<()>;

    /// Learns what the family needs from the training images, before any extraction (a random-convolution
    /// family's biases, say): the returned parameters are stored in the model. A family that draws at
    /// random keeps its seed in its parameters. Most families learn nothing.
    fn fit(config: &Self::Config, images: FitImages<'_>) -> Result<Self::Config> {
        let _ = images;
        Ok(config.clone())
    }

    /// Number of features for images of `grid`, or an error if the family cannot take such images.
    fn output_len(config: &Self::Config, grid: Grid) -> Result<usize>;

    /// The name of each feature for images of `grid`, in order; each starts with the preset's name.
    fn feature_names(config: &Self::Config, grid: Grid) -> Result<Vec<String>>;

    /// The points of the transforms the family plans for `grid`, checked against
    /// [`MAX_TRANSFORM_LEN`] (an error names the parameter): so that loading a crafted model cannot plan
    /// gigantic transforms. Families without transforms have none.
    fn transform_points(config: &Self::Config, grid: Grid) -> Result<usize> {
        let _ = (config, grid);
        Ok(0)
    }

    /// A reusable extractor for images of `grid`.
    fn extractor(config: &Self::Config, grid: Grid) -> Result<Self::Extractor>;

    /// The image grid `extractor` takes.
    fn grid(extractor: &Self::Extractor) -> Grid;

    /// Number of features `extractor` writes.
    fn len(extractor: &Self::Extractor) -> usize;

    /// Writes the features of `image` (row-major, the extractor's grid) into `out`. Must not allocate.
    fn extract_into(extractor: &mut Self::Extractor, image: &[f64], out: &mut [f64]) -> Result<()>;

    /// Whether classification computes these features otherwise than training
    /// ([`extract_fast_into`](Self::extract_fast_into)).
    fn has_fast_path(config: &Self::Config) -> bool {
        let _ = config;
        false
    }

    /// The features as classification computes them (faster, within a stated tolerance of the exact
    /// ones); by default the exact ones. Must not allocate.
    fn extract_fast_into(
        extractor: &mut Self::Extractor,
        image: &[f64],
        out: &mut [f64],
    ) -> Result<()> {
        Self::extract_into(extractor, image, out)
    }

    /// The fast features of an image that is a window of a larger row-major array (row `r` is
    /// `values[first + r * stride ..][.. cols]`), in single precision, in the extractor's own buffer: the
    /// common case of classification, read straight from the frame without a cropped copy. `None` when
    /// the family has no such path.
    fn extract_fast_window<'e>(
        extractor: &'e mut Self::Extractor,
        values: &[f64],
        first: usize,
        stride: usize,
    ) -> Option<Result<&'e [f32]>> {
        let _ = (extractor, values, first, stride);
        None
    }
}
