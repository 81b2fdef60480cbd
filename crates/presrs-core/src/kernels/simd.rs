//! Safe, runtime-dispatched SIMD kernels (`pulp`: AVX-512 or AVX2 + FMA where the CPU has them, scalar
//! otherwise).
//!
//! [`matrix_vector`] is the exact PCA projection (51 x 1025; `Pca::project_into`; classification uses the
//! fixed-point product of `kernels::fixed_dot`): `out = matrix · x` for a row-major matrix;
//! [`columns_times_vector`] the Parzen distance expansion (80 x 51) on the matrix stored by columns.
//!
//! The PCA product is limited by streaming the matrix (418 KB for the f64 PCA basis, from L2), not by
//! arithmetic, so the kernel is built to issue as few loads per multiply-add as it
//! can and to keep enough independent accumulators to hide the FMA latency:
//!
//! * rows are taken [`ROWS`] at a time; each SIMD chunk of `x` is loaded once and multiplied into all
//!   of them (one `x` load + `ROWS` matrix loads per `ROWS` FMAs), with one accumulator register per row,
//!   which also gives `ROWS` independent dependency chains;
//! * the last `rows % ROWS` rows go through narrower blocks (4, 2, 1 rows) that keep several accumulators
//!   per row (over consecutive chunks) so that they are not latency bound either;
//! * the `cols % lanes` trailing columns are added in scalar after the horizontal sum.
//!
//! Measured on the 2-core development VM (AVX-512 Xeon, 2.3 GHz): the 51 x 1025 product in f64 takes about
//! 6 us, which is what merely reading the 418 KB basis once takes there (68-78 GB/s with AVX2 or AVX-512
//! loads; a 32 KB basis reads at ~175 GB/s). AVX-512 (pulp's `x86-v4`, enabled in the workspace, chosen at
//! run time where the CPU has it) barely helps this product (about 10 %); fewer bytes do: an f32 copy of
//! the basis was 1.75x faster, and the 16-bit fixed-point basis classification now uses is faster again.
//!
//! The summation order depends only on the shape and the instruction set chosen at run time, so the
//! result is deterministic on a given machine. Nothing is allocated.

use pulp::{Arch, Simd, WithSimd};

/// Rows per block in the main loop.
const ROWS: usize = 8;

/// A floating-point element the kernel runs on (`f64`; the trait keeps the kernel independent of the
/// width, as it was when the PCA's classification path ran it on an f32 copy of its basis). It maps to
/// pulp's registers and operations of its width; dot products are reduced in the element's own
/// precision and returned as `f64`.
pub(crate) trait Element:
    Copy + core::ops::Mul<Output = Self> + core::ops::AddAssign
{
    type Reg<S: Simd>: Copy;
    const ZERO: Self;
    fn as_simd<S: Simd>(values: &[Self]) -> (&[Self::Reg<S>], &[Self]);
    fn lanes<S: Simd>() -> usize;
    fn splat<S: Simd>(simd: S, value: Self) -> Self::Reg<S>;
    fn mul_add<S: Simd>(simd: S, a: Self::Reg<S>, b: Self::Reg<S>, c: Self::Reg<S>)
    -> Self::Reg<S>;
    fn add<S: Simd>(simd: S, a: Self::Reg<S>, b: Self::Reg<S>) -> Self::Reg<S>;
    fn reduce_sum<S: Simd>(simd: S, a: Self::Reg<S>) -> Self;
    fn to_f64(self) -> f64;
}

/// `impl Element` for one float type from the names of its pulp register type and operations.
macro_rules! impl_element {
    ($t:ty, $reg:ident, $lanes:ident, $as_simd:ident, $splat:ident, $mul_add:ident, $add:ident, $reduce:ident) => {
        impl Element for $t {
            type Reg<S: Simd> = S::$reg;
            const ZERO: Self = 0.0;
            #[inline(always)]
            fn as_simd<S: Simd>(values: &[Self]) -> (&[S::$reg], &[Self]) {
                S::$as_simd(values)
            }
            #[inline(always)]
            fn lanes<S: Simd>() -> usize {
                S::$lanes
            }
            #[inline(always)]
            fn splat<S: Simd>(simd: S, value: Self) -> S::$reg {
                simd.$splat(value)
            }
            #[inline(always)]
            fn mul_add<S: Simd>(simd: S, a: S::$reg, b: S::$reg, c: S::$reg) -> S::$reg {
                simd.$mul_add(a, b, c)
            }
            #[inline(always)]
            fn add<S: Simd>(simd: S, a: S::$reg, b: S::$reg) -> S::$reg {
                simd.$add(a, b)
            }
            #[inline(always)]
            fn reduce_sum<S: Simd>(simd: S, a: S::$reg) -> Self {
                simd.$reduce(a)
            }
            #[inline(always)]
            fn to_f64(self) -> f64 {
                f64::from(self)
            }
        }
    };
}

impl_element!(
    f64,
    f64s,
    F64_LANES,
    as_simd_f64s,
    splat_f64s,
    mul_add_e_f64s,
    add_f64s,
    reduce_sum_f64s
);

/// `out = matrix · x` for a row-major `out.len() x cols` matrix (`matrix` holds at least
/// `out.len() * cols` values; any excess is ignored). Does not allocate.
///
/// # Panics
/// If `x.len() != cols` or `matrix` is shorter than `out.len() * cols`.
pub(crate) fn matrix_vector<T: Element>(matrix: &[T], cols: usize, x: &[T], out: &mut [f64]) {
    assert_eq!(x.len(), cols, "matrix_vector: x has the wrong length");
    matrix_vectors(matrix, cols, x, out.len(), out);
}

/// `outs[i] = matrix · xs[i]` for every `cols`-long vector `xs[i]` of `xs` (row-major `n x cols`), into
/// row-major `outs` (`n x rows`), for a row-major `rows x cols` matrix. Each output is bit for bit what
/// [`matrix_vector`] gives for its vector (the same blocks, accumulators and order); the loops are
/// swapped so that a block of matrix rows (8 x 1025 f64 = 64 KB) is read once for all the vectors
/// instead of once per vector. Does not allocate.
///
/// # Panics
/// If `xs` is not a whole number of vectors, `outs` is not `rows` per vector, or `matrix` is shorter than
/// `rows * cols`.
pub(crate) fn matrix_vectors<T: Element>(
    matrix: &[T],
    cols: usize,
    xs: &[T],
    rows: usize,
    outs: &mut [f64],
) {
    let needed = rows.checked_mul(cols);
    assert!(
        needed.is_some_and(|needed| needed <= matrix.len()),
        "matrix_vector: the matrix is too short"
    );
    if cols == 0 {
        outs.fill(0.0);
        return;
    }
    assert_eq!(
        xs.len() % cols,
        0,
        "matrix_vectors: xs is not whole vectors"
    );
    assert_eq!(
        outs.len(),
        xs.len() / cols * rows,
        "matrix_vectors: outs has the wrong length"
    );
    Arch::new().dispatch(MatVecs {
        matrix,
        cols,
        rows,
        xs,
        outs,
    });
}

struct MatVecs<'a, T> {
    matrix: &'a [T],
    cols: usize,
    rows: usize,
    xs: &'a [T],
    outs: &'a mut [f64],
}

impl<T: Element> WithSimd for MatVecs<'_, T> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let Self {
            matrix,
            cols,
            rows,
            xs,
            outs,
        } = self;
        if rows == 0 {
            return;
        }
        let mut first = 0;
        while first + ROWS <= rows {
            rows_for_all::<S, T, ROWS, 1>(simd, matrix, cols, rows, first, xs, outs);
            first += ROWS;
        }
        // The remaining < ROWS rows: 4, 2 then 1 at a time, with more accumulators per row.
        if rows - first >= 4 {
            rows_for_all::<S, T, 4, 2>(simd, matrix, cols, rows, first, xs, outs);
            first += 4;
        }
        if rows - first >= 2 {
            rows_for_all::<S, T, 2, 4>(simd, matrix, cols, rows, first, xs, outs);
            first += 2;
        }
        if rows - first == 1 {
            rows_for_all::<S, T, 1, 8>(simd, matrix, cols, rows, first, xs, outs);
        }
    }
}

/// Rows `first .. first + R` of the product for every vector of `xs`.
#[inline(always)]
fn rows_for_all<S: Simd, T: Element, const R: usize, const U: usize>(
    simd: S,
    matrix: &[T],
    cols: usize,
    rows: usize,
    first: usize,
    xs: &[T],
    outs: &mut [f64],
) {
    let block_rows = &matrix[first * cols..(first + R) * cols];
    for (x, out) in xs.chunks_exact(cols).zip(outs.chunks_exact_mut(rows)) {
        block::<S, T, R, U>(simd, block_rows, cols, x, &mut out[first..first + R]);
    }
}

/// `dst[r] = rows[r * cols .. (r + 1) * cols] · x` for `r < R`, with `U` accumulators per row (over
/// consecutive SIMD chunks). `rows` holds exactly `R * cols` values, `dst` `R`, `x` `cols`.
#[inline(always)]
fn block<S: Simd, T: Element, const R: usize, const U: usize>(
    simd: S,
    rows: &[T],
    cols: usize,
    x: &[T],
    dst: &mut [f64],
) {
    let (x_head, x_tail) = T::as_simd::<S>(x);
    let n = x_head.len();
    let heads: [&[T::Reg<S>]; R] =
        core::array::from_fn(|r| &T::as_simd::<S>(&rows[r * cols..(r + 1) * cols]).0[..n]);

    let zero = T::splat(simd, T::ZERO);
    let mut acc = [[zero; R]; U];
    let whole = n - n % U;
    let mut i = 0;
    while i < whole {
        for u in 0..U {
            let xv = x_head[i + u];
            for r in 0..R {
                acc[u][r] = T::mul_add(simd, heads[r][i + u], xv, acc[u][r]);
            }
        }
        i += U;
    }
    for i in whole..n {
        let xv = x_head[i];
        for r in 0..R {
            acc[0][r] = T::mul_add(simd, heads[r][i], xv, acc[0][r]);
        }
    }

    let tail_start = n * T::lanes::<S>();
    for r in 0..R {
        let mut sum = acc[0][r];
        for u in 1..U {
            sum = T::add(simd, sum, acc[u][r]);
        }
        let mut total = T::reduce_sum(simd, sum);
        let row_tail = &rows[r * cols + tail_start..(r + 1) * cols];
        for (&a, &b) in row_tail.iter().zip(x_tail) {
            total += a * b;
        }
        dst[r] = total.to_f64();
    }
}

/// Output registers per block of [`columns_times_vector`] (8 x 4 f64 lanes = 32 outputs with AVX2).
const COLUMN_BLOCK: usize = 8;

/// `out = Mᵀ · x` for a matrix stored by columns: `columns` holds `x.len()` columns of `out.len()` values
/// each, column `j` at `columns[j * out.len() ..]` (any excess is ignored). For short rows such as the
/// Parzen window's 80 x 51 distance expansion this beats [`matrix_vector`] on the row-major matrix: each
/// output lane accumulates its whole dot product in one register (`x[j]` broadcast, one FMA per column
/// per register), so there are no horizontal sums and no scalar row tails. Each output is summed over `j`
/// in order; the `out.len() % lanes` trailing outputs in scalar. Does not allocate.
///
/// # Panics
/// If `columns` is shorter than `x.len() * out.len()`.
pub(crate) fn columns_times_vector(columns: &[f64], x: &[f64], out: &mut [f64]) {
    assert!(
        x.len()
            .checked_mul(out.len())
            .is_some_and(|needed| needed <= columns.len()),
        "columns_times_vector: the matrix is too short"
    );
    Arch::new().dispatch(ColumnsTimesVector { columns, x, out });
}

struct ColumnsTimesVector<'a> {
    columns: &'a [f64],
    x: &'a [f64],
    out: &'a mut [f64],
}

impl WithSimd for ColumnsTimesVector<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let Self { columns, x, out } = self;
        let rows = out.len();
        if rows == 0 {
            return;
        }
        let lanes = S::F64_LANES;
        let whole = rows / lanes;
        // Blocks of COLUMN_BLOCK registers, and the last ten to fifteen as one block of ten (the Parzen
        // window's 80 outputs are ten AVX-512 registers: as 8 + 2, the block of two was two dependency
        // chains of 51 FMAs, bound by their latency), then 4, 2 and 1.
        let mut first = 0;
        loop {
            let left = whole - first;
            let regs = match left {
                0 => break,
                1 => 1,
                2 | 3 => 2,
                4..=7 => 4,
                10..=15 => 10,
                _ => COLUMN_BLOCK,
            };
            match regs {
                1 => column_block::<S, 1>(simd, columns, x, out, first),
                2 => column_block::<S, 2>(simd, columns, x, out, first),
                4 => column_block::<S, 4>(simd, columns, x, out, first),
                10 => column_block::<S, 10>(simd, columns, x, out, first),
                _ => column_block::<S, COLUMN_BLOCK>(simd, columns, x, out, first),
            }
            first += regs;
        }
        for (k, dst) in out.iter_mut().enumerate().skip(whole * lanes) {
            *dst = x
                .iter()
                .enumerate()
                .fold(0.0, |sum, (j, &xj)| columns[j * rows + k].mul_add(xj, sum));
        }
    }
}

/// Output registers `first .. first + R` of [`columns_times_vector`] (`R` registers of `S::F64_LANES`
/// outputs), each accumulated over every column in order.
#[inline(always)]
fn column_block<S: Simd, const R: usize>(
    simd: S,
    columns: &[f64],
    x: &[f64],
    out: &mut [f64],
    first: usize,
) {
    let rows = out.len();
    let lanes = S::F64_LANES;
    let mut acc = [simd.splat_f64s(0.0); R];
    for (j, &xj) in x.iter().enumerate() {
        let start = j * rows + first * lanes;
        let (column, _) = S::as_simd_f64s(&columns[start..start + R * lanes]);
        let xv = simd.splat_f64s(xj);
        for (a, &m) in acc.iter_mut().zip(column) {
            *a = simd.mul_add_e_f64s(m, xv, *a);
        }
    }
    let (out_regs, _) = S::as_mut_simd_f64s(&mut out[first * lanes..(first + R) * lanes]);
    out_regs.copy_from_slice(&acc);
}

/// `values[i] = exp(-values[i])` for `values[i] >= 0` (the Parzen window's kernel terms), within 3 ulp
/// of `f64::exp` (tested); arguments above 700 give `exp(-700)` (~1e-304) instead of smaller values or
/// 0, which changes no sum that also holds a term near 1, as every Parzen class sum does. Negative or
/// NaN arguments are not supported (the result is unspecified, no panic).
///
/// A plain loop the compiler vectorises under pulp's dispatch (libm's `exp` is a scalar call, about a
/// third of the Parzen stage): `exp(-z) = 2^-k · exp(-r)` with `k = round(z / ln 2)`, `r = z - k ln 2` in
/// two parts (Cody-Waite), `exp(-r)` by its Taylor polynomial of degree 13 (|r| <= ln 2 / 2: truncation
/// below 5e-18), and `2^-k` built from its exponent bits.
pub(crate) fn exp_neg_in_place(values: &mut [f64]) {
    Arch::new().dispatch(ExpNeg { values });
}

struct ExpNeg<'a> {
    values: &'a mut [f64],
}

impl WithSimd for ExpNeg<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, _simd: S) {
        for value in self.values.iter_mut() {
            *value = exp_neg(*value);
        }
    }
}

/// `exp(-z)` for `0 <= z` (clamped at 700); see [`exp_neg_in_place`].
#[inline(always)]
fn exp_neg(z: f64) -> f64 {
    // 1.5 * 2^52: adding it rounds to an integer held in the low mantissa bits.
    const ROUNDER: f64 = 6_755_399_441_055_744.0;
    const LN2_HI: f64 = 0.693_147_180_369_123_8;
    const LN2_LO: f64 = 1.908_214_929_270_587_7e-10;
    // 1/13!, 1/12!, ..., 1/1!, 1/0!: the Taylor series of exp(s), s = -r.
    const TAYLOR: [f64; 14] = [
        1.6059043836821613e-10,
        2.08767569878681e-09,
        2.505210838544172e-08,
        2.755731922398589e-07,
        2.7557319223985893e-06,
        2.48015873015873e-05,
        0.0001984126984126984,
        0.001388888888888889,
        0.008333333333333333,
        0.041666666666666664,
        0.16666666666666666,
        0.5,
        1.0,
        1.0,
    ];
    let z = z.min(700.0);
    let shifted = z.mul_add(std::f64::consts::LOG2_E, ROUNDER);
    let k = shifted - ROUNDER;
    // Cody-Waite: LN2_HI has trailing zero bits, so k * LN2_HI is exact for |k| < 2^11.
    let r = (-k).mul_add(LN2_LO, (-k).mul_add(LN2_HI, z));
    let s = -r;
    let mut poly = TAYLOR[0];
    for &c in &TAYLOR[1..] {
        poly = poly.mul_add(s, c);
    }
    // 0 <= k <= 1010: 2^-k has the biased exponent 1023 - k, taken from the low bits of `shifted`.
    let k_bits = shifted.to_bits().wrapping_sub(ROUNDER.to_bits());
    let scale = f64::from_bits((1023u64.wrapping_sub(k_bits)) << 52);
    poly * scale
}

/// `values[i] = ln(values[i])` for positive normal `values[i]` (the Parzen window's mean relative kernel
/// per class, in `[1 / count, 1]`), within 4.5e-16 relative plus 2e-16 absolute of `f64::ln` (tested). Zero, subnormal, negative, infinite or NaN arguments are not supported (the result is
/// unspecified, no panic).
///
/// A plain loop the compiler vectorises under pulp's dispatch, like [`exp_neg_in_place`]: libm's `ln` is a
/// scalar call per class. `x = 2^e · f` with `f` in `[√½, √2)` from the exponent bits, then
/// `ln f = 2 atanh(s)`, `s = (f - 1) / (f + 1)`, `|s| <= 0.172`, by its odd series to `s^23` (truncation
/// below 1e-19), and `ln x = e ln 2 + ln f` with `ln 2` in two parts.
pub(crate) fn ln_in_place(values: &mut [f64]) {
    Arch::new().dispatch(Ln { values });
}

struct Ln<'a> {
    values: &'a mut [f64],
}

impl WithSimd for Ln<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, _simd: S) {
        for value in self.values.iter_mut() {
            *value = ln(*value);
        }
    }
}

/// `ln(x)` for a positive normal `x`; see [`ln_in_place`].
#[inline(always)]
fn ln(x: f64) -> f64 {
    const LN2_HI: f64 = 0.693_147_180_369_123_8;
    const LN2_LO: f64 = 1.908_214_929_270_587_7e-10;
    const MANTISSA: u64 = (1 << 52) - 1;
    // 1/23, 1/21, ..., 1/3, 1: 2 atanh(s) = 2 s (1 + s²/3 + s⁴/5 + ...).
    const ODD: [f64; 12] = [
        1.0 / 23.0,
        1.0 / 21.0,
        1.0 / 19.0,
        1.0 / 17.0,
        1.0 / 15.0,
        1.0 / 13.0,
        1.0 / 11.0,
        1.0 / 9.0,
        1.0 / 7.0,
        1.0 / 5.0,
        1.0 / 3.0,
        1.0,
    ];
    let bits = x.to_bits();
    // The mantissa with the exponent of [1, 2); above √2 it is halved and the exponent raised, so that
    // f lies in [√½, √2).
    let unit = f64::from_bits((bits & MANTISSA) | (1023 << 52));
    let high = unit >= std::f64::consts::SQRT_2;
    let f = if high { 0.5 * unit } else { unit };
    let e = ((bits >> 52) & 0x7ff) as f64 - 1023.0 + if high { 1.0 } else { 0.0 };
    let s = (f - 1.0) / (f + 1.0);
    let s2 = s * s;
    let mut poly = ODD[0];
    for &c in &ODD[1..] {
        poly = poly.mul_add(s2, c);
    }
    // e ln 2 + 2 s poly, the small terms first; e * LN2_HI is exact (|e| < 2^11, LN2_HI's trailing zeros).
    e.mul_add(LN2_HI, e.mul_add(LN2_LO, 2.0 * s * poly))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernels::harness::{
        Backend, Harness, Portable128, Portable256, Portable512, Scalar, X86V3, X86V4,
    };
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The naive oracle: each dot product summed left to right.
    fn naive(matrix: &[f64], cols: usize, x: &[f64], out: &mut [f64]) {
        for (r, dst) in out.iter_mut().enumerate() {
            *dst = (0..cols).map(|j| matrix[r * cols + j] * x[j]).sum();
        }
    }

    /// Every backend of the f64 kernels: pulp's scalar and portable emulations with 1, 2, 4 and 8 lanes
    /// (so every lane count and tail length runs whatever the test machine has), AVX2 and AVX-512.
    const BACKENDS: [Backend; 6] = [Scalar, Portable128, Portable256, Portable512, X86V3, X86V4];

    /// The kernel on one backend, bypassing dispatch (`None`: not on this CPU).
    fn on(backend: Backend, matrix: &[f64], cols: usize, x: &[f64], out: &mut [f64]) -> Option<()> {
        if cols == 0 {
            out.fill(0.0);
            return backend.supported().then_some(());
        }
        let rows = out.len();
        backend.run(MatVecs {
            matrix,
            cols,
            rows,
            xs: x,
            outs: out,
        })
    }

    /// Checks every backend against the oracle on a random `rows x cols` matrix, within `1e-12` of the
    /// sum of the absolute products of each row (a forward error bound for any summation order is
    /// `cols * eps` times that sum: 2.3e-13 for 1025 columns).
    fn check(harness: &mut Harness, rows: usize, cols: usize, rng: &mut ChaCha8Rng) {
        // Mixed signs and magnitudes so that cancellation happens.
        let value = |rng: &mut ChaCha8Rng| {
            let scale = 10f64.powi(rng.random_range(-3..=3));
            rng.random_range(-1.0..1.0) * scale
        };
        let matrix: Vec<f64> = (0..rows * cols).map(|_| value(rng)).collect();
        let x: Vec<f64> = (0..cols).map(|_| value(rng)).collect();
        let mut expected = vec![0.0; rows];
        naive(&matrix, cols, &x, &mut expected);
        let magnitude =
            |r: usize| -> f64 { (0..cols).map(|j| (matrix[r * cols + j] * x[j]).abs()).sum() };
        for backend in BACKENDS {
            let mut got = vec![f64::NAN; rows];
            if on(backend, &matrix, cols, &x, &mut got).is_some() {
                harness.compare(backend, &format!("{rows} x {cols}"), &got, &expected, |r| {
                    1e-12 * magnitude(r)
                });
            }
        }
        // The dispatched entry point is one of them.
        let mut got = vec![f64::NAN; rows];
        matrix_vector(&matrix, cols, &x, &mut got);
        for r in 0..rows {
            assert!(
                (got[r] - expected[r]).abs() <= 1e-12 * magnitude(r),
                "dispatched {rows} x {cols}"
            );
        }
    }

    #[test]
    fn matches_the_naive_product_on_many_shapes() {
        let mut harness = Harness::new("simd::matrix_vector");
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        for rows in (0..=20).chain([31, 51, 80]) {
            for cols in (0..=19).chain([31, 32, 33, 51, 63, 64, 65, 127, 1024, 1025]) {
                check(&mut harness, rows, cols, &mut rng);
            }
        }
        check(&mut harness, 51, 1025, &mut rng); // the paper's PCA
        check(&mut harness, 80, 51, &mut rng); // the paper's Parzen expansion
        harness.finish(&BACKENDS);
    }

    /// Many vectors at once give, bit for bit, what one vector at a time gives (every row remainder).
    #[test]
    fn many_vectors_equal_one_at_a_time_bit_for_bit() {
        let mut rng = ChaCha8Rng::seed_from_u64(13);
        for (rows, cols, n) in [
            (51, 1025, 7),
            (13, 33, 5),
            (3, 9, 4),
            (1, 4, 3),
            (0, 5, 2),
            (6, 1, 2),
        ] {
            let matrix: Vec<f64> = (0..rows * cols)
                .map(|_| rng.random_range(-1.0..1.0))
                .collect();
            let xs: Vec<f64> = (0..n * cols).map(|_| rng.random_range(-9.0..9.0)).collect();
            let mut many = vec![f64::NAN; n * rows];
            matrix_vectors(&matrix, cols, &xs, rows, &mut many);
            if rows == 0 {
                continue; // nothing to compare; it must just not panic
            }
            for (x, got) in xs.chunks_exact(cols).zip(many.chunks_exact(rows)) {
                let mut one = vec![f64::NAN; rows];
                matrix_vector(&matrix, cols, x, &mut one);
                assert_eq!(got, one.as_slice(), "{rows} x {cols}");
            }
        }
    }

    #[test]
    fn exact_on_small_integers_and_ignores_excess_matrix() {
        // 3 x 5 matrix followed by junk that must not be read into the result.
        let mut matrix: Vec<f64> = (0..15).map(f64::from).collect();
        matrix.extend([1e300; 4]);
        let x = [1.0, -1.0, 2.0, 0.5, 3.0];
        let mut out = [0.0; 3];
        matrix_vector(&matrix, 5, &x, &mut out);
        assert_eq!(out, [16.5, 44.0, 71.5]);
        let mut empty: [f64; 0] = [];
        matrix_vector(&matrix, 5, &x, &mut empty);
        let mut zero_cols = [1.0; 2];
        matrix_vector::<f64>(&[], 0, &[], &mut zero_cols);
        assert_eq!(zero_cols, [0.0, 0.0]);
    }

    /// The column-major kernel against the naive row-major oracle on every backend and many shapes
    /// (every remainder of the outputs over the lanes and over the register block), within `1e-12` of
    /// the sum of absolute products.
    #[test]
    fn columns_times_vector_matches_the_naive_product() {
        let mut harness = Harness::new("simd::columns_times_vector");
        let mut rng = ChaCha8Rng::seed_from_u64(14);
        for rows in (0..=19).chain([31, 32, 33, 63, 64, 65, 80, 129]) {
            for cols in [0, 1, 2, 3, 7, 51, 64] {
                let matrix: Vec<f64> = (0..rows * cols)
                    .map(|_| rng.random_range(-1.0..1.0) * 10f64.powi(rng.random_range(-3..=3)))
                    .collect();
                let x: Vec<f64> = (0..cols).map(|_| rng.random_range(-1e3..1e3)).collect();
                let mut expected = vec![0.0; rows];
                naive(&matrix, cols, &x, &mut expected);
                // Column-major copy of the row-major matrix.
                let columns: Vec<f64> = (0..cols)
                    .flat_map(|j| (0..rows).map(move |r| (r, j)))
                    .map(|(r, j)| matrix[r * cols + j])
                    .collect();
                for backend in BACKENDS {
                    let mut got = vec![f64::NAN; rows];
                    let run = backend.run(ColumnsTimesVector {
                        columns: &columns,
                        x: &x,
                        out: &mut got,
                    });
                    if run.is_some() {
                        let case = format!("{rows} x {cols}");
                        harness.compare(backend, &case, &got, &expected, |r| {
                            1e-12
                                * (0..cols)
                                    .map(|j| (matrix[r * cols + j] * x[j]).abs())
                                    .sum::<f64>()
                        });
                    }
                }
                let mut got = vec![f64::NAN; rows];
                columns_times_vector(&columns, &x, &mut got);
                for r in 0..rows {
                    let magnitude: f64 =
                        (0..cols).map(|j| (matrix[r * cols + j] * x[j]).abs()).sum();
                    assert!(
                        (got[r] - expected[r]).abs() <= 1e-12 * magnitude,
                        "dispatched"
                    );
                }
            }
        }
        harness.finish(&BACKENDS);
    }

    /// The vectorised `exp(-z)` against libm's on a dense sweep, random arguments and the edges, on the
    /// dispatched instruction set and pulp's scalar emulation: within 3 ulp (relative 7e-16).
    #[test]
    fn exp_neg_matches_libm() {
        let mut rng = ChaCha8Rng::seed_from_u64(15);
        let mut z: Vec<f64> = (0..=70_000).map(|i| f64::from(i) * 0.01).collect();
        z.extend((0..20_000).map(|_| rng.random_range(0.0..700.0)));
        z.extend((0..2_000).map(|_| rng.random_range(0.0..1e-6)));
        z.extend([
            0.0,
            f64::MIN_POSITIVE,
            1e-300,
            0.5 * std::f64::consts::LN_2,
            699.999,
            700.0,
        ]);
        let want: Vec<f64> = z.iter().map(|&z| (-z).exp()).collect();
        let mut harness = Harness::new("simd::exp_neg_in_place");
        for backend in BACKENDS {
            let mut got = z.clone();
            if backend.run(ExpNeg { values: &mut got }).is_some() {
                harness.compare(backend, "sweep", &got, &want, |i| 7e-16 * want[i]);
            }
        }
        harness.finish(&BACKENDS);
        let mut got = z.clone();
        exp_neg_in_place(&mut got);
        assert!(
            got.iter()
                .zip(&want)
                .all(|(g, w)| (g - w).abs() <= 7e-16 * w),
            "dispatched"
        );
        let mut clamped = [701.0, 1e6, f64::INFINITY];
        exp_neg_in_place(&mut clamped);
        for value in clamped {
            assert!((value - (-700f64).exp()).abs() <= 7e-16 * (-700f64).exp());
        }
    }

    /// The vectorised `ln` against libm's over the Parzen window's range and beyond, on the dispatched
    /// instruction set and pulp's scalar emulation.
    #[test]
    fn ln_matches_libm() {
        let mut rng = ChaCha8Rng::seed_from_u64(16);
        let mut x: Vec<f64> = (1..=100_000).map(|i| f64::from(i) * 1e-5).collect();
        x.extend((0..20_000).map(|_| rng.random_range(1e-4..1.0)));
        x.extend((0..5_000).map(|_| 10f64.powf(rng.random_range(-300.0..300.0))));
        x.extend((0..5_000).map(|_| 1.0 + rng.random_range(-1e-6..1e-6)));
        x.extend([
            1.0,
            0.5,
            2.0,
            f64::MIN_POSITIVE,
            f64::MAX,
            std::f64::consts::SQRT_2,
            std::f64::consts::FRAC_1_SQRT_2,
            1.0 / 80.0,
        ]);
        let want: Vec<f64> = x.iter().map(|&x| x.ln()).collect();
        let tolerance = |i: usize| 4.5e-16 * want[i].abs() + 1e-16 * x[i].max(1.0 / x[i]).min(2.0);
        let mut harness = Harness::new("simd::ln_in_place");
        for backend in BACKENDS {
            let mut got = x.clone();
            if backend.run(Ln { values: &mut got }).is_some() {
                harness.compare(backend, "sweep", &got, &want, tolerance);
            }
        }
        harness.finish(&BACKENDS);
        let mut got = x.clone();
        ln_in_place(&mut got);
        assert!(
            (0..x.len()).all(|i| (got[i] - want[i]).abs() <= tolerance(i)),
            "dispatched"
        );
    }

    #[test]
    #[should_panic]
    fn short_matrix_panics() {
        matrix_vector(&[1.0; 5], 3, &[1.0; 3], &mut [0.0; 2]);
    }
}
