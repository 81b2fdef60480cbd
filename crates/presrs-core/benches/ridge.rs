//! The ridge classifier at MiniRocket's size (issue #33): fitting on 1,000 vectors of 10,000 features
//! (4 classes; the Gram matrix, its eigendecomposition and the leave-one-out over the 10 default
//! alphas), the same at the chosen alpha pinned (one Cholesky solve over blocks, the fit on every sample
//! when the automatic choice searched alpha on its subsample), and classifying one 10,000-feature vector.
//!
//! `cargo bench -p presrs-core --bench ridge -- --warm-up-time 1 --measurement-time 20`

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use presrs_core::classifier::{
    ClassifierFamily, FitData, LabeledVectors, RidgeConfig, RidgeFamily,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const SAMPLES: usize = 1_000;
const FEATURES: usize = 10_000;
const CLASSES: usize = 4;
const SEED: u64 = 33;

/// `SAMPLES` vectors of `CLASSES` overlapping classes: a class pattern plus uniform noise, with
/// uneven feature scales.
fn problem() -> (Vec<f64>, Vec<usize>) {
    let mut rng = ChaCha8Rng::seed_from_u64(SEED);
    let patterns: Vec<f64> = (0..CLASSES * FEATURES)
        .map(|_| rng.random_range(-0.05..0.05))
        .collect();
    let classes: Vec<usize> = (0..SAMPLES).map(|i| i % CLASSES).collect();
    let vectors = classes
        .iter()
        .flat_map(|&class| {
            let pattern = &patterns[class * FEATURES..(class + 1) * FEATURES];
            pattern
                .iter()
                .enumerate()
                .map(|(j, p)| (p + rng.random_range(-1.0..1.0)) * (1.0 + (j % 7) as f64))
                .collect::<Vec<_>>()
        })
        .collect();
    (vectors, classes)
}

fn ridge(c: &mut Criterion) {
    let (vectors, classes) = problem();
    let data = FitData {
        train: LabeledVectors {
            vectors: &vectors,
            classes: &classes,
        },
        validation: LabeledVectors {
            vectors: &[],
            classes: &[],
        },
        n_classes: CLASSES,
        dims: FEATURES,
        calibrate: true,
    };
    let config = RidgeConfig::default();
    c.bench_function("ridge_fit_1000x10000", |b| {
        b.iter(|| {
            black_box(
                RidgeFamily::fit(&config, black_box(data))
                    .map(|m| m.alpha())
                    .ok(),
            )
        })
    });

    let Ok(model) = RidgeFamily::fit(&config, data) else {
        panic!("the ridge benchmark problem failed to fit");
    };
    let Some(pinned) = RidgeFamily::pinned(&config, &model) else {
        panic!("ridge pins its alpha");
    };
    c.bench_function("ridge_fit_pinned_1000x10000", |b| {
        b.iter(|| {
            black_box(
                RidgeFamily::fit(&pinned, black_box(data))
                    .map(|m| m.alpha())
                    .ok(),
            )
        })
    });
    let mut scratch = model.scratch();
    let mut posteriors = vec![0.0; CLASSES];
    let mut next = 0;
    c.bench_function("ridge_classify_one_10000", |b| {
        b.iter(|| {
            next = (next + 1) % SAMPLES;
            let x = &vectors[next * FEATURES..(next + 1) * FEATURES];
            black_box(
                model
                    .classify_into(black_box(x), &mut scratch, &mut posteriors)
                    .ok(),
            )
        })
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = ridge
}
criterion_main!(benches);
