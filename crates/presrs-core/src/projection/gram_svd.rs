//! The leading singular values and right singular vectors of a wide centred matrix (`n` samples, `p >
//! n` features) from its `n x n` Gram matrix: `Xc Xcᵀ = U S² Uᵀ`, then `V = Xcᵀ U S⁻¹` for the
//! components kept. The exact thin SVD of `Xc` holds an `n x p` centred copy, its `p x n` right factor
//! and the decomposition's workspace at once, and runs in one sequential decomposition; here the Gram
//! matrix is summed over panels of centred columns in faer's parallel products (no centred copy), one
//! `n x n` symmetric eigendecomposition runs sequentially (its rounding does not depend on the thread
//! count), and only the kept axes are formed. The squared spectrum loses the small singular values'
//! relative precision, so an axis is taken from the Gram matrix only when its eigenvalue is at least
//! `RELATIVE_FLOOR` of the largest (then it agrees with the exact SVD's to about `1e-10`, tested);
//! otherwise the caller takes the exact SVD. Hand-written: faer has the pieces, not this use of them.

use faer::diag::Diag;
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, Par};

use crate::error::{CoreError, Result};
use crate::linalg::symmetric_eigen;

/// Columns centred at a time: the panel is `n x PANEL` (a few MB for thousands of samples).
const PANEL: usize = 512;

/// From this many samples, with at least twice as many features, a PCA is fitted from the Gram
/// matrix. Below it the exact SVD is cheap, and every model fitted on fewer samples (the paper's 52
/// vectors, the shared sets' folds) keeps the PCA it always had, bit for bit.
pub const GRAM_MIN_SAMPLES: usize = 1000;

/// The smallest ratio of a kept component's eigenvalue to the largest for which its axis is formed
/// from the Gram matrix (singular values down to 1e-3 of the largest).
const RELATIVE_FLOOR: f64 = 1e-6;

/// Whether a PCA of `n_samples x n_features` is fitted from the Gram matrix.
pub fn uses_gram(n_samples: usize, n_features: usize) -> bool {
    n_samples >= GRAM_MIN_SAMPLES && n_features >= 2 * n_samples
}

/// The `k` leading singular values and right singular vectors (one per column, `p x k`) of `rows`
/// less `mean`; `None` when a kept component's eigenvalue is below `RELATIVE_FLOOR` of the largest
/// (the exact SVD is then needed).
pub fn gram_svd(rows: &[&[f64]], mean: &[f64], k: usize) -> Result<Option<(Diag<f64>, Mat<f64>)>> {
    let (n, p) = (rows.len(), mean.len());
    let par = Par::rayon(0);
    let mut gram = Mat::<f64>::zeros(n, n);
    // The panel transposed (`width x n`, column-major): each sample's centred values are contiguous.
    let mut panel = Mat::<f64>::zeros(PANEL.min(p), n);
    for start in (0..p).step_by(PANEL) {
        let width = PANEL.min(p - start);
        centre_panel(rows, mean, start, width, &mut panel);
        let part = panel.as_ref().subrows(0, width);
        matmul(gram.as_mut(), Accum::Add, part.transpose(), part, 1.0, par);
    }
    let (values, vectors) = eigen(&gram)?;
    drop(gram);
    // Ascending: the leading components are the last columns.
    let leading = |c: usize| n - 1 - c;
    let largest = values[leading(0)];
    if k == 0 || k > n || largest.is_nan() || largest <= 0.0 {
        return Ok(None);
    }
    if values[leading(k - 1)] < RELATIVE_FLOOR * largest {
        return Ok(None);
    }
    let singular: Vec<f64> = (0..k).map(|c| values[leading(c)].sqrt()).collect();
    let left = Mat::from_fn(n, k, |i, c| vectors[(i, leading(c))] / singular[c]);
    let mut right = Mat::<f64>::zeros(p, k);
    for start in (0..p).step_by(PANEL) {
        let width = PANEL.min(p - start);
        centre_panel(rows, mean, start, width, &mut panel);
        matmul(
            right.as_mut().subrows_mut(start, width),
            Accum::Replace,
            panel.as_ref().subrows(0, width),
            left.as_ref(),
            1.0,
            par,
        );
    }
    let mut diagonal = Diag::<f64>::zeros(k);
    for (c, s) in singular.into_iter().enumerate() {
        diagonal[c] = s;
    }
    Ok(Some((diagonal, right)))
}

/// Columns `start..start + width` of `rows` less their means, into the first `width` rows of
/// `panel` (one column per sample).
fn centre_panel(rows: &[&[f64]], mean: &[f64], start: usize, width: usize, panel: &mut Mat<f64>) {
    let mean = &mean[start..start + width];
    for (i, row) in rows.iter().enumerate() {
        let values = &row[start..start + width];
        for ((out, value), m) in panel.col_mut(i).iter_mut().zip(values).zip(mean) {
            *out = value - m;
        }
    }
}

/// The eigenvalues (ascending) and eigenvectors of the symmetric `gram`.
fn eigen(gram: &Mat<f64>) -> Result<(Vec<f64>, Mat<f64>)> {
    let n = gram.nrows();
    let (values, vectors) = symmetric_eigen(gram.as_ref()).map_err(|err| CoreError::Param {
        name: "pca",
        reason: format!(
            "the eigendecomposition of the {n} x {n} Gram matrix did not converge: {err:?}"
        ),
    })?;
    Ok(((0..n).map(|j| values[j]).collect(), vectors))
}
