//! The two inner loops of the MiniRocket transform (`features::rocket`), chosen at run time by the CPU
//! (pulp: scalar, AVX2, AVX-512):
//!
//! - [`sum_at_offsets`]: `out[t] = data[o0 + t] + data[o1 + t] + ...`, summed left to right in the
//!   order of the offsets. The transform builds every convolution output from such sums of shifted rows
//!   (the nine taps of a dilation, then a kernel's channel terms), so one kernel serves both;
//! - [`count_greater`]: `counts[f] = #{t : values[t] > thresholds[f]}`, the proportion of positive
//!   values before its division.
//!
//! Both vectorise over `t` and keep each output's own order of operations, so every backend gives the
//! same bits as the scalar loop (the harness checks it with tolerance 0). Nothing is allocated.

use pulp::{Arch, Simd, WithSimd};

/// Output registers summed at once per pass over the offsets of [`sum_at_offsets`] (then 4, 2, 1 for
/// what is left): independent chains of additions, and one walk over the offsets per block.
const SUM_BLOCK: usize = 8;

/// Thresholds compared at once per pass over the values of [`count_greater`].
const COUNT_BLOCK: usize = 8;

/// `out[t] = ((data[offsets[0] + t] + data[offsets[1] + t]) + ...) + data[offsets[m-1] + t]` for every
/// `t < out.len()`, the terms added in the order of `offsets`; `out` is zero for no offsets.
///
/// # Panics
/// If some `offsets[i] + out.len()` exceeds `data.len()`.
pub(crate) fn sum_at_offsets(data: &[f64], offsets: &[usize], out: &mut [f64]) {
    let len = out.len();
    assert!(
        offsets
            .iter()
            .all(|&offset| offset.checked_add(len).is_some_and(|end| end <= data.len())),
        "sum_at_offsets: an offset reads past the data"
    );
    Arch::new().dispatch(SumAtOffsets { data, offsets, out });
}

struct SumAtOffsets<'a> {
    data: &'a [f64],
    offsets: &'a [usize],
    out: &'a mut [f64],
}

impl WithSimd for SumAtOffsets<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let Self { data, offsets, out } = self;
        let Some((&first, rest)) = offsets.split_first() else {
            out.fill(0.0);
            return;
        };
        let lanes = S::F64_LANES;
        let mut start = 0;
        for registers in [SUM_BLOCK, 4, 2, 1] {
            while start + registers * lanes <= out.len() {
                match registers {
                    SUM_BLOCK => sum_block::<S, SUM_BLOCK>(simd, data, first, rest, start, out),
                    4 => sum_block::<S, 4>(simd, data, first, rest, start, out),
                    2 => sum_block::<S, 2>(simd, data, first, rest, start, out),
                    _ => sum_block::<S, 1>(simd, data, first, rest, start, out),
                }
                start += registers * lanes;
            }
        }
        let whole = start;
        for (t, dst) in out.iter_mut().enumerate().skip(whole) {
            *dst = rest
                .iter()
                .fold(data[first + t], |sum, &offset| sum + data[offset + t]);
        }
    }
}

/// Outputs `start .. start + R * lanes` of [`sum_at_offsets`], in `R` registers.
#[inline(always)]
fn sum_block<S: Simd, const R: usize>(
    simd: S,
    data: &[f64],
    first: usize,
    rest: &[usize],
    start: usize,
    out: &mut [f64],
) {
    let block = R * S::F64_LANES;
    let (head, _) = S::as_simd_f64s(&data[first + start..first + start + block]);
    let mut acc: [S::f64s; R] = core::array::from_fn(|r| head[r]);
    for &offset in rest {
        let (terms, _) = S::as_simd_f64s(&data[offset + start..offset + start + block]);
        for (a, &term) in acc.iter_mut().zip(terms) {
            *a = simd.add_f64s(*a, term);
        }
    }
    let (dst, _) = S::as_mut_simd_f64s(&mut out[start..start + block]);
    dst.copy_from_slice(&acc);
}

/// `counts[f] = ` the number of `values[t] > thresholds[f]` (a NaN value counts for none), for
/// `f < thresholds.len()`.
///
/// # Panics
/// If `counts` and `thresholds` differ in length.
pub(crate) fn count_greater(values: &[f64], thresholds: &[f64], counts: &mut [u64]) {
    assert_eq!(
        thresholds.len(),
        counts.len(),
        "count_greater: one count per threshold"
    );
    Arch::new().dispatch(CountGreater {
        values,
        thresholds,
        counts,
    });
}

struct CountGreater<'a> {
    values: &'a [f64],
    thresholds: &'a [f64],
    counts: &'a mut [u64],
}

impl WithSimd for CountGreater<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let Self {
            values,
            thresholds,
            counts,
        } = self;
        for (block, dst) in thresholds
            .chunks(COUNT_BLOCK)
            .zip(counts.chunks_mut(COUNT_BLOCK))
        {
            match block.len() {
                COUNT_BLOCK => count_block::<S, COUNT_BLOCK>(simd, values, block, dst),
                4..=7 => {
                    count_block::<S, 4>(simd, values, &block[..4], &mut dst[..4]);
                    count_rest::<S>(simd, values, &block[4..], &mut dst[4..]);
                }
                _ => count_rest::<S>(simd, values, block, dst),
            }
        }
    }
}

/// Thresholds in blocks of 2 then 1 (what a block of 4 or 8 leaves).
#[inline(always)]
fn count_rest<S: Simd>(simd: S, values: &[f64], thresholds: &[f64], counts: &mut [u64]) {
    let mut pairs = thresholds.chunks_exact(2);
    let mut dsts = counts.chunks_exact_mut(2);
    for (pair, dst) in (&mut pairs).zip(&mut dsts) {
        count_block::<S, 2>(simd, values, pair, dst);
    }
    if let ([threshold], [dst]) = (pairs.remainder(), dsts.into_remainder()) {
        count_block::<S, 1>(simd, values, &[*threshold], core::slice::from_mut(dst));
    }
}

/// [`count_greater`] for exactly `B` thresholds: each vector of values is loaded once and compared with
/// all of them; each comparison selects 1 or 0 into a lane's count.
#[inline(always)]
fn count_block<S: Simd, const B: usize>(
    simd: S,
    values: &[f64],
    thresholds: &[f64],
    counts: &mut [u64],
) {
    let splats: [S::f64s; B] = core::array::from_fn(|f| simd.splat_f64s(thresholds[f]));
    let (zero, one) = (simd.splat_u64s(0), simd.splat_u64s(1));
    let mut acc = [zero; B];
    let (head, tail) = S::as_simd_f64s(values);
    for &value in head {
        for (a, &threshold) in acc.iter_mut().zip(&splats) {
            let greater = simd.greater_than_f64s(value, threshold);
            *a = simd.add_u64s(*a, simd.select_u64s(greater, one, zero));
        }
    }
    let mut lanes = [0u64; 16];
    for f in 0..B {
        simd.partial_store_u64s(&mut lanes, acc[f]);
        let vector: u64 = lanes[..S::F64_LANES].iter().sum();
        let scalar = tail.iter().filter(|&&value| value > thresholds[f]).count() as u64;
        counts[f] = vector + scalar;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernels::harness::{
        Backend, Harness, Portable128, Portable256, Portable512, Scalar, X86V3, X86V4,
    };
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    const BACKENDS: [Backend; 6] = [Scalar, Portable128, Portable256, Portable512, X86V3, X86V4];

    /// The oracle: each output summed left to right, one at a time.
    fn naive_sum(data: &[f64], offsets: &[usize], out: &mut [f64]) {
        for (t, dst) in out.iter_mut().enumerate() {
            *dst = match offsets.split_first() {
                None => 0.0,
                Some((&first, rest)) => {
                    let mut sum = data[first + t];
                    for &offset in rest {
                        sum += data[offset + t];
                    }
                    sum
                }
            };
        }
    }

    /// Every backend gives the oracle's bits (tolerance 0: the order of each output's additions is the
    /// same), over lengths that leave every remainder of the block and the lanes, and 0 to 40 offsets.
    #[test]
    fn sum_at_offsets_matches_the_left_to_right_sum_bit_for_bit() {
        let mut harness = Harness::new("rocket::sum_at_offsets");
        let mut rng = ChaCha8Rng::seed_from_u64(33);
        let data: Vec<f64> = (0..1200)
            .map(|_| rng.random_range(-1.0..1.0) * 10f64.powi(rng.random_range(-4..=4)))
            .collect();
        for len in (0..=40).chain([63, 64, 65, 75, 128, 300]) {
            for terms in [0, 1, 2, 4, 9, 13, 36, 40] {
                let offsets: Vec<usize> = (0..terms)
                    .map(|_| rng.random_range(0..=data.len() - len))
                    .collect();
                let mut want = vec![f64::NAN; len];
                naive_sum(&data, &offsets, &mut want);
                for backend in BACKENDS {
                    let mut got = vec![f64::NAN; len];
                    let op = SumAtOffsets {
                        data: &data,
                        offsets: &offsets,
                        out: &mut got,
                    };
                    if backend.run(op).is_some() {
                        harness.compare(backend, &format!("{len} x {terms}"), &got, &want, |_| 0.0);
                    }
                }
                let mut got = vec![f64::NAN; len];
                sum_at_offsets(&data, &offsets, &mut got);
                assert_eq!(got, want, "dispatched {len} x {terms}");
            }
        }
        harness.finish(&BACKENDS);
    }

    #[test]
    #[should_panic(expected = "reads past the data")]
    fn sum_at_offsets_refuses_an_offset_past_the_end() {
        sum_at_offsets(&[1.0; 10], &[0, 3], &mut [0.0; 8]);
    }

    /// Every backend counts exactly what the definition counts, with ties (values equal to a
    /// threshold do not count), NaN values and every remainder of the blocks and lanes.
    #[test]
    fn count_greater_counts_exactly() {
        let mut harness = Harness::new("rocket::count_greater");
        let mut rng = ChaCha8Rng::seed_from_u64(34);
        for len in (0..=40).chain([63, 64, 65, 75, 128, 300]) {
            for thresholds_len in [0, 1, 2, 3, 4, 5, 7, 8, 9, 15, 17, 119] {
                // Small integers: many values tie with a threshold.
                let mut values: Vec<f64> = (0..len)
                    .map(|_| f64::from(rng.random_range(-5i32..=5)))
                    .collect();
                if len > 3 {
                    values[len / 2] = f64::NAN;
                }
                let thresholds: Vec<f64> = (0..thresholds_len)
                    .map(|_| f64::from(rng.random_range(-12i32..=12)) * 0.5)
                    .collect();
                let want: Vec<f64> = thresholds
                    .iter()
                    .map(|&b| values.iter().filter(|&&v| v > b).count() as f64)
                    .collect();
                for backend in BACKENDS {
                    let mut counts = vec![u64::MAX; thresholds_len];
                    let op = CountGreater {
                        values: &values,
                        thresholds: &thresholds,
                        counts: &mut counts,
                    };
                    if backend.run(op).is_some() {
                        let got: Vec<f64> = counts.iter().map(|&c| c as f64).collect();
                        let case = format!("{len} values, {thresholds_len} thresholds");
                        harness.compare(backend, &case, &got, &want, |_| 0.0);
                    }
                }
                let mut counts = vec![u64::MAX; thresholds_len];
                count_greater(&values, &thresholds, &mut counts);
                let got: Vec<f64> = counts.iter().map(|&c| c as f64).collect();
                assert_eq!(got, want, "dispatched");
            }
        }
        harness.finish(&BACKENDS);
    }
}
