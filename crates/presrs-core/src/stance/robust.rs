//! Robust statistics shared by the offline and the causal stance detectors: median, quantiles and the
//! noise sigma from the median absolute deviation. One definition, so that both detectors measure the
//! baseline and the noise alike.

/// Scale factor turning a median absolute deviation into a standard deviation for Gaussian noise.
pub(crate) const MAD_TO_SIGMA: f64 = 1.482_602_218_505_602;

/// Linearly interpolated quantile `level` in [0, 1] of `values` (reordered, by selection: O(n)). 0 for no
/// values.
pub(crate) fn quantile(values: &mut [f64], level: f64) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let position = level.clamp(0.0, 1.0) * (values.len() - 1) as f64;
    let below = position.floor() as usize;
    let weight = position - below as f64;
    let (_, low, rest) = values.select_nth_unstable_by(below, f64::total_cmp);
    let low = *low;
    // The next order statistic is the smallest of the rest; the largest value is its own neighbour.
    let high = rest.iter().copied().min_by(f64::total_cmp).unwrap_or(low);
    // Weighted, not `low + (high - low) * weight`: the sum of two large loads must not overflow.
    low * (1.0 - weight) + high * weight
}

/// Median of `values` (reordered): the mean of the two middle values for an even count; 0 for none.
pub(crate) fn median(values: &mut [f64]) -> f64 {
    quantile(values, 0.5)
}

/// Median of `values` and its robust sigma ([`MAD_TO_SIGMA`] x MAD). Reorders `values`; 0s for none.
pub(crate) fn median_and_sigma(values: &mut [f64]) -> (f64, f64) {
    let centre = median(values);
    for value in values.iter_mut() {
        *value = (*value - centre).abs();
    }
    (centre, MAD_TO_SIGMA * median(values))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantile_interpolates() {
        assert_eq!(quantile(&mut [3.0, 1.0, 2.0], 0.5), 2.0);
        assert_eq!(quantile(&mut [4.0, 1.0], 0.5), 2.5);
        assert_eq!(quantile(&mut [4.0, 1.0, 2.0, 3.0, 0.0], 0.0), 0.0);
        assert_eq!(quantile(&mut [4.0, 1.0, 2.0, 3.0, 0.0], 1.0), 4.0);
        assert_eq!(quantile(&mut [4.0, 1.0, 2.0, 3.0, 0.0], 0.1), 0.4);
        assert_eq!(quantile(&mut [], 0.3), 0.0);
    }

    /// Against the sorted-array definition (what both detectors used before they shared this module).
    #[test]
    fn quantile_matches_sorting() {
        let values: Vec<f64> = (0..97)
            .map(|i| ((i * 37) % 101) as f64 * 0.5 - 7.0)
            .collect();
        for n in [1, 2, 5, 10, 97] {
            let mut sorted = values[..n].to_vec();
            sorted.sort_unstable_by(f64::total_cmp);
            for level in [0.0, 0.1, 0.25, 0.5, 0.9, 1.0] {
                let position = level * (n - 1) as f64;
                let below = position.floor() as usize;
                let above = (below + 1).min(n - 1);
                let weight = position - below as f64;
                let expected = sorted[below] * (1.0 - weight) + sorted[above] * weight;
                let got = quantile(&mut values[..n].to_vec(), level);
                assert_eq!(got.to_bits(), expected.to_bits(), "n {n}, level {level}");
            }
        }
    }

    #[test]
    fn median_of_even_and_odd() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [4.0, 1.0, 3.0, 2.0]), 2.5);
        assert_eq!(median(&mut []), 0.0);
        // Two huge loads: their mean, not infinity.
        assert_eq!(median(&mut [f64::MAX, f64::MAX]), f64::MAX);
    }

    #[test]
    fn sigma_of_a_known_sample() {
        let (centre, sigma) = median_and_sigma(&mut [1.0, 2.0, 3.0, 4.0, 100.0]);
        assert_eq!(centre, 3.0);
        assert_eq!(sigma, MAD_TO_SIGMA * 1.0);
    }
}
