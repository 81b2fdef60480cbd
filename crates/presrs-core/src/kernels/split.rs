//! The split step of the single-precision real FFT (the 1-D |FFT| features): from the half-length
//! complex spectrum `Z` to the magnitudes `|X[k]|`, as plain loops compiled for the CPU's instruction set.
//! `split_avx512` is the same step written out in AVX-512 registers.

use realfft::num_complex::Complex;

/// The split step of 1-D |FFT| (`features::fft1d`) on the pairs `(k, M-k)`, `0 < k < M-k`, and the output.
pub(crate) struct SplitSpectrum<'a> {
    pub(crate) z: &'a [Complex<f32>],
    pub(crate) twiddle_re: &'a [f32],
    pub(crate) twiddle_im: &'a [f32],
    pub(crate) low: &'a mut [f32],
    pub(crate) high: &'a mut [f32],
    /// `M + 1` magnitudes; the middle bin of an even `M` is left to the caller.
    pub(crate) out: &'a mut [f32],
}

impl pulp::WithSimd for SplitSpectrum<'_> {
    type Output = ();

    /// Plain loops, compiled with the instruction set `S` enables (pulp's dispatch), which the compiler
    /// vectorises (the magnitudes into `low`/`high`, then into `out` in order).
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        let Self {
            z,
            twiddle_re,
            twiddle_im,
            low,
            high,
            out,
        } = self;
        let pairs = low.len();
        let m = z.len();
        // Z[k] and Z[M-k] for k = 1 .. pairs, read straight from the spectrum.
        let inputs = z[1..pairs]
            .iter()
            .zip(z[m + 1 - pairs..m].iter().rev())
            .zip(twiddle_re[1..].iter().zip(&twiddle_im[1..]));
        for (((a, c), (&wr, &wi)), (lo, hi)) in
            inputs.zip(low[1..].iter_mut().zip(high[1..].iter_mut()))
        {
            (*lo, *hi) = split_pair(*a, *c, wr, wi);
        }
        out[0] = (z[0].re + z[0].im).abs();
        out[m] = (z[0].re - z[0].im).abs();
        out[1..pairs].copy_from_slice(&low[1..]);
        for (dst, &v) in out[m + 1 - pairs..m].iter_mut().zip(high[1..].iter().rev()) {
            *dst = v;
        }
    }
}

/// `(|X[k]|, |X[M-k]|)` from `a = Z[k]`, `c = Z[M-k]` and `W^k = (wr, wi)`.
#[inline(always)]
pub(crate) fn split_pair(a: Complex<f32>, c: Complex<f32>, wr: f32, wi: f32) -> (f32, f32) {
    let (ar, ai, cr, ci) = (a.re, a.im, c.re, c.im);
    let (even_re, even_im) = (0.5 * (ar + cr), 0.5 * (ai - ci));
    let (odd_re, odd_im) = (0.5 * (ai + ci), 0.5 * (cr - ar));
    let (t_re, t_im) = (wr * odd_re - wi * odd_im, wr * odd_im + wi * odd_re);
    let (p_re, p_im) = (even_re + t_re, even_im + t_im);
    let (q_re, q_im) = (even_re - t_re, even_im - t_im);
    (
        (p_re * p_re + p_im * p_im).sqrt(),
        (q_re * q_re + q_im * q_im).sqrt(),
    )
}
