//! The PCA basis in fixed point, and the fast projection on it (the classification path).
//!
//! The basis without its first column is a [`FixedMatrix`] (16-bit integers, one scale per axis); the
//! first column is kept in f64 and multiplied exactly: the first feature of the 1-D |FFT| is the DC bin,
//! the image's total load, far above the others, and kept out of the fixed-point chunks it does not
//! coarsen the steps of the low frequencies it would share a chunk with (1025 features leave 1024, whole
//! chunks). Features `1..` are centred in f32 on the means rounded to f32; what that rounding moves each
//! output by is added back exactly. The error bound is stated on [`super::Pca::project_fast_into`].

use crate::error::{CoreError, Result, check_len};
use crate::kernels::{FixedMatrix, FixedVector};

/// The derived, fixed-point form of a PCA's basis and mean (not serialised: rebuilt from them).
#[derive(Clone, Debug, PartialEq)]
pub(super) struct FixedBasis {
    n_features: usize,
    n_components: usize,
    /// `basis` without its first column, in 16-bit fixed point: a quarter of the bytes of the f64 basis
    /// (which bounded the f64 projection's time; this one is bound by its integer multiply-adds).
    matrix: FixedMatrix,
    /// The first column of `basis`, multiplied exactly.
    first: Vec<f64>,
    /// `mean[0]`.
    mean_first: f64,
    /// `mean[1..]` in f32: the fixed-point path centres f32 features in f32.
    mean_rest_f32: Vec<f32>,
    /// `Σ_{i ≥ 1} basis[k][i] · (mean_rest_f32[i - 1] - mean[i])`: what rounding the means to f32 moves
    /// each output by, added back exactly.
    correction: Vec<f64>,
}

/// The buffers of [`Pca::project_fast_into`](super::Pca::project_fast_into) and
/// [`Pca::project_fast_many`](super::Pca::project_fast_many) (the centred inputs in fixed point), made
/// once per session.
#[derive(Clone, Debug, Default)]
pub struct ProjectionScratch {
    centred: Vec<FixedVector>,
    /// Features `1..` of one f64 input in f32.
    single: Vec<f32>,
}

impl FixedBasis {
    /// From a row-major `n_components x n_features` basis (`n_features ≥ 1`) and its mean.
    pub(super) fn new(basis: &[f64], mean: &[f64], n_features: usize) -> Self {
        let n_components = basis.len() / n_features;
        let rest: Vec<f64> = basis
            .chunks_exact(n_features)
            .flat_map(|row| &row[1..])
            .copied()
            .collect();
        let matrix = FixedMatrix::from_f64(&rest, n_components, n_features - 1);
        let first = basis.iter().step_by(n_features).copied().collect();
        #[allow(clippy::cast_possible_truncation)]
        let mean_rest_f32: Vec<f32> = mean[1..].iter().map(|&m| m as f32).collect();
        let correction = basis
            .chunks_exact(n_features)
            .map(|row| {
                row[1..]
                    .iter()
                    .zip(mean_rest_f32.iter().zip(&mean[1..]))
                    .map(|(&loading, (&rounded, &exact))| loading * (f64::from(rounded) - exact))
                    .sum()
            })
            .collect();
        Self {
            n_features,
            n_components,
            matrix,
            first,
            mean_first: mean[0],
            mean_rest_f32,
            correction,
        }
    }

    /// Buffers for one input at a time (more are added as batches need them).
    pub(super) fn scratch(&self) -> ProjectionScratch {
        ProjectionScratch {
            centred: vec![FixedVector::with_chunks(self.matrix.chunks_per_row())],
            single: Vec::with_capacity(self.mean_rest_f32.len()),
        }
    }

    /// The fast projection of the whole input vectors in `xs` (f64 or f32) into `out` (`n_components`
    /// values per input), each input's features `1..` rounded to f32 (if they are not already) and
    /// quantized, the first kept exact. Allocates only to grow `scratch`.
    pub(super) fn project<T: FastInput>(
        &self,
        xs: &[T],
        scratch: &mut ProjectionScratch,
        out: &mut [f64],
    ) -> Result<()> {
        if xs.len() % self.n_features != 0 {
            return Err(CoreError::Shape {
                what: "pca inputs",
                expected: format!("whole vectors of {} features", self.n_features),
                got: format!("{} values", xs.len()),
            });
        }
        let n = xs.len() / self.n_features;
        check_len("pca outputs", n * self.n_components, out.len())?;
        if scratch.centred.len() < n {
            scratch.centred.resize_with(n, FixedVector::default);
        }
        let centred = &mut scratch.centred[..n];
        for (vector, x) in centred.iter_mut().zip(xs.chunks_exact(self.n_features)) {
            let rest = T::as_single(&x[1..], &mut scratch.single);
            vector.quantize_difference(rest, &self.mean_rest_f32, self.matrix.chunks_per_row());
        }
        self.matrix.times_vectors(centred, out);
        let firsts = xs.chunks_exact(self.n_features).map(|x| x[0].widen());
        for (first, out) in firsts.zip(out.chunks_exact_mut(self.n_components)) {
            let centred = first - self.mean_first;
            for ((value, &loading), &correction) in
                out.iter_mut().zip(&self.first).zip(&self.correction)
            {
                *value += loading * centred + correction;
            }
        }
        Ok(())
    }
}

/// A feature value the fast projection reads: f64 (rounded to f32 on the way in) or f32 (read as it is,
/// the fast 1-D |FFT|'s output). Sealed: only these two.
pub trait FastInput: Copy + sealed::Sealed {
    /// `values` in f32: themselves, or rounded into `buffer` (cleared first).
    #[doc(hidden)]
    fn as_single<'a>(values: &'a [Self], buffer: &'a mut Vec<f32>) -> &'a [f32];
    #[doc(hidden)]
    fn widen(self) -> f64;
}

mod sealed {
    pub trait Sealed {}
    impl Sealed for f64 {}
    impl Sealed for f32 {}
}

impl FastInput for f64 {
    fn as_single<'a>(values: &'a [f64], buffer: &'a mut Vec<f32>) -> &'a [f32] {
        buffer.clear();
        #[allow(clippy::cast_possible_truncation)]
        buffer.extend(values.iter().map(|&value| value as f32));
        buffer
    }

    fn widen(self) -> f64 {
        self
    }
}

impl FastInput for f32 {
    fn as_single<'a>(values: &'a [f32], _buffer: &'a mut Vec<f32>) -> &'a [f32] {
        values
    }

    fn widen(self) -> f64 {
        f64::from(self)
    }
}
