//! The paper's feature vector (eqs. 3-5): the magnitude of the 1-D DFT of the row-major vectorised image.
//!
//! The image `I` (rows x cols) is laid out row after row into `X` of length `N` (zero-padded), the real DFT
//! `Y = FFT(X)` is taken and `F = |Y|[0 ..= N/2]` is kept, because the spectrum of a real signal is mirrored.
//! With the paper's 38 x 41 images and `N = 2048` this gives `n = 1025` features.

use std::sync::Arc;

use realfft::num_complex::Complex;

use realfft::{RealFftPlanner, RealToComplex};
use rustfft::{Fft, FftPlanner};
use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result, check_len};
use crate::features::family::{FeatureFamily, MAX_TRANSFORM_LEN};
use crate::frame::Grid;
#[cfg(target_arch = "x86_64")]
use crate::kernels::SplitAvx512;
use crate::kernels::{Aligned, Radix4Fft, SplitSpectrum};

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

    /// The name of each feature, in order: `fft1d_bin{k}`, the magnitude at frequency bin `k` of the
    /// `N`-point transform (`k / N` cycles per sensel along the row-major image).
    pub fn feature_names(&self, grid: Grid) -> Result<Vec<String>> {
        let len = self.output_len(grid)?;
        Ok((0..len).map(|k| format!("fft1d_bin{k}")).collect())
    }
}

/// Computes 1-D |FFT| features of images of one grid. Holds the FFT plans and every buffer, so
/// [`extract_into`](Self::extract_into) and [`extract_fast_into`](Self::extract_fast_into) do not
/// allocate. Cloning shares the (immutable) plans.
#[derive(Clone)]
pub struct Fft1dExtractor {
    grid: Grid,
    plan: Arc<dyn RealToComplex<f64>>,
    /// The zero-padded signal `X`; realfft uses it as scratch, so it is re-filled on every call.
    signal: Vec<f64>,
    spectrum: Vec<Complex<f64>>,
    scratch: Vec<Complex<f64>>,
    /// The single-precision transform of the classification path (even `N` only; boxed, as it holds
    /// its buffers and twiddles inline).
    fast: Option<Box<HalfLengthF32>>,
    /// For odd `N`, where the window of [`extract_fast_window_into`](Self::extract_fast_window_into) is
    /// copied for the exact path (empty otherwise).
    window_copy: Vec<f64>,
    /// The single-precision features of the last fast extraction (`output_len` long).
    fast_out: Vec<f32>,
    /// For odd `N`: the exact features, before they are rounded into `fast_out` (empty otherwise).
    exact_out: Vec<f64>,
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
            fast: (fft_len % 2 == 0).then(|| Box::new(HalfLengthF32::new(fft_len))),
            window_copy: if fft_len % 2 == 0 {
                Vec::new()
            } else {
                vec![0.0; grid.len()]
            },
            fast_out: vec![0.0; fft_len / 2 + 1],
            exact_out: if fft_len % 2 == 0 {
                Vec::new()
            } else {
                vec![0.0; fft_len / 2 + 1]
            },
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

    /// [`extract_into`](Self::extract_into) in single precision, for classification: the transform
    /// runs in f32 (a complex FFT of length `N/2` on the even/odd samples, then the split into the real
    /// spectrum), about 2.5x faster than the f64 path; each feature is within ~1e-6 of the largest one
    /// of the exact features (tested against the naive DFT). The classifier's PCA rounds the centred
    /// features more coarsely still (to 15 bits per block of 64, `Pca::project_fast_into`), so this adds
    /// no new kind of error. Odd `N` falls back to the exact path.
    pub fn extract_fast_into(&mut self, image: &[f64], out: &mut [f64]) -> Result<()> {
        check_len("fft1d image", self.grid.len(), image.len())?;
        let cols = self.grid.cols;
        self.extract_fast_window_into(image, 0, cols, out)
    }

    /// [`extract_fast_into`](Self::extract_fast_into) on an image that is a window of a larger row-major
    /// array: its row `r` is `values[first + r * stride ..][.. cols]`. Classification reads the crop of
    /// a frame this way, straight into the transform's buffer (no cropped copy: copying 38 short rows
    /// cost more than the rest of the packing).
    pub fn extract_fast_window_into(
        &mut self,
        values: &[f64],
        first: usize,
        stride: usize,
        out: &mut [f64],
    ) -> Result<()> {
        check_len("fft1d feature buffer", self.output_len(), out.len())?;
        let features = self.extract_fast_window(values, first, stride)?;
        for (dst, &value) in out.iter_mut().zip(features) {
            *dst = f64::from(value);
        }
        Ok(())
    }

    /// [`extract_fast_window_into`](Self::extract_fast_window_into) in the precision the fast path computes
    /// in: the features as f32, in the extractor's buffer (what the PCA's fixed-point projection reads,
    /// `Pca::project_fast_into`; widening them to f64 only to round them back cost a tenth of a
    /// classification). Odd `N` computes them exactly and rounds them to f32.
    pub fn extract_fast_window(
        &mut self,
        values: &[f64],
        first: usize,
        stride: usize,
    ) -> Result<&[f32]> {
        let Grid { rows, cols } = self.grid;
        let end = (rows - 1)
            .checked_mul(stride)
            .and_then(|offset| offset.checked_add(first))
            .and_then(|start| start.checked_add(cols));
        if stride < cols || end.is_none_or(|end| end > values.len()) {
            return Err(CoreError::Shape {
                what: "fft1d image window",
                expected: format!("{rows} rows of {cols} values, {stride} apart from {first}"),
                got: format!("{} values", values.len()),
            });
        }
        let window = Window {
            values,
            first,
            stride,
            rows,
            cols,
        };
        match self.fast.as_mut() {
            Some(fast) => fast.magnitudes(window, &mut self.fast_out),
            None => {
                // Odd N: the exact path on a copy of the window.
                let mut image = std::mem::take(&mut self.window_copy);
                let mut exact = std::mem::take(&mut self.exact_out);
                for (r, dst) in image.chunks_exact_mut(cols).enumerate() {
                    dst.copy_from_slice(window.row(r));
                }
                let result = self.extract_into(&image, &mut exact);
                #[allow(clippy::cast_possible_truncation)]
                for (dst, &value) in self.fast_out.iter_mut().zip(&exact) {
                    *dst = value as f32;
                }
                self.window_copy = image;
                self.exact_out = exact;
                result?;
            }
        }
        Ok(&self.fast_out)
    }

    /// The features of `image` in a new vector.
    pub fn extract(&mut self, image: &[f64]) -> Result<Vec<f64>> {
        let mut out = vec![0.0; self.output_len()];
        self.extract_into(image, &mut out)?;
        Ok(out)
    }
}

/// The paper's 1-D |FFT| as a [`FeatureFamily`]: it has a fast path (single precision, read straight
/// from the frame's crop) that classification uses.
#[derive(Debug)]
pub struct Fft1dFamily;

impl FeatureFamily for Fft1dFamily {
    const NAME: &'static str = "fft1d";
    const PRESETS: &'static [&'static str] = &["fft1d"];
    type Config = Fft1dConfig;
    type Extractor = Fft1dExtractor;

    fn preset(_index: usize) -> Fft1dConfig {
        Fft1dConfig::PAPER
    }

    fn check(config: &Fft1dConfig) -> Result<()> {
        if config.fft_len == Some(0) {
            return Err(CoreError::Param {
                name: "fft_len",
                reason: "the transform length must be positive".into(),
            });
        }
        Ok(())
    }

    fn output_len(config: &Fft1dConfig, grid: Grid) -> Result<usize> {
        config.output_len(grid)
    }

    fn feature_names(config: &Fft1dConfig, grid: Grid) -> Result<Vec<String>> {
        config.feature_names(grid)
    }

    fn transform_points(config: &Fft1dConfig, grid: Grid) -> Result<usize> {
        let len = config.resolved_len(grid)?;
        if len > MAX_TRANSFORM_LEN {
            return Err(CoreError::Param {
                name: "fft_len",
                reason: format!(
                    "the transform length {len} exceeds the limit of {MAX_TRANSFORM_LEN}"
                ),
            });
        }
        Ok(len)
    }

    fn extractor(config: &Fft1dConfig, grid: Grid) -> Result<Fft1dExtractor> {
        Fft1dExtractor::new(grid, config)
    }

    fn grid(extractor: &Fft1dExtractor) -> Grid {
        extractor.grid()
    }

    fn len(extractor: &Fft1dExtractor) -> usize {
        extractor.output_len()
    }

    fn extract_into(extractor: &mut Fft1dExtractor, image: &[f64], out: &mut [f64]) -> Result<()> {
        extractor.extract_into(image, out)
    }

    fn has_fast_path(_config: &Fft1dConfig) -> bool {
        true
    }

    fn extract_fast_into(
        extractor: &mut Fft1dExtractor,
        image: &[f64],
        out: &mut [f64],
    ) -> Result<()> {
        extractor.extract_fast_into(image, out)
    }

    fn extract_fast_window<'e>(
        extractor: &'e mut Fft1dExtractor,
        values: &[f64],
        first: usize,
        stride: usize,
    ) -> Option<Result<&'e [f32]>> {
        Some(extractor.extract_fast_window(values, first, stride))
    }
}

/// An image inside a larger row-major array (checked by its maker to lie inside `values`).
#[derive(Clone, Copy)]
struct Window<'a> {
    values: &'a [f64],
    first: usize,
    stride: usize,
    rows: usize,
    cols: usize,
}

impl<'a> Window<'a> {
    fn row(&self, r: usize) -> &'a [f64] {
        let start = self.first + r * self.stride;
        &self.values[start..start + self.cols]
    }
}

/// `|DFT_N(x)|[0 ..= N/2]` of a real signal (zero-padded to an even `N`) in single precision, through a
/// complex FFT of length `M = N/2`: with `z[n] = x[2n] + i x[2n+1]` and `Z = FFT_M(z)`,
/// `X[k] = E[k] + W^k O[k]` where `E[k] = (Z[k] + conj Z[M-k]) / 2`, `O[k] = (Z[k] - conj Z[M-k]) / 2i`
/// and `W = exp(-2 pi i / N)`; the pair `(k, M-k)` shares `E` and `O` (`X[M-k] = conj(E - W^k O)`).
/// realfft does the same in f64, but its split step runs scalar; here it runs on whole SIMD registers
/// (a loop compiled for the CPU's instruction set, reading `Z[k]` and `Z[M-k]` straight from the
/// spectrum: copying them into separate real and imaginary arrays first cost more than the arithmetic,
/// the copy stalling on the FFT's just-written output). On AVX-512 CPUs the transform is presrs's
/// [`Radix4Fft`] when `M` is a power of four, and the split step is written out in registers
/// (`split_avx512`).
#[derive(Clone)]
struct HalfLengthF32 {
    fft: Arc<dyn Fft<f32>>,
    /// The AVX-512 transform, used instead of `fft` when the CPU has it and `M` is a power of four
    /// (`M = 1024` for the paper's images).
    radix4: Option<Radix4Fft>,
    z: Aligned<Complex<f32>>,
    /// rustfft's scratch, or the radix-4 transform's second buffer (`M` long).
    scratch: Aligned<Complex<f32>>,
    /// `W^k` for `k = 0 .. pairs` (index 0 unused).
    twiddle_re: Vec<f32>,
    twiddle_im: Vec<f32>,
    /// `|X[k]|` and `|X[M-k]|` for the pairs (index 0 unused).
    low: Vec<f32>,
    high: Vec<f32>,
    /// The split step in AVX-512 registers, when the CPU has them.
    #[cfg(target_arch = "x86_64")]
    split_avx512: Option<SplitAvx512>,
}

impl HalfLengthF32 {
    /// `n` even and positive.
    fn new(n: usize) -> Self {
        let m = n / 2;
        let fft = FftPlanner::<f32>::new().plan_fft_forward(m);
        let radix4 = Radix4Fft::new(m);
        let scratch_len = if radix4.is_some() {
            m
        } else {
            fft.get_inplace_scratch_len()
        };
        // Pairs (k, M-k) with 0 < k < M-k.
        let pairs = m.saturating_sub(1) / 2 + 1;
        let angle = |k: usize| -2.0 * std::f64::consts::PI * k as f64 / n as f64;
        #[allow(clippy::cast_possible_truncation)]
        let twiddle =
            |f: fn(f64) -> f64| (0..pairs).map(|k| f(angle(k)) as f32).collect::<Vec<_>>();
        let (twiddle_re, twiddle_im) = (twiddle(f64::cos), twiddle(f64::sin));
        Self {
            scratch: Aligned::new(scratch_len),
            fft,
            radix4,
            z: Aligned::new(m),
            low: vec![0.0; pairs],
            high: vec![0.0; pairs],
            #[cfg(target_arch = "x86_64")]
            split_avx512: SplitAvx512::new(&twiddle_re, &twiddle_im, m),
            twiddle_re,
            twiddle_im,
        }
    }

    /// `out[k] = |X[k]|` for `k = 0 ..= M` of the image in `window` (row after row, at most `N` values),
    /// `out` `M + 1` long.
    fn magnitudes(&mut self, window: Window<'_>, out: &mut [f32]) {
        let m = self.z.len();
        pulp::Arch::new().dispatch(Pack {
            window,
            z: &mut self.z,
        });
        let Self {
            fft,
            radix4,
            z,
            scratch,
            twiddle_re,
            twiddle_im,
            low,
            high,
            #[cfg(target_arch = "x86_64")]
            split_avx512,
        } = self;
        let z: &[Complex<f32>] = match radix4 {
            Some(radix4) => radix4.process(z, scratch),
            None => {
                fft.process_with_scratch(z, scratch);
                z
            }
        };
        let split_in_registers = {
            #[cfg(target_arch = "x86_64")]
            {
                if let Some(split) = split_avx512 {
                    split.run(z, out);
                }
                split_avx512.is_some()
            }
            #[cfg(not(target_arch = "x86_64"))]
            {
                false
            }
        };
        if !split_in_registers {
            pulp::Arch::new().dispatch(SplitSpectrum {
                z,
                twiddle_re,
                twiddle_im,
                low,
                high,
                out,
            });
        }
        if m % 2 == 0 && m > 0 {
            // k = M/2 pairs with itself: W^{M/2} = -i, so X = E - i O = (Re Z, -Im Z).
            out[m / 2] = z[m / 2].norm();
        }
    }
}

/// `z[n] = x[2n] + i x[2n+1]` in f32 for the image `x` read row after row from its window, zero beyond.
/// `z` is written as the flat array of its real and imaginary parts, which is `x` itself: each row is one
/// contiguous conversion, whatever the parity of its start.
struct Pack<'a> {
    window: Window<'a>,
    z: &'a mut [Complex<f32>],
}

impl pulp::WithSimd for Pack<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        let Self { window, z } = self;
        let flat: &mut [f32] = pulp::bytemuck::cast_slice_mut(z);
        let (image, padding) = flat.split_at_mut(window.rows * window.cols);
        for (r, dst) in image.chunks_exact_mut(window.cols).enumerate() {
            #[allow(clippy::cast_possible_truncation)]
            for (dst, &value) in dst.iter_mut().zip(window.row(r)) {
                *dst = value as f32;
            }
        }
        padding.fill(0.0);
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

    /// A window of a larger array gives bit for bit the features of the same image copied out, for even
    /// (fast path) and odd (exact fallback) transform lengths; windows that do not fit are errors.
    #[test]
    fn a_window_is_the_image_it_frames() {
        let (in_rows, in_cols) = (9, 11);
        let values: Vec<f64> = (0..in_rows * in_cols)
            .map(|i| ((i * 37) % 101) as f64 * 0.25)
            .collect();
        let grid = Grid::new(5, 7);
        let (row0, col0) = (3, 2);
        let image: Vec<f64> = (0..grid.rows)
            .flat_map(|r| {
                let start = (row0 + r) * in_cols + col0;
                values[start..start + grid.cols].to_vec()
            })
            .collect();
        for fft_len in [None, Some(64), Some(35), Some(41)] {
            let config = Fft1dConfig { fft_len };
            let mut extractor = Fft1dExtractor::new(grid, &config).unwrap();
            let n = extractor.output_len();
            let (mut copied, mut framed) = (vec![0.0; n], vec![f64::NAN; n]);
            extractor.extract_fast_into(&image, &mut copied).unwrap();
            extractor
                .extract_fast_window_into(&values, row0 * in_cols + col0, in_cols, &mut framed)
                .unwrap();
            assert_eq!(copied, framed, "{fft_len:?}");
            // The last row would run past the end; a stride shorter than a row overlaps rows.
            let last_start = (in_rows - grid.rows + 1) * in_cols;
            assert!(
                extractor
                    .extract_fast_window_into(&values, last_start, in_cols, &mut framed)
                    .is_err()
            );
            assert!(
                extractor
                    .extract_fast_window_into(&values, 0, grid.cols - 1, &mut framed)
                    .is_err()
            );
        }
    }

    /// The whole single-precision path as this CPU runs it (on AVX-512: presrs's radix-4 FFT and the
    /// split step in registers) against the path every other CPU runs (rustfft and the compiled loop),
    /// on the paper's sizes and a random image.
    #[test]
    fn every_cpu_path_gives_the_same_magnitudes() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(6);
        let (rows, cols) = (38, 41);
        let values: Vec<f64> = (0..rows * cols)
            .map(|_| f64::from(rng.random_range(0u8..=255)))
            .collect();
        let window = Window {
            values: &values,
            first: 0,
            stride: cols,
            rows,
            cols,
        };
        let mut here = HalfLengthF32::new(2048);
        let mut elsewhere = HalfLengthF32 {
            radix4: None,
            #[cfg(target_arch = "x86_64")]
            split_avx512: None,
            ..HalfLengthF32::new(2048)
        };
        let (mut a, mut b) = (vec![f32::NAN; 1025], vec![f32::NAN; 1025]);
        here.magnitudes(window, &mut a);
        elsewhere.magnitudes(window, &mut b);
        let sum: f64 = values.iter().sum();
        for (k, (&a, &b)) in a.iter().zip(&b).enumerate() {
            let (a, b) = (f64::from(a), f64::from(b));
            assert!((a - b).abs() <= 1e-6 * sum, "bin {k}: {a} vs {b}");
        }
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
