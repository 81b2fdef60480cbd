//! What a MiniRocket model takes from the series length and the configuration alone (no data, no
//! randomness): the dilations, how many features each dilation gets, and the quantile level of each
//! bias. As the paper and aeon's MiniRocket do.

use super::kernels::KERNEL_LENGTH;

/// The dilations, ascending and distinct, and the features (biases) per kernel at each of them, for
/// series of `length >= 9` values, `features_per_kernel >= 1` and `max_dilations >= 1`.
///
/// Up to `min(features_per_kernel, max_dilations)` dilations are spaced exponentially from 1 to
/// `(length - 1) / 8` (the largest whose kernel of 9 taps spans at most the series) and truncated to
/// integers; a dilation that repeats is kept once and gets the features of each repeat. The features
/// are shared out in proportion, the remainder one at a time from the smallest dilation.
pub fn dilations(
    length: usize,
    features_per_kernel: usize,
    max_dilations: usize,
) -> (Vec<usize>, Vec<usize>) {
    let count = features_per_kernel.min(max_dilations).max(1);
    let multiplier = features_per_kernel as f64 / count as f64;
    let span = (KERNEL_LENGTH - 1) as f64;
    let max_exponent = (length.saturating_sub(1) as f64 / span).max(1.0).log2();
    let step = if count > 1 {
        max_exponent / (count - 1) as f64
    } else {
        0.0
    };
    let mut dilations: Vec<usize> = Vec::with_capacity(count);
    let mut repeats: Vec<usize> = Vec::with_capacity(count);
    for i in 0..count {
        let exponent = if i + 1 == count && count > 1 {
            max_exponent
        } else {
            i as f64 * step
        };
        // Truncation, as the reference does; the largest is at most (length - 1) / 8.
        let dilation = (2f64.powf(exponent) as usize).clamp(1, max_dilation(length));
        if dilations.last() == Some(&dilation) {
            if let Some(last) = repeats.last_mut() {
                *last += 1;
            }
        } else {
            dilations.push(dilation);
            repeats.push(1);
        }
    }
    let mut features: Vec<usize> = repeats
        .iter()
        .map(|&repeat| (repeat as f64 * multiplier) as usize)
        .collect();
    let mut remainder = features_per_kernel.saturating_sub(features.iter().sum());
    let mut i = 0;
    while remainder > 0 {
        features[i] += 1;
        remainder -= 1;
        i = (i + 1) % features.len();
    }
    (dilations, features)
}

/// The largest dilation for series of `length` values: `(length - 1) / 8` (at least 1), so that the
/// 9 taps `t - 4d ..= t + 4d` of an output inside the series fit in it.
pub fn max_dilation(length: usize) -> usize {
    (length.saturating_sub(1) / (KERNEL_LENGTH - 1)).max(1)
}

/// The quantile level of bias `index` (counted over the whole feature vector): the fractional part of
/// `(index + 1) * golden ratio`, a low-discrepancy sequence in `(0, 1)`.
pub fn quantile_level(index: usize) -> f64 {
    let golden = (5f64.sqrt() + 1.0) / 2.0;
    ((index + 1) as f64 * golden).rem_euclid(1.0)
}

/// The `level` quantile of ascending `sorted` values (non-empty), interpolated linearly between the
/// two nearest order statistics (numpy's default, `method="linear"`).
pub fn quantile_of_sorted(sorted: &[f64], level: f64) -> f64 {
    let last = sorted.len().saturating_sub(1);
    let position = level * last as f64;
    let below = (position.floor() as usize).min(last);
    let above = (below + 1).min(last);
    let fraction = position - below as f64;
    sorted[below] + (sorted[above] - sorted[below]) * fraction
}

#[cfg(test)]
mod tests {
    use super::*;

    /// aeon's `_fit_dilations` on the same inputs, as numpy gives them (`np.unique(np.logspace(0,
    /// np.log2((n - 1) / 8), min(f, 32), base=2).astype(np.int32), return_counts=True)`, the counts
    /// times `f / min(f, 32)` truncated, the remainder shared from the first).
    #[test]
    fn dilations_follow_the_reference() {
        assert_eq!(dilations(9, 119, 32), (vec![1], vec![119]));
        let expected = [
            (
                129,
                vec![1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 16],
                vec![30, 19, 12, 8, 12, 4, 8, 4, 4, 3, 3, 3, 3, 3, 3],
            ),
            (
                128,
                vec![1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15],
                vec![30, 19, 12, 12, 8, 4, 8, 4, 4, 3, 3, 3, 3, 3, 3],
            ),
            (
                75,
                vec![1, 2, 3, 4, 5, 6, 7, 8, 9],
                vec![38, 23, 15, 12, 7, 11, 3, 7, 3],
            ),
        ];
        for (length, d, f) in expected {
            assert_eq!(dilations(length, 119, 32), (d, f), "length {length}");
        }
        // Fewer features per kernel than max dilations: one dilation per feature.
        let (d, f) = dilations(1000, 3, 32);
        assert_eq!(d, vec![1, 11, 124]);
        assert_eq!(f, vec![1, 1, 1]);
        for length in 9..400 {
            for per_kernel in [1, 2, 5, 30, 119, 500] {
                let (d, f) = dilations(length, per_kernel, 32);
                assert!(d.windows(2).all(|w| w[0] < w[1]));
                assert!(d.iter().all(|&d| d >= 1 && 8 * d < length));
                assert_eq!(f.iter().sum::<usize>(), per_kernel, "{length} {per_kernel}");
                assert!(f.iter().all(|&f| f >= 1));
            }
        }
    }

    #[test]
    fn quantiles_are_the_golden_ratio_sequence_and_numpy_linear() {
        assert!((quantile_level(0) - 0.618_033_988_749_895).abs() < 1e-15);
        assert!((quantile_level(1) - 0.236_067_977_499_789_8).abs() < 1e-15);
        let sorted = [1.0, 2.0, 4.0, 8.0, 16.0];
        assert_eq!(quantile_of_sorted(&sorted, 0.0), 1.0);
        assert_eq!(quantile_of_sorted(&sorted, 1.0), 16.0);
        assert_eq!(quantile_of_sorted(&sorted, 0.5), 4.0);
        assert_eq!(quantile_of_sorted(&sorted, 0.625), 6.0);
        assert_eq!(quantile_of_sorted(&[3.0], 0.3), 3.0);
    }
}
