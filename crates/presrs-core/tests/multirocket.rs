//! MultiRocket (`features::rocket::multi`): the fast transform and the fit against the slow oracle (the
//! definition), and the transform against aeon's on aeon's own fitted parameters
//! (`fixtures/multirocket/make_fixture.py`).

#![allow(clippy::unwrap_used, clippy::expect_used)]

use presrs_core::features::rocket::{
    MultiRocketConfig, MultiRocketModel, RocketConfig, RocketModel, oracle,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::{Value, json};

fn samples(count: usize, channels: usize, length: usize, integers: bool, seed: u64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..count * channels * length)
        .map(|_| {
            if integers {
                f64::from(rng.random_range(-3i32..=3))
            } else {
                rng.random_range(-1.0..1.0) * 10f64.powi(rng.random_range(-1..=1))
            }
        })
        .collect()
}

fn config(biases_per_kernel: usize, seed: u64) -> MultiRocketConfig {
    MultiRocketConfig {
        num_features: 8 * 84 * biases_per_kernel,
        seed,
        ..MultiRocketConfig::default()
    }
}

/// The largest difference between the fast transform and the oracle over `sets` of samples.
fn worst_difference(model: &MultiRocketModel, sets: &[&[f64]]) -> f64 {
    let mut scratch = model.scratch();
    let mut fast = vec![f64::NAN; model.output_len()];
    let mut worst = 0f64;
    for sample in sets
        .iter()
        .flat_map(|set| set.chunks_exact(model.sample_len()))
    {
        model
            .transform_into(sample, &mut fast, &mut scratch)
            .unwrap();
        let slow = oracle::multi_transform(model, sample);
        assert_eq!(slow.len(), fast.len());
        for (f, s) in fast.iter().zip(&slow) {
            worst = worst.max((f - s).abs() / (1.0 + s.abs()));
        }
    }
    worst
}

/// The fast transform gives the oracle's four pooled values of every bias, for 1 to 11 channels,
/// lengths 10 to 200, continuous values and small integers (outputs equal to a bias: the LSPV's
/// breaks), on the training samples (whose convolutions gave the biases) and on fresh ones.
#[test]
fn fast_transform_matches_the_oracle() {
    for (case, &(channels, length)) in [
        (1, 10),
        (2, 17),
        (3, 40),
        (1, 75),
        (7, 64),
        (11, 128),
        (2, 200),
    ]
    .iter()
    .enumerate()
    {
        for integers in [false, true] {
            let seed = case as u64;
            let train = samples(3, channels, length, integers, 300 + seed);
            let fresh = samples(2, channels, length, integers, 400 + seed);
            let model = MultiRocketModel::fit(&config(4, seed), &train, channels, length).unwrap();
            assert_eq!(model.differences().length(), length - 1);
            assert_eq!(model.output_len(), 8 * 84 * 4);
            let worst = worst_difference(&model, &[&train, &fresh]);
            assert!(
                worst <= 1e-12,
                "{channels} x {length} integers {integers}: off by {worst:e}"
            );
        }
    }
}

/// Each representation's biases are the oracle's quantiles: the series' of the series, the
/// differences' of the first differences; the two draw their own random choices.
#[test]
fn both_representations_fit_their_own_biases() {
    let (channels, length) = (4, 50);
    let train = samples(5, channels, length, false, 9);
    let model = MultiRocketModel::fit(&config(5, 2), &train, channels, length).unwrap();
    let differences: Vec<f64> = train
        .chunks_exact(length)
        .flat_map(|row| row.windows(2).map(|w| w[1] - w[0]))
        .collect();
    for (rocket, data) in [
        (model.series(), &train[..]),
        (model.differences(), &differences[..]),
    ] {
        let slow = oracle::biases(rocket, data);
        for (fast, slow) in rocket.biases().iter().zip(&slow) {
            assert!((fast - slow).abs() <= 1e-12, "{fast} vs {slow}");
        }
    }
    assert_ne!(model.series().examples(), model.differences().examples());
    // The same seed, the same model; the pooled features are finite and in range.
    let again = MultiRocketModel::fit(&config(5, 2), &train, channels, length).unwrap();
    assert_eq!(again, model);
    let mut scratch = model.scratch();
    let mut out = vec![0.0; model.output_len()];
    model
        .transform_into(&train[..channels * length], &mut out, &mut scratch)
        .unwrap();
    let block = model.series().output_len();
    assert!(out[..block].iter().all(|p| (0.0..=1.0).contains(p)));
    assert!(
        out[block..2 * block]
            .iter()
            .all(|&s| s >= 0.0 && s < length as f64)
    );
    assert!(
        out[3 * block..4 * block]
            .iter()
            .all(|&m| m >= -1.0 && m < length as f64)
    );
}

/// A model file round trips; a damaged one (differences of another length) is refused on reading;
/// short series, wrong buffers and non-finite values are clear errors.
#[test]
fn model_files_and_bad_input() {
    let train = samples(3, 2, 30, false, 4);
    let model = MultiRocketModel::fit(&config(3, 0), &train, 2, 30).unwrap();
    let text = serde_json::to_string(&model).unwrap();
    assert_eq!(
        serde_json::from_str::<MultiRocketModel>(&text).unwrap(),
        model
    );
    let other = RocketModel::fit(&RocketConfig::default(), &train, 2, 30).unwrap();
    let mut damaged: Value = serde_json::from_str(&text).unwrap();
    damaged["differences"] = serde_json::to_value(&other).unwrap();
    let err = serde_json::from_value::<MultiRocketModel>(damaged)
        .unwrap_err()
        .to_string();
    assert!(err.contains("differences"), "{err}");
    let err = MultiRocketModel::fit(&config(3, 0), &samples(2, 2, 9, false, 1), 2, 9)
        .unwrap_err()
        .to_string();
    assert!(err.contains("at least 10"), "{err}");
    let mut scratch = model.scratch();
    let mut out = vec![0.0; model.output_len()];
    assert!(
        model
            .transform_into(&train[..59], &mut out, &mut scratch)
            .is_err()
    );
    assert!(
        model
            .transform_into(&train[..60], &mut out[1..], &mut scratch)
            .is_err()
    );
    let mut bad = train[..60].to_vec();
    bad[33] = f64::NAN;
    let err = model
        .transform_into(&bad, &mut out, &mut scratch)
        .unwrap_err()
        .to_string();
    assert!(err.contains("NaN"), "{err}");
}

/// A RocketModel of aeon's fitted parameters for one representation (`series x length`).
fn aeon_representation(parameters: &Value, channels: usize, length: usize) -> RocketModel {
    let per_kernel: u64 = parameters["features_per_dilation"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_u64().unwrap())
        .sum();
    let combinations = parameters["padded"].as_array().unwrap().len();
    let fields = json!({
        "config": {"num_features": 84 * per_kernel, "max_dilations_per_kernel": 32, "seed": 0},
        "channels": channels,
        "length": length,
        "dilations": parameters["dilations"],
        "features_per_dilation": parameters["features_per_dilation"],
        "channels_per_combination": parameters["channels_per_combination"],
        "channel_indices": parameters["channel_indices"],
        "padded": parameters["padded"],
        "examples": vec![0; combinations],
        "biases": parameters["biases"],
    });
    serde_json::from_value(fields).unwrap()
}

/// Given aeon's fitted parameters, presrs's transform gives aeon's features of the series: PPV, LSPV and
/// MIPV to float32 rounding (the comparisons with the biases are exact on both sides: small integers),
/// MPV to float32 rounding of its sums. The differences' features are not aeon's: aeon 1.6 aligns the
/// four left taps of the differences' kernels from the series' length (`end = n_timepoints - padding`
/// where the differences have `n_timepoints - 1` values), one value off the definition, which presrs
/// follows (`fast_transform_matches_the_oracle`); the test checks that they differ, so that a fixed
/// aeon shows here.
#[test]
fn transform_matches_aeon_on_aeon_s_parameters() {
    let text = include_str!("fixtures/multirocket/multirocket_aeon.json");
    let document: Value = serde_json::from_str(text).unwrap();
    for case in document["cases"].as_array().unwrap() {
        let name = case["name"].as_str().unwrap();
        let channels = case["channels"].as_u64().unwrap() as usize;
        let length = case["length"].as_u64().unwrap() as usize;
        let per_kernel = case["biases_per_kernel"].as_u64().unwrap() as usize;
        let series = aeon_representation(&case["series"], channels, length);
        let differences = aeon_representation(&case["differences"], channels, length - 1);
        let model =
            MultiRocketModel::from_parts(config(per_kernel, 0), series, differences).unwrap();
        let mut scratch = model.scratch();
        let mut out = vec![0.0; model.output_len()];
        let samples = case["samples"].as_array().unwrap();
        let expected = case["features"].as_array().unwrap();
        for (sample, expected) in samples.iter().zip(expected) {
            let sample: Vec<f64> = serde_json::from_value(sample.clone()).unwrap();
            let expected: Vec<f64> = serde_json::from_value(expected.clone()).unwrap();
            assert_eq!(expected.len(), out.len(), "{name}");
            model
                .transform_into(&sample, &mut out, &mut scratch)
                .unwrap();
            let series = 4 * model.series().output_len();
            for (i, (got, want)) in out[..series].iter().zip(&expected).enumerate() {
                assert!(
                    (got - want).abs() <= 1e-5 * (1.0 + want.abs()),
                    "{name} feature {i}: presrs {got}, aeon {want}"
                );
            }
            let off = out[series..]
                .iter()
                .zip(&expected[series..])
                .filter(|(got, want)| (*got - *want).abs() > 1e-5 * (1.0 + want.abs()))
                .count();
            assert!(
                off > 0,
                "{name}: aeon's differences now follow the definition"
            );
        }
    }
}
