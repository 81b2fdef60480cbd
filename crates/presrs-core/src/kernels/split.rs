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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernels::harness::{
        Backend, Harness, Portable128, Portable256, Portable512, Scalar, X86V3, X86V4,
    };
    use rand::{Rng, SeedableRng};

    /// Both split steps (the compiled loop on every backend, the AVX-512 registers where the CPU has
    /// them) against the oracle, the split of the same spectrum in f64 with exact twiddles, within
    /// `1e-6` of the largest magnitude (f32 rounding), on lengths with no whole block of 8 pairs, whole
    /// blocks only, and blocks and a tail (odd and even `M`). The middle bin of an even `M` is the
    /// caller's and is not compared.
    #[test]
    fn every_split_step_matches_the_f64_split() {
        const LOOP: [Backend; 6] = [Scalar, Portable128, Portable256, Portable512, X86V3, X86V4];
        let mut compiled = Harness::new("split (compiled loop)");
        let mut registers = Harness::new("split_avx512");
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        for n in [2usize, 4, 6, 16, 34, 36, 66, 130, 1000, 2048, 2050] {
            let m = n / 2;
            let pairs = m.saturating_sub(1) / 2 + 1;
            let angle = |k: usize| -2.0 * std::f64::consts::PI * k as f64 / n as f64;
            let twiddle_re: Vec<f32> = (0..pairs).map(|k| angle(k).cos() as f32).collect();
            let twiddle_im: Vec<f32> = (0..pairs).map(|k| angle(k).sin() as f32).collect();
            let z: Vec<Complex<f32>> = (0..m)
                .map(|_| Complex::new(rng.random_range(-1e4..1e4), rng.random_range(-1e4..1e4)))
                .collect();
            let wide = |v: Complex<f32>| Complex::new(f64::from(v.re), f64::from(v.im));
            let mut want = vec![0.0; m + 1];
            want[0] = f64::from(z[0].re) + f64::from(z[0].im);
            want[m] = (f64::from(z[0].re) - f64::from(z[0].im)).abs();
            want[0] = want[0].abs();
            for k in 1..pairs {
                let (a, c) = (wide(z[k]), wide(z[m - k]).conj());
                let (even, odd) = ((a + c) * 0.5, (a - c) * Complex::new(0.0, -0.5));
                let w = Complex::new(angle(k).cos(), angle(k).sin());
                want[k] = (even + w * odd).norm();
                want[m - k] = (even - w * odd).norm();
            }
            let largest = want.iter().copied().fold(0.0, f64::max);
            let case = format!("n {n}");
            let compare = |harness: &mut Harness, backend, got: &[f32]| {
                let mut got: Vec<f64> = got.iter().map(|&v| f64::from(v)).collect();
                if m % 2 == 0 && m > 0 {
                    got[m / 2] = want[m / 2];
                }
                harness.compare(backend, &case, &got, &want, |_| 1e-6 * largest);
            };
            for backend in LOOP {
                let (mut low, mut high) = (vec![0.0; pairs], vec![0.0; pairs]);
                let mut got = vec![f32::NAN; m + 1];
                let run = backend.run(SplitSpectrum {
                    z: &z,
                    twiddle_re: &twiddle_re,
                    twiddle_im: &twiddle_im,
                    low: &mut low,
                    high: &mut high,
                    out: &mut got,
                });
                if run.is_some() {
                    compare(&mut compiled, backend, &got);
                }
            }
            #[cfg(target_arch = "x86_64")]
            if let Some(split) = super::super::SplitAvx512::new(&twiddle_re, &twiddle_im, m) {
                let mut got = vec![f32::NAN; m + 1];
                split.run(&z, &mut got);
                compare(&mut registers, X86V4, &got);
            }
        }
        compiled.finish(&LOOP);
        registers.finish(&[X86V4]);
    }
}
