//! The MiniRocket transform of one sample allocates nothing with the model's scratch
//! (`RocketModel::scratch`), and a scratch made for another model grows once, then no more.
//!
//! The counting allocator is process-wide, so this file holds a single test.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::alloc::System;

use presrs_core::features::rocket::{RocketConfig, RocketModel, RocketScratch};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use stats_alloc::{INSTRUMENTED_SYSTEM, Region, StatsAlloc};

#[global_allocator]
static GLOBAL: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

#[test]
fn transform_into_does_not_allocate() {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let (channels, length) = (5, 64);
    let data: Vec<f64> = (0..6 * channels * length)
        .map(|_| rng.random_range(-1.0..1.0))
        .collect();
    let (train, inputs) = data.split_at(3 * channels * length);
    let config = RocketConfig {
        num_features: 84 * 10,
        ..RocketConfig::default()
    };
    let model = RocketModel::fit(&config, train, channels, length).unwrap();
    let mut out = vec![0.0; model.output_len()];

    let mut scratch = model.scratch();
    let region = Region::new(GLOBAL);
    for sample in inputs.chunks_exact(model.sample_len()) {
        model
            .transform_into(sample, &mut out, &mut scratch)
            .unwrap();
    }
    let stats = region.change();
    assert_eq!(stats.allocations + stats.reallocations, 0, "{stats:?}");

    // A default scratch grows on the first sample only.
    let mut grown = RocketScratch::default();
    model
        .transform_into(&inputs[..model.sample_len()], &mut out, &mut grown)
        .unwrap();
    let region = Region::new(GLOBAL);
    for sample in inputs.chunks_exact(model.sample_len()) {
        model.transform_into(sample, &mut out, &mut grown).unwrap();
    }
    let stats = region.change();
    assert_eq!(stats.allocations + stats.reallocations, 0, "{stats:?}");
}
