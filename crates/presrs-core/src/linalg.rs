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
