//! How far to trust the confidences a model reports: a reliability tally of (confidence, right or wrong)
//! pairs, with the expected calibration error over equal-width confidence bins (Naeini et al. 2015; Guo
//! et al. 2017). A calibrated model is right in about 90 % of the images it gives a confidence near 0.9.

use serde::{Deserialize, Serialize};

/// Equal-width confidence bins of [`Reliability`]: `[0, 0.1), [0.1, 0.2), ..., [0.9, 1]`.
pub const BINS: usize = 10;

/// One confidence bin.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ReliabilityBin {
    /// Predictions whose confidence fell in this bin.
    pub count: u64,
    /// Sum of their confidences.
    pub confidence_sum: f64,
    /// How many of them were right.
    pub right: u64,
}

impl ReliabilityBin {
    /// Mean confidence of the bin's predictions (`None` when empty).
    pub fn mean_confidence(&self) -> Option<f64> {
        (self.count > 0).then(|| self.confidence_sum / self.count as f64)
    }

    /// Share of the bin's predictions that were right (`None` when empty).
    pub fn accuracy(&self) -> Option<f64> {
        (self.count > 0).then(|| self.right as f64 / self.count as f64)
    }
}

/// A tally of predictions' confidences against whether they were right. Merging two tallies gives the
/// tally of both sets of predictions.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Reliability {
    /// [`BINS`] equal-width bins over `[0, 1]`.
    pub bins: Vec<ReliabilityBin>,
    /// Sums over the right and the wrong predictions: (count, confidence sum).
    pub right: (u64, f64),
    pub wrong: (u64, f64),
}

impl Default for Reliability {
    fn default() -> Self {
        Self {
            bins: vec![ReliabilityBin::default(); BINS],
            right: (0, 0.0),
            wrong: (0, 0.0),
        }
    }
}

impl Reliability {
    /// Adds one prediction: its confidence (clamped to `[0, 1]`; NaN counts as 0) and whether it was right.
    pub fn add(&mut self, confidence: f64, right: bool) {
        let confidence = if confidence.is_nan() {
            0.0
        } else {
            confidence.clamp(0.0, 1.0)
        };
        // The last bin is closed: a confidence of exactly 1 belongs to [0.9, 1].
        let index = ((confidence * BINS as f64) as usize).min(BINS - 1);
        if self.bins.len() != BINS {
            self.bins = vec![ReliabilityBin::default(); BINS];
        }
        let bin = &mut self.bins[index];
        bin.count += 1;
        bin.confidence_sum += confidence;
        let side = if right {
            bin.right += 1;
            &mut self.right
        } else {
            &mut self.wrong
        };
        side.0 += 1;
        side.1 += confidence;
    }

    /// Adds every prediction of `other`.
    pub fn merge(&mut self, other: &Reliability) {
        if self.bins.len() != BINS {
            self.bins = vec![ReliabilityBin::default(); BINS];
        }
        for (bin, theirs) in self.bins.iter_mut().zip(&other.bins) {
            bin.count += theirs.count;
            bin.confidence_sum += theirs.confidence_sum;
            bin.right += theirs.right;
        }
        self.right.0 += other.right.0;
        self.right.1 += other.right.1;
        self.wrong.0 += other.wrong.0;
        self.wrong.1 += other.wrong.1;
    }

    /// Number of predictions tallied.
    pub fn count(&self) -> u64 {
        self.right.0 + self.wrong.0
    }

    /// Mean confidence of every prediction (`None` when none).
    pub fn mean_confidence(&self) -> Option<f64> {
        let n = self.count();
        (n > 0).then(|| (self.right.1 + self.wrong.1) / n as f64)
    }

    /// Share of the predictions that were right (`None` when none).
    pub fn accuracy(&self) -> Option<f64> {
        let n = self.count();
        (n > 0).then(|| self.right.0 as f64 / n as f64)
    }

    /// Mean confidence of the right predictions (`None` when none was right).
    pub fn mean_confidence_right(&self) -> Option<f64> {
        (self.right.0 > 0).then(|| self.right.1 / self.right.0 as f64)
    }

    /// Mean confidence of the wrong predictions (`None` when none was wrong).
    pub fn mean_confidence_wrong(&self) -> Option<f64> {
        (self.wrong.0 > 0).then(|| self.wrong.1 / self.wrong.0 as f64)
    }

    /// Expected calibration error: the count-weighted mean over the bins of |accuracy - mean confidence|
    /// (0: calibrated; `None` when no prediction was tallied).
    pub fn expected_calibration_error(&self) -> Option<f64> {
        let n = self.count();
        (n > 0).then(|| {
            self.bins
                .iter()
                .filter(|bin| bin.count > 0)
                .map(|bin| (bin.right as f64 - bin.confidence_sum).abs())
                .sum::<f64>()
                / n as f64
        })
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    /// The definition, from the list of predictions.
    fn naive_ece(predictions: &[(f64, bool)]) -> f64 {
        let mut total = 0.0;
        for b in 0..BINS {
            let lo = b as f64 / BINS as f64;
            let hi = (b + 1) as f64 / BINS as f64;
            let members: Vec<&(f64, bool)> = predictions
                .iter()
                .filter(|(c, _)| *c >= lo && (*c < hi || (b == BINS - 1 && *c <= hi)))
                .collect();
            if members.is_empty() {
                continue;
            }
            let m = members.len() as f64;
            let conf = members.iter().map(|(c, _)| c).sum::<f64>() / m;
            let acc = members.iter().filter(|(_, r)| *r).count() as f64 / m;
            total += m * (acc - conf).abs();
        }
        total / predictions.len() as f64
    }

    fn pseudo_random(n: usize) -> Vec<(f64, bool)> {
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        (0..n)
            .map(|_| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                let confidence = (state >> 11) as f64 / (1u64 << 53) as f64;
                (confidence, state % 3 != 0)
            })
            .collect()
    }

    #[test]
    fn the_tally_matches_the_definition_and_merges() {
        let predictions = pseudo_random(1000);
        let mut all = Reliability::default();
        let (mut first, mut second) = (Reliability::default(), Reliability::default());
        for (i, &(c, r)) in predictions.iter().enumerate() {
            all.add(c, r);
            if i < 400 { &mut first } else { &mut second }.add(c, r);
        }
        assert!(
            (all.expected_calibration_error().unwrap() - naive_ece(&predictions)).abs() < 1e-12
        );
        first.merge(&second);
        for (merged, whole) in first.bins.iter().zip(&all.bins) {
            assert_eq!((merged.count, merged.right), (whole.count, whole.right));
            assert!((merged.confidence_sum - whole.confidence_sum).abs() < 1e-9);
        }
        assert_eq!((first.right.0, first.wrong.0), (all.right.0, all.wrong.0));
        assert_eq!(all.count(), 1000);
        let right = predictions.iter().filter(|p| p.1).count();
        assert_eq!(all.accuracy().unwrap(), right as f64 / 1000.0);
        let mean_right =
            predictions.iter().filter(|p| p.1).map(|p| p.0).sum::<f64>() / right as f64;
        assert!((all.mean_confidence_right().unwrap() - mean_right).abs() < 1e-12);
    }

    #[test]
    fn calibrated_and_overconfident_tallies() {
        // 0.8 confident and right 8 times in 10: calibrated. Confidence 1 and right half the time: 0.5 off.
        let mut calibrated = Reliability::default();
        let mut overconfident = Reliability::default();
        for i in 0..100 {
            calibrated.add(0.8, i % 10 < 8);
            overconfident.add(1.0, i % 2 == 0);
        }
        assert!(calibrated.expected_calibration_error().unwrap() < 1e-12);
        assert!((overconfident.expected_calibration_error().unwrap() - 0.5).abs() < 1e-12);
        assert_eq!(overconfident.bins[BINS - 1].count, 100);
        assert_eq!(Reliability::default().expected_calibration_error(), None);
        let mut odd = Reliability::default();
        odd.add(f64::NAN, false);
        odd.add(1.5, true);
        assert_eq!(odd.bins[0].count, 1);
        assert_eq!(odd.bins[BINS - 1].count, 1);
    }
}
