//! The PCA projection stage on its own: the SIMD kernel in f64 (`Pca::project_into`) and in fixed
//! point (`Pca::project_fast_into`, the classification path: 16-bit basis, 15-bit input blocks) against
//! faer's matmul on the same row-major 51 x 1025 basis (the previous implementation), and on 4 x 1025
//! (f64) and 16 x 1025 (fixed point) bases that fit in L1: where the time per row is the same as for the
//! 51 rows read from L2, the kernel is bound by its arithmetic, not by L2.
//!
//! `cargo bench -p presrs-core --bench pca_stage -- --warm-up-time 1 --measurement-time 3`

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use faer::linalg::matmul::matmul;
use faer::{Accum, ColMut, ColRef, MatRef, Par};
use presrs_core::projection::pca::Pca;
use presrs_core::testing::bench_fixture;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn faer_project(basis: &[f64], cols: usize, x: &[f64], out: &mut [f64]) {
    let rows = out.len();
    matmul(
        ColMut::from_slice_mut(out),
        Accum::Replace,
        MatRef::from_row_major_slice(basis, rows, cols),
        ColRef::from_slice(x),
        1.0,
        Par::Seq,
    );
}

fn pca_stage(c: &mut Criterion) {
    let Ok((model, frames)) = bench_fixture(2024, 1) else {
        panic!("the benchmark fixture failed to train");
    };
    let Ok(features) = model
        .session()
        .features(&frames[0].view())
        .map(<[f64]>::to_vec)
    else {
        panic!("feature extraction failed");
    };
    let Some(pca) = model.pca() else {
        panic!("the paper's model has a PCA step");
    };
    let cols = pca.n_features();
    let mut out = vec![0.0; pca.n_components()];

    let mut group = c.benchmark_group("pca_stage");
    group.bench_function("simd_project_51x1025", |b| {
        b.iter(|| black_box(pca.project_into(black_box(&features), &mut out).ok()))
    });
    let mut scratch = pca.scratch();
    group.bench_function("fixed_point_project_51x1025", |b| {
        b.iter(|| {
            black_box(
                pca.project_fast_into(black_box(&features), &mut scratch, &mut out)
                    .ok(),
            )
        })
    });
    group.bench_function("faer_matmul_51x1025", |b| {
        b.iter(|| {
            faer_project(pca.basis(), cols, black_box(&features), &mut out);
            black_box(out[0])
        })
    });

    // A 4-component PCA of random data: 32 KB of basis, resident in L1.
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let samples: Vec<f64> = (0..8 * cols).map(|_| rng.random_range(-1.0..1.0)).collect();
    let Ok(small) = Pca::fit(&samples, cols, 4) else {
        panic!("the small PCA failed to fit");
    };
    let mut small_out = vec![0.0; 4];
    group.bench_function("simd_project_4x1025_l1", |b| {
        b.iter(|| {
            black_box(
                small
                    .project_into(black_box(&features), &mut small_out)
                    .ok(),
            )
        })
    });
    group.bench_function("faer_matmul_4x1025_l1", |b| {
        b.iter(|| {
            faer_project(small.basis(), cols, black_box(&features), &mut small_out);
            black_box(small_out[0])
        })
    });
    // A 16-component PCA (16 x 1024 x 2 B = 32 KB of 16-bit basis, resident in L1): the fixed-point
    // kernel's arithmetic cost per row, to compare with the 51-row basis streamed from L2.
    let samples: Vec<f64> = (0..24 * cols)
        .map(|_| rng.random_range(-1.0..1.0))
        .collect();
    let Ok(l1_fixed) = Pca::fit(&samples, cols, 16) else {
        panic!("the 16-component PCA failed to fit");
    };
    let mut l1_scratch = l1_fixed.scratch();
    let mut l1_out = vec![0.0; 16];
    group.bench_function("fixed_point_project_16x1025_l1", |b| {
        b.iter(|| {
            black_box(
                l1_fixed
                    .project_fast_into(black_box(&features), &mut l1_scratch, &mut l1_out)
                    .ok(),
            )
        })
    });
    group.finish();
}

criterion_group!(benches, pca_stage);
criterion_main!(benches);
