//! Dense linear algebra shared by the classifiers, the projections and the novelty score, on top of
//! faer: what several of them would otherwise each write out.

use faer::diag::Diag;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::evd::{
    ComputeEigenvectors, EvdError, self_adjoint_evd, self_adjoint_evd_scratch,
};
use faer::{Mat, MatRef, Par};

/// The eigenvalues (ascending) and eigenvectors (one per column) of the symmetric `matrix` (its
/// lower triangle read). Sequential: faer's parallel tridiagonalisation sums per-thread parts, so its
/// rounding would depend on the thread count.
pub(crate) fn symmetric_eigen(matrix: MatRef<'_, f64>) -> Result<(Diag<f64>, Mat<f64>), EvdError> {
    let n = matrix.nrows();
    let mut values = Diag::<f64>::zeros(n);
    let mut vectors = Mat::<f64>::zeros(n, n);
    let par = Par::Seq;
    let mut workspace = MemBuffer::new(self_adjoint_evd_scratch::<f64>(
        n,
        ComputeEigenvectors::Yes,
        par,
        Default::default(),
    ));
    self_adjoint_evd(
        matrix,
        values.as_mut(),
        Some(vectors.as_mut()),
        par,
        MemStack::new(&mut workspace),
        Default::default(),
    )?;
    Ok((values, vectors))
}

/// The mean and scale of every column of the rows `rows()` gives (`dims` values each): the population standard
/// deviation, or 1 where the variance is within rounding of zero (scikit-learn's `StandardScaler`:
/// `var <= n ε var + (n ε mean)²`), so that a constant column standardises to 0. Two passes.
pub(crate) fn column_standardisation<'r, T, I>(
    rows: impl Fn() -> I,
    dims: usize,
) -> (Vec<f64>, Vec<f64>)
where
    T: Copy + Into<f64> + 'r,
    I: Iterator<Item = &'r [T]>,
{
    let n = rows().count() as f64;
    let mut means = vec![0.0; dims];
    for row in rows() {
        means.iter_mut().zip(row).for_each(|(m, &v)| *m += v.into());
    }
    means.iter_mut().for_each(|m| *m /= n);
    let mut variances = vec![0.0; dims];
    for row in rows() {
        for ((var, &v), m) in variances.iter_mut().zip(row).zip(&means) {
            let d = v.into() - m;
            *var += d * d;
        }
    }
    let scales = variances
        .iter()
        .zip(&means)
        .map(|(sum, mean)| {
            let var = sum / n;
            let bound = n * f64::EPSILON * var + (n * mean * f64::EPSILON).powi(2);
            if var <= bound { 1.0 } else { var.sqrt() }
        })
        .collect();
    (means, scales)
}
