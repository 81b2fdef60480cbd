//! Synthetic fixtures for tests and benchmarks: a synthetic stance stream over the images of
//! [`synthetic`](crate::synthetic), whose generator and bench setup are re-exported here under the names
//! the tests use.
//!
//! Behind the `testing` cargo feature (always on in this crate's own unit tests), never on in a
//! production build: tests and benchmarks enable it through their dev-dependencies.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::frame::Frame;
pub use crate::synthetic::bench_workload as bench_fixture;
pub use crate::synthetic::{SYNTHETIC_CLASSES, synthetic_frame};

/// `per_class` synthetic images of each of the four classes, with their labels, drawn from `seed`.
pub fn labeled_set(per_class: usize, seed: u64) -> Vec<(Frame, &'static str)> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..4 * per_class)
        .map(|i| (synthetic_frame(i % 4, &mut rng), SYNTHETIC_CLASSES[i % 4]))
        .collect()
}

/// A synthetic 100 Hz movie for benchmarks and tests of the online path: `stances` times, 20 empty flight
/// frames then a 14-frame stance whose load follows a half sine over the print of [`synthetic_frame`]
/// (class `i % 4` for the `i`-th stance).
pub fn synthetic_stream(stances: usize, rng: &mut impl Rng) -> Vec<Frame> {
    const FLIGHT_FRAMES: usize = 20;
    const STANCE_FRAMES: usize = 14;
    let mut frames = Vec::with_capacity(stances * (FLIGHT_FRAMES + STANCE_FRAMES));
    for i in 0..stances {
        let print = synthetic_frame(i % 4, rng);
        frames.extend((0..FLIGHT_FRAMES).map(|_| Frame::zeros(print.grid())));
        for j in 0..STANCE_FRAMES {
            let scale = (std::f64::consts::PI * (j as f64 + 0.5) / STANCE_FRAMES as f64).sin();
            let mut frame = print.clone();
            for v in frame.values_mut() {
                *v = (*v * scale).round();
            }
            frames.push(frame);
        }
    }
    frames
}
