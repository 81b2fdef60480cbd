//! Classification latency and batch throughput on the paper-sized synthetic setup
//! (`testing::bench_fixture`: 44 x 44 frames cropped to 38 x 41, |FFT| N = 2048 -> 1025 features,
//! PCA to 51, Parzen window over 80 stored vectors).
//!
//! `cargo bench -p presrs-core --bench classify -- --warm-up-time 1 --measurement-time 3`

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use presrs_core::FrameView;
use presrs_core::features::{Fft1dConfig, Fft1dExtractor};
use presrs_core::testing::bench_fixture;

const SEED: u64 = 2024;
const BATCH: usize = 256;

fn classify(c: &mut Criterion) {
    let Ok((model, frames)) = bench_fixture(SEED, BATCH) else {
        panic!("the benchmark fixture failed to train");
    };
    let views: Vec<FrameView<'_>> = frames.iter().map(|frame| frame.view()).collect();

    let mut session = model.session();
    let mut next = 0;
    c.bench_function("classify_one_38x41", |b| {
        b.iter(|| {
            // cycle through different frames so the branch predictor cannot learn one input
            next = (next + 1) % views.len();
            let prediction = session.classify(black_box(&views[next]));
            black_box(prediction.map(|p| p.class).ok())
        })
    });

    let mut stages = model.session();
    // Exact features (what training computes).
    c.bench_function("features_only_38x41", |b| {
        b.iter(|| black_box(stages.features(black_box(&views[0])).map(|f| f[0]).ok()))
    });
    // The classifier's path: the 1-D |FFT| in single precision.
    let cropped = model.crop().apply(&views[0]).map(|c| c.values().to_vec());
    let mut fast_extractor = Fft1dExtractor::new(model.image_grid(), &Fft1dConfig::PAPER);
    let mut fast_features = vec![0.0; model.n_features()];
    if let (Ok(cropped), Ok(extractor)) = (&cropped, &mut fast_extractor) {
        c.bench_function("features_fast_38x41", |b| {
            b.iter(|| {
                black_box(
                    extractor
                        .extract_fast_into(black_box(cropped), &mut fast_features)
                        .ok(),
                )
            })
        });
    }
    let features = model
        .session()
        .features(&views[0])
        .map(<[f64]>::to_vec)
        .unwrap_or_default();
    let Some(pca) = model.pca() else {
        panic!("the paper's model has a PCA step");
    };
    let mut reduced = vec![0.0; pca.n_components()];
    let mut projection = pca.scratch();
    c.bench_function("pca_project_1025_to_51", |b| {
        b.iter(|| {
            black_box(
                pca.project_fast_into(black_box(&features), &mut projection, &mut reduced)
                    .ok(),
            )
        })
    });

    let classifier = model.classifier();
    let mut scratch = classifier.scratch();
    let mut posteriors = vec![0.0; classifier.n_classes()];
    c.bench_function("parzen_only_80x51", |b| {
        b.iter(|| {
            black_box(
                classifier
                    .classify_into(black_box(&reduced), &mut scratch, &mut posteriors)
                    .ok(),
            )
        })
    });

    let mut group = c.benchmark_group("batch");
    group.throughput(Throughput::Elements(BATCH as u64));
    group.bench_function("classify_batch_256", |b| {
        b.iter(|| black_box(model.classify_batch(black_box(&views)).len()))
    });
    group.finish();
}

criterion_group!(benches, classify);
criterion_main!(benches);
