//! Matrix-vector products in 16-bit fixed point: the PCA projection of the classification path.
//!
//! Why: in f64 or f32 the 51 x 1025 projection is bound by moving the basis (418 or 209 KB) through the
//! core, not by the arithmetic of one image. As 16-bit integers the basis is a quarter of the f64 bytes,
//! and one integer multiply-add instruction (`pmaddwd`) takes 32 (AVX-512) or 16 (AVX2) products of
//! 16-bit values and sums them in exact pairs, where a half-precision basis would need a conversion per
//! value. At that size the product is bound by those instructions instead: an L1-resident basis costs
//! the same per row as the full one read from L2 (`benches/pca_stage.rs`).
//!
//! Representation: row `r` of the matrix is `s_r · q_r` with integers `|q_rc| ≤ 32767` and
//! `s_r = max_c |w_rc| / 32767` (the rows are principal axes: their loadings share one scale well). A
//! vector `d` (f32: the features of the classification path are) is quantized when it is multiplied
//! ([`FixedVector`]), in block floating point, in two passes (differences and chunk maxima, then integers):
//! each chunk
//! `k` of [`CHUNK`] values has its own scale `t_k = max_{c∈k} |d_c| / 16383`, because the values of a
//! feature vector span orders of magnitude (the DC bin of an image's spectrum is far above its high
//! frequencies), and one scale for all would round the small ones away. The vector's integers have 15
//! bits so that a lane's integer sum over a whole chunk (two pair sums, at most `4 · 32767 · 16383 <
//! 2³¹`) is exact in an i32: one conversion to f32 and one multiply-add by `t_k` per chunk. Each rounding
//! moves a value by at most half a step, so
//!
//! `|Σ_c w_rc d_c − s_r Σ_k t_k Σ_{c∈k} q_rc p_c| ≤ ½ s_r Σ_c |d_c| + ½ Σ_k t_k Σ_{c∈k} |w_rc| + ¼ s_r Σ_k t_k · CHUNK`
//!
//! plus the f32 arithmetic on the exact integer sums (a few `2⁻²⁴` of the sum of the represented terms'
//! magnitudes): about `2⁻¹⁶` of the largest loading and `2⁻¹⁵` of each chunk's largest value. Tested
//! against the f64 product.
//!
//! Layout: row-major, each row padded with zeros to whole chunks; a quantized vector has the same chunks,
//! its padding zero.
//!
//! Kernels (chosen at run time): AVX-512BW, AVX2, or a scalar loop with the same integer sums. The order
//! of summation depends only on the shape and the kernel, so results are deterministic on a given
//! machine.

/// Values per chunk: two AVX-512 registers of 16-bit integers, four AVX2 registers.
pub(crate) const CHUNK: usize = 64;

/// The largest integer of a matrix row (symmetric: -32768 is never used).
const LIMIT: f64 = 32767.0;

/// The largest integer of a vector: 15 bits, so that the integer sum of a lane over a whole chunk, two
/// pair sums of at most `2 · 32767 · 16383` each, fits in an i32 and one conversion to f32 serves it.
const VECTOR_LIMIT: f64 = 16383.0;

/// Rows per block in the main loop: each chunk of a vector is loaded once for this many rows, and each
/// row has its own accumulator (independent dependency chains).
const ROWS: usize = 8;

/// [`CHUNK`] 16-bit integers (128 bytes) on a 64-byte boundary, so that every 512-bit load of the
/// products is one cache line. With the plain array's 2-byte alignment the allocator decided, and a basis
/// that happened to start mid-line split every load of the product in two (the PCA stage measured about
/// 30 % slower after unrelated changes moved the allocation).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub(crate) struct Chunk([i16; CHUNK]);

impl Chunk {
    const ZERO: Self = Self([0; CHUNK]);
}

impl core::ops::Deref for Chunk {
    type Target = [i16; CHUNK];

    #[inline(always)]
    fn deref(&self) -> &[i16; CHUNK] {
        &self.0
    }
}

impl core::ops::DerefMut for Chunk {
    #[inline(always)]
    fn deref_mut(&mut self) -> &mut [i16; CHUNK] {
        &mut self.0
    }
}

/// A `rows x cols` matrix in 16-bit fixed point with one scale per row, each row padded to whole
/// [`CHUNK`]s.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct FixedMatrix {
    rows: usize,
    cols: usize,
    chunks_per_row: usize,
    /// `scale_r`: row `r` is `scale_r · q_r`.
    scales: Vec<f64>,
    /// `q`, `rows * chunks_per_row` chunks.
    chunks: Vec<Chunk>,
}

/// A vector quantized for products with a [`FixedMatrix`]: chunk `k` is `scales[k] · chunks[k]`.
#[derive(Clone, Debug, Default)]
pub(crate) struct FixedVector {
    scales: Vec<f32>,
    chunks: Vec<Chunk>,
    /// Scratch of [`quantize_difference`](Self::quantize_difference): `x - mean`, and each chunk's
    /// largest magnitude, then its reciprocal scale.
    differences: Vec<f32>,
    inverses: Vec<f32>,
}

/// The scale of a matrix row of largest magnitude `max` (finite), and its reciprocal (0 for a zero row).
fn row_scale(max: f64) -> (f64, f64) {
    if max == 0.0 {
        (0.0, 0.0)
    } else {
        (max / LIMIT, LIMIT / max)
    }
}

/// Adding `1.5 · 2⁵²` to `v` with `|v| ≤ 2⁵¹` rounds it to an integer (to nearest, ties to even), which
/// then sits in the low bits of the sum's bit pattern: no conversion instruction, so loops vectorize.
const ROUNDER: f64 = 6_755_399_441_055_744.0;

/// The integer in the low bits of `(v + ROUNDER).to_bits()`, for `|v| ≤ 32767.5` (matrix values stay
/// within 32767.5, vector values within 16383.5; anything else, NaN included, gives an unspecified
/// value, and the chunk's scale is NaN then).
#[inline(always)]
fn low_bits(bits: u64) -> i16 {
    // Two's complement in the low 16 bits: truncating is the intent.
    #[allow(clippy::cast_possible_truncation)]
    let q = bits as i16;
    q
}

impl FixedMatrix {
    /// Quantizes the row-major `rows x cols` matrix `values` (finite values).
    ///
    /// # Panics
    /// If `values` does not hold `rows * cols` values.
    pub(crate) fn from_f64(values: &[f64], rows: usize, cols: usize) -> Self {
        assert_eq!(
            Some(values.len()),
            rows.checked_mul(cols),
            "FixedMatrix: wrong number of values"
        );
        let chunks_per_row = cols.div_ceil(CHUNK);
        let mut chunks = vec![Chunk::ZERO; rows * chunks_per_row];
        let mut scales = vec![0.0; rows];
        if cols > 0 {
            for ((row_chunks, row), scale) in chunks
                .chunks_exact_mut(chunks_per_row)
                .zip(values.chunks_exact(cols))
                .zip(&mut scales)
            {
                let max = row.iter().fold(0.0f64, |max, value| max.max(value.abs()));
                let (row_scale, inverse) = row_scale(max);
                *scale = row_scale;
                let row_values = row_chunks.iter_mut().flat_map(|chunk| chunk.0.iter_mut());
                for (dst, &value) in row_values.zip(row) {
                    *dst = low_bits((value * inverse + ROUNDER).to_bits());
                }
            }
        }
        Self {
            rows,
            cols,
            chunks_per_row,
            scales,
            chunks,
        }
    }

    #[cfg(test)]
    pub(crate) fn rows(&self) -> usize {
        self.rows
    }

    /// Chunks per (padded) row, and per quantized vector.
    pub(crate) fn chunks_per_row(&self) -> usize {
        self.chunks_per_row
    }

    /// The element at `(row, col)` as represented, `scale_r · q_rc`.
    ///
    /// # Panics
    /// If `(row, col)` is outside the matrix.
    #[cfg(test)]
    pub(crate) fn get(&self, row: usize, col: usize) -> f64 {
        assert!(
            row < self.rows && col < self.cols,
            "FixedMatrix: out of range"
        );
        let chunk = &self.chunks[row * self.chunks_per_row + col / CHUNK];
        self.scales[row] * f64::from(chunk[col % CHUNK])
    }

    /// `outs[i] = self · xs[i]` for each quantized vector (`chunks_per_row` chunks each) into row-major
    /// `outs` (`rows` values per vector). A block of [`ROWS`] rows (8 x 1088 x 2 B = 17 KB: L1) is read
    /// once for all the vectors. Does not allocate.
    ///
    /// # Panics
    /// If a vector does not have `chunks_per_row` chunks or `outs` does not hold `rows` values per vector.
    pub(crate) fn times_vectors(&self, xs: &[FixedVector], outs: &mut [f64]) {
        assert_eq!(
            outs.len(),
            xs.len() * self.rows,
            "FixedMatrix: outs has the wrong length"
        );
        assert!(
            xs.iter().all(|x| x.chunks.len() == self.chunks_per_row),
            "FixedMatrix: a vector has the wrong length"
        );
        #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
        {
            if let Some(simd) = pulp::x86::V4::try_new() {
                return simd.vectorize(Product {
                    kernel: simd,
                    matrix: self,
                    xs,
                    outs,
                });
            }
            if let Some(simd) = pulp::x86::V3::try_new() {
                return simd.vectorize(Product {
                    kernel: simd,
                    matrix: self,
                    xs,
                    outs,
                });
            }
        }
        self.times_vectors_with(ScalarKernel, xs, outs);
    }

    /// [`times_vectors`](Self::times_vectors) on the given kernel (the tests run every kernel the CPU
    /// has). Inlined into pulp's `vectorize`, so it is compiled for the kernel's instruction set.
    #[inline(always)]
    fn times_vectors_with<K: PairDot>(&self, kernel: K, xs: &[FixedVector], outs: &mut [f64]) {
        let rows = self.rows;
        let mut first = 0;
        while first + ROWS <= rows {
            self.rows_for_all::<K, ROWS, 1>(kernel, first, xs, outs);
            first += ROWS;
        }
        // The remaining < ROWS rows: 4, 2 then 1 at a time, with more accumulators per row.
        if rows - first >= 4 {
            self.rows_for_all::<K, 4, 2>(kernel, first, xs, outs);
            first += 4;
        }
        if rows - first >= 2 {
            self.rows_for_all::<K, 2, 4>(kernel, first, xs, outs);
            first += 2;
        }
        if rows - first == 1 {
            self.rows_for_all::<K, 1, 8>(kernel, first, xs, outs);
        }
    }

    /// Rows `first .. first + R` of the product for every vector, with `U` accumulators per row (over
    /// consecutive chunks).
    #[inline(always)]
    fn rows_for_all<K: PairDot, const R: usize, const U: usize>(
        &self,
        kernel: K,
        first: usize,
        xs: &[FixedVector],
        outs: &mut [f64],
    ) {
        let n = self.chunks_per_row;
        let block = &self.chunks[first * n..(first + R) * n];
        let rows: [&[Chunk]; R] = core::array::from_fn(|r| &block[r * n..(r + 1) * n]);
        for (x, out) in xs.iter().zip(outs.chunks_exact_mut(self.rows)) {
            let (x_chunks, x_scales) = (&x.chunks[..n], &x.scales[..n]);
            let zero = kernel.zero();
            let mut acc = [[zero; R]; U];
            let whole = n - n % U;
            let mut i = 0;
            while i < whole {
                for u in 0..U {
                    let (xv, scale) = (&x_chunks[i + u], kernel.splat(x_scales[i + u]));
                    for r in 0..R {
                        acc[u][r] = kernel.add_products(acc[u][r], &rows[r][i + u], xv, scale);
                    }
                }
                i += U;
            }
            for i in whole..n {
                let (xv, scale) = (&x_chunks[i], kernel.splat(x_scales[i]));
                for r in 0..R {
                    acc[0][r] = kernel.add_products(acc[0][r], &rows[r][i], xv, scale);
                }
            }
            for r in 0..R {
                let mut sum = acc[0][r];
                for u in 1..U {
                    sum = kernel.add(sum, acc[u][r]);
                }
                out[first + r] = self.scales[first + r] * f64::from(kernel.sum(sum));
            }
        }
    }
}

impl FixedVector {
    /// A zero vector of `chunks` chunks, to be set by [`quantize_difference`](Self::quantize_difference)
    /// (which allocates only if it needs more chunks).
    pub(crate) fn with_chunks(chunks: usize) -> Self {
        Self {
            scales: vec![0.0; chunks],
            chunks: vec![Chunk::ZERO; chunks],
            differences: vec![0.0; chunks * CHUNK],
            inverses: vec![0.0; chunks],
        }
    }

    /// Sets this vector to `x - mean` quantized into `chunks` chunks (at least `x.len()` values; the
    /// padding is zero). The difference is formed in f32 (exact when the two are within a factor of two
    /// of each other, else rounded by at most `2⁻²⁴` of it), each chunk's scale is its largest magnitude /
    /// 16383 in f32, and each value is rounded to the nearest multiple of it. Two passes over f32 values
    /// (an earlier version took three over f64 ones): the classification path, whose features are f32
    /// already. A non-finite difference (or a sum of magnitudes beyond f32's range) makes every product
    /// NaN.
    ///
    /// # Panics
    /// If `mean` is not as long as `x` or `x` does not fit in `chunks`.
    pub(crate) fn quantize_difference(&mut self, x: &[f32], mean: &[f32], chunks: usize) {
        assert_eq!(
            x.len(),
            mean.len(),
            "FixedVector: mean has the wrong length"
        );
        assert!(x.len() <= chunks * CHUNK, "FixedVector: too few chunks");
        // Compiled for the CPU's instruction set, so that the loops vectorize; the narrowing of the
        // integers to 16 bits is written per instruction set (`NarrowChunk`).
        #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
        {
            if let Some(simd) = pulp::x86::V4::try_new() {
                return simd.vectorize(Quantize {
                    simd,
                    vector: self,
                    x,
                    mean,
                    chunks,
                });
            }
            if let Some(simd) = pulp::x86::V3::try_new() {
                return simd.vectorize(Quantize {
                    simd,
                    vector: self,
                    x,
                    mean,
                    chunks,
                });
            }
        }
        pulp::NullaryFnOnce::call(Quantize {
            simd: pulp::Scalar::new(),
            vector: self,
            x,
            mean,
            chunks,
        });
    }
}

/// The scale of a vector chunk of largest magnitude `max` (`max / 16383`), and the reciprocal to quantize
/// with (with which `|d| · inverse ≤ 16383` up to a few f32 roundings, well below the 16383.5 that would
/// round to 16384). A chunk of zeros gets 0; a non-finite `max` (a NaN or infinite value) gets NaN, so the
/// product comes out NaN rather than silently finite; a scale below f32's normal range is raised to its
/// smallest normal (the steps are then finer than needed, never too coarse).
fn chunk_scale(max: f32) -> (f32, f32) {
    if max == 0.0 {
        return (0.0, 0.0);
    }
    #[allow(clippy::cast_possible_truncation)]
    let (limit, step) = (VECTOR_LIMIT as f32, (1.0 / VECTOR_LIMIT) as f32);
    // One division (the reciprocal of `max / 16383` would be a second one, dependent on the first):
    // `max · step` and `16383 / max` are each within an f32 rounding of the exact pair.
    let scale = max * step;
    if !max.is_finite() {
        (f32::NAN, 0.0)
    } else if scale < f32::MIN_POSITIVE {
        (f32::MIN_POSITIVE, 1.0 / f32::MIN_POSITIVE)
    } else {
        (scale, limit / max)
    }
}

/// `v` (with `|v| ≤ 16383.5`) rounded to the nearest integer, ties to even: what the vector kernels'
/// conversions (`cvtps2dq` under the default rounding mode) give.
#[inline(always)]
fn round_to_i16(v: f32) -> i16 {
    // In range by the caller's scale: the cast neither saturates nor truncates a fraction.
    #[allow(clippy::cast_possible_truncation)]
    let q = v.round_ties_even() as i16;
    q
}

/// Pass 2 of [`FixedVector::quantize_difference`] on one instruction set: `out[j] = round(d[j] · inverse)`
/// (ties to even) for a whole chunk. Written per instruction set because the compiled generic loop
/// narrowed the 32-bit integers to 16 bits lane by lane (`vpextrw`/`vpinsrw`), which cost more than the
/// arithmetic of both passes.
trait NarrowChunk: Copy {
    fn narrow_chunk(self, d: &[f32; CHUNK], inverse: f32, out: &mut [i16; CHUNK]);
}

impl NarrowChunk for pulp::Scalar {
    #[inline(always)]
    fn narrow_chunk(self, d: &[f32; CHUNK], inverse: f32, out: &mut [i16; CHUNK]) {
        for (dst, &d) in out.iter_mut().zip(d) {
            *dst = round_to_i16(d * inverse);
        }
    }
}

/// [`FixedVector::quantize_difference`] on one instruction set.
struct Quantize<'a, S> {
    simd: S,
    vector: &'a mut FixedVector,
    x: &'a [f32],
    mean: &'a [f32],
    chunks: usize,
}

impl<S: pulp::Simd + NarrowChunk> pulp::NullaryFnOnce for Quantize<'_, S> {
    type Output = ();

    #[inline(always)]
    fn call(self) {
        let Self {
            simd,
            vector,
            x,
            mean,
            chunks,
        } = self;
        vector.scales.resize(chunks, 0.0);
        vector.chunks.resize(chunks, Chunk::ZERO);
        vector.inverses.resize(chunks, 0.0);
        vector.differences.resize(x.len(), 0.0);
        let whole = x.len() / CHUNK;
        let split = whole * CHUNK;
        // Pass 1: the differences (kept, so pass 2 does not form them again), each chunk's largest
        // magnitude, and lane-wise sums of magnitudes: finite when every difference is (x86 `max`
        // ignores NaN, so the maxima alone would not tell).
        let mut sums = [simd.splat_f32s(0.0); 4];
        for (((x, mean), d), max_out) in x[..split]
            .chunks_exact(CHUNK)
            .zip(mean[..split].chunks_exact(CHUNK))
            .zip(vector.differences[..split].chunks_exact_mut(CHUNK))
            .zip(&mut vector.inverses)
        {
            // Whole groups of four registers: a chunk is 64 values, a multiple of four registers of any
            // width. Four sums, so that no addition waits on the previous one.
            let (x, mean, d) = (
                S::as_simd_f32s(x).0,
                S::as_simd_f32s(mean).0,
                S::as_mut_simd_f32s(d).0,
            );
            let mut max = simd.splat_f32s(0.0);
            for ((x, mean), d) in x
                .chunks_exact(4)
                .zip(mean.chunks_exact(4))
                .zip(d.chunks_exact_mut(4))
            {
                for (((&x, &mean), d), sum) in x.iter().zip(mean).zip(d).zip(&mut sums) {
                    *d = simd.sub_f32s(x, mean);
                    let magnitude = simd.abs_f32s(*d);
                    max = simd.max_f32s(max, magnitude);
                    *sum = simd.add_f32s(*sum, magnitude);
                }
            }
            *max_out = simd.reduce_max_f32s(max);
        }
        let mut rest_sum = 0.0f32;
        if let Some(max_out) = vector.inverses.get_mut(whole) {
            let mut max = 0.0f32;
            for ((&x, &mean), d) in x[split..]
                .iter()
                .zip(&mean[split..])
                .zip(&mut vector.differences[split..])
            {
                *d = x - mean;
                max = max.max(d.abs());
                rest_sum += d.abs();
            }
            *max_out = max;
        }
        if let Some(tail) = vector.inverses.get_mut(whole + 1..) {
            tail.fill(0.0);
        }
        for (scale, max_then_inverse) in vector.scales.iter_mut().zip(&mut vector.inverses) {
            (*scale, *max_then_inverse) = chunk_scale(*max_then_inverse);
        }
        // Pass 2: the integers.
        for ((d, &inverse), dst) in vector.differences[..split]
            .chunks_exact(CHUNK)
            .zip(&vector.inverses)
            .zip(&mut vector.chunks)
        {
            if let Ok(d) = <&[f32; CHUNK]>::try_from(d) {
                simd.narrow_chunk(d, inverse, dst);
            }
        }
        // The partial chunk (if any) and the padding chunks after it.
        if let Some(tail) = vector.chunks.get_mut(whole..) {
            tail.fill(Chunk::ZERO);
        }
        if let (Some(dst), Some(&inverse)) =
            (vector.chunks.get_mut(whole), vector.inverses.get(whole))
        {
            for (dst, &d) in dst.iter_mut().zip(&vector.differences[split..]) {
                *dst = round_to_i16(d * inverse);
            }
        }
        let sum = simd.add_f32s(
            simd.add_f32s(sums[0], sums[1]),
            simd.add_f32s(sums[2], sums[3]),
        );
        if !(simd.reduce_sum_f32s(sum) + rest_sum).is_finite() {
            vector.scales.fill(f32::NAN);
        }
    }
}

/// One way of multiplying chunks of 16-bit integers into f32 accumulators.
trait PairDot: Copy {
    /// Lane-wise f32 sums.
    type Acc: Copy;
    /// A chunk's scale in every lane.
    type Scale: Copy;
    fn zero(self) -> Self::Acc;
    fn splat(self, scale: f32) -> Self::Scale;
    /// `acc + scale · (the products w[j] x[j] of lane i)` for each lane: two pairs per lane (one from
    /// each half of the chunk), summed exactly in i32 (at most `4 · 32767 · 16383 < 2³¹`), converted to
    /// f32 and multiplied by the chunk's scale (one FMA).
    fn add_products(
        self,
        acc: Self::Acc,
        w: &[i16; CHUNK],
        x: &[i16; CHUNK],
        scale: Self::Scale,
    ) -> Self::Acc;
    fn add(self, a: Self::Acc, b: Self::Acc) -> Self::Acc;
    /// The sum of the lanes.
    fn sum(self, acc: Self::Acc) -> f32;
}

/// Runs a product inside pulp's `vectorize`, so the kernel is compiled for its instruction set.
struct Product<'a, K> {
    kernel: K,
    matrix: &'a FixedMatrix,
    xs: &'a [FixedVector],
    outs: &'a mut [f64],
}

impl<K: PairDot> pulp::NullaryFnOnce for Product<'_, K> {
    type Output = ();

    #[inline(always)]
    fn call(self) {
        self.matrix
            .times_vectors_with(self.kernel, self.xs, self.outs);
    }
}

#[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
mod x86 {
    use super::{CHUNK, NarrowChunk, PairDot};
    use pulp::Simd;
    use pulp::x86::{V3, V4};

    #[cfg(target_arch = "x86")]
    use core::arch::x86::{__m256, __m256i, __m512, __m512i};
    #[cfg(target_arch = "x86_64")]
    use core::arch::x86_64::{__m256, __m256i, __m512, __m512i};

    /// AVX-512: four registers of f32 scaled, converted (`vcvtps2dq`, nearest even) and narrowed
    /// (`vpmovdw`).
    impl NarrowChunk for V4 {
        #[inline(always)]
        fn narrow_chunk(self, d: &[f32; CHUNK], inverse: f32, out: &mut [i16; CHUNK]) {
            let d: [__m512; 4] = pulp::cast(*d);
            let inverse = self.avx512f._mm512_set1_ps(inverse);
            let narrowed: [__m256i; 4] = core::array::from_fn(|i| {
                let scaled = self.avx512f._mm512_mul_ps(d[i], inverse);
                self.avx512f
                    ._mm512_cvtepi32_epi16(self.avx512f._mm512_cvtps_epi32(scaled))
            });
            *out = pulp::cast(narrowed);
        }
    }

    /// AVX2: eight registers scaled and converted (`vcvtps2dq`), packed in pairs (`vpackssdw`, which
    /// interleaves 128-bit halves) and put back in order (`vpermq`).
    impl NarrowChunk for V3 {
        #[inline(always)]
        fn narrow_chunk(self, d: &[f32; CHUNK], inverse: f32, out: &mut [i16; CHUNK]) {
            let d: [__m256; 8] = pulp::cast(*d);
            let inverse = self.avx._mm256_set1_ps(inverse);
            let words = |i: usize| {
                self.avx
                    ._mm256_cvtps_epi32(self.avx._mm256_mul_ps(d[i], inverse))
            };
            let packed: [__m256i; 4] = core::array::from_fn(|i| {
                let pairs = self.avx2._mm256_packs_epi32(words(2 * i), words(2 * i + 1));
                self.avx2._mm256_permute4x64_epi64::<0b11_01_10_00>(pairs)
            });
            *out = pulp::cast(packed);
        }
    }

    /// AVX-512: a chunk is two registers (`vpmaddwd` each, `vpaddd`, `vcvtdq2ps`, `vfmadd`).
    impl PairDot for V4 {
        type Acc = pulp::f32x16;
        type Scale = pulp::f32x16;

        #[inline(always)]
        fn zero(self) -> Self::Acc {
            self.splat_f32s(0.0)
        }

        #[inline(always)]
        fn splat(self, scale: f32) -> Self::Scale {
            self.splat_f32s(scale)
        }

        #[inline(always)]
        fn add_products(
            self,
            acc: Self::Acc,
            w: &[i16; CHUNK],
            x: &[i16; CHUNK],
            scale: Self::Scale,
        ) -> Self::Acc {
            let w: [__m512i; 2] = pulp::cast(*w);
            let x: [__m512i; 2] = pulp::cast(*x);
            let pairs = self.avx512f._mm512_add_epi32(
                self.avx512bw._mm512_madd_epi16(w[0], x[0]),
                self.avx512bw._mm512_madd_epi16(w[1], x[1]),
            );
            let pairs: pulp::f32x16 = pulp::cast(self.avx512f._mm512_cvtepi32_ps(pairs));
            self.mul_add_e_f32s(pairs, scale, acc)
        }

        #[inline(always)]
        fn add(self, a: Self::Acc, b: Self::Acc) -> Self::Acc {
            self.add_f32s(a, b)
        }

        #[inline(always)]
        fn sum(self, acc: Self::Acc) -> f32 {
            self.reduce_sum_f32s(acc)
        }
    }

    /// AVX2: a chunk is four registers, summed in two accumulators.
    impl PairDot for V3 {
        type Acc = [pulp::f32x8; 2];
        type Scale = pulp::f32x8;

        #[inline(always)]
        fn zero(self) -> Self::Acc {
            [self.splat_f32x8(0.0); 2]
        }

        #[inline(always)]
        fn splat(self, scale: f32) -> Self::Scale {
            self.splat_f32x8(scale)
        }

        #[inline(always)]
        fn add_products(
            self,
            acc: Self::Acc,
            w: &[i16; CHUNK],
            x: &[i16; CHUNK],
            scale: Self::Scale,
        ) -> Self::Acc {
            let w: [__m256i; 4] = pulp::cast(*w);
            let x: [__m256i; 4] = pulp::cast(*x);
            core::array::from_fn(|h| {
                let pairs = self.avx2._mm256_add_epi32(
                    self.avx2._mm256_madd_epi16(w[h], x[h]),
                    self.avx2._mm256_madd_epi16(w[h + 2], x[h + 2]),
                );
                let pairs: pulp::f32x8 = pulp::cast(self.avx._mm256_cvtepi32_ps(pairs));
                self.mul_add_f32x8(pairs, scale, acc[h])
            })
        }

        #[inline(always)]
        fn add(self, a: Self::Acc, b: Self::Acc) -> Self::Acc {
            [self.add_f32x8(a[0], b[0]), self.add_f32x8(a[1], b[1])]
        }

        #[inline(always)]
        fn sum(self, acc: Self::Acc) -> f32 {
            self.reduce_sum_f32s(self.add_f32x8(acc[0], acc[1]))
        }
    }
}

/// Any CPU: the same pair sums, lane by lane.
#[derive(Clone, Copy, Debug)]
struct ScalarKernel;

impl PairDot for ScalarKernel {
    type Acc = [f32; CHUNK / 4];
    type Scale = f32;

    #[inline(always)]
    fn zero(self) -> Self::Acc {
        [0.0; CHUNK / 4]
    }

    #[inline(always)]
    fn splat(self, scale: f32) -> Self::Scale {
        scale
    }

    #[inline(always)]
    fn add_products(
        self,
        acc: Self::Acc,
        w: &[i16; CHUNK],
        x: &[i16; CHUNK],
        scale: Self::Scale,
    ) -> Self::Acc {
        // Lane i sums the pairs at 2i and CHUNK/2 + 2i, as the AVX-512 kernel does.
        core::array::from_fn(|i| {
            let sum: i32 = [2 * i, 2 * i + 1, CHUNK / 2 + 2 * i, CHUNK / 2 + 2 * i + 1]
                .iter()
                .map(|&j| i32::from(w[j]) * i32::from(x[j]))
                .sum();
            // The conversion of the exact integer sum to f32 is the rounding the SIMD kernels make.
            #[allow(clippy::cast_precision_loss)]
            let sum = sum as f32;
            sum.mul_add(scale, acc[i])
        })
    }

    #[inline(always)]
    fn add(self, a: Self::Acc, b: Self::Acc) -> Self::Acc {
        core::array::from_fn(|i| a[i] + b[i])
    }

    #[inline(always)]
    fn sum(self, acc: Self::Acc) -> f32 {
        acc.iter().sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernels::harness::{Backend, Harness, Scalar, X86V3, X86V4};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    type Run = Box<dyn Fn(&FixedMatrix, &[FixedVector], &mut [f64])>;

    /// The backends of both kernels (the product and the quantization): a scalar loop, AVX2, AVX-512.
    const BACKENDS: [Backend; 3] = [Scalar, X86V3, X86V4];

    /// Every kernel this CPU can run.
    fn kernels() -> Vec<(Backend, Run)> {
        let mut all: Vec<(Backend, Run)> = vec![(
            Scalar,
            Box::new(|m: &FixedMatrix, xs: &[FixedVector], outs: &mut [f64]| {
                m.times_vectors_with(ScalarKernel, xs, outs)
            }),
        )];
        #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
        {
            if let Some(simd) = pulp::x86::V3::try_new() {
                all.push((
                    X86V3,
                    Box::new(
                        move |m: &FixedMatrix, xs: &[FixedVector], outs: &mut [f64]| {
                            simd.vectorize(Product {
                                kernel: simd,
                                matrix: m,
                                xs,
                                outs,
                            })
                        },
                    ),
                ));
            }
            if let Some(simd) = pulp::x86::V4::try_new() {
                all.push((
                    X86V4,
                    Box::new(
                        move |m: &FixedMatrix, xs: &[FixedVector], outs: &mut [f64]| {
                            simd.vectorize(Product {
                                kernel: simd,
                                matrix: m,
                                xs,
                                outs,
                            })
                        },
                    ),
                ));
            }
        }
        all
    }

    fn quantized(d: &[f64], chunks: usize) -> FixedVector {
        let mut v = FixedVector::default();
        let d: Vec<f32> = d.iter().map(|&v| v as f32).collect();
        v.quantize_difference(&d, &vec![0.0; d.len()], chunks);
        v
    }

    #[test]
    fn each_value_is_within_half_a_step() {
        let values = [1.0, -0.333_333_333, 1e-7, -3e-5, 0.099_975, -0.5, 0.0];
        let m = FixedMatrix::from_f64(&values, 1, values.len());
        let step = 1.0 / LIMIT;
        for (col, &value) in values.iter().enumerate() {
            assert!((m.get(0, col) - value).abs() <= step / 2.0, "{value}");
        }
        // The largest magnitude is represented exactly, with the largest integer.
        assert_eq!(m.get(0, 0), 1.0);
        // Each chunk of a vector has its own scale: here 6 / 16383 and 1e-3 / 16383 (as f32).
        let mut d = vec![0.0; 2 * CHUNK];
        d[..3].copy_from_slice(&[3.0, -6.0, 0.5]);
        d[CHUNK] = 1e-3;
        d[CHUNK + 1] = -2.5e-4;
        let v = quantized(&d, 2);
        let scales = [(6.0 / VECTOR_LIMIT) as f32, (1e-3 / VECTOR_LIMIT) as f32];
        assert_eq!(v.scales, scales);
        let expected = |value: f64, k: usize| (value / f64::from(scales[k])).round() as i16;
        assert_eq!(
            v.chunks[0][..4],
            [expected(3.0, 0), -16383, expected(0.5, 0), 0]
        );
        assert_eq!(v.chunks[1][..3], [16383, expected(-2.5e-4, 1), 0]);
        // A chunk of zeros has scale 0; the padding of a short vector is zero.
        let v = quantized(&[0.0, 0.0, 1.0], 1);
        assert_eq!(v.chunks[0][..4], [0, 0, 16383, 0]);
    }

    /// Against the f64 product of the unquantized values, within the stated bound.
    #[test]
    fn matches_the_exact_product_within_the_stated_bound() {
        let mut harness = Harness::new("fixed_dot::times_vectors");
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for &(rows, cols) in &[
            (1, 1),
            (3, 5),
            (8, 32),
            (9, 33),
            (15, 63),
            (51, 1025),
            (2, 100),
            (7, 65),
        ] {
            let values: Vec<f64> = (0..rows * cols)
                .map(|_| rng.random_range(-1.0..1.0) * 10f64.powi(rng.random_range(-4..1)))
                .collect();
            let m = FixedMatrix::from_f64(&values, rows, cols);
            let ds: Vec<Vec<f64>> = (0..3)
                .map(|_| {
                    (0..cols)
                        .map(|_| rng.random_range(-1.0..1.0) * 10f64.powi(rng.random_range(-2..5)))
                        .collect()
                })
                .collect();
            let xs: Vec<FixedVector> = ds
                .iter()
                .map(|d| quantized(d, m.chunks_per_row()))
                .collect();
            // The oracle, the f64 product of the unquantized values, and the stated bound, chunk by
            // chunk, plus the f32 arithmetic: a few roundings of the sum of the magnitudes of the
            // represented terms.
            let mut exact = vec![0.0; xs.len() * rows];
            let mut bounds = vec![0.0; xs.len() * rows];
            for (v, (d, x)) in ds.iter().zip(&xs).enumerate() {
                for r in 0..rows {
                    let w = &values[r * cols..(r + 1) * cols];
                    exact[v * rows + r] = w.iter().zip(d).map(|(a, b)| a * b).sum();
                    let sum_abs_d: f64 = d.iter().map(|v| v.abs()).sum();
                    let s_r = m.scales[r];
                    let mut bound = 0.5 * s_r * sum_abs_d;
                    let mut represented = 0.0;
                    for (k, &t) in x.scales.iter().enumerate() {
                        let t = f64::from(t);
                        let columns = k * CHUNK..((k + 1) * CHUNK).min(cols);
                        let w_k: f64 = w[columns.clone()].iter().map(|v| v.abs()).sum();
                        bound += 0.5 * t * w_k + 0.25 * s_r * t * CHUNK as f64;
                        represented += columns
                            .map(|c| (m.get(r, c) * t * f64::from(x.chunks[k][c % CHUNK])).abs())
                            .sum::<f64>();
                    }
                    bounds[v * rows + r] = bound + 4e-6 * represented;
                }
            }
            for (backend, run) in kernels() {
                let mut outs = vec![f64::NAN; xs.len() * rows];
                run(&m, &xs, &mut outs);
                harness.compare(backend, &format!("{rows}x{cols}"), &outs, &exact, |i| {
                    bounds[i]
                });
            }
            let mut outs = vec![f64::NAN; xs.len() * rows];
            m.times_vectors(&xs, &mut outs);
            assert!(
                (0..outs.len()).all(|i| (outs[i] - exact[i]).abs() <= bounds[i]),
                "dispatched"
            );
        }
        harness.finish(&BACKENDS);
    }

    #[test]
    fn every_kernel_gives_the_pair_sums_exactly_on_small_integers() {
        // Integer matrix and vector whose largest values are the limit: everything is exact.
        let cols = 70;
        let w: Vec<f64> = (0..3 * cols)
            .map(|i| {
                if i % cols == 0 {
                    LIMIT
                } else {
                    (i % 7) as f64 - 3.0
                }
            })
            .collect();
        let m = FixedMatrix::from_f64(&w, 3, cols);
        let d: Vec<f64> = (0..cols)
            .map(|i| {
                if i % CHUNK == 1 {
                    -VECTOR_LIMIT
                } else {
                    (i % 5) as f64
                }
            })
            .collect();
        let x = quantized(&d, m.chunks_per_row());
        for (backend, run) in kernels() {
            let mut outs = vec![0.0; 3];
            run(&m, std::slice::from_ref(&x), &mut outs);
            for r in 0..3 {
                let exact: f64 = (0..cols).map(|c| w[r * cols + c] * d[c]).sum();
                assert_eq!(outs[r], exact, "{backend:?} row {r}");
            }
        }
    }

    /// The largest integers of both sides, signs aligned: each lane's integer sum over a chunk is
    /// `4 · 32767 · 16383`, just below 2³¹, and must not wrap.
    #[test]
    fn the_largest_products_do_not_overflow() {
        let cols = 3 * CHUNK;
        let m = FixedMatrix::from_f64(&vec![0.25; cols], 1, cols);
        for sign in [1.0, -1.0] {
            let x = quantized(&vec![sign * 7.0; cols], m.chunks_per_row());
            for (backend, run) in kernels() {
                let mut outs = [0.0];
                run(&m, std::slice::from_ref(&x), &mut outs);
                let exact = sign * 0.25 * 7.0 * cols as f64;
                assert!(
                    (outs[0] - exact).abs() <= 1e-6 * exact.abs(),
                    "{backend:?}: {outs:?}"
                );
            }
        }
    }

    #[test]
    fn batching_does_not_change_a_result() {
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        let (rows, cols) = (51, 1025);
        let values: Vec<f64> = (0..rows * cols)
            .map(|_| rng.random_range(-0.2..0.2))
            .collect();
        let m = FixedMatrix::from_f64(&values, rows, cols);
        let d: Vec<f64> = (0..cols).map(|_| rng.random_range(-1e4..1e4)).collect();
        let one = quantized(&d, m.chunks_per_row());
        let two = [one.clone(), quantized(&vec![1.0; cols], m.chunks_per_row())];
        for (backend, run) in kernels() {
            let mut single = vec![0.0; rows];
            run(&m, std::slice::from_ref(&one), &mut single);
            let mut pair = vec![0.0; 2 * rows];
            run(&m, &two, &mut pair);
            assert_eq!(
                single[..],
                pair[..rows],
                "{backend:?}: batching changed a result"
            );
        }
    }

    #[test]
    fn non_finite_vectors_give_nan_and_zero_vectors_zero() {
        let m = FixedMatrix::from_f64(&[1.0, 2.0, 3.0, 4.0], 2, 2);
        for bad in [f64::NAN, f64::INFINITY] {
            let x = quantized(&[1.0, bad], 1);
            let mut outs = [0.0; 2];
            m.times_vectors(std::slice::from_ref(&x), &mut outs);
            assert!(outs.iter().all(|v| v.is_nan()), "{bad}: {outs:?}");
        }
        let x = quantized(&[0.0, 0.0], 1);
        let mut outs = [1.0; 2];
        m.times_vectors(std::slice::from_ref(&x), &mut outs);
        assert_eq!(outs, [0.0; 2]);
        // In a whole chunk (the SIMD path) as in the last, partial one.
        let cols = CHUNK + 8;
        let m = FixedMatrix::from_f64(&vec![0.5; cols], 1, cols);
        for at in [3, CHUNK + 2] {
            for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                let mut d = vec![1.0; cols];
                d[at] = bad;
                let x = quantized(&d, m.chunks_per_row());
                let mut outs = [0.0];
                m.times_vectors(std::slice::from_ref(&x), &mut outs);
                assert!(outs[0].is_nan(), "{bad} at {at}: {outs:?}");
            }
        }
    }

    /// `d - mean` quantized by every instruction set this CPU has, by hand (`Quantize` on that set).
    fn quantized_by_each(d: &[f32], mean: &[f32], chunks: usize) -> Vec<(Backend, FixedVector)> {
        let run = |name, quantize: &dyn Fn(&mut FixedVector)| {
            let mut v = FixedVector::default();
            quantize(&mut v);
            (name, v)
        };
        let mut all = vec![run(Scalar, &|vector| {
            pulp::NullaryFnOnce::call(Quantize {
                simd: pulp::Scalar::new(),
                vector,
                x: d,
                mean,
                chunks,
            })
        })];
        #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
        {
            if let Some(simd) = pulp::x86::V3::try_new() {
                all.push(run(X86V3, &|vector| {
                    simd.vectorize(Quantize {
                        simd,
                        vector,
                        x: d,
                        mean,
                        chunks,
                    })
                }));
            }
            if let Some(simd) = pulp::x86::V4::try_new() {
                all.push(run(X86V4, &|vector| {
                    simd.vectorize(Quantize {
                        simd,
                        vector,
                        x: d,
                        mean,
                        chunks,
                    })
                }));
            }
        }
        all
    }

    /// Every instruction set gives the integers of the plain definition, `round(d · 16383 / max)` with
    /// ties to even, and the scales `max / 16383`, on whole and partial chunks, including ties, the
    /// largest magnitudes (±16383) and values that differ in sign only.
    #[test]
    fn every_instruction_set_quantizes_like_the_definition() {
        let mut rng = ChaCha8Rng::seed_from_u64(17);
        let len = 3 * CHUNK + 21;
        let mut x: Vec<f32> = (0..len).map(|_| rng.random_range(-1e4f32..1e4)).collect();
        let mean: Vec<f32> = (0..len).map(|_| rng.random_range(-1e3f32..1e3)).collect();
        // Chunk 1 holds exact ties: d = k + 0.5 steps with max 16383 (one step is 1).
        for (j, value) in x[CHUNK..2 * CHUNK].iter_mut().enumerate() {
            *value = mean[CHUNK + j] + (j as f32 - 32.0) + 0.5;
        }
        x[CHUNK] = mean[CHUNK] + 16383.0;
        x[CHUNK + 1] = mean[CHUNK + 1] - 16383.0;
        let chunks = len.div_ceil(CHUNK) + 1;
        let results = quantized_by_each(&x, &mean, chunks);
        // The oracle: the plain definition, exactly (tolerance 0), scales and integers.
        let mut want = Vec::new();
        for k in 0..chunks {
            let range = (k * CHUNK).min(len)..((k + 1) * CHUNK).min(len);
            let d: Vec<f32> = range.map(|i| x[i] - mean[i]).collect();
            let max = d.iter().fold(0.0f32, |m, v| m.max(v.abs()));
            let (scale, inverse) = chunk_scale(max);
            want.push(f64::from(scale));
            want.extend((0..CHUNK).map(|j| {
                f64::from(
                    d.get(j)
                        .map_or(0, |&d| (d * inverse).round_ties_even() as i16),
                )
            }));
        }
        let mut harness = Harness::new("fixed_dot::quantize_difference");
        for (backend, v) in &results {
            let got: Vec<f64> = v
                .scales
                .iter()
                .zip(&v.chunks)
                .flat_map(|(&scale, chunk)| {
                    std::iter::once(f64::from(scale)).chain(chunk.iter().map(|&q| f64::from(q)))
                })
                .collect();
            harness.compare(*backend, "3 chunks and 21", &got, &want, |_| 0.0);
        }
        harness.finish(&BACKENDS);
        // The ties of chunk 1 went to even integers.
        let (_, v) = &results[0];
        assert_eq!(&v.chunks[1][2..6], &[-30, -28, -28, -26]);
        assert_eq!(&v.chunks[1][..2], &[16383, -16383]);
    }

    #[test]
    fn empty_shapes() {
        let m = FixedMatrix::from_f64(&[], 3, 0);
        let x = quantized(&[], m.chunks_per_row());
        let mut outs = vec![1.0; 3];
        m.times_vectors(std::slice::from_ref(&x), &mut outs);
        assert_eq!(outs, [0.0; 3]);
        let m = FixedMatrix::from_f64(&[], 0, 4);
        m.times_vectors(std::slice::from_ref(&quantized(&[1.0; 4], 1)), &mut []);
        assert_eq!(m.rows(), 0);
    }
}
