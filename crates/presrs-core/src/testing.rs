//! Synthetic fixtures for tests and benchmarks: a learnable paper-sized pressure image per class, a
//! synthetic stance stream, and the trained setup of `presrs bench`.
//!
//! Behind the `testing` cargo feature (always on in this crate's own unit tests): fixtures are not part of
//! the algorithms' API. Crates, tests and benchmarks that need them enable the feature (as a dev-dependency
//! feature where only their tests do).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::error::Result;
use crate::frame::{Frame, Grid};
use crate::pipeline::config::TrainConfig;
use crate::pipeline::extract::LabeledImage;
use crate::pipeline::model::TrainedModel;
use crate::pipeline::train::train;

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

/// Class names of [`synthetic_frame`]'s four classes, in class-index order (sorted, as [`train`] orders them).
pub const SYNTHETIC_CLASSES: [&str; 4] = ["carpet", "clay", "grass", "wood"];

/// A synthetic pressure image for benchmarks and tests: a 44 x 44 frame of a foot print whose texture
/// depends on `class` (an index into [`SYNTHETIC_CLASSES`], taken modulo 4). Deterministic for a given RNG
/// state. Not a physical model (the simulator crate has one); it only has to be learnable and paper-sized.
pub fn synthetic_frame(class: usize, rng: &mut impl Rng) -> Frame {
    const SIZE: usize = 44;
    let mut frame = Frame::zeros(Grid::new(SIZE, SIZE));
    // Foot print: an ellipse inside the paper's 38 x 41 region, jittered by a sensel or two.
    let centre_row = 19.0 + rng.random_range(-1.5..1.5);
    let centre_col = 23.5 + rng.random_range(-1.5..1.5);
    let load = rng.random_range(0.8..1.2);
    let phase = rng.random_range(0.0..std::f64::consts::TAU);
    for (index, value) in frame.values_mut().iter_mut().enumerate() {
        let (row, col) = ((index / SIZE) as f64, (index % SIZE) as f64);
        let radius2 = ((row - centre_row) / 16.0).powi(2) + ((col - centre_col) / 17.0).powi(2);
        if radius2 >= 1.0 {
            continue;
        }
        let envelope = 120.0 * load * (1.0 - radius2).sqrt();
        let texture = match class % 4 {
            // "carpet": fine-grained, independent per sensel
            0 => 0.5 + rng.random_range(0.0..1.0),
            // "clay": blotchy, low spatial frequency
            1 => 1.0 + 0.6 * (0.45 * row + phase).sin() * (0.35 * col).cos(),
            // "grass": stripes along the columns with sparse sharp points
            2 => {
                let stripes = 0.7 + 0.6 * (2.1 * col + phase).sin().max(0.0);
                let spike = if rng.random_range(0.0..1.0) < 0.05 {
                    1.5
                } else {
                    0.0
                };
                stripes + spike
            }
            // "wood": smooth and even
            _ => 1.0 + 0.05 * rng.random_range(-1.0..1.0),
        };
        *value = (envelope * texture).round().clamp(0.0, 255.0);
    }
    frame
}

/// The paper-sized setup of `presrs bench` and the criterion benchmarks: four synthetic classes on the
/// 44 x 44 array, 13 training + 7 validation images each (80 stored vectors), the paper's settings
/// ([`TrainConfig::default`]: crop to 38 x 41, |FFT| with N = 2048, PCA to 51, Parzen window), and
/// `n_test` further frames to classify (cycling through the classes). Deterministic in `seed`.
pub fn bench_fixture(seed: u64, n_test: usize) -> Result<(TrainedModel, Vec<Frame>)> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut make = |count: usize| -> Vec<(Frame, &'static str)> {
        (0..count)
            .map(|i| (synthetic_frame(i % 4, &mut rng), SYNTHETIC_CLASSES[i % 4]))
            .collect()
    };
    let train_set = make(4 * 13);
    let validation_set = make(4 * 7);
    let test_frames = make(n_test).into_iter().map(|(frame, _)| frame).collect();
    let model = train(
        &as_images(&train_set),
        &as_images(&validation_set),
        &TrainConfig::default().check()?,
    )?;
    Ok((model, test_frames))
}

fn as_images<'a>(set: &'a [(Frame, &'static str)]) -> Vec<LabeledImage<'a>> {
    set.iter()
        .map(|(frame, label)| LabeledImage::new(frame.view(), label))
        .collect()
}
