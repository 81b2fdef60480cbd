//! Magnitude of the 2-D DFT of the (cropped, optionally zero-padded) image.
//!
//! The image (`rows x cols`) is placed in the top-left corner of a `pad_rows x pad_cols` zero grid and
//! `Y[k][l] = Σ_r Σ_c I[r][c] e^{-2πi (k r / R + l c / C)}` is computed with a real FFT along the rows and a
//! complex FFT along the columns. The spectrum of a real image is Hermitian (`Y[k][l] = conj Y[-k][-l]`),
//! so only the non-redundant half is kept:
//!
//! - [`Fft2dForm::Half`]: `|Y[k][l]|` for `l = 0 ..= C/2` and every `k`, except that on the columns `l = 0`
//!   and (for even `C`) `l = C/2`, which are their own mirror, only `k = 0 ..= R/2` is kept. Row-major by
//!   `l` inside `k`, skipping the dropped entries.
//! - [`Fft2dForm::Polar`]: a compact, shift- and rotation-robust summary of the whole spectrum: the sum of
//!   `|Y|` over `radial_bins` rings of spatial frequency `|f| = sqrt(fk² + fl²)` (cycles per sensel, up to
//!   `sqrt(1/2)`), followed by the sum over `angular_bins` wedges of orientation `atan2(fk, fl) mod π`
//!   (the DC term is left out of the wedges). The magnitude ignores circular shifts; the rings ignore
//!   rotations (up to the grid's anisotropy), and the wedges keep the texture's orientation. Each stored
//!   half-spectrum cell stands for itself and its mirror; a Nyquist cell (even sizes) is binned by its
//!   stored position.

use std::sync::Arc;

use realfft::num_complex::Complex;
use realfft::{RealFftPlanner, RealToComplex};
use rustfft::{Fft, FftPlanner};
use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result, check_len};
use crate::features::family::{FeatureFamily, MAX_TRANSFORM_LEN};
use crate::frame::Grid;

/// What is kept of the 2-D magnitude spectrum.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Fft2dForm {
    /// The non-redundant half of `|Y|`.
    #[default]
    Half,
    /// Ring and wedge sums of `|Y|`.
    Polar,
}

/// Parameters of the 2-D |FFT| features.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Fft2dConfig {
    /// Transform size along the rows (`None`: the image's row count, no padding). A size smaller than
    /// the image's rows grows to the next power of two at least that count, so a padded transform fits
    /// any image.
    #[serde(default)]
    pub pad_rows: Option<usize>,
    /// Transform size along the columns (`None`: the image's column count); grown like `pad_rows`.
    #[serde(default)]
    pub pad_cols: Option<usize>,
    #[serde(default)]
    pub form: Fft2dForm,
    /// Rings of [`Fft2dForm::Polar`].
    #[serde(default = "default_radial_bins")]
    pub radial_bins: usize,
    /// Wedges of [`Fft2dForm::Polar`].
    #[serde(default = "default_angular_bins")]
    pub angular_bins: usize,
}

fn default_radial_bins() -> usize {
    24
}

fn default_angular_bins() -> usize {
    12
}

impl Default for Fft2dConfig {
    fn default() -> Self {
        Self::HALF
    }
}

impl Fft2dConfig {
    /// The non-redundant half spectrum, no padding.
    pub const HALF: Self = Self {
        pad_rows: None,
        pad_cols: None,
        form: Fft2dForm::Half,
        radial_bins: 24,
        angular_bins: 12,
    };

    /// 24 rings and 12 wedges, padded to 64 x 64 (finer frequency sampling); a side longer than 64 is
    /// padded to the next power of two at least its length (a 60 x 75 image: 64 x 128).
    pub const POLAR: Self = Self {
        pad_rows: Some(64),
        pad_cols: Some(64),
        form: Fft2dForm::Polar,
        radial_bins: 24,
        angular_bins: 12,
    };

    /// Checks the parameters on their own.
    pub fn check(&self) -> Result<()> {
        let bad = |reason: &str| {
            Err(CoreError::Param {
                name: "fft2d",
                reason: reason.into(),
            })
        };
        if self.pad_rows == Some(0) || self.pad_cols == Some(0) {
            return bad("the transform sizes must be positive");
        }
        if self.form == Fft2dForm::Polar && (self.radial_bins == 0 || self.angular_bins == 0) {
            return bad("the polar form needs at least one ring and one wedge");
        }
        Ok(())
    }

    /// The transform size `(R, C)` for images of `grid`: the configured padding, grown to the next power
    /// of two at least the image's side where it is shorter; the image's size where none is configured.
    pub fn resolved(&self, grid: Grid) -> Result<(usize, usize)> {
        self.check()?;
        if grid.is_empty() {
            return Err(CoreError::Param {
                name: "fft2d image",
                reason: format!("the image grid {grid} has no sensels"),
            });
        }
        let fit = |pad: Option<usize>, side: usize| match pad {
            None => side,
            Some(pad) if pad >= side => pad,
            Some(_) => side.next_power_of_two(),
        };
        Ok((fit(self.pad_rows, grid.rows), fit(self.pad_cols, grid.cols)))
    }

    /// The name of each feature, in order. Half form: `fft2d_r{k}_c{l}`, the magnitude at row frequency
    /// bin `k` and column frequency bin `l` of the `R x C` transform. Polar form: `fft2d_polar_ring{i}`
    /// (sum over ring `i`, from the lowest frequencies out), then `fft2d_polar_wedge{j}` (sum over wedge
    /// `j`, by direction).
    pub fn feature_names(&self, grid: Grid) -> Result<Vec<String>> {
        let (rows, cols) = self.resolved(grid)?;
        Ok(match self.form {
            // The order of `Fft2dExtractor::extract_into`.
            Fft2dForm::Half => (0..rows)
                .flat_map(|k| (0..cols / 2 + 1).map(move |l| (k, l)))
                .filter(|&(k, l)| !(self_mirrored(l, cols) && k > rows / 2))
                .map(|(k, l)| format!("fft2d_r{k}_c{l}"))
                .collect(),
            Fft2dForm::Polar => (0..self.radial_bins)
                .map(|i| format!("fft2d_polar_ring{i}"))
                .chain((0..self.angular_bins).map(|j| format!("fft2d_polar_wedge{j}")))
                .collect(),
        })
    }

    /// Number of features for images of `grid`.
    pub fn output_len(&self, grid: Grid) -> Result<usize> {
        let (rows, cols) = self.resolved(grid)?;
        Ok(match self.form {
            Fft2dForm::Half => half_len(rows, cols),
            Fft2dForm::Polar => self.radial_bins + self.angular_bins,
        })
    }
}

/// The 2-D |FFT| as a [`FeatureFamily`], with two presets: `fft2d` (the half spectrum) and `fft2d_polar`
/// (ring and wedge sums).
#[derive(Debug)]
pub struct Fft2dFamily;

impl FeatureFamily for Fft2dFamily {
    const NAME: &'static str = "fft2d";
    const PRESETS: &'static [&'static str] = &["fft2d", "fft2d_polar"];
    type Config = Fft2dConfig;
    type Extractor = Fft2dExtractor;

    fn preset(index: usize) -> Fft2dConfig {
        if index == 1 {
            Fft2dConfig::POLAR
        } else {
            Fft2dConfig::HALF
        }
    }

    fn preset_of(config: &Fft2dConfig) -> usize {
        usize::from(config.form == Fft2dForm::Polar)
    }

    fn check(config: &Fft2dConfig) -> Result<()> {
        config.check()
    }

    fn output_len(config: &Fft2dConfig, grid: Grid) -> Result<usize> {
        config.output_len(grid)
    }

    fn feature_names(config: &Fft2dConfig, grid: Grid) -> Result<Vec<String>> {
        config.feature_names(grid)
    }

    fn transform_points(config: &Fft2dConfig, grid: Grid) -> Result<usize> {
        let too_large = |name: &'static str, what: String| CoreError::Param {
            name,
            reason: format!("{what} exceeds the limit of {MAX_TRANSFORM_LEN}"),
        };
        for (name, bins) in [
            ("radial_bins", config.radial_bins),
            ("angular_bins", config.angular_bins),
        ] {
            if bins > MAX_TRANSFORM_LEN {
                return Err(too_large(name, format!("{bins} bins")));
            }
        }
        let rows = config.pad_rows.unwrap_or(grid.rows);
        let cols = config.pad_cols.unwrap_or(grid.cols);
        match rows.checked_mul(cols) {
            Some(points) if points <= MAX_TRANSFORM_LEN => Ok(points),
            _ => Err(too_large(
                "pad_rows",
                format!("the {rows} x {cols} transform (pad_rows x pad_cols)"),
            )),
        }
    }

    fn extractor(config: &Fft2dConfig, grid: Grid) -> Result<Fft2dExtractor> {
        Fft2dExtractor::new(grid, config)
    }

    fn grid(extractor: &Fft2dExtractor) -> Grid {
        extractor.grid()
    }

    fn len(extractor: &Fft2dExtractor) -> usize {
        extractor.output_len()
    }

    fn extract_into(extractor: &mut Fft2dExtractor, image: &[f64], out: &mut [f64]) -> Result<()> {
        extractor.extract_into(image, out)
    }
}

/// Columns `0 ..= C/2` of which `l = 0` and (even `C`) `l = C/2` keep only `k = 0 ..= R/2`.
fn half_len(rows: usize, cols: usize) -> usize {
    let half_cols = cols / 2 + 1;
    let self_mirrored = if cols % 2 == 0 && cols > 1 { 2 } else { 1 };
    self_mirrored * (rows / 2 + 1) + (half_cols - self_mirrored) * rows
}

/// Whether column `l` of a `C`-column transform is its own mirror.
fn self_mirrored(l: usize, cols: usize) -> bool {
    l == 0 || (cols % 2 == 0 && 2 * l == cols)
}

/// Signed frequency index of `k` in a length-`n` transform, as a fraction of the sampling rate.
fn signed_frequency(k: usize, n: usize) -> f64 {
    let k = if 2 * k > n {
        k as f64 - n as f64
    } else {
        k as f64
    };
    k / n as f64
}

/// Computes 2-D |FFT| features; holds plans and buffers (no allocation per image).
#[derive(Clone)]
pub struct Fft2dExtractor {
    grid: Grid,
    config: Fft2dConfig,
    rows: usize,
    cols: usize,
    row_plan: Arc<dyn RealToComplex<f64>>,
    col_plan: Arc<dyn Fft<f64>>,
    row_in: Vec<f64>,
    row_out: Vec<Complex<f64>>,
    row_scratch: Vec<Complex<f64>>,
    /// The half spectrum, `rows x (cols/2 + 1)`, column-major (one contiguous column per `l`).
    half: Vec<Complex<f64>>,
    col_scratch: Vec<Complex<f64>>,
    /// For the polar form: per half-spectrum cell (column-major), (ring, wedge or usize::MAX, weight).
    bins: Vec<(usize, usize, f64)>,
}

impl std::fmt::Debug for Fft2dExtractor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Fft2dExtractor")
            .field("grid", &self.grid)
            .field("config", &self.config)
            .finish_non_exhaustive()
    }
}

impl Fft2dExtractor {
    pub fn new(grid: Grid, config: &Fft2dConfig) -> Result<Self> {
        let (rows, cols) = config.resolved(grid)?;
        let row_plan = RealFftPlanner::<f64>::new().plan_fft_forward(cols);
        let col_plan = FftPlanner::<f64>::new().plan_fft_forward(rows);
        let half_cols = cols / 2 + 1;
        let mut bins = Vec::new();
        if config.form == Fft2dForm::Polar {
            let max_radius = 0.5f64.sqrt();
            for l in 0..half_cols {
                for k in 0..rows {
                    let (fk, fl) = (signed_frequency(k, rows), signed_frequency(l, cols));
                    let radius = (fk * fk + fl * fl).sqrt();
                    let ring = ((radius / max_radius * config.radial_bins as f64) as usize)
                        .min(config.radial_bins - 1);
                    let wedge = if k == 0 && l == 0 {
                        usize::MAX
                    } else {
                        let angle = fk.atan2(fl).rem_euclid(std::f64::consts::PI);
                        ((angle / std::f64::consts::PI * config.angular_bins as f64) as usize)
                            .min(config.angular_bins - 1)
                    };
                    // Every column but the self-mirrored ones stands for itself and its mirror.
                    let weight = if self_mirrored(l, cols) { 1.0 } else { 2.0 };
                    bins.push((ring, wedge, weight));
                }
            }
        }
        Ok(Self {
            grid,
            config: *config,
            rows,
            cols,
            row_in: row_plan.make_input_vec(),
            row_out: row_plan.make_output_vec(),
            row_scratch: row_plan.make_scratch_vec(),
            half: vec![Complex::default(); rows * half_cols],
            col_scratch: vec![Complex::default(); col_plan.get_inplace_scratch_len()],
            row_plan,
            col_plan,
            bins,
        })
    }

    pub fn grid(&self) -> Grid {
        self.grid
    }

    /// The transform size `(R, C)`.
    pub fn transform_size(&self) -> (usize, usize) {
        (self.rows, self.cols)
    }

    pub fn output_len(&self) -> usize {
        match self.config.form {
            Fft2dForm::Half => half_len(self.rows, self.cols),
            Fft2dForm::Polar => self.config.radial_bins + self.config.angular_bins,
        }
    }

    /// The complex half spectrum `Y[k][l]`, `l = 0 ..= C/2`, after [`extract_into`](Self::extract_into)
    /// (column-major: `half_spectrum()[l * R + k]`).
    pub fn half_spectrum(&self) -> &[Complex<f64>] {
        &self.half
    }

    pub fn extract_into(&mut self, image: &[f64], out: &mut [f64]) -> Result<()> {
        check_len("fft2d image", self.grid.len(), image.len())?;
        check_len("fft2d feature buffer", self.output_len(), out.len())?;
        let (rows, cols) = (self.rows, self.cols);
        let half_cols = cols / 2 + 1;
        let fft_error = |err: realfft::FftError| CoreError::Param {
            name: "fft2d",
            reason: err.to_string(),
        };
        // Rows: a real FFT of each image row; padding rows have a zero spectrum.
        self.half.fill(Complex::default());
        for r in 0..self.grid.rows {
            let src = &image[r * self.grid.cols..(r + 1) * self.grid.cols];
            let (head, tail) = self.row_in.split_at_mut(self.grid.cols);
            head.copy_from_slice(src);
            tail.fill(0.0);
            self.row_plan
                .process_with_scratch(&mut self.row_in, &mut self.row_out, &mut self.row_scratch)
                .map_err(fft_error)?;
            for (l, value) in self.row_out.iter().enumerate() {
                self.half[l * rows + r] = *value;
            }
        }
        // Columns: a complex FFT of each stored column, in place.
        for column in self.half.chunks_exact_mut(rows) {
            self.col_plan
                .process_with_scratch(column, &mut self.col_scratch);
        }
        match self.config.form {
            Fft2dForm::Half => {
                let mut index = 0;
                for k in 0..rows {
                    for l in 0..half_cols {
                        if self_mirrored(l, cols) && k > rows / 2 {
                            continue;
                        }
                        out[index] = self.half[l * rows + k].norm();
                        index += 1;
                    }
                }
            }
            Fft2dForm::Polar => {
                out.fill(0.0);
                let radial = self.config.radial_bins;
                for (value, &(ring, wedge, weight)) in self.half.iter().zip(&self.bins) {
                    let magnitude = value.norm() * weight;
                    out[ring] += magnitude;
                    if wedge != usize::MAX {
                        out[radial + wedge] += magnitude;
                    }
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_lengths() {
        // 4 x 4: columns 0 and 2 keep k = 0..=2, column 1 keeps 4: 3 + 3 + 4
        assert_eq!(half_len(4, 4), 10);
        // 3 x 5: column 0 keeps k = 0..=1, columns 1, 2 keep 3
        assert_eq!(half_len(3, 5), 8);
        assert_eq!(half_len(38, 41), 20 + 20 * 38);
    }
}
