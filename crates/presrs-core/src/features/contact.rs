//! Contact geometry: how large, how elongated and how concentrated the load is, the measures a
//! spectrum or a texture holds only implicitly (two cylinders of different diameters give nearly the
//! same ring and wedge sums of the 2-D |FFT|, and the same co-occurrence texture, but not the same
//! contact width).
//!
//! For an image of `rows x cols` sensels (values `<= 0` carry no load), `v⁺` its loads, `peak` their
//! maximum and `scale = sqrt(rows · cols)` (so that lengths do not depend on the sensor's size):
//!
//! - **areas**: for each share `s` of [`ContactConfig::area_shares`], the share of sensels whose load
//!   is above `s · peak`;
//! - **moments**: the load-weighted centroid and covariance of the sensel positions; its eigenvalues
//!   `λ1 >= λ2` give the major and minor lengths `sqrt(λ) / scale` and the elongation `λ2 / λ1` (0 for
//!   a contact of one point);
//! - **intensity**: `ln(1 + mean load)` and `ln(1 + peak)` (logs: loads span decades between a light
//!   touch and a stance);
//! - **radial profile**: for each radius `r` of [`ContactConfig::profile_radii`] (shares of
//!   `scale / 2`), the share of the total load within `r · scale / 2` of the centroid.
//!
//! An image without load gives zeros. The raw measures are in unlike units (shares, lengths, logs of
//! the sensor's units), so the family learns from the training images each measure's mean and spread
//! and writes the standardised values ([`ContactScale`]): every measure then weighs alike once the part
//! is scaled to unit norm beside other families. Cheap: two passes over the image.

use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result, check_len};
use crate::features::family::{FeatureFamily, FitImages};
use crate::frame::Grid;
use crate::linalg::column_standardisation;

/// Measures besides the areas and the profile: major and minor length, elongation, mean and peak.
const MOMENT_AND_INTENSITY_MEASURES: usize = 5;

/// The most area shares, and the most profile radii, a configuration (or a model file) may hold: each
/// costs a comparison per sensel of every image.
pub const MAX_CONTACT_LEVELS: usize = 64;

/// Parameters of the contact-geometry features.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactConfig {
    /// Shares of the image's peak load above which a sensel counts in an area (each in (0, 1)).
    #[serde(default = "default_area_shares")]
    pub area_shares: Vec<f64>,
    /// Radii of the radial profile, as shares of half the image's geometric-mean side (each > 0).
    #[serde(default = "default_profile_radii")]
    pub profile_radii: Vec<f64>,
    /// Each measure's mean and spread over the training images (absent before training).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fitted: Option<ContactScale>,
}

/// The standardisation learned at training: `(raw - mean) / spread` per measure.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactScale {
    pub mean: Vec<f64>,
    pub spread: Vec<f64>,
}

fn default_area_shares() -> Vec<f64> {
    vec![0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 0.9]
}

fn default_profile_radii() -> Vec<f64> {
    vec![0.05, 0.1, 0.15, 0.2, 0.3, 0.4, 0.6, 0.8]
}

impl Default for ContactConfig {
    /// Seven areas (5-90 % of the peak), the moments and intensities, an eight-radius profile: 20
    /// measures.
    fn default() -> Self {
        Self {
            area_shares: default_area_shares(),
            profile_radii: default_profile_radii(),
            fitted: None,
        }
    }
}

impl ContactConfig {
    /// Number of measures (the same for every image grid).
    pub fn measures(&self) -> usize {
        self.area_shares.len() + MOMENT_AND_INTENSITY_MEASURES + self.profile_radii.len()
    }

    pub fn check(&self) -> Result<()> {
        let bad = |reason: String| {
            Err(CoreError::Param {
                name: "contact",
                reason,
            })
        };
        if self.area_shares.len() > MAX_CONTACT_LEVELS
            || self.profile_radii.len() > MAX_CONTACT_LEVELS
        {
            return bad(format!(
                "at most {MAX_CONTACT_LEVELS} area shares and {MAX_CONTACT_LEVELS} profile radii, got \
                 {} and {}",
                self.area_shares.len(),
                self.profile_radii.len()
            ));
        }
        if self.area_shares.iter().any(|s| !(*s > 0.0 && *s < 1.0)) {
            return bad("every area share must be in (0, 1)".into());
        }
        if self
            .profile_radii
            .iter()
            .any(|r| !(r.is_finite() && *r > 0.0))
        {
            return bad("every profile radius must be positive and finite".into());
        }
        if let Some(scale) = &self.fitted {
            check_len("contact means", self.measures(), scale.mean.len())?;
            check_len("contact spreads", self.measures(), scale.spread.len())?;
            if scale.mean.iter().any(|m| !m.is_finite())
                || scale.spread.iter().any(|s| !(s.is_finite() && *s > 0.0))
            {
                return bad("every fitted mean must be finite and every spread positive".into());
            }
        }
        Ok(())
    }

    pub fn output_len(&self, grid: Grid) -> Result<usize> {
        self.check()?;
        if grid.is_empty() {
            return Err(CoreError::Param {
                name: "contact image",
                reason: format!("the image grid {grid} has no sensels"),
            });
        }
        Ok(self.measures())
    }

    /// `contact_area_above_{share}`, `contact_major_length`, `contact_minor_length`,
    /// `contact_elongation`, `contact_log_mean`, `contact_log_peak`, `contact_load_within_{radius}`.
    pub fn feature_names(&self, grid: Grid) -> Result<Vec<String>> {
        self.output_len(grid)?;
        let mut names: Vec<String> = self
            .area_shares
            .iter()
            .map(|s| format!("contact_area_above_{s}"))
            .collect();
        names.extend(
            [
                "major_length",
                "minor_length",
                "elongation",
                "log_mean",
                "log_peak",
            ]
            .map(|m| format!("contact_{m}")),
        );
        names.extend(
            self.profile_radii
                .iter()
                .map(|r| format!("contact_load_within_{r}")),
        );
        Ok(names)
    }
}

/// Writes the raw (unstandardised) measures of `image` (of `grid`) into `out` (`config.measures()`
/// long). Does not allocate.
pub fn raw_measures_into(
    config: &ContactConfig,
    grid: Grid,
    image: &[f64],
    out: &mut [f64],
) -> Result<()> {
    check_len("contact image", grid.len(), image.len())?;
    check_len("contact measures", config.measures(), out.len())?;
    if config.area_shares.len().max(config.profile_radii.len()) > MAX_CONTACT_LEVELS {
        return config.check();
    }
    out.fill(0.0);
    let load = |v: f64| v.max(0.0);
    let (mut total, mut peak, mut row_sum, mut col_sum) = (0.0, 0.0f64, 0.0, 0.0);
    for (index, &v) in image.iter().enumerate() {
        let v = load(v);
        total += v;
        peak = peak.max(v);
        row_sum += v * (index / grid.cols) as f64;
        col_sum += v * (index % grid.cols) as f64;
    }
    if total <= 0.0 {
        return Ok(());
    }
    let (areas, rest) = out.split_at_mut(config.area_shares.len());
    let (moments, profile) = rest.split_at_mut(MOMENT_AND_INTENSITY_MEASURES);
    let len = image.len() as f64;
    let scale = len.sqrt();
    let (centre_row, centre_col) = (row_sum / total, col_sum / total);
    // The levels and the squared radii, once per image (on the stack: at most MAX_CONTACT_LEVELS);
    // squared because `d < r` is `d² < r²` for distances, without a root per sensel.
    let mut levels = [0.0; MAX_CONTACT_LEVELS];
    let mut limits = [0.0; MAX_CONTACT_LEVELS];
    for (level, share) in levels.iter_mut().zip(&config.area_shares) {
        *level = share * peak;
    }
    for (limit, radius) in limits.iter_mut().zip(&config.profile_radii) {
        *limit = (radius * scale / 2.0).powi(2);
    }
    let (levels, limits) = (
        &levels[..config.area_shares.len()],
        &limits[..config.profile_radii.len()],
    );
    // One pass around the centre of pressure: the areas, the second moments, the radial profile.
    let (mut rr, mut cc, mut rc) = (0.0, 0.0, 0.0);
    for (index, &v) in image.iter().enumerate() {
        let v = load(v);
        for (area, level) in areas.iter_mut().zip(levels) {
            *area += f64::from(u8::from(v > *level));
        }
        let (dr, dc) = (
            (index / grid.cols) as f64 - centre_row,
            (index % grid.cols) as f64 - centre_col,
        );
        rr += v * dr * dr;
        cc += v * dc * dc;
        rc += v * dr * dc;
        let squared = dr * dr + dc * dc;
        for (within, limit) in profile.iter_mut().zip(limits) {
            if squared < *limit {
                *within += v;
            }
        }
    }
    areas.iter_mut().for_each(|area| *area /= len);
    profile.iter_mut().for_each(|within| *within /= total);
    let (rr, cc, rc) = (rr / total, cc / total, rc / total);
    // The eigenvalues of [[rr, rc], [rc, cc]], largest first.
    let half_trace = 0.5 * (rr + cc);
    let root = (0.25 * (rr - cc) * (rr - cc) + rc * rc).sqrt();
    let (major, minor) = (half_trace + root, (half_trace - root).max(0.0));
    moments[0] = major.sqrt() / scale;
    moments[1] = minor.sqrt() / scale;
    moments[2] = if major > 0.0 { minor / major } else { 0.0 };
    moments[3] = (total / len).ln_1p();
    moments[4] = peak.ln_1p();
    Ok(())
}

/// Computes the standardised contact measures; holds its grid and scale.
#[derive(Clone, Debug)]
pub struct ContactExtractor {
    grid: Grid,
    /// The measures' parameters (its fitted scale moved to `scale`).
    config: ContactConfig,
    scale: ContactScale,
}

impl ContactExtractor {
    /// An extractor for images of `grid`; the features are learned, so `config` must be fitted.
    pub fn new(grid: Grid, config: &ContactConfig) -> Result<Self> {
        config.output_len(grid)?;
        let mut config = config.clone();
        let scale = config.fitted.take().ok_or_else(|| CoreError::Param {
            name: "contact",
            reason: "the contact measures are standardised by their spread over the training \
                     images: train a model with them (they have no extractor before training)"
                .into(),
        })?;
        Ok(Self {
            grid,
            config,
            scale,
        })
    }

    pub fn extract_into(&self, image: &[f64], out: &mut [f64]) -> Result<()> {
        raw_measures_into(&self.config, self.grid, image, out)?;
        for ((value, mean), spread) in out.iter_mut().zip(&self.scale.mean).zip(&self.scale.spread)
        {
            *value = (*value - mean) / spread;
        }
        Ok(())
    }
}

/// Contact geometry as a [`FeatureFamily`]: learns its standardisation from the training images.
#[derive(Debug)]
pub struct ContactFamily;

impl FeatureFamily for ContactFamily {
    const NAME: &'static str = "contact";
    const PRESETS: &'static [&'static str] = &["contact"];
    const LEARNS: bool = true;
    type Config = ContactConfig;
    type Extractor = ContactExtractor;

    fn preset(_index: usize) -> ContactConfig {
        ContactConfig::default()
    }

    fn check(config: &ContactConfig) -> Result<()> {
        config.check()
    }

    /// Each measure's mean and spread over `images` (a spread within rounding of zero, a measure
    /// constant over the training images, is taken as 1: the measure is then 0 for them and reads any
    /// departure; `linalg::column_standardisation`, as ridge standardises).
    fn fit(config: &ContactConfig, images: FitImages<'_>) -> Result<ContactConfig> {
        config.output_len(images.grid)?;
        if images.is_empty() {
            return Err(CoreError::NotEnoughData(
                "contact: no training images to fit on".into(),
            ));
        }
        let measures = config.measures();
        let mut raw = vec![0.0; images.len() * measures];
        for (index, out) in raw.chunks_exact_mut(measures.max(1)).enumerate() {
            raw_measures_into(config, images.grid, images.image(index), out)?;
        }
        let (mean, spread) = column_standardisation(|| raw.chunks_exact(measures.max(1)), measures);
        Ok(ContactConfig {
            fitted: Some(ContactScale { mean, spread }),
            ..config.clone()
        })
    }

    fn output_len(config: &ContactConfig, grid: Grid) -> Result<usize> {
        config.output_len(grid)
    }

    fn feature_names(config: &ContactConfig, grid: Grid) -> Result<Vec<String>> {
        config.feature_names(grid)
    }

    fn extractor(config: &ContactConfig, grid: Grid) -> Result<ContactExtractor> {
        ContactExtractor::new(grid, config)
    }

    fn grid(extractor: &ContactExtractor) -> Grid {
        extractor.grid
    }

    fn len(extractor: &ContactExtractor) -> usize {
        extractor.config.measures()
    }

    fn extract_into(
        extractor: &mut ContactExtractor,
        image: &[f64],
        out: &mut [f64],
    ) -> Result<()> {
        extractor.extract_into(image, out)
    }
}
