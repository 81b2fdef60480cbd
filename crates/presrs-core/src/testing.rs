//! Synthetic fixtures for tests and benchmarks: a synthetic stance stream over the images of
//! [`synthetic`](crate::synthetic), whose generator and bench setup are re-exported here under the names
//! the tests use.
//!
//! Behind the `testing` cargo feature (always on in this crate's own unit tests), never on in a
//! production build: tests and benchmarks enable it through their dev-dependencies.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::classifier::ClassifierKind;
use crate::crop::Crop;
use crate::error::Result;
use crate::features::{FeatureConfig, RocketFamily, RocketParams};
use crate::frame::{Frame, Grid};
use crate::pipeline::{LabeledImage, StanceImages, TrainConfig, TrainedModel, train, train_early};
use crate::preprocess::Preprocess;
use crate::sample::SampleKind;
use crate::stance::summary::{SummaryConfig, pad_to, summarise};
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

/// A synthetic 100 Hz movie of stances of `lens` frames (the `i`-th of class `i % 4`, a half-sine load
/// over its print) after 20-frame flights with a few noisy sensels, drawn from `seed`; with each
/// stance as `(first frame, frames, class)`.
pub fn stance_stream(lens: &[usize], seed: u64) -> (Vec<Frame>, Vec<(usize, usize, usize)>) {
    const FLIGHT_FRAMES: usize = 20;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut frames = Vec::new();
    let mut stances = Vec::new();
    for (i, &len) in lens.iter().enumerate() {
        let print = synthetic_frame(i % 4, &mut rng);
        for _ in 0..FLIGHT_FRAMES {
            let mut flight = Frame::zeros(print.grid());
            for _ in 0..3 {
                let at = rng.random_range(0..flight.values().len());
                flight.values_mut()[at] = rng.random_range(3.0..6.0);
            }
            frames.push(flight);
        }
        stances.push((frames.len(), len, i % 4));
        for j in 0..len {
            let scale = (std::f64::consts::PI * (j as f64 + 0.5) / len as f64).sin();
            let mut frame = print.clone();
            for v in frame.values_mut() {
                *v = (*v * scale).round();
            }
            frames.push(frame);
        }
    }
    frames.extend((0..FLIGHT_FRAMES).map(|_| Frame::zeros(Grid::new(44, 44))));
    (frames, stances)
}

/// The sample a whole-stance model of `length` frames takes for `frames`: their summary
/// ([`summarise`]) laid into the length ([`pad_to`]), as offline training and `classify` make it.
pub fn stance_sample(frames: &[Frame], length: usize) -> Result<Frame> {
    let views: Vec<_> = frames.iter().map(Frame::view).collect();
    let summary = summarise(&views, &SummaryConfig::default())?;
    Ok(pad_to(&summary.view(), length)?.0)
}

/// A whole-stance model of `length` frames, small and quick (168 MiniRocket features, 12 components,
/// linear discriminant), trained on the `stances` (`(first frame, frames, class)`) of `frames`.
pub fn stance_model(
    frames: &[Frame],
    stances: &[(usize, usize, usize)],
    length: usize,
) -> Result<TrainedModel> {
    stance_model_with(frames, stances, length, 168, 12, ClassifierKind::LDA)
}

/// [`stance_model`] with `num_features` MiniRocket features, `dims` components and `classifier`.
pub fn stance_model_with(
    frames: &[Frame],
    stances: &[(usize, usize, usize)],
    length: usize,
    num_features: usize,
    dims: usize,
    classifier: ClassifierKind,
) -> Result<TrainedModel> {
    let samples = stances
        .iter()
        .map(|&(start, len, class)| {
            let sample = stance_sample(&frames[start..start + len], length)?;
            Ok((sample, SYNTHETIC_CLASSES[class]))
        })
        .collect::<Result<Vec<_>>>()?;
    let images: Vec<_> = samples
        .iter()
        .map(|(frame, label)| LabeledImage::new(frame.view(), label))
        .collect();
    let config = TrainConfig {
        crop: Crop::NONE,
        features: FeatureConfig::of::<RocketFamily>(RocketParams {
            num_features,
            ..RocketParams::default()
        }),
        dims,
        classifier: classifier.default_config(),
        preprocess: Preprocess::NONE,
    }
    .check()?;
    train(&images, &[], &config)?.with_sample(SampleKind::Stance {
        summary: SummaryConfig::default(),
        length: None,
    })
}

/// [`stance_model`] with classifiers for the decision points `points` (frames after touchdown), each
/// trained on the training stances cut there, and `auto`'s threshold learned from their inner folds.
pub fn stance_model_with_points(
    frames: &[Frame],
    stances: &[(usize, usize, usize)],
    length: usize,
    points: &[usize],
) -> Result<TrainedModel> {
    let model = stance_model(frames, stances, length)?;
    let cut = |k: usize| {
        stances
            .iter()
            .map(|&(start, len, _)| stance_sample(&frames[start..start + len.min(k + 1)], k + 1))
            .collect::<Result<Vec<_>>>()
    };
    let whole: Vec<Frame> = stances
        .iter()
        .map(|&(start, len, _)| stance_sample(&frames[start..start + len], length))
        .collect::<Result<_>>()?;
    let cuts: Vec<(usize, Vec<Frame>)> = points
        .iter()
        .map(|&k| Ok((k, cut(k)?)))
        .collect::<Result<_>>()?;

    let train_set = StanceImages {
        whole: labeled(&whole, stances),
        cuts: cuts
            .iter()
            .map(|(k, set)| (*k, labeled(set, stances)))
            .collect(),
        stance_frames: stances.iter().map(|s| s.1).collect(),
    };
    let validation = StanceImages {
        cuts: points.iter().map(|&k| (k, Vec::new())).collect(),
        ..StanceImages::default()
    };
    let early = train_early(&model, &train_set, &validation, None, 1, None)?;
    model.with_early(early)
}

/// `set`'s frames labelled with the classes of `stances`, in order.
fn labeled<'a>(set: &'a [Frame], stances: &[(usize, usize, usize)]) -> Vec<LabeledImage<'a>> {
    set.iter()
        .zip(stances)
        .map(|(frame, stance)| LabeledImage::new(frame.view(), SYNTHETIC_CLASSES[stance.2]))
        .collect()
}
