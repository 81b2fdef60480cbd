//! Principal component analysis fitted on training features.
//!
//! The data are mean-centred and the thin SVD `Xc = U S Vᵀ` of the centred `n_samples x n_features` matrix
//! is taken (faer, sequential so results do not depend on the thread count). The principal axes are the
//! rows of `Vᵀ`, the explained variances `s² / (n - 1)`. At most `n_samples - 1` components carry variance
//! after centring, so `min(dims, n_samples - 1, n_features)` are kept (the paper: 51 from 52 vectors).
//!
//! Large wide fits take a faster route to the same leading components: more than
//! [`EXACT_SVD_MAX_SAMPLES`] samples, a randomised range finder; from
//! [`GRAM_MIN_SAMPLES`] samples with at least twice as many
//! features, the eigendecomposition of the `n x n` Gram matrix (`super::gram_svd`).
//!
//! An axis is only defined up to sign; each is flipped so that its largest-magnitude loading (the first one
//! on ties) is positive, which makes the fit deterministic.

use faer::diag::Diag;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::svd::{ComputeSvdVectors, svd, svd_scratch};
use faer::{Mat, Par};
use serde::{Deserialize, Serialize};

pub use super::fixed_basis::ProjectionScratch;
use super::fixed_basis::{FastInput, FixedBasis};
use super::gram_svd;
pub use super::gram_svd::GRAM_MIN_SAMPLES;
use crate::error::{CoreError, Result, check_len};

/// A fitted PCA: `project(x) = basis · (x - mean)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "PcaFields", into = "PcaFields")]
pub struct Pca {
    n_features: usize,
    mean: Vec<f64>,
    /// `n_components x n_features`, row-major; rows are orthonormal principal axes.
    basis: Vec<f64>,
    /// Variance of the training data along each axis, non-increasing.
    explained_variance: Vec<f64>,
    /// Total variance of the training data (sum over all features), for explained-variance ratios.
    total_variance: f64,
    /// `basis · mean`, derived (not serialised): projecting is then `basis · x - projected_mean`, one
    /// matrix-vector product with no centred copy of `x`.
    projected_mean: Vec<f64>,
    /// The basis in fixed point (derived, not serialised): what [`Pca::project_fast_into`] multiplies.
    fixed: FixedBasis,
}

/// The serialised form of [`Pca`]; checked on the way in.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct PcaFields {
    n_features: usize,
    mean: Vec<f64>,
    basis: Vec<f64>,
    explained_variance: Vec<f64>,
    total_variance: f64,
}

impl From<Pca> for PcaFields {
    fn from(pca: Pca) -> Self {
        Self {
            n_features: pca.n_features,
            mean: pca.mean,
            basis: pca.basis,
            explained_variance: pca.explained_variance,
            total_variance: pca.total_variance,
        }
    }
}

impl TryFrom<PcaFields> for Pca {
    type Error = CoreError;

    fn try_from(fields: PcaFields) -> Result<Self> {
        let bad = |reason: String| CoreError::Param {
            name: "pca",
            reason,
        };
        let n_components = fields.explained_variance.len();
        if fields.n_features == 0 || n_components == 0 {
            return Err(bad(
                "a PCA needs at least one feature and one component".into()
            ));
        }
        if fields.mean.len() != fields.n_features
            || Some(fields.basis.len()) != n_components.checked_mul(fields.n_features)
        {
            return Err(bad(format!(
                "mean has {} values and basis {} for {} features and {} components",
                fields.mean.len(),
                fields.basis.len(),
                fields.n_features,
                n_components
            )));
        }
        let all_finite = fields
            .mean
            .iter()
            .chain(&fields.basis)
            .chain(&fields.explained_variance)
            .all(|value| value.is_finite());
        if !all_finite || !fields.total_variance.is_finite() {
            return Err(bad("non-finite values".into()));
        }
        Ok(Self::new(
            fields.n_features,
            fields.mean,
            fields.basis,
            fields.explained_variance,
            fields.total_variance,
        ))
    }
}

/// Checks the input of [`Pca::fit`]; the number of samples.
fn check_fit_input(samples: &[f64], n_features: usize, max_components: usize) -> Result<usize> {
    check_shape(n_features, max_components)?;
    if samples.len() % n_features != 0 {
        return Err(CoreError::Shape {
            what: "pca training matrix",
            expected: format!("a multiple of {n_features} values"),
            got: samples.len().to_string(),
        });
    }
    let rows: Vec<&[f64]> = samples.chunks_exact(n_features).collect();
    check_rows(&rows)?;
    Ok(rows.len())
}

/// The checks of [`Pca::fit`] that need no data: features and components to keep.
fn check_shape(n_features: usize, max_components: usize) -> Result<()> {
    if n_features == 0 {
        return Err(CoreError::Param {
            name: "pca features",
            reason: "feature vectors are empty".into(),
        });
    }
    if max_components == 0 {
        return Err(CoreError::Param {
            name: "dims",
            reason: "at least one principal component must be kept".into(),
        });
    }
    Ok(())
}

/// The checks of [`Pca::fit`] on its rows (each of the right length): two or more, finite.
fn check_rows(rows: &[&[f64]]) -> Result<()> {
    if rows.len() < 2 {
        return Err(CoreError::NotEnoughData(format!(
            "PCA needs at least 2 training vectors, got {}",
            rows.len()
        )));
    }
    if rows
        .iter()
        .any(|row| row.iter().any(|value| !value.is_finite()))
    {
        return Err(CoreError::Param {
            name: "pca training matrix",
            reason: "contains NaN or infinite values".into(),
        });
    }
    Ok(())
}

/// The thin SVD of `centred` (`n_samples x n_features`): its singular values and right singular
/// vectors (one per column).
fn thin_svd(centred: &Mat<f64>) -> Result<(Diag<f64>, Mat<f64>)> {
    let (n_samples, n_features) = (centred.nrows(), centred.ncols());
    let rank = n_samples.min(n_features);
    let mut singular = Diag::<f64>::zeros(rank);
    let mut left = Mat::<f64>::zeros(n_samples, rank);
    let mut right = Mat::<f64>::zeros(n_features, rank);
    // Sequential: a parallel SVD may round differently with the thread count; this one is small.
    let par = Par::Seq;
    let mut workspace = MemBuffer::new(svd_scratch::<f64>(
        n_samples,
        n_features,
        ComputeSvdVectors::Thin,
        ComputeSvdVectors::Thin,
        par,
        Default::default(),
    ));
    svd(
        centred.as_ref(),
        singular.as_mut(),
        Some(left.as_mut()),
        Some(right.as_mut()),
        par,
        MemStack::new(&mut workspace),
        Default::default(),
    )
    .map_err(|err| CoreError::Param {
        name: "pca",
        reason: format!("the SVD did not converge: {err:?}"),
    })?;
    Ok((singular, right))
}

/// Above this many samples a PCA that keeps few components is fitted by a randomised range finder
/// (Halko, Martinsson and Tropp 2011) instead of the exact thin SVD: the exact one costs `O(n p min(n, p))` in one
/// sequential decomposition (and two `n x min(n, p)`-sized factors), the range finder `O(n p l)` in
/// parallel matrix products for `l` a little above the components kept. At most this many samples (every
/// training set an automatic choice scores its candidates on, `selection::SCORING_SAMPLES`) keep the
/// exact SVD and the models they always gave.
pub const EXACT_SVD_MAX_SAMPLES: usize = 4000;

/// Power iterations of the range finder: each multiplies the gap between the kept components and
/// the rest by itself once more (Halko, Martinsson and Tropp 2011, section 4.5).
const POWER_ITERATIONS: usize = 4;

/// The seed of the range finder's Gaussian test matrix (a fixed one: the fit is deterministic).
const RANGE_SEED: u64 = 0x5CA1_E5EE_D000_0001;

/// Whether [`Pca::fit`] takes the randomised range finder: more than [`EXACT_SVD_MAX_SAMPLES`]
/// samples, and a range of `sketch_width` well below both sides of the matrix.
fn uses_range_finder(n_samples: usize, n_features: usize, n_components: usize) -> bool {
    n_samples > EXACT_SVD_MAX_SAMPLES
        && 2 * sketch_width(n_samples, n_features, n_components) <= n_samples.min(n_features)
}

/// The width `l` of the range finder's sketch for `k` components: `2k + 10`, at most the rank.
fn sketch_width(n_samples: usize, n_features: usize, k: usize) -> usize {
    (2 * k + 10).min(n_samples.min(n_features))
}

/// The leading `k` singular values and right singular vectors (one per column) of the centred
/// `samples` (`n x p` row-major, centred on `mean` without a centred copy), by the randomised range
/// finder with power iterations (Halko, Martinsson and Tropp 2011, algorithms 4.4 and 5.1): `Q`, an
/// orthonormal basis of `Xc Ω` for a seeded Gaussian `Ω` (`p x l`), refined by `q` passes of
/// `Q ← orth(Xc orth(Xcᵀ Q))`; then the exact SVD of the small `Qᵀ Xc` (`l x p`). With `l = 2k + 10`
/// and four passes the leading components agree with the exact SVD's to rounding wherever the
/// spectrum falls at all past the `k`-th (tested against it). The products are faer's, split over the
/// cores by their outputs (the result does not depend on the thread count); the orthonormalisations
/// and the small SVD are sequential.
fn randomised_svd(samples: &[f64], mean: &[f64], k: usize) -> Result<(Diag<f64>, Mat<f64>)> {
    use faer::linalg::matmul::matmul;
    use faer::{Accum, MatRef};
    use rand::{Rng, SeedableRng};

    let n_features = mean.len();
    let n_samples = samples.len() / n_features;
    let l = sketch_width(n_samples, n_features, k);
    let x = MatRef::from_row_major_slice(samples, n_samples, n_features);
    let mean_row = MatRef::from_row_major_slice(mean, 1, n_features);
    let par = Par::rayon(0);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(RANGE_SEED);
    // Standard normal values (Box-Muller; the cosine branch only).
    let omega = Mat::from_fn(n_features, l, |_, _| {
        let u: f64 = 1.0 - rng.random::<f64>();
        let v: f64 = rng.random::<f64>();
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    });
    // Xc B = X B - 1 (meanᵀ B) and Xcᵀ Q = Xᵀ Q - mean (1ᵀ Q): the centring, without a centred copy.
    let times = |right: &Mat<f64>| -> Mat<f64> {
        let mut out = Mat::zeros(n_samples, right.ncols());
        matmul(&mut out, Accum::Replace, x, right, 1.0, par);
        let mut shift = Mat::zeros(1, right.ncols());
        matmul(&mut shift, Accum::Replace, mean_row, right, 1.0, Par::Seq);
        for j in 0..right.ncols() {
            let s = shift[(0, j)];
            out.col_mut(j).iter_mut().for_each(|v| *v -= s);
        }
        out
    };
    let transposed_times = |left: &Mat<f64>| -> Mat<f64> {
        let mut out = Mat::zeros(n_features, left.ncols());
        matmul(&mut out, Accum::Replace, x.transpose(), left, 1.0, par);
        for j in 0..left.ncols() {
            let s: f64 = left.col(j).iter().sum();
            out.col_mut(j)
                .iter_mut()
                .zip(mean)
                .for_each(|(v, m)| *v -= m * s);
        }
        out
    };
    let mut q = times(&omega);
    orthonormalise(&mut q);
    for _ in 0..POWER_ITERATIONS {
        let mut z = transposed_times(&q);
        orthonormalise(&mut z);
        q = times(&z);
        orthonormalise(&mut q);
    }
    // Qᵀ Xc = (Xcᵀ Q)ᵀ, `l x p`: its right singular vectors are Xc's leading ones.
    let small = transposed_times(&q).transpose().to_owned();
    thin_svd(&small)
}

/// Orthonormalises the columns of `m` in place (classical Gram-Schmidt, twice: "twice is enough",
/// Giraud et al. 2005); a column that depends on the earlier ones (to rounding) becomes zero.
fn orthonormalise(m: &mut Mat<f64>) {
    for j in 0..m.ncols() {
        let original: f64 = m.col(j).iter().map(|v| v * v).sum::<f64>().sqrt();
        for _ in 0..2 {
            for i in 0..j {
                let dot: f64 = m
                    .col(i)
                    .iter()
                    .zip(m.col(j).iter())
                    .map(|(a, b)| a * b)
                    .sum();
                let (done, rest) = m.as_mut().split_at_col_mut(j);
                rest.col_mut(0)
                    .iter_mut()
                    .zip(done.col(i).iter())
                    .for_each(|(v, u)| *v -= dot * u);
            }
        }
        let norm: f64 = m.col(j).iter().map(|v| v * v).sum::<f64>().sqrt();
        let scale = if norm > 1e-10 * original && norm > 0.0 {
            1.0 / norm
        } else {
            0.0
        };
        m.col_mut(j).iter_mut().for_each(|v| *v *= scale);
    }
}

impl Pca {
    /// Fits on `samples` (`n_samples x n_features`, row-major), keeping
    /// `min(max_components, n_samples - 1, n_features)` components.
    pub fn fit(samples: &[f64], n_features: usize, max_components: usize) -> Result<Self> {
        check_fit_input(samples, n_features, max_components)?;
        let rows: Vec<&[f64]> = samples.chunks_exact(n_features).collect();
        Self::fit_checked_rows(&rows, Some(samples), n_features, max_components)
    }

    /// [`fit`](Self::fit) on rows held elsewhere (e.g. some rows of a larger feature table), without a
    /// copy of them: the same PCA as `fit` on the rows laid end to end.
    pub fn fit_rows(rows: &[&[f64]], n_features: usize, max_components: usize) -> Result<Self> {
        check_shape(n_features, max_components)?;
        if let Some(row) = rows.iter().find(|row| row.len() != n_features) {
            return Err(CoreError::Shape {
                what: "pca training row",
                expected: format!("{n_features} values"),
                got: row.len().to_string(),
            });
        }
        check_rows(rows)?;
        Self::fit_checked_rows(rows, None, n_features, max_components)
    }

    /// [`fit`](Self::fit) on checked rows (at least two, each `n_features` finite values); `contiguous`
    /// the same rows laid end to end when the caller has them so (the range finder reads them so).
    fn fit_checked_rows(
        rows: &[&[f64]],
        contiguous: Option<&[f64]>,
        n_features: usize,
        max_components: usize,
    ) -> Result<Self> {
        let n_samples = rows.len();
        let mut mean = vec![0.0; n_features];
        for row in rows {
            for (acc, value) in mean.iter_mut().zip(row.iter()) {
                *acc += value;
            }
        }
        for acc in &mut mean {
            *acc /= n_samples as f64;
        }
        let total_variance = rows
            .iter()
            .flat_map(|row| row.iter().zip(&mean).map(|(x, m)| (x - m) * (x - m)))
            .sum::<f64>()
            / (n_samples - 1) as f64;
        let n_components = max_components.min(n_samples - 1).min(n_features);
        let (singular, right) = if uses_range_finder(n_samples, n_features, n_components) {
            match contiguous {
                Some(samples) => randomised_svd(samples, &mean, n_components)?,
                None => {
                    let samples: Vec<f64> =
                        rows.iter().flat_map(|row| row.iter().copied()).collect();
                    randomised_svd(&samples, &mean, n_components)?
                }
            }
        } else if let Some(leading) = gram_svd::uses_gram(n_samples, n_features)
            .then(|| gram_svd::gram_svd(rows, &mean, n_components))
            .transpose()?
            .flatten()
        {
            leading
        } else {
            let centred = Mat::from_fn(n_samples, n_features, |i, j| rows[i][j] - mean[j]);
            thin_svd(&centred)?
        };
        let singular = singular.column_vector();
        let mut basis = Vec::with_capacity(n_components * n_features);
        let mut explained_variance = Vec::with_capacity(n_components);
        for k in 0..n_components {
            let axis = right.col(k);
            let mut pivot = 0;
            for j in 1..n_features {
                if axis[j].abs() > axis[pivot].abs() {
                    pivot = j;
                }
            }
            let sign = if axis[pivot] < 0.0 { -1.0 } else { 1.0 };
            basis.extend((0..n_features).map(|j| sign * axis[j]));
            let s = singular[k];
            explained_variance.push(s * s / (n_samples - 1) as f64);
        }
        Ok(Self::new(
            n_features,
            mean,
            basis,
            explained_variance,
            total_variance,
        ))
    }

    /// Assembles a PCA from consistent parts (checked by the callers) and derives `projected_mean`.
    fn new(
        n_features: usize,
        mean: Vec<f64>,
        basis: Vec<f64>,
        explained_variance: Vec<f64>,
        total_variance: f64,
    ) -> Self {
        let mut projected_mean = vec![0.0; explained_variance.len()];
        matrix_vector(&basis, n_features, &mean, &mut projected_mean);
        let fixed = FixedBasis::new(&basis, &mean, n_features);
        Self {
            n_features,
            mean,
            basis,
            explained_variance,
            total_variance,
            projected_mean,
            fixed,
        }
    }

    /// Length of the input vectors.
    pub fn n_features(&self) -> usize {
        self.n_features
    }

    /// Number of kept components (length of the projected vectors).
    pub fn n_components(&self) -> usize {
        self.explained_variance.len()
    }

    /// The training mean.
    pub fn mean(&self) -> &[f64] {
        &self.mean
    }

    /// The principal axes, `n_components x n_features` row-major (the paper's `U`).
    pub fn basis(&self) -> &[f64] {
        &self.basis
    }

    /// Principal axis `k` (unit length).
    pub fn component(&self, k: usize) -> &[f64] {
        &self.basis[k * self.n_features..(k + 1) * self.n_features]
    }

    /// Training variance along each kept axis, non-increasing.
    pub fn explained_variance(&self) -> &[f64] {
        &self.explained_variance
    }

    /// Fraction of the total training variance along each kept axis.
    pub fn explained_variance_ratio(&self) -> Vec<f64> {
        self.explained_variance
            .iter()
            .map(|v| {
                if self.total_variance > 0.0 {
                    v / self.total_variance
                } else {
                    0.0
                }
            })
            .collect()
    }

    /// Writes `basis · (x - mean)` into `out` (`n_components` long). Does not allocate.
    pub fn project_into(&self, x: &[f64], out: &mut [f64]) -> Result<()> {
        check_len("pca input", self.n_features, x.len())?;
        check_len("pca output", self.n_components(), out.len())?;
        matrix_vector(&self.basis, self.n_features, x, out);
        for (value, offset) in out.iter_mut().zip(&self.projected_mean) {
            *value -= offset;
        }
        Ok(())
    }

    /// Buffers for [`project_fast_into`](Self::project_fast_into).
    pub fn scratch(&self) -> ProjectionScratch {
        self.fixed.scratch()
    }

    /// Writes `basis · (x - mean)` into `out` the fast way, in fixed point (`fixed_basis`): each
    /// axis in 16-bit integers with one scale (its largest loading / 32767), the features `1..` rounded to
    /// f32 and centred in f32 (on the means rounded to f32, whose rounding is added back exactly), then
    /// rounded in blocks of 64 features, each block to 15-bit integers with its own scale (its largest
    /// value / 16383), the integer products summed exactly in i32, then scaled and summed in f32. The
    /// first feature (the DC bin of the 1-D |FFT|, far above the rest) is multiplied exactly. This is the
    /// classification path (training and classifying both use it, so they agree): the product is bound by
    /// its integer multiply-adds, and 16-bit integers are a quarter of the f64 basis's bytes.
    ///
    /// Error: each output is within
    /// `2⁻¹⁶ maxᵢ |basisₖᵢ| Σᵢ |xᵢ - meanᵢ| + 2⁻¹⁵ Σ_blocks (max_block |x - mean|) Σ_block |basisₖᵢ|`
    /// (half a step of each rounding), plus a few f32 roundings (of the features, `2⁻²⁴` of each, and of
    /// the sums), of the exact value (about `1e-5` of the largest output; tested against
    /// [`project_into`](Self::project_into)). Rounding the axes by `2⁻¹⁶` of their largest loading is far
    /// below how well tens of training images determine them, and rounding the centred features by `2⁻¹⁵`
    /// of their block's largest one below what one count of an 8-bit sensel changes them by. Rounding a
    /// feature to f32 moves it by `2⁻²⁴` of its value: below its block's step unless its values sit more
    /// than about 500 times their spread away from zero (the DC bin does, and is kept exact). Does not
    /// allocate.
    ///
    /// The features may be f64 (rounded to f32 on the way in) or f32 (the fast 1-D |FFT|'s output,
    /// read as they are: bit for bit the result on the same values widened to f64).
    pub fn project_fast_into<T: FastInput>(
        &self,
        x: &[T],
        scratch: &mut ProjectionScratch,
        out: &mut [f64],
    ) -> Result<()> {
        check_len("pca input", self.n_features, x.len())?;
        check_len("pca output", self.n_components(), out.len())?;
        self.fixed.project(x, scratch, out)
    }

    /// [`project_fast_into`](Self::project_fast_into) for many inputs at once (f64 or f32): `xs` holds
    /// whole input vectors (row-major), `out` receives `n_components` values per input. Each result is
    /// bit for bit the one-at-a-time result; the basis is read once per block of its rows for all inputs
    /// instead of once per input (what makes batches faster). Allocates only to grow `scratch`.
    pub fn project_fast_many<T: FastInput>(
        &self,
        xs: &[T],
        scratch: &mut ProjectionScratch,
        out: &mut [f64],
    ) -> Result<()> {
        self.fixed.project(xs, scratch, out)
    }

    /// `basis · (x - mean)` in a new vector.
    pub fn project(&self, x: &[f64]) -> Result<Vec<f64>> {
        let mut out = vec![0.0; self.n_components()];
        self.project_into(x, &mut out)?;
        Ok(out)
    }

    /// Writes `mean + basisᵀ · z` into `out` (`n_features` long): the point of feature space that projects
    /// to `z`. Does not allocate.
    pub fn reconstruct_into(&self, z: &[f64], out: &mut [f64]) -> Result<()> {
        check_len("pca reduced input", self.n_components(), z.len())?;
        check_len("pca reconstruction", self.n_features, out.len())?;
        out.copy_from_slice(&self.mean);
        for (&weight, axis) in z.iter().zip(self.basis.chunks_exact(self.n_features)) {
            for (dst, a) in out.iter_mut().zip(axis) {
                *dst += weight * a;
            }
        }
        Ok(())
    }
}

/// `out = matrix · x` for a row-major `out.len() x cols` f64 matrix: the safe runtime-dispatched SIMD kernel
/// of `crate::kernels` (AVX2 + FMA where available; this product is most of the classification time).
/// Sequential, deterministic on a given machine, and does not allocate. Lengths are the caller's
/// responsibility (panics if `x` is not `cols` long or `matrix` is too short).
pub(crate) fn matrix_vector(matrix: &[f64], cols: usize, x: &[f64], out: &mut [f64]) {
    crate::kernels::matrix_vector(matrix, cols, x, out);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `n x p` rows of a falling spectrum (singular values `10 · 0.8^r` over 60 random directions),
    /// a little noise and an offset far from zero in every feature.
    fn falling_spectrum(n: usize, p: usize, seed: u64) -> Vec<f64> {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut uniform = |scale: f64| scale * (rng.random::<f64>() - 0.5);
        let rank = 60.min(p);
        let scores: Vec<f64> = (0..n * rank).map(|_| uniform(1.0)).collect();
        let axes: Vec<f64> = (0..rank * p).map(|_| uniform(1.0)).collect();
        let offsets: Vec<f64> = (0..p).map(|_| 5.0 + uniform(2.0)).collect();
        let mut x = vec![0.0; n * p];
        for i in 0..n {
            for r in 0..rank {
                let weight = 10.0 * 0.8f64.powi(r as i32) * scores[i * rank + r];
                for j in 0..p {
                    x[i * p + j] += weight * axes[r * p + j];
                }
            }
            for j in 0..p {
                x[i * p + j] += offsets[j] + uniform(1e-3);
            }
        }
        x
    }

    /// The column means of `samples` (`n x p`) and the exact thin SVD of the rows less them.
    fn centred_svd(samples: &[f64], n: usize, p: usize) -> (Vec<f64>, Diag<f64>, Mat<f64>) {
        let mut mean = vec![0.0; p];
        for row in samples.chunks_exact(p) {
            mean.iter_mut()
                .zip(row)
                .for_each(|(m, v)| *m += v / n as f64);
        }
        let centred = Mat::from_fn(n, p, |i, j| samples[i * p + j] - mean[j]);
        let (values, axes) = thin_svd(&centred).unwrap();
        (mean, values, axes)
    }

    /// Checks `fast` against the exact SVD of the same `n x p` rows (`values`, `axes`): its first `k`
    /// variances and axes within `tolerance` (relative; axes up to sign), each axis's largest loading
    /// positive (the sign rule).
    fn assert_agrees_with_svd(
        fast: &Pca,
        (values, axes): (&Diag<f64>, &Mat<f64>),
        n: usize,
        k: usize,
        tolerance: f64,
    ) {
        let p = fast.n_features();
        for c in 0..k {
            let s = values.column_vector()[c];
            let variance = s * s / (n - 1) as f64;
            let found = fast.explained_variance()[c];
            assert!((variance - found).abs() <= tolerance * variance, "{c}");
            let dot: f64 = (0..p).map(|j| axes[(j, c)] * fast.component(c)[j]).sum();
            assert!((dot.abs() - 1.0).abs() < tolerance, "axis {c}: {dot}");
            let pivot = (0..p)
                .max_by(|&a, &b| {
                    fast.component(c)[a]
                        .abs()
                        .total_cmp(&fast.component(c)[b].abs())
                })
                .unwrap();
            assert!(fast.component(c)[pivot] > 0.0);
        }
    }

    /// The oracle: the range finder's leading singular values and axes are the exact SVD's.
    #[test]
    fn the_range_finder_agrees_with_the_exact_svd() {
        let (n, p, k) = (500, 300, 12);
        let samples = falling_spectrum(n, p, 11);
        let (mean, exact_values, exact_axes) = centred_svd(&samples, n, p);
        let (values, axes) = randomised_svd(&samples, &mean, k).unwrap();
        for c in 0..k {
            let (exact, found) = (exact_values.column_vector()[c], values.column_vector()[c]);
            assert!(
                (exact - found).abs() <= 1e-9 * exact,
                "{c}: {exact} {found}"
            );
            let dot: f64 = (0..p).map(|j| exact_axes[(j, c)] * axes[(j, c)]).sum();
            assert!((dot.abs() - 1.0).abs() < 1e-9, "axis {c}: {dot}");
        }
    }

    /// Above `EXACT_SVD_MAX_SAMPLES` the fit takes the range finder (when it keeps few components)
    /// and gives the exact fit's PCA to rounding; at or below it, the exact SVD as always.
    #[test]
    fn large_fits_take_the_range_finder_and_agree_with_the_exact_one() {
        assert!(!uses_range_finder(EXACT_SVD_MAX_SAMPLES, 10_000, 102));
        assert!(uses_range_finder(EXACT_SVD_MAX_SAMPLES + 1, 10_000, 102));
        assert!(!uses_range_finder(EXACT_SVD_MAX_SAMPLES + 1, 400, 102));
        let (n, p, k) = (EXACT_SVD_MAX_SAMPLES + 1, 120, 6);
        assert!(uses_range_finder(n, p, k));
        let samples = falling_spectrum(n, p, 12);
        let fast = Pca::fit(&samples, p, k).unwrap();
        let (_, values, axes) = centred_svd(&samples, n, p);
        assert_eq!(fast.n_components(), k);
        assert_agrees_with_svd(&fast, (&values, &axes), n, k, 1e-9);
    }

    /// Wide fits from `GRAM_MIN_SAMPLES` samples take the Gram matrix and give the exact SVD's PCA
    /// to rounding (variances, axes and the sign rule); narrower or smaller ones keep the exact SVD.
    #[test]
    fn wide_fits_take_the_gram_matrix_and_agree_with_the_exact_svd() {
        use super::gram_svd::{GRAM_MIN_SAMPLES, uses_gram};
        assert!(!uses_gram(GRAM_MIN_SAMPLES - 1, 10_000));
        assert!(uses_gram(GRAM_MIN_SAMPLES, 2 * GRAM_MIN_SAMPLES));
        assert!(!uses_gram(GRAM_MIN_SAMPLES, 2 * GRAM_MIN_SAMPLES - 1));
        let (n, p, k) = (GRAM_MIN_SAMPLES, 2 * GRAM_MIN_SAMPLES + 37, 20);
        let samples = falling_spectrum(n, p, 13);
        let rows: Vec<&[f64]> = samples.chunks_exact(p).collect();
        let fast = Pca::fit_rows(&rows, p, k).unwrap();
        assert_eq!(fast, Pca::fit(&samples, p, k).unwrap());
        let (_, values, axes) = centred_svd(&samples, n, p);
        assert_agrees_with_svd(&fast, (&values, &axes), n, k, 1e-10);
        // Components at the rounding floor (60 directions, then noise of 1e-3): the exact SVD's.
        let deep = Pca::fit(&samples, p, 80).unwrap();
        let (_, tail_values, _) = centred_svd(&samples, n, p);
        let s = tail_values.column_vector()[79];
        let variance = s * s / (n - 1) as f64;
        let found = deep.explained_variance()[79];
        assert!(
            (variance - found).abs() <= 1e-9 * variance,
            "{variance} {found}"
        );
    }

    /// Rows held elsewhere give the PCA of the same rows laid end to end, exactly (the exact SVD and
    /// the range finder); bad rows are refused as `fit` refuses them.
    #[test]
    fn rows_in_place_give_the_pca_of_the_same_rows() {
        for (n, p, k) in [(40, 30, 5), (EXACT_SVD_MAX_SAMPLES + 1, 60, 4)] {
            let samples = falling_spectrum(n, p, 21);
            let rows: Vec<&[f64]> = samples.chunks_exact(p).collect();
            assert_eq!(
                Pca::fit_rows(&rows, p, k).unwrap(),
                Pca::fit(&samples, p, k).unwrap()
            );
        }
        let short = [1.0, 2.0];
        let long = [1.0, 2.0, 3.0];
        assert!(Pca::fit_rows(&[&short[..], &long[..]], 2, 1).is_err());
        assert!(Pca::fit_rows(&[&short[..]], 2, 1).is_err());
        assert!(Pca::fit_rows(&[&short[..], &[f64::NAN, 1.0][..]], 2, 1).is_err());
        assert!(Pca::fit_rows(&[&short[..], &[3.0, 1.0][..]], 2, 0).is_err());
    }

    #[test]
    fn rejects_bad_input() {
        assert!(Pca::fit(&[1.0, 2.0, 3.0], 3, 2).is_err()); // one sample
        assert!(Pca::fit(&[1.0, 2.0, 3.0, 4.0], 3, 2).is_err()); // ragged
        assert!(Pca::fit(&[1.0, 2.0, 3.0, 4.0], 2, 0).is_err()); // no components
        assert!(Pca::fit(&[1.0, f64::NAN, 3.0, 4.0], 2, 1).is_err());
    }

    #[test]
    fn line_in_the_plane() {
        // points on the line y = 2x: one axis (1, 2)/sqrt(5), all variance on it
        let samples = [0.0, 0.0, 1.0, 2.0, 2.0, 4.0, 3.0, 6.0];
        let pca = Pca::fit(&samples, 2, 5).unwrap();
        assert_eq!(pca.n_components(), 2); // min(5, n - 1 = 3, n_features = 2)
        assert!(pca.explained_variance()[1].abs() < 1e-12);
        let axis = pca.component(0);
        let norm = 5f64.sqrt();
        assert!((axis[0] - 1.0 / norm).abs() < 1e-12 && (axis[1] - 2.0 / norm).abs() < 1e-12);
        let projected: Vec<f64> = samples
            .chunks(2)
            .map(|row| pca.project(row).unwrap()[0])
            .collect();
        let var = projected.iter().map(|p| p * p).sum::<f64>() / 3.0;
        assert!((pca.explained_variance()[0] - var).abs() < 1e-12);
        assert!((pca.explained_variance_ratio()[0] - 1.0).abs() < 1e-12);
        let z = pca.project(&[5.0, 10.0]).unwrap();
        let mut back = [0.0; 2];
        pca.reconstruct_into(&z, &mut back).unwrap();
        assert!((back[0] - 5.0).abs() < 1e-12 && (back[1] - 10.0).abs() < 1e-12);
    }
}
