//! Fitting a PCA of wide data (rocket-like features: many more features than samples), 51 components:
//! the exact thin SVD at `GRAM_MIN_SAMPLES - 1` samples against the Gram matrix's eigendecomposition
//! at `GRAM_MIN_SAMPLES` (the first size that takes it), on the same number of features, so that the
//! two routes are compared on nearly the same matrix.
//!
//! `cargo bench -p presrs-core --bench pca_fit -- --warm-up-time 1 --measurement-time 20`

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use presrs_core::projection::pca::{GRAM_MIN_SAMPLES, Pca};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// `n x p` values in [0, 1) with a few shared directions, as PPV features are.
fn wide(n: usize, p: usize) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(44);
    let directions: Vec<f64> = (0..8 * p).map(|_| rng.random::<f64>()).collect();
    (0..n)
        .flat_map(|_| {
            let weights: Vec<f64> = (0..8).map(|_| rng.random::<f64>() / 8.0).collect();
            let noise: Vec<f64> = (0..p).map(|_| 0.1 * rng.random::<f64>()).collect();
            (0..p)
                .map(|j| {
                    let shared: f64 = (0..8).map(|r| weights[r] * directions[r * p + j]).sum();
                    shared + noise[j]
                })
                .collect::<Vec<_>>()
        })
        .collect()
}

fn pca_fit(c: &mut Criterion) {
    let p = 4000;
    let mut group = c.benchmark_group("pca_fit");
    group.sample_size(10);
    for (name, n) in [
        ("exact_svd_999x4000", GRAM_MIN_SAMPLES - 1),
        ("gram_1000x4000", GRAM_MIN_SAMPLES),
    ] {
        let samples = wide(n, p);
        group.bench_function(name, |b| {
            b.iter(|| black_box(Pca::fit(black_box(&samples), p, 51).ok()))
        });
    }
    group.finish();
}

criterion_group!(benches, pca_fit);
criterion_main!(benches);
