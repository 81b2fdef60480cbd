//! Ridge regression at one given `α` by a Cholesky solve, reading the feature rows block by block: the
//! fit of a pinned ridge (its `α` and temperature chosen by leave-one-out on a subsample, see
//! [`RidgePin`](super::RidgePin)) on data too large for the leave-one-out's eigendecomposition.
//!
//! Why not the eigendecomposition of `fit.rs` here: it is `O(r³)` and sequential (`r = min(n, p)`,
//! see `loo.rs`) and needs a standardised copy of every row; one `α` needs neither. With `Z` the
//! standardised rows (`n x p`) and `Y_c` the centred targets:
//! - `n > p`: `(ZᵀZ + αI) W = Zᵀ Y_c`, `ZᵀZ` and `Zᵀ Y_c` summed over blocks of rows;
//! - `n <= p`: `(ZZᵀ + αI) C = Y_c`, `W = Zᵀ C`, `ZZᵀ` summed over panels of columns.
//!
//! Only one block (or panel) is standardised at a time, in `f64`, so the rows may be held in `f32`
//! (the features' single precision) and are never copied whole. Both systems are positive definite for
//! `α > 0`; faer's Cholesky factor and products run on every core.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::{cholesky_in_place, cholesky_in_place_scratch};
use faer::linalg::cholesky::llt::solve::{solve_in_place, solve_in_place_scratch};
use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{BlockStructure, matmul as triangular_matmul};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::{Accum, Mat, MatMut, MatRef, Par};

use super::loo::Decomposition;
use crate::error::{CoreError, Result};

/// Rows standardised at a time (`n > p`), or columns (`n <= p`): a block of `512 x 10,000` `f64` is
/// 41 MB, large enough that the products run at the matrix kernels' speed.
const BLOCK: usize = 512;

/// Feature rows of one element type, in parts (the training rows, then the validation rows), each
/// row-major with `dims` values per row.
pub(super) struct Rows<'a, T> {
    pub parts: Vec<&'a [T]>,
    pub dims: usize,
}

impl<T: Copy + Into<f64>> Rows<'_, T> {
    pub fn len(&self) -> usize {
        self.parts.iter().map(|p| p.len() / self.dims).sum()
    }

    /// Every row, in order.
    pub fn iter(&self) -> impl Iterator<Item = &[T]> {
        self.parts.iter().flat_map(|p| p.chunks_exact(self.dims))
    }
}

/// The standardisation `z = (x - means) / scales` of some rows.
pub(super) struct Standardisation<'a> {
    pub means: &'a [f64],
    pub scales: &'a [f64],
}

impl Standardisation<'_> {
    /// Rows `rows` (indices `first..first + out.nrows()`), columns `columns`, standardised into `out`.
    fn fill<T: Copy + Into<f64>>(
        &self,
        rows: &[&[T]],
        first: usize,
        columns: std::ops::Range<usize>,
        mut out: MatMut<'_, f64>,
    ) {
        for (c, j) in columns.enumerate() {
            let (mean, scale) = (self.means[j], self.scales[j]);
            for r in 0..out.nrows() {
                out[(r, c)] = (rows[first + r][j].into() - mean) / scale;
            }
        }
    }
}

/// The coefficients (`p x k`) of ridge at `alpha` on the standardised `rows` for the centred targets
/// `targets` (`n x k`); the intercepts are the targets' means (the features are centred).
pub(super) fn solve<T: Copy + Into<f64> + Sync>(
    rows: &Rows<'_, T>,
    standardisation: &Standardisation<'_>,
    targets: MatRef<'_, f64>,
    alpha: f64,
) -> Result<Mat<f64>> {
    let all: Vec<&[T]> = rows.iter().collect();
    let (n, p) = (all.len(), rows.dims);
    match Decomposition::for_shape(n, p) {
        Decomposition::Covariance => {
            let (mut system, mut rhs) = covariance_system(&all, p, standardisation, targets);
            factor_and_solve(system.as_mut(), rhs.as_mut(), alpha)?;
            Ok(rhs)
        }
        Decomposition::Gram => {
            let mut system = gram_system(&all, p, standardisation);
            let mut dual = targets.to_owned();
            factor_and_solve(system.as_mut(), dual.as_mut(), alpha)?;
            drop(system);
            Ok(primal_of(&all, p, standardisation, dual.as_ref()))
        }
    }
}

/// `ZᵀZ` (lower triangle) and `Zᵀ Y_c`, summed over blocks of rows.
fn covariance_system<T: Copy + Into<f64> + Sync>(
    rows: &[&[T]],
    p: usize,
    standardisation: &Standardisation<'_>,
    targets: MatRef<'_, f64>,
) -> (Mat<f64>, Mat<f64>) {
    let n = rows.len();
    let mut system = Mat::<f64>::zeros(p, p);
    let mut rhs = Mat::<f64>::zeros(p, targets.ncols());
    let mut block = Mat::<f64>::zeros(BLOCK.min(n), p);
    for first in (0..n).step_by(BLOCK) {
        let size = BLOCK.min(n - first);
        let mut z = block.as_mut().subrows_mut(0, size);
        standardisation.fill(rows, first, 0..p, z.rb_mut());
        let z = z.rb();
        triangular_matmul(
            system.as_mut(),
            BlockStructure::TriangularLower,
            Accum::Add,
            z.transpose(),
            BlockStructure::Rectangular,
            z,
            BlockStructure::Rectangular,
            1.0,
            Par::rayon(0),
        );
        matmul(
            rhs.as_mut(),
            Accum::Add,
            z.transpose(),
            targets.subrows(first, size),
            1.0,
            Par::rayon(0),
        );
    }
    (system, rhs)
}

/// `ZZᵀ` (lower triangle), summed over panels of columns.
pub(super) fn gram_system<T: Copy + Into<f64> + Sync>(
    rows: &[&[T]],
    p: usize,
    standardisation: &Standardisation<'_>,
) -> Mat<f64> {
    let n = rows.len();
    let mut system = Mat::<f64>::zeros(n, n);
    let mut panel = Mat::<f64>::zeros(n, BLOCK.min(p));
    for first in (0..p).step_by(BLOCK) {
        let width = BLOCK.min(p - first);
        let mut z = panel.as_mut().subcols_mut(0, width);
        standardisation.fill(rows, 0, first..first + width, z.rb_mut());
        let z = z.rb();
        triangular_matmul(
            system.as_mut(),
            BlockStructure::TriangularLower,
            Accum::Add,
            z,
            BlockStructure::Rectangular,
            z.transpose(),
            BlockStructure::Rectangular,
            1.0,
            Par::rayon(0),
        );
    }
    system
}

/// `Zᵀ C` (`p x k`), panel by panel.
pub(super) fn primal_of<T: Copy + Into<f64> + Sync>(
    rows: &[&[T]],
    p: usize,
    standardisation: &Standardisation<'_>,
    dual: MatRef<'_, f64>,
) -> Mat<f64> {
    let n = rows.len();
    let mut coefficients = Mat::<f64>::zeros(p, dual.ncols());
    let mut panel = Mat::<f64>::zeros(n, BLOCK.min(p));
    for first in (0..p).step_by(BLOCK) {
        let width = BLOCK.min(p - first);
        let mut z = panel.as_mut().subcols_mut(0, width);
        standardisation.fill(rows, 0, first..first + width, z.rb_mut());
        matmul(
            coefficients.as_mut().subrows_mut(first, width),
            Accum::Replace,
            z.rb().transpose(),
            dual,
            1.0,
            Par::rayon(0),
        );
    }
    coefficients
}

/// Solves `(system + αI) x = rhs` in place (`system`'s lower triangle holds the symmetric matrix; it is
/// overwritten by its Cholesky factor).
fn factor_and_solve(mut system: MatMut<'_, f64>, rhs: MatMut<'_, f64>, alpha: f64) -> Result<()> {
    let r = system.nrows();
    for j in 0..r {
        system[(j, j)] += alpha;
    }
    let par = Par::rayon(0);
    let mut workspace =
        MemBuffer::new(cholesky_in_place_scratch::<f64>(r, par, Default::default()));
    cholesky_in_place(
        system.rb_mut(),
        Default::default(),
        par,
        MemStack::new(&mut workspace),
        Default::default(),
    )
    .map_err(|err| CoreError::Param {
        name: "ridge",
        reason: format!(
            "the {r} x {r} system at alpha {alpha:e} is not positive definite ({err:?}); \
             check the features for extreme values, or give larger alphas"
        ),
    })?;
    let mut solve_workspace = MemBuffer::new(solve_in_place_scratch::<f64>(r, rhs.ncols(), par));
    solve_in_place(system.rb(), rhs, par, MemStack::new(&mut solve_workspace));
    Ok(())
}
