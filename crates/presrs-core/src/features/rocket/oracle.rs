//! MiniRocket by the definition, slowly: each convolution output is the dilated convolution summed
//! channel by channel and tap by tap, `C[t] = sum over channels, sum over k of w[k] x[t + (k - 4) d]`
//! (zero outside the series), each feature the share of counted outputs above its bias. No shared
//! sums, no SIMD, nothing reused between kernels: what the fast paths (`transform`, `fit`) are tested
//! against. Inputs are assumed checked (a fitted or loaded model, samples of its shape).

use super::kernels::{KERNEL_LENGTH, kernel_weights};
use super::model::{Combination, RocketModel};
use super::plan::{quantile_level, quantile_of_sorted};

/// The convolution output of `combination` at position `t` of `sample` (`channels x length`).
pub fn convolution_at(
    combination: &Combination<'_>,
    sample: &[f64],
    length: usize,
    t: usize,
) -> f64 {
    let weights = kernel_weights(combination.kernel);
    let mut sum = 0.0;
    for &channel in combination.channels {
        let series = &sample[channel * length..(channel + 1) * length];
        for (k, &weight) in weights.iter().enumerate() {
            let position = t as isize
                + (k as isize - (KERNEL_LENGTH / 2) as isize) * combination.dilation as isize;
            if (0..length as isize).contains(&position) {
                sum += weight * series[position as usize];
            }
        }
    }
    sum
}

/// The features of one sample by the definition.
pub fn transform(model: &RocketModel, sample: &[f64]) -> Vec<f64> {
    let length = model.length();
    let mut features = vec![0.0; model.output_len()];
    for combination in model.combinations() {
        let outputs: Vec<f64> = combination
            .outputs
            .clone()
            .map(|t| convolution_at(&combination, sample, length, t))
            .collect();
        for feature in combination.features.clone() {
            let bias = model.biases()[feature];
            let above = outputs.iter().filter(|&&value| value > bias).count();
            features[feature] = above as f64 / outputs.len() as f64;
        }
    }
    features
}

/// The biases by the definition, from the model's own choices (channels, examples) and its training
/// `samples`: each the quantile of its combination's zero-padded convolution of its example.
pub fn biases(model: &RocketModel, samples: &[f64]) -> Vec<f64> {
    let (length, sample_len) = (model.length(), model.sample_len());
    let mut biases = vec![0.0; model.output_len()];
    for combination in model.combinations() {
        let example = model.examples()[combination.index];
        let sample = &samples[example * sample_len..(example + 1) * sample_len];
        let mut outputs: Vec<f64> = (0..length)
            .map(|t| convolution_at(&combination, sample, length, t))
            .collect();
        outputs.sort_by(f64::total_cmp);
        for feature in combination.features.clone() {
            biases[feature] = quantile_of_sorted(&outputs, quantile_level(feature));
        }
    }
    biases
}
