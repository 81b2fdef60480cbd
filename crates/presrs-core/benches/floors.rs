//! What this CPU allows, next to what a classification takes: bare kernels that do only the part of a
//! stage no implementation of the paper's pipeline can skip, to tell how far the classification path is
//! from the machine's limits (and so which speed targets are within reach).
//!
//! - `madd_stream_51x1024_l2`: one pass of `vpmaddwd` (AVX-512) over a 51 x 1024 basis of 16-bit
//!   integers (104 KB, the PCA axes as the classification path stores them; read from L2), the vector in
//!   registers and L1, the products summed in i32 and nothing else: no conversion, no scaling, no
//!   quantization of the input. The projection cannot move its basis through the core faster than this.
//! - `madd_stream_16x1024_l1`: the same over 16 axes (32 KB, resident in L1): the multiplier's own rate.
//! - `rustfft_1024_f32`: rustfft's forward 1024-point complex FFT in f32 (its AVX2 kernels), the
//!   transform at the heart of the 1-D |FFT| of a 38 x 41 image (N = 2048 real values as 1024 complex
//!   ones), in L1.
//! - `classify_one_38x41`: a whole classification (crop, features, PCA, Parzen window), for reference.
//!
//! `cargo bench -p presrs-core --bench floors -- --warm-up-time 1 --measurement-time 3`

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use presrs_core::FrameView;
use presrs_core::testing::bench_fixture;
use rustfft::FftPlanner;
use rustfft::num_complex::Complex;

/// Features per axis (the 1025 of eq. 5 less the DC one, which the projection multiplies exactly).
const FEATURES: usize = 1024;

fn floors(c: &mut Criterion) {
    let mut group = c.benchmark_group("floors");
    #[cfg(target_arch = "x86_64")]
    madd::register(&mut group);

    let fft = FftPlanner::<f32>::new().plan_fft_forward(FEATURES);
    let mut data: Vec<Complex<f32>> = (0..FEATURES)
        .map(|i| Complex::new((i % 97) as f32, 0.0))
        .collect();
    let original = data.clone();
    let mut scratch = vec![Complex::new(0.0, 0.0); fft.get_inplace_scratch_len()];
    group.bench_function("rustfft_1024_f32", |b| {
        b.iter(|| {
            data.copy_from_slice(&original);
            fft.process_with_scratch(black_box(&mut data), &mut scratch);
            black_box(data[1])
        })
    });

    let Ok((model, frames)) = bench_fixture(2024, 64) else {
        panic!("the benchmark fixture failed to train");
    };
    let views: Vec<FrameView<'_>> = frames.iter().map(|frame| frame.view()).collect();
    let mut session = model.session();
    let mut next = 0;
    group.bench_function("classify_one_38x41", |b| {
        b.iter(|| {
            next = (next + 1) % views.len();
            black_box(
                session
                    .classify(black_box(&views[next]))
                    .map(|p| p.class)
                    .ok(),
            )
        })
    });
    group.finish();
}

#[cfg(target_arch = "x86_64")]
mod madd {
    use super::{FEATURES, black_box};
    use core::arch::x86_64::__m512i;
    use criterion::BenchmarkGroup;
    use criterion::measurement::WallTime;
    use pulp::x86::V4;

    /// 32 pairs of 16-bit integers per register.
    const PER_REGISTER: usize = 32;
    /// Registers per axis.
    const REGISTERS: usize = FEATURES / PER_REGISTER;
    /// Axes per pass over a block of the vector: independent accumulators, as the real kernel has.
    const ROWS: usize = 8;

    /// `Σ_axes Σ_j madd(axis_j, vector_j)` in i32 lanes: the multiplies and adds of the projection, no
    /// more.
    struct Stream<'a> {
        simd: V4,
        basis: &'a [__m512i],
        vector: &'a [__m512i; REGISTERS],
    }

    impl pulp::NullaryFnOnce for Stream<'_> {
        type Output = i32;

        #[inline(always)]
        fn call(self) -> i32 {
            let Self {
                simd,
                basis,
                vector,
            } = self;
            let (f, bw) = (simd.avx512f, simd.avx512bw);
            let mut acc = [f._mm512_setzero_si512(); ROWS];
            let blocks = basis.chunks_exact(ROWS * REGISTERS);
            let rest = blocks.remainder();
            for block in blocks {
                for (j, &x) in vector.iter().enumerate() {
                    for (r, acc) in acc.iter_mut().enumerate() {
                        let product = bw._mm512_madd_epi16(block[r * REGISTERS + j], x);
                        *acc = f._mm512_add_epi32(*acc, product);
                    }
                }
            }
            // The axes after the last whole block, one at a time.
            for axis in rest.chunks_exact(REGISTERS) {
                for (j, (&w, &x)) in axis.iter().zip(vector).enumerate() {
                    let product = bw._mm512_madd_epi16(w, x);
                    acc[j % ROWS] = f._mm512_add_epi32(acc[j % ROWS], product);
                }
            }
            let total = acc.iter().fold(f._mm512_setzero_si512(), |sum, &a| {
                f._mm512_add_epi32(sum, a)
            });
            f._mm512_reduce_add_epi32(total)
        }
    }

    pub(super) fn register(group: &mut BenchmarkGroup<'_, WallTime>) {
        let Some(simd) = V4::try_new() else {
            eprintln!("floors: no AVX-512 on this CPU, the vpmaddwd floors are skipped");
            return;
        };
        let f = simd.avx512f;
        // Small integers: the sums never overflow, whatever the order.
        #[allow(clippy::cast_possible_truncation, clippy::cast_possible_wrap)]
        let value = |i: usize| f._mm512_set1_epi16((i % 61) as i16 - 30);
        let vector: [__m512i; REGISTERS] = core::array::from_fn(value);
        for (name, axes) in [
            ("madd_stream_51x1024_l2", 51),
            ("madd_stream_16x1024_l1", 16),
        ] {
            let basis: Vec<__m512i> = (0..axes * REGISTERS).map(value).collect();
            group.bench_function(name, |b| {
                b.iter(|| {
                    black_box(simd.vectorize(Stream {
                        simd,
                        basis: black_box(&basis),
                        vector: &vector,
                    }))
                })
            });
        }
    }
}

criterion_group!(benches, floors);
criterion_main!(benches);
