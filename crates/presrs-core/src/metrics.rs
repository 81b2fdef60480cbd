//! Plain summary metrics of classification results: mean and spread over repeats, the confusion matrix.
//!
//! A leaf: evaluation, automatic selection and the trained model's selection record all use these, and it
//! imports none of them (that import circle existed while `MeanStd` lived in the evaluation engine).

use serde::{Deserialize, Serialize};

/// Mean and spread over repeats.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MeanStd {
    pub mean: f64,
    pub std: f64,
}

impl MeanStd {
    /// Mean and sample standard deviation (0 for a single value).
    pub fn of(values: &[f64]) -> Self {
        if values.is_empty() {
            return Self::default();
        }
        let n = values.len() as f64;
        let mean = values.iter().sum::<f64>() / n;
        let std = if values.len() > 1 {
            (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
        } else {
            0.0
        };
        Self { mean, std }
    }
}

/// Counts of true class (rows) against predicted class (columns), summed over repeats.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Confusion {
    pub labels: Vec<String>,
    pub counts: Vec<Vec<u64>>,
}

impl Confusion {
    /// All zero, for `labels` in both directions.
    pub(crate) fn new(labels: Vec<String>) -> Self {
        let n = labels.len();
        Self {
            labels,
            counts: vec![vec![0; n]; n],
        }
    }

    /// Each row divided by its total (rows of an absent class stay 0).
    pub fn row_normalised(&self) -> Vec<Vec<f64>> {
        self.counts
            .iter()
            .map(|row| {
                let total: u64 = row.iter().sum();
                row.iter()
                    .map(|&c| {
                        if total == 0 {
                            0.0
                        } else {
                            c as f64 / total as f64
                        }
                    })
                    .collect()
            })
            .collect()
    }

    /// Recall of each class: correct / true count.
    pub fn recall(&self) -> Vec<f64> {
        (0..self.labels.len())
            .map(|i| ratio(self.counts[i][i], self.counts[i].iter().sum()))
            .collect()
    }

    /// Precision of each class: correct / predicted count.
    pub fn precision(&self) -> Vec<f64> {
        (0..self.labels.len())
            .map(|j| {
                ratio(
                    self.counts[j][j],
                    self.counts.iter().map(|row| row[j]).sum(),
                )
            })
            .collect()
    }
}

/// `num / den`, 0 for an empty denominator.
pub(crate) fn ratio(num: u64, den: u64) -> f64 {
    if den == 0 {
        0.0
    } else {
        num as f64 / den as f64
    }
}
