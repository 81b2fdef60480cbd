//! Online segmentation + classification throughput and decision latency on one core: a synthetic 100 Hz
//! hopper stream (14-frame stances of the paper-sized synthetic foot prints under a half-sine load,
//! 20-frame flights) through `OnlineClassifier` with the paper's pipeline (`bench_fixture`).
//!
//! `cargo bench -p presrs-core --bench online -- --warm-up-time 1 --measurement-time 3`
//!
//! Before the criterion runs it prints the whole-stream throughput (frames/s) and the decision latency
//! percentiles (time of the `push` of a frame that produced a decision), measured with `Instant`.

use std::hint::black_box;
use std::time::Instant;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use presrs_core::Frame;
use presrs_core::online::{Calibration, OnlineClassifier, OnlineEvent, OnlineParams};
use presrs_core::pipeline::TrainedModel;
use presrs_core::stance::{ValidSegmentParams, segment};
use presrs_core::testing::{bench_fixture, synthetic_stream};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

const STANCES: usize = 100;

fn stream() -> Vec<Frame> {
    synthetic_stream(STANCES, &mut ChaCha8Rng::seed_from_u64(7))
}

fn classifier<'m>(model: &'m TrainedModel, frames: &[Frame], fuse: bool) -> OnlineClassifier<'m> {
    let totals: Vec<f64> = frames.iter().map(|f| f.view().total()).collect();
    let Ok(seg) = segment(&totals, &ValidSegmentParams::default()) else {
        panic!("segmentation failed");
    };
    let online = OnlineParams {
        fusion_offsets: if fuse {
            vec![4, 5, 6, 7, 8]
        } else {
            Vec::new()
        },
        ..OnlineParams::default()
    };
    let Ok(c) = OnlineClassifier::new(
        model,
        &ValidSegmentParams::default(),
        &online,
        Calibration::from_segmentations([&seg]),
    ) else {
        panic!("classifier failed");
    };
    c
}

fn report(model: &TrainedModel, frames: &[Frame], fuse: bool) {
    let mut c = classifier(model, frames, fuse);
    let mut latencies = Vec::new();
    // The same frame classified alone right after its decision: what one classification costs under the
    // same machine load, to tell the decision's own overhead from the classification and the scheduler.
    let mut alone = Vec::new();
    let mut session = model.session();
    // One pass to warm caches and the FFT plan, then PASSES measured ones.
    const PASSES: usize = 20;
    let mut start = Instant::now();
    // Time spent on the extra classifications, left out of the throughput.
    let mut extra = 0.0;
    for pass in 0..=PASSES {
        if pass == 1 {
            latencies.clear();
            alone.clear();
            extra = 0.0;
            start = Instant::now();
        }
        for frame in frames {
            let t0 = Instant::now();
            let decided = match c.push(&frame.view()) {
                Ok(step) => step
                    .events
                    .iter()
                    .any(|e| matches!(e, OnlineEvent::Decision(_))),
                Err(_) => false,
            };
            if decided {
                latencies.push(t0.elapsed().as_secs_f64() * 1e6);
                let t1 = Instant::now();
                black_box(session.classify(&frame.view()).map(|p| p.class).ok());
                let us = t1.elapsed().as_secs_f64() * 1e6;
                alone.push(us);
                extra += us * 1e-6;
            }
        }
    }
    let secs = start.elapsed().as_secs_f64() - extra;
    latencies.sort_by(f64::total_cmp);
    alone.sort_by(f64::total_cmp);
    let q = |p: f64| latencies[((latencies.len() - 1) as f64 * p).round() as usize];
    let qa = |p: f64| alone[((alone.len() - 1) as f64 * p).round() as usize];
    eprintln!(
        "online (fusion {fuse}): {} frames in {secs:.3} s = {:.0} frames/s ({:.0}x real time at 100 Hz); \
         {} decisions, latency p50 {:.1} us, p99 {:.1} us, max {:.1} us; the decided frame classified \
         alone: p50 {:.1} us, p99 {:.1} us, max {:.1} us",
        PASSES * frames.len(),
        (PASSES * frames.len()) as f64 / secs,
        (PASSES * frames.len()) as f64 / secs / 100.0,
        latencies.len(),
        q(0.5),
        q(0.99),
        q(1.0),
        qa(0.5),
        qa(0.99),
        qa(1.0)
    );
}

fn online(c: &mut Criterion) {
    let Ok((model, _)) = bench_fixture(2024, 0) else {
        panic!("the benchmark fixture failed to train");
    };
    let frames = stream();
    report(&model, &frames, false);
    report(&model, &frames, true);
    let mut group = c.benchmark_group("online");
    group.throughput(Throughput::Elements(frames.len() as u64));
    for fuse in [false, true] {
        let mut cl = classifier(&model, &frames, fuse);
        let name = if fuse {
            "stream_fused"
        } else {
            "stream_single"
        };
        group.bench_function(name, |b| {
            b.iter(|| {
                for frame in &frames {
                    black_box(
                        cl.push(black_box(&frame.view()))
                            .map(|s| s.events.len())
                            .ok(),
                    );
                }
            })
        });
    }
    group.finish();
}

criterion_group!(benches, online);
criterion_main!(benches);
