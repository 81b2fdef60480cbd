//! The split step of 1-D |FFT| (`features::fft1d`) written out in AVX-512 registers: the compiled loop of
//! `SplitSpectrum` (`kernels::split`) reverses `Z[M-k]` and gathers real and imaginary parts value by value, and took
//! about a third of the time of the transform itself.
//!
//! A block is 8 consecutive `k`: `A = Z[k ..]`, `C = Z[M-k-7 ..]` reversed (one `vpermpd`), then with
//! `S = A + conj C`, `D = A - conj C` and `V = -i W^k` (stored as (re, re) and (im, im) lane pairs),
//! `2 X[k] = S + V D` and `2 conj X[M-k] = S - V D`; the squared parts of both are gathered into one
//! register (`X[M-k]` reversed, so that both halves land in ascending order) and one square root gives
//! 16 magnitudes, stored as two halves.

use pulp::Simd;
use pulp::x86::V4;
use realfft::num_complex::Complex;

use super::aligned::Aligned;
use super::radix4::avx512::{from_ps, ps, times};
use super::split::split_pair;

#[derive(Clone, Debug)]
pub(crate) struct Split {
    simd: V4,
    /// `V = -i W^k = (wi, -wr)` for `k = 0 .. pairs`, each value twice: the (re, re) and (im, im)
    /// registers of [`times`]. The scalar tail reads `W^k` back from them.
    v_re: Aligned<f32>,
    v_im: Aligned<f32>,
    m: usize,
}

impl Split {
    /// For the real transform whose pairs have the twiddles `W^k = (twiddle_re[k], twiddle_im[k])`
    /// and whose complex FFT has length `m`; `None` without AVX-512.
    pub(crate) fn new(twiddle_re: &[f32], twiddle_im: &[f32], m: usize) -> Option<Self> {
        let simd = V4::try_new()?;
        let v_re: Vec<f32> = twiddle_im.iter().flat_map(|&wi| [wi, wi]).collect();
        let v_im: Vec<f32> = twiddle_re.iter().flat_map(|&wr| [-wr, -wr]).collect();
        let (v_re, v_im) = (Aligned::from_slice(&v_re), Aligned::from_slice(&v_im));
        Some(Self {
            simd,
            v_re,
            v_im,
            m,
        })
    }

    /// `out[k] = |X[k]|` for `k = 0 ..= M` except the middle bin of an even `M` (left to the caller).
    ///
    /// # Panics
    /// If `z` is not `M` long or `out` not `M + 1`.
    pub(crate) fn run(&self, z: &[Complex<f32>], out: &mut [f32]) {
        assert!(
            z.len() == self.m && out.len() == self.m + 1,
            "split: wrong lengths"
        );
        self.simd.vectorize(Run {
            split: self,
            z,
            out,
        });
    }
}

struct Run<'a> {
    split: &'a Split,
    z: &'a [Complex<f32>],
    out: &'a mut [f32],
}

impl pulp::NullaryFnOnce for Run<'_> {
    type Output = ();

    #[inline(always)]
    fn call(self) {
        let Self { split, z, out } = self;
        let (simd, m) = (split.simd, split.m);
        let f = simd.avx512f;
        let pairs = split.v_re.len() / 2;
        out[0] = (z[0].re + z[0].im).abs();
        out[m] = (z[0].re - z[0].im).abs();
        // Blocks of 8 pairs from k = 1.
        let blocks = (pairs - 1) / 8;
        let ascending = V4::as_simd_c32s(&z[1..1 + 8 * blocks]).0;
        let descending = V4::as_simd_c32s(&z[m - 8 * blocks..m]).0;
        let v_re = V4::as_simd_f32s(&split.v_re[2..2 + 16 * blocks]).0;
        let v_im = V4::as_simd_f32s(&split.v_im[2..2 + 16 * blocks]).0;
        let (head, tail) = out.split_at_mut(m - 8 * blocks);
        let low = head[1..1 + 8 * blocks].chunks_exact_mut(8);
        let high = tail[..8 * blocks].chunks_exact_mut(8);
        let reverse = f._mm512_setr_epi64(7, 6, 5, 4, 3, 2, 1, 0);
        // The sign bit of each imaginary part.
        let conjugate = f._mm512_castsi512_ps(f._mm512_set1_epi64(i64::MIN));
        // Lanes 0..8: |X[k]|² halves (even, odd lanes of P²); lanes 8..16: those of Q², reversed.
        let even = f._mm512_setr_epi32(0, 2, 4, 6, 8, 10, 12, 14, 30, 28, 26, 24, 22, 20, 18, 16);
        let odd = f._mm512_setr_epi32(1, 3, 5, 7, 9, 11, 13, 15, 31, 29, 27, 25, 23, 21, 19, 17);
        let half = f._mm512_set1_ps(0.5);
        for ((((&a, &c), (&vr, &vi)), low), high) in ascending
            .iter()
            .zip(descending.iter().rev())
            .zip(v_re.iter().zip(v_im))
            .zip(low)
            .zip(high.rev())
        {
            let c = f._mm512_castpd_ps(f._mm512_permutexvar_pd(reverse, f._mm512_castps_pd(ps(c))));
            let c_conj = simd.avx512dq._mm512_xor_ps(c, conjugate);
            let s = f._mm512_add_ps(ps(a), c_conj);
            let d = f._mm512_sub_ps(ps(a), c_conj);
            let t = ps(times(simd, from_ps(d), vr, vi));
            let p = f._mm512_add_ps(s, t);
            let q = f._mm512_sub_ps(s, t);
            let (p2, q2) = (f._mm512_mul_ps(p, p), f._mm512_mul_ps(q, q));
            let sums = f._mm512_add_ps(
                f._mm512_permutex2var_ps(p2, even, q2),
                f._mm512_permutex2var_ps(p2, odd, q2),
            );
            let magnitudes = f._mm512_mul_ps(f._mm512_sqrt_ps(sums), half);
            let magnitudes: [[f32; 8]; 2] = pulp::cast(magnitudes);
            low.copy_from_slice(&magnitudes[0]);
            high.copy_from_slice(&magnitudes[1]);
        }
        // The pairs after the last whole block.
        for k in 1 + 8 * blocks..pairs {
            let (wr, wi) = (-split.v_im[2 * k], split.v_re[2 * k]);
            let (lo, hi) = split_pair(z[k], z[m - k], wr, wi);
            out[k] = lo;
            out[m - k] = hi;
        }
    }
}
