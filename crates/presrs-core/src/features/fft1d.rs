//! The paper's feature vector (eqs. 3-5): the magnitude of the 1-D DFT of the row-major vectorised image.
//!
//! The image `I` (rows x cols) is laid out row after row into `X` of length `N` (zero-padded), the real DFT
//! `Y = FFT(X)` is taken and `F = |Y|[0 ..= N/2]` is kept, because the spectrum of a real signal is mirrored.
//! With the paper's 38 x 41 images and `N = 2048` this gives `n = 1025` features.

use std::sync::Arc;

use realfft::num_complex::Complex;
use realfft::{RealFftPlanner, RealToComplex};
use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result};
use crate::frame::Grid;

/// Parameters of the 1-D |FFT| features.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Fft1dConfig {
    /// The transform length `N`. `None` picks the next power of two at least `rows * cols` (2048 for the
    /// paper's 38 x 41 images). Any length at least `rows * cols` is allowed (realfft handles every length).
    #[serde(default)]
    pub fft_len: Option<usize>,
}

impl Fft1dConfig {
    /// The paper's setting: `N` = next power of two (2048 for 38 x 41 images).
    pub const PAPER: Self = Self { fft_len: None };

    /// The transform length used for images of `grid`, or an error if the image does not fit in it.
    pub fn resolved_len(&self, grid: Grid) -> Result<usize> {
        if grid.is_empty() {
            return Err(CoreError::Param {
                name: "fft1d image",
                reason: format!("the image grid {grid} has no sensels"),
            });
        }
        match self.fft_len {
            None => grid
                .len()
                .checked_next_power_of_two()
                .ok_or_else(|| CoreError::Param {
                    name: "fft_len",
                    reason: format!("no power of two holds the {grid} image"),
                }),
            Some(len) if len >= grid.len() => Ok(len),
            Some(len) => Err(CoreError::Param {
                name: "fft_len",
                reason: format!(
                    "the transform length {len} is shorter than the {} sensels of a {grid} image",
                    grid.len()
                ),
            }),
        }
    }

    /// Number of features for images of `grid`: `N/2 + 1` (N/2 rounded down for odd `N`).
    pub fn output_len(&self, grid: Grid) -> Result<usize> {
        self.resolved_len(grid).map(|len| len / 2 + 1)
    }
}

/// Computes 1-D |FFT| features of images of one grid. Holds the FFT plan and every buffer, so
/// [`extract_into`](Self::extract_into) does not allocate. Cloning shares the (immutable) plan.
#[derive(Clone)]
pub struct Fft1dExtractor {
    grid: Grid,
    plan: Arc<dyn RealToComplex<f64>>,
    /// The zero-padded signal `X`; realfft uses it as scratch, so it is re-filled on every call.
    signal: Vec<f64>,
    spectrum: Vec<Complex<f64>>,
    scratch: Vec<Complex<f64>>,
}

impl std::fmt::Debug for Fft1dExtractor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Fft1dExtractor")
            .field("grid", &self.grid)
            .field("fft_len", &self.fft_len())
            .finish_non_exhaustive()
    }
}

impl Fft1dExtractor {
    /// An extractor for images of `grid` with the transform length chosen by `config`.
    pub fn new(grid: Grid, config: &Fft1dConfig) -> Result<Self> {
        let fft_len = config.resolved_len(grid)?;
        Ok(Self::with_len(grid, fft_len))
    }

    /// Builds the plan; `fft_len >= grid.len() > 0` must already hold (checked by [`Fft1dConfig`]).
    fn with_len(grid: Grid, fft_len: usize) -> Self {
        let plan = RealFftPlanner::<f64>::new().plan_fft_forward(fft_len);
        Self {
            grid,
            signal: plan.make_input_vec(),
            spectrum: plan.make_output_vec(),
            scratch: plan.make_scratch_vec(),
            plan,
        }
    }

    /// The image grid this extractor takes.
    pub fn grid(&self) -> Grid {
        self.grid
    }

    /// The transform length `N`.
    pub fn fft_len(&self) -> usize {
        self.signal.len()
    }

    /// Number of features, `N/2 + 1`.
    pub fn output_len(&self) -> usize {
        self.spectrum.len()
    }

    /// Writes the features of `image` (row-major, `grid` sized) into `out` (`output_len` long).
    pub fn extract_into(&mut self, image: &[f64], out: &mut [f64]) -> Result<()> {
        check_len("fft1d image", self.grid.len(), image.len())?;
        check_len("fft1d feature buffer", self.output_len(), out.len())?;
        let (head, padding) = self.signal.split_at_mut(image.len());
        head.copy_from_slice(image);
        padding.fill(0.0);
        self.plan
            .process_with_scratch(&mut self.signal, &mut self.spectrum, &mut self.scratch)
            .map_err(|err| CoreError::Param {
                name: "fft1d",
                reason: err.to_string(),
            })?;
        // Two passes so the square roots run on whole SIMD registers (the interleaved re/im layout keeps
        // a single fused loop scalar). Not `hypot`: it is several times slower, and sums of sensel values
        // cannot overflow when squared.
        for (dst, value) in out.iter_mut().zip(&self.spectrum) {
            *dst = value.norm_sqr();
        }
        for dst in out.iter_mut() {
            *dst = dst.sqrt();
        }
        Ok(())
    }

    /// The features of `image` in a new vector.
    pub fn extract(&mut self, image: &[f64]) -> Result<Vec<f64>> {
        let mut out = vec![0.0; self.output_len()];
        self.extract_into(image, &mut out)?;
        Ok(out)
    }
}

fn check_len(what: &'static str, expected: usize, got: usize) -> Result<()> {
    if expected == got {
        Ok(())
    } else {
        Err(CoreError::Shape {
            what,
            expected: expected.to_string(),
            got: got.to_string(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_sizes() {
        let grid = Grid::new(38, 41);
        assert_eq!(Fft1dConfig::PAPER.resolved_len(grid).unwrap(), 2048);
        assert_eq!(Fft1dConfig::PAPER.output_len(grid).unwrap(), 1025);
        let odd = Fft1dConfig {
            fft_len: Some(1559),
        };
        assert_eq!(odd.output_len(grid).unwrap(), 780);
        let short = Fft1dConfig {
            fft_len: Some(1557),
        };
        assert!(short.resolved_len(grid).is_err());
        assert!(Fft1dConfig::PAPER.resolved_len(Grid::new(0, 4)).is_err());
    }

    #[test]
    fn constant_image_has_its_sum_at_dc() {
        let grid = Grid::new(2, 3);
        let mut extractor = Fft1dExtractor::new(grid, &Fft1dConfig::PAPER).unwrap();
        let features = extractor.extract(&[1.0; 6]).unwrap();
        assert_eq!(features.len(), 5);
        assert!((features[0] - 6.0).abs() < 1e-12);
    }

    #[test]
    fn wrong_buffer_sizes_are_errors() {
        let mut extractor = Fft1dExtractor::new(Grid::new(2, 2), &Fft1dConfig::PAPER).unwrap();
        let mut out = vec![0.0; 3];
        assert!(extractor.extract_into(&[0.0; 3], &mut out).is_err());
        assert!(extractor.extract_into(&[0.0; 4], &mut out[..2]).is_err());
        assert!(extractor.extract_into(&[0.0; 4], &mut out).is_ok());
    }
}
