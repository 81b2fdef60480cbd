//! Online segmentation + classification throughput and decision latency on one core: a synthetic 100 Hz
//! hopper stream (14-frame stances of the paper-sized synthetic foot prints under a half-sine load,
//! 20-frame flights) through `OnlineClassifier` with the paper's pipeline (`bench_fixture`).
//!
//! `cargo bench -p presrs-core --bench online -- --warm-up-time 1 --measurement-time 3`
//!
//! Before the criterion runs it prints the whole-stream throughput (frames/s) and the decision latency
//! percentiles (time of the `push` of a frame that produced a decision), measured with `Instant`.
//!
//! A whole-stance model (`online/stance_*`: MiniRocket, 9,996 features, ridge; stances of 90 to 127
//! frames laid into 128): `stance_stream` pushes a stream of stances frame by frame (each frame's
//! summary column kept, each stance decided at its lift-off); `stance_push_flight` and
//! `stance_push_loaded` one frame in flight and one inside a stance (no decision); `stance_decision`
//! the decision alone (the kept stance laid out as the model's sample, and classified), and
//! `stance_layout` its first part (the layout, with the area counted).

use std::hint::black_box;
use std::time::Instant;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use presrs_core::Frame;
use presrs_core::classifier::ClassifierKind;
use presrs_core::online::{Calibration, OnlineClassifier, OnlineEvent, OnlineParams, StanceBuffer};
use presrs_core::pipeline::TrainedModel;
use presrs_core::sample::SampleKind;
use presrs_core::stance::{ValidSegmentParams, segment};
use presrs_core::testing::{bench_fixture, stance_model_with, stance_stream, synthetic_stream};
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

/// The whole-stance model of the benchmark and a stream to judge.
fn stance_setup() -> (TrainedModel, Vec<Frame>) {
    let lens = |n: usize, seed: usize| -> Vec<usize> {
        (0..n).map(|i| 90 + (i * 7 + seed) % 38).collect()
    };
    let (train, stances) = stance_stream(&lens(48, 0), 1);
    let Ok(model) = stance_model_with(&train, &stances, 128, 10_000, 40, ClassifierKind::RIDGE)
    else {
        panic!("the whole-stance model failed to train");
    };
    (model, stance_stream(&lens(12, 3), 2).0)
}

fn whole_stance(c: &mut Criterion) {
    let (model, frames) = stance_setup();
    let mut group = c.benchmark_group("online");
    group.throughput(Throughput::Elements(frames.len() as u64));
    let mut cl = classifier(&model, &frames, false);
    group.bench_function("stance_stream", |b| {
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
    group.throughput(Throughput::Elements(1));
    // Frame 0 is in flight, frame 40 inside the first stance (from frame 20): neither decides.
    let flight = frames[0].clone();
    let loaded = frames[40].clone();
    group.bench_function("stance_push_flight", |b| {
        b.iter(|| {
            black_box(
                cl.push(black_box(&flight.view()))
                    .map(|s| s.events.len())
                    .ok(),
            )
        })
    });
    let mut cl = classifier(&model, &frames, false);
    for frame in &frames[..40] {
        black_box(cl.push(&frame.view()).ok());
    }
    group.bench_function("stance_push_loaded", |b| {
        b.iter(|| {
            black_box(
                cl.push(black_box(&loaded.view()))
                    .map(|s| s.events.len())
                    .ok(),
            )
        })
    });
    let SampleKind::Stance { summary, length } = model.sample() else {
        panic!("not a whole-stance model");
    };
    let Ok(mut buffer) = StanceBuffer::new(summary, length.unwrap_or(128)) else {
        panic!("no stance buffer");
    };
    if buffer.set_grid(frames[0].grid()).is_err() {
        panic!("the frames do not fit the summary");
    }
    let stance_len = 90;
    for (t, frame) in frames[20..20 + stance_len].iter().enumerate() {
        buffer.keep(t, &frame.view());
    }
    group.bench_function("stance_layout", |b| {
        b.iter(|| {
            black_box(
                buffer
                    .sample(0, black_box(stance_len))
                    .map(|s| s.values()[0])
                    .ok(),
            )
        })
    });
    let mut session = model.session();
    group.bench_function("stance_decision", |b| {
        b.iter(|| {
            let class = buffer
                .sample(0, black_box(stance_len))
                .and_then(|sample| session.classify(&sample).map(|p| p.class));
            black_box(class.ok())
        })
    });
    group.finish();
}

criterion_group!(benches, online, whole_stance);
criterion_main!(benches);
