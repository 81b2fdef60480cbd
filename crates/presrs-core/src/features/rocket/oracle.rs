//! MiniRocket by the definition, slowly: each convolution output is the dilated convolution summed
//! channel by channel and tap by tap, `C[t] = sum over channels, sum over k of w[k] x[t + (k - 4) d]`
//! (zero outside the series), each feature the share of counted outputs above its bias. No shared
//! sums, no SIMD, nothing reused between kernels: what the fast paths (`transform`, `fit`) are tested
//! against. Inputs are assumed checked (a fitted or loaded model, samples of its shape).

use super::kernels::{KERNEL_LENGTH, kernel_weights};
use super::model::{Combination, RocketModel};
use super::multi::{MultiRocketModel, POOLS};
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

/// MultiRocket's features of one sample by the definition: each representation (the series, then its
/// first differences computed here) convolved output by output, and each bias's four pooled values
/// computed from the list of outputs above and below it (see [`super::multi`]).
pub fn multi_transform(model: &MultiRocketModel, sample: &[f64]) -> Vec<f64> {
    let (channels, length) = (model.channels(), model.length());
    let differences: Vec<f64> = (0..channels)
        .flat_map(|c| {
            let row = &sample[c * length..(c + 1) * length];
            (1..length).map(move |t| row[t] - row[t - 1])
        })
        .collect();
    let mut features = Vec::with_capacity(model.output_len());
    for (rocket, series) in [
        (model.series(), sample),
        (model.differences(), &differences[..]),
    ] {
        let mut blocks = vec![vec![0.0; rocket.output_len()]; POOLS];
        for combination in rocket.combinations() {
            let outputs: Vec<f64> = combination
                .outputs
                .clone()
                .map(|t| convolution_at(&combination, series, rocket.length(), t))
                .collect();
            for feature in combination.features.clone() {
                let pooled = pooled_by_definition(&outputs, rocket.biases()[feature]);
                for (block, value) in blocks.iter_mut().zip(pooled) {
                    block[feature] = value;
                }
            }
        }
        features.extend(blocks.into_iter().flatten());
    }
    features
}

/// PPV, LSPV, MPV, MIPV of `outputs` against `bias`: the positions above it and below it listed,
/// then each operator from its list.
fn pooled_by_definition(outputs: &[f64], bias: f64) -> [f64; POOLS] {
    let above: Vec<usize> = (0..outputs.len()).filter(|&t| outputs[t] > bias).collect();
    let below: Vec<usize> = (0..outputs.len()).filter(|&t| outputs[t] < bias).collect();
    // The stretches between consecutive outputs below the bias, the first and last outputs as bounds.
    let bounds: Vec<usize> = std::iter::once(0)
        .chain(below.iter().copied())
        .chain(std::iter::once(outputs.len() - 1))
        .collect();
    let longest = bounds.windows(2).map(|w| w[1].saturating_sub(w[0])).max();
    let n = above.len() as f64;
    let ppv = n / outputs.len() as f64;
    if above.is_empty() {
        return [ppv, longest.unwrap_or(0) as f64, 0.0, -1.0];
    }
    let mpv = above.iter().map(|&t| outputs[t] + bias).sum::<f64>() / n;
    let mipv = above.iter().sum::<usize>() as f64 / n;
    [ppv, longest.unwrap_or(0) as f64, mpv, mipv]
}
