//! Exact leave-one-out residuals of ridge regression with an unpenalised intercept, for every
//! regularisation `α` of a grid at the cost of one eigendecomposition, as scikit-learn's `_RidgeGCV`.
//!
//! With centred features `Z` (`n x p`) and targets `Y` (`n x k`, centred to `Y_c` by the intercept),
//! ridge is a linear smoother: the fitted values are `Ȳ + M Y_c`, `M = Z (ZᵀZ + αI)⁻¹ Zᵀ`, and its hat
//! matrix is `H = 11ᵀ/n + M` (the intercept's column `1` is orthogonal to the centred `Z`). Leaving
//! vector `i` out and refitting changes its residual to `e_i / (1 - H_ii)` (the classic identity for
//! penalised least squares), so every leave-one-out residual comes from `M` alone. `M` is read off one
//! eigendecomposition, chosen like scikit-learn's default `gcv_mode` by the shape:
//! - `n <= p` (gram): `ZZᵀ = Q Λ Qᵀ` (`n x n`). With `D = (Λ + αI)⁻¹`, `c = Q D Qᵀ Y_c` is
//!   `(ZZᵀ + αI)⁻¹ Y_c`, the residual is `α c`, `1 - H_ii = α (Σ_j D_j Q_ij² - 1 / (α n))` (the
//!   eigenvector `1/√n` has eigenvalue 0), so the leave-one-out residual is `c_i / (Σ_j D_j Q_ij² - 1 /
//!   (α n))`, and the coefficients are `Zᵀ c`;
//! - `n > p` (cov): `ZᵀZ = V Λ Vᵀ` (`p x p`). With `P = Z V`, `M = P D Pᵀ`, `H_ii = 1/n + Σ_j D_j P_ij²`
//!   and the coefficients are `V D Pᵀ Y_c`.
//!
//! Each `α` then costs `O(n r k)` (`r` = `n` or `p`); the decomposition `O(n p min(n, p))` is paid once.
//! Eigenvalues within rounding of zero are read as zero (see `symmetric_eigen`).

use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{BlockStructure, matmul as triangular_matmul};
use faer::{Accum, Mat, MatRef, Par};

use crate::error::{CoreError, Result};

/// Which matrix is decomposed (scikit-learn's `gcv_mode` "gram" and "cov").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Decomposition {
    /// `Z Zᵀ`, `n x n`: more features than vectors.
    Gram,
    /// `Zᵀ Z`, `p x p`: more vectors than features.
    Covariance,
}

impl Decomposition {
    /// scikit-learn's choice: the Gram matrix when `n <= p`.
    pub fn for_shape(n: usize, p: usize) -> Self {
        if n <= p { Self::Gram } else { Self::Covariance }
    }
}

/// One eigendecomposition of centred features, ready to give the leave-one-out residuals and the
/// coefficients of any `α > 0`.
pub struct Spectrum<'a> {
    /// The features, when the coefficients are read from them here (`None`: a Gram matrix given by
    /// [`Spectrum::from_gram`], whose coefficients the caller forms from [`Spectrum::dual`]).
    z: Option<MatRef<'a, f64>>,
    decomposition: Decomposition,
    /// `Λ`, clamped at zero.
    eigenvalues: Vec<f64>,
    /// `Q` (gram, `n x n`) or `P = Z V` (cov, `n x p`).
    basis: Mat<f64>,
    /// `V` (cov only).
    eigenvectors: Option<Mat<f64>>,
    /// `basisᵀ Y_c`, `r x k`.
    projected: Mat<f64>,
    centred_targets: Mat<f64>,
    target_means: Vec<f64>,
}

impl<'a> Spectrum<'a> {
    /// Decomposes `z` (`n x p`, columns centred, finite, `n >= 2`) for targets `targets` (`n x k`);
    /// `par` parallelises the matrix products (faer splits their outputs, so the result does not depend
    /// on the thread count); the eigendecomposition itself is sequential (see `symmetric_eigen`).
    pub fn new(z: MatRef<'a, f64>, targets: MatRef<'_, f64>, par: Par) -> Result<Self> {
        let (n, p) = (z.nrows(), z.ncols());
        let decomposition = Decomposition::for_shape(n, p);
        let (eigenvalues, eigenvectors) = match decomposition {
            Decomposition::Gram => symmetric_eigen(z, par)?,
            Decomposition::Covariance => symmetric_eigen(z.transpose(), par)?,
        };
        Self::finish(
            Some(z),
            decomposition,
            eigenvalues,
            eigenvectors,
            targets,
            par,
        )
    }

    /// The Gram mode (`n <= p`) from the lower triangle of `Z Zᵀ` (`n x n`) of `p` features, formed by
    /// the caller (block by block, without a standardised copy of `Z`): the leave-one-out residuals as
    /// [`new`](Self::new) gives them; the coefficients are `Zᵀ` [`dual`](Self::dual).
    pub fn from_gram(gram: Mat<f64>, p: usize, targets: MatRef<'_, f64>) -> Result<Self> {
        let (eigenvalues, eigenvectors) = eigen_of(gram, p)?;
        Self::finish(
            None,
            Decomposition::Gram,
            eigenvalues,
            eigenvectors,
            targets,
            Par::Seq,
        )
    }

    /// The rest of [`new`](Self::new): the basis and the projected targets.
    fn finish(
        z: Option<MatRef<'a, f64>>,
        decomposition: Decomposition,
        eigenvalues: Vec<f64>,
        eigenvectors: Mat<f64>,
        targets: MatRef<'_, f64>,
        par: Par,
    ) -> Result<Self> {
        let (target_means, centred_targets) = centre_columns(targets);
        let (basis, eigenvectors) = match (decomposition, z) {
            // (a Gram matrix given by the caller is always the Gram mode)
            (Decomposition::Gram, _) | (Decomposition::Covariance, None) => (eigenvectors, None),
            (Decomposition::Covariance, Some(z)) => {
                let (n, p) = (z.nrows(), z.ncols());
                let mut basis = Mat::zeros(n, p);
                matmul(&mut basis, Accum::Replace, z, &eigenvectors, 1.0, par);
                // A direction of zero eigenvalue is one Z does not reach: Z v_j is rounding noise
                // (about √ε‖Z‖), which 1 / α would otherwise blow up into the coefficients.
                for (j, &value) in eigenvalues.iter().enumerate() {
                    if value == 0.0 {
                        basis.col_mut(j).fill(0.0);
                    }
                }
                (basis, Some(eigenvectors))
            }
        };
        let mut projected = Mat::zeros(basis.ncols(), centred_targets.ncols());
        matmul(
            &mut projected,
            Accum::Replace,
            basis.transpose(),
            &centred_targets,
            1.0,
            par,
        );
        Ok(Self {
            z,
            decomposition,
            eigenvalues,
            basis,
            eigenvectors,
            projected,
            centred_targets,
            target_means,
        })
    }

    /// The mean of each target column (the intercepts: the features are centred).
    pub fn target_means(&self) -> &[f64] {
        &self.target_means
    }

    /// `D Pᵀ Y_c` (or `D Qᵀ Y_c`): the projected targets scaled by `1 / (λ_j + α)`.
    fn shrunk(&self, alpha: f64) -> Mat<f64> {
        Mat::from_fn(self.projected.nrows(), self.projected.ncols(), |j, t| {
            self.projected[(j, t)] / (self.eigenvalues[j] + alpha)
        })
    }

    /// The leave-one-out residuals at `alpha` (`n x k`): entry `(i, t)` is target `t` of vector `i`
    /// less its prediction by the model fitted without vector `i`.
    pub fn leave_one_out(&self, alpha: f64) -> Mat<f64> {
        let n = self.basis.nrows();
        let shrunk = self.shrunk(alpha);
        let mut smoothed = Mat::zeros(n, shrunk.ncols());
        matmul(
            &mut smoothed,
            Accum::Replace,
            &self.basis,
            &shrunk,
            1.0,
            Par::Seq,
        );
        // Σ_j D_j basis_ij², column by column (the basis is column-major): the squares are not
        // kept, an `n x r` matrix as large as the basis itself.
        let mut diagonal = vec![0.0; n];
        for (j, &value) in self.eigenvalues.iter().enumerate() {
            let weight = 1.0 / (value + alpha);
            for (d, b) in diagonal.iter_mut().zip(self.basis.col(j).iter()) {
                *d += b * b * weight;
            }
        }
        let nf = n as f64;
        Mat::from_fn(n, shrunk.ncols(), |i, t| match self.decomposition {
            // c_i / (Σ_j D_j Q_ij² - 1 / (α n))
            Decomposition::Gram => smoothed[(i, t)] / (diagonal[i] - 1.0 / (alpha * nf)),
            // (y_i - ŷ_i) / (1 - H_ii)
            Decomposition::Covariance => {
                (self.centred_targets[(i, t)] - smoothed[(i, t)]) / (1.0 - diagonal[i] - 1.0 / nf)
            }
        })
    }

    /// `(Z Zᵀ + αI)⁻¹ Y_c = Q D Qᵀ Y_c` (`n x k`) in the Gram mode, whose `Zᵀ` product is the
    /// coefficients; `None` in the covariance mode.
    pub fn dual(&self, alpha: f64) -> Option<Mat<f64>> {
        if self.decomposition != Decomposition::Gram {
            return None;
        }
        let shrunk = self.shrunk(alpha);
        let mut dual = Mat::zeros(self.basis.nrows(), shrunk.ncols());
        matmul(
            &mut dual,
            Accum::Replace,
            &self.basis,
            &shrunk,
            1.0,
            Par::Seq,
        );
        Some(dual)
    }

    /// The coefficients at `alpha`, `p x k` (one column per target); `None` for a spectrum
    /// [`from_gram`](Self::from_gram), whose caller forms them from [`dual`](Self::dual).
    pub fn coefficients(&self, alpha: f64) -> Option<Mat<f64>> {
        let z = self.z?;
        let shrunk = self.shrunk(alpha);
        let mut coefficients = Mat::zeros(z.ncols(), shrunk.ncols());
        match (&self.eigenvectors, self.dual(alpha)) {
            // V D Pᵀ Y_c
            (Some(vectors), _) => matmul(
                &mut coefficients,
                Accum::Replace,
                vectors,
                &shrunk,
                1.0,
                Par::Seq,
            ),
            // Zᵀ Q D Qᵀ Y_c
            (None, dual) => matmul(
                &mut coefficients,
                Accum::Replace,
                z.transpose(),
                dual?.as_ref(),
                1.0,
                Par::Seq,
            ),
        }
        Some(coefficients)
    }
}

/// The column means of `m` and `m` less them.
pub(super) fn centre_columns(m: MatRef<'_, f64>) -> (Vec<f64>, Mat<f64>) {
    let n = m.nrows().max(1) as f64;
    let means: Vec<f64> = (0..m.ncols())
        .map(|t| (0..m.nrows()).map(|i| m[(i, t)]).sum::<f64>() / n)
        .collect();
    let centred = Mat::from_fn(m.nrows(), m.ncols(), |i, t| m[(i, t)] - means[t]);
    (means, centred)
}

/// The eigenvalues (ascending) and eigenvectors (columns) of `a aᵀ`; only its lower triangle is
/// computed, which is all the decomposition reads. Eigenvalues within rounding of zero (below `λ_max ·
/// max(rows, cols) · ε`, numpy's `matrix_rank` tolerance) are set to zero: in the gram mode the
/// eigenvector `1/√n` of a centred `Z` has eigenvalue exactly 0, and its rounding (about 1e-13 of a
/// Gram matrix of norm 1e3) would otherwise leave a relative error of 1e-8 in the leave-one-out
/// denominators at a small `α`, which subtract `1 / (α n)` from a sum holding `1 / ((λ_0 + α) n)`.
fn symmetric_eigen(a: MatRef<'_, f64>, par: Par) -> Result<(Vec<f64>, Mat<f64>)> {
    let r = a.nrows();
    let mut product = Mat::<f64>::zeros(r, r);
    triangular_matmul(
        &mut product,
        BlockStructure::TriangularLower,
        Accum::Replace,
        a,
        BlockStructure::Rectangular,
        a.transpose(),
        BlockStructure::Rectangular,
        1.0,
        par,
    );
    eigen_of(product, a.nrows().max(a.ncols()))
}

/// The eigenvalues (ascending, those within rounding of zero set to zero, see [`symmetric_eigen`])
/// and eigenvectors of the symmetric `product` (its lower triangle read), a Gram matrix of data whose
/// larger side is `largest_side`.
fn eigen_of(product: Mat<f64>, largest_side: usize) -> Result<(Vec<f64>, Mat<f64>)> {
    let r = product.nrows();
    // (sequential: the rounding, and at worst the chosen α, would otherwise depend on the thread
    // count; it costs little next to the product)
    let (values, vectors) =
        crate::linalg::symmetric_eigen(product.as_ref()).map_err(|err| CoreError::Param {
            name: "ridge",
            reason: format!(
                "the eigendecomposition of the {r} x {r} Gram matrix did not converge ({err:?}); \
                 check the features for extreme values"
            ),
        })?;
    let largest = (0..r).map(|j| values[j]).fold(0.0, f64::max);
    let tolerance = largest * largest_side as f64 * f64::EPSILON;
    let eigenvalues = (0..r)
        .map(|j| {
            if values[j] <= tolerance {
                0.0
            } else {
                values[j]
            }
        })
        .collect();
    Ok((eigenvalues, vectors))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Features with centred columns (`n x p`, uneven scales) and `±1` targets (`n x k`) that depend on
    /// them, so that the fits are not trivial.
    fn problem(n: usize, p: usize, k: usize, seed: u64) -> (Mat<f64>, Mat<f64>) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let raw = Mat::from_fn(n, p, |_, j| {
            (1.0 + j as f64 * 0.3) * rng.random_range(-1.0..1.0)
        });
        let (_, z) = centre_columns(raw.as_ref());
        let y = Mat::from_fn(n, k, |i, t| {
            let signal = z[(i, t % p)] - 0.5 * z[(i, (t + 1) % p)];
            if signal + rng.random_range(-0.5..0.5) > 0.0 {
                1.0
            } else {
                -1.0
            }
        });
        (z, y)
    }

    /// `x` solving `a x = b` by Gaussian elimination with partial pivoting (`a` square, row by row).
    fn solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
        let m = b.len();
        for col in 0..m {
            let pivot = (col..m)
                .max_by(|&r, &s| a[r][col].abs().total_cmp(&a[s][col].abs()))
                .unwrap();
            a.swap(col, pivot);
            b.swap(col, pivot);
            for row in col + 1..m {
                let factor = a[row][col] / a[col][col];
                for c in col..m {
                    a[row][c] -= factor * a[col][c];
                }
                b[row] -= factor * b[col];
            }
        }
        let mut x = vec![0.0; m];
        for row in (0..m).rev() {
            let rest: f64 = (row + 1..m).map(|c| a[row][c] * x[c]).sum();
            x[row] = (b[row] - rest) / a[row][row];
        }
        x
    }

    /// Ridge with an intercept fitted on the rows `keep` of `z` and `y` (centred by their own means,
    /// normal equations `(XᵀX + αI) w = Xᵀ y` solved directly): (coefficients `p x k`, intercepts).
    fn direct_fit(
        z: &Mat<f64>,
        y: &Mat<f64>,
        keep: &[usize],
        alpha: f64,
    ) -> (Vec<Vec<f64>>, Vec<f64>) {
        let (p, k, m) = (z.ncols(), y.ncols(), keep.len() as f64);
        let x_mean: Vec<f64> = (0..p)
            .map(|j| keep.iter().map(|&i| z[(i, j)]).sum::<f64>() / m)
            .collect();
        let y_mean: Vec<f64> = (0..k)
            .map(|t| keep.iter().map(|&i| y[(i, t)]).sum::<f64>() / m)
            .collect();
        let gram: Vec<Vec<f64>> = (0..p)
            .map(|a| {
                (0..p)
                    .map(|b| {
                        let cross: f64 = keep
                            .iter()
                            .map(|&i| (z[(i, a)] - x_mean[a]) * (z[(i, b)] - x_mean[b]))
                            .sum();
                        cross + if a == b { alpha } else { 0.0 }
                    })
                    .collect()
            })
            .collect();
        let mut coefficients = Vec::new();
        let mut intercepts = Vec::new();
        for t in 0..k {
            let rhs: Vec<f64> = (0..p)
                .map(|a| {
                    keep.iter()
                        .map(|&i| (z[(i, a)] - x_mean[a]) * (y[(i, t)] - y_mean[t]))
                        .sum()
                })
                .collect();
            let w = solve(gram.clone(), rhs);
            intercepts.push(y_mean[t] - w.iter().zip(&x_mean).map(|(w, m)| w * m).sum::<f64>());
            coefficients.push(w);
        }
        (coefficients, intercepts)
    }

    #[test]
    fn leave_one_out_equals_refitting_without_each_vector() {
        // Gram (n < p, n = p) and covariance (n > p) decompositions, one and several targets; the last
        // with two equal features (a zero eigenvalue of ZᵀZ).
        let cases = [
            (12, 30, 3, 1),
            (10, 10, 1, 2),
            (30, 6, 4, 3),
            (25, 8, 1, 4),
            (20, 5, 2, 7),
        ];
        for (n, p, k, seed) in cases {
            let (mut z, y) = problem(n, p, k, seed);
            if seed == 7 {
                for i in 0..n {
                    z[(i, 1)] = z[(i, 0)];
                }
            }
            let spectrum = Spectrum::new(z.as_ref(), y.as_ref(), Par::Seq).unwrap();
            if n <= p {
                // A Gram matrix given whole gives the same residuals and dual.
                let mut gram = Mat::<f64>::zeros(n, n);
                matmul(&mut gram, Accum::Replace, &z, z.transpose(), 1.0, Par::Seq);
                let given = Spectrum::from_gram(gram, p, y.as_ref()).unwrap();
                assert!(given.coefficients(1.0).is_none());
                for alpha in [1e-2, 0.7, 50.0] {
                    let (a, b) = (given.leave_one_out(alpha), spectrum.leave_one_out(alpha));
                    let (c, d) = (given.dual(alpha).unwrap(), spectrum.dual(alpha).unwrap());
                    for i in 0..n {
                        for t in 0..k {
                            assert!((a[(i, t)] - b[(i, t)]).abs() < 1e-9);
                            assert!((c[(i, t)] - d[(i, t)]).abs() < 1e-9);
                        }
                    }
                }
            }
            assert_eq!(
                spectrum.decomposition,
                if n <= p {
                    Decomposition::Gram
                } else {
                    Decomposition::Covariance
                }
            );
            for alpha in [1e-2, 0.7, 50.0] {
                let fast = spectrum.leave_one_out(alpha);
                for i in 0..n {
                    let keep: Vec<usize> = (0..n).filter(|&r| r != i).collect();
                    let (w, b) = direct_fit(&z, &y, &keep, alpha);
                    for t in 0..k {
                        let prediction = b[t] + (0..p).map(|j| w[t][j] * z[(i, j)]).sum::<f64>();
                        let slow = y[(i, t)] - prediction;
                        assert!(
                            (fast[(i, t)] - slow).abs() < 1e-9,
                            "{n} x {p}, alpha {alpha}, vector {i}, target {t}: {} vs {slow}",
                            fast[(i, t)]
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn coefficients_and_intercepts_solve_the_normal_equations() {
        for (n, p, k, seed) in [(12, 30, 2, 5), (40, 7, 3, 6)] {
            let (z, y) = problem(n, p, k, seed);
            let spectrum = Spectrum::new(z.as_ref(), y.as_ref(), Par::rayon(2)).unwrap();
            let all: Vec<usize> = (0..n).collect();
            for alpha in [1e-3, 2.0, 300.0] {
                let fast = spectrum.coefficients(alpha).unwrap();
                let (w, b) = direct_fit(&z, &y, &all, alpha);
                for t in 0..k {
                    assert!((spectrum.target_means()[t] - b[t]).abs() < 1e-12);
                    for j in 0..p {
                        assert!(
                            (fast[(j, t)] - w[t][j]).abs() < 1e-9,
                            "{n} x {p}, alpha {alpha}: {} vs {}",
                            fast[(j, t)],
                            w[t][j]
                        );
                    }
                }
            }
        }
    }
}
