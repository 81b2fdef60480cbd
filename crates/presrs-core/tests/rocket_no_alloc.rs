//! The MiniRocket transform of one sample allocates nothing with the model's scratch
//! (`RocketModel::scratch`), and a scratch made for another model grows once, then no more.
//!
//! The counting allocator is process-wide, so this file holds a single test, and each measurement is
//! the fewest allocations of three runs: a thread of the fit's parallel pool may still free or
//! allocate while the first run is measured (seen on a loaded machine), while an allocation of the
//! transform itself shows in every run.

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
    let allocated = fewest_allocations(|| {
        for sample in inputs.chunks_exact(model.sample_len()) {
            model
                .transform_into(sample, &mut out, &mut scratch)
                .unwrap();
        }
    });
    assert_eq!(allocated, 0);

    // A default scratch grows on the first sample only.
    let mut grown = RocketScratch::default();
    model
        .transform_into(&inputs[..model.sample_len()], &mut out, &mut grown)
        .unwrap();
    let allocated = fewest_allocations(|| {
        for sample in inputs.chunks_exact(model.sample_len()) {
            model.transform_into(sample, &mut out, &mut grown).unwrap();
        }
    });
    assert_eq!(allocated, 0);
}

/// The fewest allocations and reallocations counted while `run` runs, over three runs.
fn fewest_allocations(mut run: impl FnMut()) -> usize {
    (0..3)
        .map(|_| {
            let region = Region::new(GLOBAL);
            run();
            let stats = region.change();
            stats.allocations + stats.reallocations
        })
        .min()
        .unwrap_or(0)
}
