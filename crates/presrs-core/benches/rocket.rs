//! The MiniRocket transform of ONE sample on one thread (`features::rocket`), for the two shapes of
//! issue #33: 11 channels x 128 frames (stance summaries) and 60 x 75 (the `icub20` taxels x time), the
//! paper's 10,000 features (9,996), a model fitted on a few random samples. aeon's MiniRocket on the
//! same shapes: `bench/rocket/aeon_peer.py` (see bench/rocket/README.md).
//!
//! `cargo bench -p presrs-core --bench rocket -- --warm-up-time 1 --measurement-time 5`

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use presrs_core::features::rocket::{RocketConfig, RocketModel};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Training samples for the fit.
const TRAIN: usize = 8;
/// Distinct samples transformed in turn (so the timing is not that of one input in cache).
const INPUTS: usize = 16;

fn transform_one(c: &mut Criterion) {
    let mut group = c.benchmark_group("rocket_transform_one");
    for (channels, length) in [(11, 128), (60, 75)] {
        let mut rng = ChaCha8Rng::seed_from_u64(33);
        let mut draw = |count: usize| -> Vec<f64> {
            (0..count * channels * length)
                .map(|_| rng.random_range(-1.0..1.0))
                .collect()
        };
        let train = draw(TRAIN);
        let inputs = draw(INPUTS);
        let Ok(model) = RocketModel::fit(&RocketConfig::default(), &train, channels, length) else {
            panic!("the benchmark model failed to fit");
        };
        let mut scratch = model.scratch();
        let mut out = vec![0.0; model.output_len()];
        let mut next = 0;
        group.bench_function(format!("{channels}x{length}"), |b| {
            b.iter(|| {
                next = (next + 1) % INPUTS;
                let sample = &inputs[next * model.sample_len()..(next + 1) * model.sample_len()];
                let done = model.transform_into(black_box(sample), &mut out, &mut scratch);
                black_box((done.is_ok(), out[0]))
            })
        });
    }
    group.finish();
}

criterion_group!(benches, transform_one);
criterion_main!(benches);
