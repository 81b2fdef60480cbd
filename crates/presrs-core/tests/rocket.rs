//! MiniRocket (`features::rocket`): the fast transform, the batch transform and the parallel fit against
//! the slow oracle (the definition), seeding, and bad input.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use presrs_core::features::rocket::{RocketConfig, RocketModel, oracle};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// How the random test series are drawn.
#[derive(Clone, Copy, Debug)]
enum Values {
    /// Continuous values of mixed scale and offset: no ties.
    Continuous,
    /// Small integers: many outputs tie with each other and with the biases, and every sum is exact.
    SmallIntegers,
}

fn samples(count: usize, channels: usize, length: usize, values: Values, seed: u64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let offset = rng.random_range(-5.0..5.0);
    (0..count * channels * length)
        .map(|_| match values {
            Values::Continuous => {
                offset + rng.random_range(-1.0..1.0) * 10f64.powi(rng.random_range(-1..=1))
            }
            Values::SmallIntegers => f64::from(rng.random_range(-3i32..=3)),
        })
        .collect()
}

fn config(num_features: usize, seed: u64) -> RocketConfig {
    RocketConfig {
        num_features,
        seed,
        ..RocketConfig::default()
    }
}

/// The largest difference between the fast transform and the oracle over `tests` samples (the training
/// samples first, whose convolutions gave the biases, then fresh ones).
fn worst_difference(model: &RocketModel, train: &[f64], fresh: &[f64]) -> f64 {
    let mut scratch = model.scratch();
    let mut fast = vec![f64::NAN; model.output_len()];
    let mut worst = 0f64;
    for sample in train
        .chunks_exact(model.sample_len())
        .chain(fresh.chunks_exact(model.sample_len()))
    {
        model
            .transform_into(sample, &mut fast, &mut scratch)
            .unwrap();
        let slow = oracle::transform(model, sample);
        for (f, s) in fast.iter().zip(&slow) {
            worst = worst.max((f - s).abs());
        }
    }
    worst
}

/// The fast transform gives the oracle's features within 1e-12 (in fact exactly) for 1, 2, 3, 7 and 11
/// channels, lengths 9 to 300, continuous values and small integers (ties), on the training samples and
/// on fresh ones; the kernels alternate between padded and unpadded at every dilation.
#[test]
fn fast_transform_matches_the_oracle() {
    let cases = [
        (1, 9),
        (1, 10),
        (2, 17),
        (3, 40),
        (1, 75),
        (7, 64),
        (11, 128),
        (3, 300),
        (2, 33),
    ];
    for (case, &(channels, length)) in cases.iter().enumerate() {
        for values in [Values::Continuous, Values::SmallIntegers] {
            let seed = case as u64;
            let train = samples(3, channels, length, values, 100 + seed);
            let fresh = samples(2, channels, length, values, 200 + seed);
            let model = RocketModel::fit(&config(84 * 6, seed), &train, channels, length).unwrap();
            let combinations: Vec<_> = model.combinations().collect();
            assert!(
                combinations.iter().any(|c| c.padded) && combinations.iter().any(|c| !c.padded)
            );
            let worst = worst_difference(&model, &train, &fresh);
            assert!(
                worst <= 1e-12,
                "{channels} x {length} {values:?}: off by {worst:e}"
            );
        }
    }
}

/// The paper's 10,000 features (9,996) on 11 channels x 128, against the oracle.
#[test]
fn paper_sized_model_matches_the_oracle() {
    let train = samples(4, 11, 128, Values::Continuous, 7);
    let fresh = samples(1, 11, 128, Values::Continuous, 8);
    let model = RocketModel::fit(&RocketConfig::default(), &train, 11, 128).unwrap();
    assert_eq!(model.output_len(), 9996);
    assert_eq!(
        model.dilations(),
        [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15]
    );
    assert!(worst_difference(&model, &train[..11 * 128], &fresh) <= 1e-12);
}

/// The fitted biases (computed in parallel, through the fast convolution) are the oracle's: quantiles
/// of the definition's convolution of each combination's example, within 1e-12.
#[test]
fn parallel_fit_biases_match_the_oracle() {
    for (channels, length) in [(1, 9), (3, 50), (11, 128), (60, 75)] {
        let train = samples(5, channels, length, Values::Continuous, 40 + length as u64);
        let model = RocketModel::fit(&config(84 * 5, 3), &train, channels, length).unwrap();
        let slow = oracle::biases(&model, &train);
        for (i, (fast, slow)) in model.biases().iter().zip(&slow).enumerate() {
            assert!(
                (fast - slow).abs() <= 1e-12,
                "{channels} x {length} bias {i}: {fast} vs {slow}"
            );
        }
        assert!(model.examples().iter().all(|&e| e < 5));
    }
}

/// The fit does not depend on the number of threads: one thread gives the same model bit for bit.
#[test]
fn fit_is_the_same_on_one_thread() {
    let train = samples(6, 5, 60, Values::Continuous, 9);
    let parallel = RocketModel::fit(&config(1000, 11), &train, 5, 60).unwrap();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let serial = pool.install(|| RocketModel::fit(&config(1000, 11), &train, 5, 60).unwrap());
    assert_eq!(parallel, serial);
}

/// The batch transform (parallel) gives, row by row, what one sample at a time gives, bit for bit,
/// and so the oracle's features.
#[test]
fn batch_transform_matches_one_at_a_time_and_the_oracle() {
    let (channels, length) = (4, 45);
    let train = samples(3, channels, length, Values::Continuous, 12);
    let model = RocketModel::fit(&config(84 * 4, 5), &train, channels, length).unwrap();
    let batch_input = samples(9, channels, length, Values::Continuous, 13);
    let batch = model.transform_batch(&batch_input).unwrap();
    assert_eq!(batch.len(), 9 * model.output_len());
    let mut scratch = model.scratch();
    let mut one = vec![0.0; model.output_len()];
    for (sample, row) in batch_input
        .chunks_exact(model.sample_len())
        .zip(batch.chunks_exact(model.output_len()))
    {
        model
            .transform_into(sample, &mut one, &mut scratch)
            .unwrap();
        assert_eq!(row, one.as_slice());
        let slow = oracle::transform(&model, sample);
        assert!(row.iter().zip(&slow).all(|(a, b)| (a - b).abs() <= 1e-12));
    }
    assert!(model.transform_batch(&[]).unwrap().is_empty());
}

/// The same seed gives the same model; another seed other channel combinations and examples.
#[test]
fn the_seed_decides_every_random_choice() {
    let train = samples(8, 6, 40, Values::Continuous, 14);
    let a = RocketModel::fit(&config(840, 1), &train, 6, 40).unwrap();
    let b = RocketModel::fit(&config(840, 1), &train, 6, 40).unwrap();
    let c = RocketModel::fit(&config(840, 2), &train, 6, 40).unwrap();
    assert_eq!(a, b);
    assert_ne!(a.examples(), c.examples());
    let channels = |m: &RocketModel| -> Vec<Vec<usize>> {
        m.combinations().map(|c| c.channels.to_vec()).collect()
    };
    assert_ne!(channels(&a), channels(&c));
    assert_ne!(a.biases(), c.biases());
    // Channel counts span 1 ..= min(channels, 9), each combination's channels distinct.
    let counts: Vec<usize> = a.combinations().map(|c| c.channels.len()).collect();
    assert!(counts.contains(&1) && counts.iter().all(|&n| (1..=6).contains(&n)));
}

/// One channel is univariate MiniRocket: every combination is channel 0.
#[test]
fn one_channel_uses_it_everywhere() {
    let train = samples(2, 1, 30, Values::Continuous, 15);
    let model = RocketModel::fit(&config(84 * 3, 0), &train, 1, 30).unwrap();
    assert!(model.combinations().all(|c| c.channels == [0]));
}

/// The features are proportions, and a model survives a trip through JSON (checked on reading).
#[test]
fn features_are_proportions_and_the_model_round_trips() {
    let train = samples(3, 2, 20, Values::Continuous, 16);
    let model = RocketModel::fit(&config(300, 4), &train, 2, 20).unwrap();
    assert_eq!(model.output_len(), 252);
    assert_eq!(model.feature_names().len(), 252);
    let features = model.transform_batch(&train).unwrap();
    assert!(features.iter().all(|&f| (0.0..=1.0).contains(&f)));
    let json = serde_json::to_string(&model).unwrap();
    let back: RocketModel = serde_json::from_str(&json).unwrap();
    assert_eq!(back, model);
    assert_eq!(back.transform_batch(&train).unwrap(), features);
}

/// Bad parameters and bad input are errors that say what is wrong, never panics.
#[test]
fn bad_input_is_a_clear_error() {
    let train = samples(2, 3, 20, Values::Continuous, 17);
    let zero = config(0, 0);
    let err = RocketModel::fit(&zero, &train, 3, 20)
        .unwrap_err()
        .to_string();
    assert!(err.contains("num_features"), "{err}");
    let short = samples(2, 3, 8, Values::Continuous, 17);
    let err = RocketModel::fit(&config(100, 0), &short, 3, 8)
        .unwrap_err()
        .to_string();
    assert!(err.contains("at least 9"), "{err}");
    assert!(RocketModel::fit(&config(100, 0), &[], 3, 20).is_err());
    assert!(RocketModel::fit(&config(100, 0), &train[..59], 3, 20).is_err());
    assert!(RocketModel::fit(&config(100, 0), &train, 0, 20).is_err());
    let mut nan = train.clone();
    nan[60 + 20 + 5] = f64::NAN;
    let err = RocketModel::fit(&config(100, 0), &nan, 3, 20)
        .unwrap_err()
        .to_string();
    assert!(err.contains("sample 1, channel 1, position 5"), "{err}");

    let model = RocketModel::fit(&config(100, 0), &train, 3, 20).unwrap();
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
    let err = model
        .transform_into(&nan[60..120], &mut out, &mut scratch)
        .unwrap_err();
    assert!(err.to_string().contains("channel 1, position 5"), "{err}");
    assert!(model.transform_batch(&train[..61]).is_err());
}

/// A crafted model file is refused when read, naming what is inconsistent.
#[test]
fn a_crafted_model_is_refused_on_reading() {
    let train = samples(2, 3, 40, Values::Continuous, 18);
    let model = RocketModel::fit(&config(168, 0), &train, 3, 40).unwrap();
    let good: serde_json::Value = serde_json::to_value(&model).unwrap();
    let mut too_far = model.dilations().to_vec();
    *too_far.last_mut().unwrap() = 64;
    let edits = [
        ("dilations", serde_json::json!(too_far), "dilations"),
        ("length", serde_json::json!(8), "at least 9"),
        ("channels", serde_json::json!(0), "channel"),
        ("biases", serde_json::json!([0.5]), "biases"),
        ("padded", serde_json::json!([true]), "padded"),
        (
            "features_per_dilation",
            serde_json::json!([0]),
            "features_per_dilation",
        ),
        (
            "channels_per_combination",
            serde_json::json!([]),
            "channels_per_combination",
        ),
        ("unknown_field", serde_json::json!(1), "unknown field"),
    ];
    for (field, value, expected) in edits {
        let mut crafted = good.clone();
        crafted[field] = value;
        let err = serde_json::from_value::<RocketModel>(crafted)
            .unwrap_err()
            .to_string();
        assert!(err.contains(expected), "{field}: {err}");
    }
    // A channel out of range, and a channel twice in one combination (the lengths intact).
    let mut crafted = good.clone();
    crafted["channel_indices"][0] = serde_json::json!(3);
    let err = serde_json::from_value::<RocketModel>(crafted)
        .unwrap_err()
        .to_string();
    assert!(err.contains("channel_indices"), "{err}");
    let mut start = 0;
    for combination in model.combinations() {
        if combination.channels.len() >= 2 {
            let mut crafted = good.clone();
            crafted["channel_indices"][start + 1] = serde_json::json!(combination.channels[0]);
            let err = serde_json::from_value::<RocketModel>(crafted)
                .unwrap_err()
                .to_string();
            assert!(err.contains("distinct"), "{err}");
            break;
        }
        start += combination.channels.len();
    }
    assert!(model.check().is_ok());
}
