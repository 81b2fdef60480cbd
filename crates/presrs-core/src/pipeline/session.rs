//! Classification: [`Session`] (one frame at a time, reused buffers, no allocation) and the batch path
//! ([`TrainedModel::classify_batch`]); the one room where the online and the offline paths meet.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::classifier::ClassifierScratch;
use crate::error::{CoreError, Result, check_len};
use crate::features::Precision;
use crate::features::contact::{ContactConfig, raw_measures_into};
use crate::frame::FrameView;
use crate::novelty::{Novelty, NoveltyScratch};
use crate::pipeline::extract::Preprocessor;
use crate::pipeline::model::TrainedModel;
use crate::projection::pca::{Pca, ProjectionScratch};

impl TrainedModel {
    /// A classification session with its own buffers (one per thread).
    pub fn session(&self) -> Session<'_> {
        let fields = &self.fields;
        Session {
            model: self,
            preprocessor: Preprocessor::new(
                fields.crop,
                fields.preprocess,
                fields.image_grid,
                self.extractor.clone(),
            ),
            features: vec![0.0; self.n_features()],
            projection: fields.pca.as_ref().map(Pca::scratch).unwrap_or_default(),
            reduced: vec![0.0; fields.pca.as_ref().map_or(0, Pca::n_components)],
            scratch: fields.classifier.scratch(),
            posteriors: vec![0.0; fields.class_names.len()],
            novelty: fields
                .novelty
                .as_ref()
                .map(|novelty| novelty.scratch())
                .unwrap_or_default(),
            contact: Vec::new(),
        }
    }

    /// Classifies many frames in parallel; results in input order, each equal (bit for bit) to what a
    /// [`Session`] gives for that frame. Frames go in blocks of [`BATCH_BLOCK`] per rayon task: the
    /// features of a block are projected together, so the PCA basis is read once per block rather than
    /// once per frame (without a PCA, each frame of a block goes through the session).
    pub fn classify_batch(&self, frames: &[FrameView<'_>]) -> Vec<Result<Classification>> {
        frames
            .par_chunks(BATCH_BLOCK)
            .map_init(
                || BatchSession::new(self),
                |session, block| session.classify_block(block),
            )
            .flatten()
            .collect()
    }
}

/// Classifies frames one at a time with reused buffers: no allocation per call.
#[derive(Debug)]
pub struct Session<'m> {
    model: &'m TrainedModel,
    preprocessor: Preprocessor,
    features: Vec<f64>,
    projection: ProjectionScratch,
    reduced: Vec<f64>,
    scratch: ClassifierScratch,
    posteriors: Vec<f64>,
    novelty: NoveltyScratch,
    /// The raw contact measures of the frame, when the novelty score reads them.
    contact: Vec<f64>,
}

/// The result of [`Session::classify`], borrowing the session's buffers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prediction<'s> {
    pub class: usize,
    pub label: &'s str,
    /// The posterior of `class`, capped by the sample's credibility when the model scores novelty
    /// ([`Novelty::capped`]; `posteriors` are the classifier's own).
    pub confidence: f64,
    /// Posterior of every class, in class-index order (equal priors).
    pub posteriors: &'s [f64],
    /// How far the frame lies from every class, when the model scores novelty; `unknown` says it is
    /// none of them (`class` is then the nearest one).
    pub novelty: Option<Novelty>,
}

impl Prediction<'_> {
    pub fn to_classification(&self) -> Classification {
        Classification {
            class: self.class,
            confidence: self.confidence,
            posteriors: self.posteriors.to_vec(),
            novelty: self.novelty,
        }
    }
}

/// An owned prediction (from [`TrainedModel::classify_batch`]); the label is
/// `model.class_names()[class]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Classification {
    pub class: usize,
    pub confidence: f64,
    pub posteriors: Vec<f64>,
    /// As [`Prediction::novelty`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub novelty: Option<Novelty>,
}

impl<'m> Session<'m> {
    pub fn model(&self) -> &'m TrainedModel {
        self.model
    }

    /// Classifies one frame. Errors when the frame's grid does not give the model's grid once cropped,
    /// or when it holds non-finite values.
    pub fn classify(&mut self, frame: &FrameView<'_>) -> Result<Prediction<'_>> {
        let contact = self.contact_measures(frame)?;
        self.reduce(frame)?;
        let model = self.model;
        let reduced = if model.fields.pca.is_some() {
            &self.reduced
        } else {
            &self.features
        };
        let class = classify_reduced(model, reduced, &mut self.scratch, &mut self.posteriors)?;
        let contact = contact.then_some(&self.contact[..]);
        let novelty = novelty_of(model, reduced, contact, &mut self.novelty)?;
        Ok(Prediction {
            class,
            label: &model.fields.class_names[class],
            confidence: reported_confidence(self.posteriors[class], novelty),
            posteriors: &self.posteriors,
            novelty,
        })
    }

    /// When the model's novelty score reads the contact's geometry, its raw measures of `frame`'s
    /// prepared image (cropped and transformed as the features see it) into the session's buffer;
    /// whether it does.
    pub(crate) fn contact_measures(&mut self, frame: &FrameView<'_>) -> Result<bool> {
        let Some(part) = self.model.novelty().and_then(|n| n.contact()) else {
            return Ok(false);
        };
        let mut buffer = std::mem::take(&mut self.contact);
        buffer.resize(part.measures(), 0.0);
        let written = self.raw_contact_into(part.config(), frame, &mut buffer);
        self.contact = buffer;
        written.map(|()| true)
    }

    /// The raw contact measures of `config` of `frame`'s prepared image (cropped and transformed as
    /// the features see it) into `out` (`config.measures()` long).
    pub(crate) fn raw_contact_into(
        &mut self,
        config: &ContactConfig,
        frame: &FrameView<'_>,
        out: &mut [f64],
    ) -> Result<()> {
        let grid = self.preprocessor.preparation.image_grid;
        let image = self.preprocessor.preparation.prepare(frame)?;
        raw_measures_into(config, grid, image, out)
    }

    /// The feature vector of `frame` (before PCA), exact: as training computes it.
    pub fn features(&mut self, frame: &FrameView<'_>) -> Result<&[f64]> {
        self.preprocessor
            .features_into(frame, &mut self.features, Precision::Exact)?;
        Ok(&self.features)
    }

    /// The feature vector of `frame` as classification computes it (before PCA): the fast path, with the
    /// 1-D |FFT| in single precision (within ~1e-6 of the largest exact feature).
    pub fn fast_features(&mut self, frame: &FrameView<'_>) -> Result<&[f64]> {
        self.preprocessor
            .features_into(frame, &mut self.features, Precision::Fast)?;
        Ok(&self.features)
    }

    /// The features of `frame` in the precision classification computes them in, f32, when it takes the
    /// common path (1-D |FFT| features, no absent sensels, no load normalisation; `None` otherwise, and
    /// [`fast_features`](Self::fast_features) gives them): the values of `fast_features`, before they
    /// are widened to f64. [`Pca::project_fast_into`](crate::projection::pca::Pca::project_fast_into) reads them as they are.
    pub fn fast_features_f32(&mut self, frame: &FrameView<'_>) -> Result<Option<&[f32]>> {
        self.preprocessor.fast_f32_features(frame)
    }

    /// The vector of `frame` the classifier sees: the [`fast_features`](Self::fast_features) and the
    /// PCA's fixed-point projection, or the fast features themselves when there is no PCA step.
    pub fn reduce(&mut self, frame: &FrameView<'_>) -> Result<&[f64]> {
        let Some(pca) = &self.model.fields.pca else {
            self.preprocessor
                .features_into(frame, &mut self.features, Precision::Fast)?;
            return Ok(&self.features);
        };
        match self.preprocessor.fast_f32_features(frame)? {
            // The same values as `fast_features` gives, without widening them to f64 and back.
            Some(features) => {
                pca.project_fast_into(features, &mut self.projection, &mut self.reduced)?;
            }
            None => {
                self.preprocessor
                    .features_into(frame, &mut self.features, Precision::Fast)?;
                pca.project_fast_into(&self.features, &mut self.projection, &mut self.reduced)?;
            }
        }
        Ok(&self.reduced)
    }
}

/// Frames per block of [`TrainedModel::classify_batch`]: their features (64 x 1025 x 8 B = 512 KB) and
/// quantized copies (64 x 2 KB) stay in L2 while the basis is streamed through once.
pub const BATCH_BLOCK: usize = 64;

/// The classifier step shared by [`Session`] and [`BatchSession`]: refuses a non-finite reduced vector
/// (the image held NaN or infinite values), then writes the posteriors and returns the class.
fn classify_reduced(
    model: &TrainedModel,
    reduced: &[f64],
    scratch: &mut ClassifierScratch,
    posteriors: &mut [f64],
) -> Result<usize> {
    if reduced.iter().any(|value| !value.is_finite()) {
        return Err(CoreError::Param {
            name: "image",
            reason: "contains NaN or infinite values".into(),
        });
    }
    model
        .fields
        .classifier
        .classify_into(reduced, scratch, posteriors)
}

/// The confidence a decision reports: the class's posterior, capped by the sample's credibility when
/// the model scores novelty (`crate::novelty`).
pub(crate) fn reported_confidence(posterior: f64, novelty: Option<Novelty>) -> f64 {
    novelty.map_or(posterior, |n| n.capped(posterior))
}

/// The novelty of a reduced vector (with the image's raw contact measures when the score reads them),
/// when the model scores it.
fn novelty_of(
    model: &TrainedModel,
    reduced: &[f64],
    contact: Option<&[f64]>,
    scratch: &mut NoveltyScratch,
) -> Result<Option<Novelty>> {
    model
        .fields
        .novelty
        .as_ref()
        .map(|novelty| novelty.score_parts_into(reduced, contact, scratch))
        .transpose()
}

/// Buffers for classifying a block of frames together (one per rayon worker in
/// [`TrainedModel::classify_batch`]): a session's, plus the block's features and reduced vectors.
#[derive(Debug)]
struct BatchSession<'m> {
    session: Session<'m>,
    /// Row-major `block x n_features`, in the single precision the projection reads (the fast features
    /// as they are, any others rounded).
    features: Vec<f32>,
    /// Row-major `block x n_components`.
    reduced: Vec<f64>,
    /// Row-major `block x measures`: the raw contact measures, when the novelty score reads them.
    contacts: Vec<f64>,
}

impl<'m> BatchSession<'m> {
    fn new(model: &'m TrainedModel) -> Self {
        Self {
            session: model.session(),
            features: Vec::new(),
            reduced: Vec::new(),
            contacts: Vec::new(),
        }
    }

    fn classify_block(&mut self, frames: &[FrameView<'_>]) -> Vec<Result<Classification>> {
        let session = &mut self.session;
        let model = session.model;
        let Some(pca) = &model.fields.pca else {
            // No basis to share: each frame as a session classifies it.
            return frames
                .iter()
                .map(|frame| Ok(session.classify(frame)?.to_classification()))
                .collect();
        };
        let (n_features, dims) = (pca.n_features(), pca.n_components());
        let measures = model
            .novelty()
            .and_then(|n| n.contact())
            .map_or(0, |part| part.measures());
        self.features.resize(frames.len() * n_features, 0.0);
        self.reduced.resize(frames.len() * dims, 0.0);
        self.contacts.resize(frames.len() * measures, 0.0);
        // A frame whose features fail keeps its error; its row is zeroed and its projection ignored.
        let mut failed: Vec<Option<CoreError>> = Vec::with_capacity(frames.len());
        for (k, (frame, row)) in frames
            .iter()
            .zip(self.features.chunks_exact_mut(n_features))
            .enumerate()
        {
            let contact = &mut self.contacts[k * measures..(k + 1) * measures];
            let error = contact_into(session, frame, contact)
                .and_then(|()| single_features_into(session, frame, row))
                .err();
            if error.is_some() {
                row.fill(0.0);
            }
            failed.push(error);
        }
        if let Err(err) =
            pca.project_fast_many(&self.features, &mut session.projection, &mut self.reduced)
        {
            // Cannot happen (the buffers are sized above); every frame gets the reason all the same.
            let reason = err.to_string();
            return frames
                .iter()
                .map(|_| {
                    Err(CoreError::Param {
                        name: "pca",
                        reason: reason.clone(),
                    })
                })
                .collect();
        }
        let contacts = &self.contacts;
        failed
            .into_iter()
            .zip(self.reduced.chunks_exact(dims))
            .enumerate()
            .map(|(k, (error, reduced))| match error {
                Some(err) => Err(err),
                None => {
                    let class = classify_reduced(
                        model,
                        reduced,
                        &mut session.scratch,
                        &mut session.posteriors,
                    )?;
                    let contact =
                        (measures > 0).then(|| &contacts[k * measures..(k + 1) * measures]);
                    let novelty = novelty_of(model, reduced, contact, &mut session.novelty)?;
                    Ok(Classification {
                        class,
                        confidence: reported_confidence(session.posteriors[class], novelty),
                        posteriors: session.posteriors.clone(),
                        novelty,
                    })
                }
            })
            .collect()
    }
}

/// The raw contact measures of `frame` into `out` when the model's novelty score reads them (`out`
/// is then as long as they are; empty otherwise).
fn contact_into(session: &mut Session<'_>, frame: &FrameView<'_>, out: &mut [f64]) -> Result<()> {
    if out.is_empty() || !session.contact_measures(frame)? {
        return Ok(());
    }
    out.copy_from_slice(&session.contact);
    Ok(())
}

/// The features of `frame` as classification computes them, in f32, into `out`: straight from the fast
/// path, or computed in f64 by the session and rounded.
fn single_features_into(
    session: &mut Session<'_>,
    frame: &FrameView<'_>,
    out: &mut [f32],
) -> Result<()> {
    if let Some(features) = session.preprocessor.fast_f32_features(frame)? {
        check_len("feature buffer", features.len(), out.len())?;
        out.copy_from_slice(features);
        return Ok(());
    }
    session
        .preprocessor
        .features_into(frame, &mut session.features, Precision::Fast)?;
    check_len("feature buffer", session.features.len(), out.len())?;
    #[allow(clippy::cast_possible_truncation)]
    for (dst, &value) in out.iter_mut().zip(&session.features) {
        *dst = value as f32;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use crate::frame::Frame;
    use crate::testing::bench_fixture;

    #[test]
    fn classify_equals_classify_batch() {
        let (model, frames) = bench_fixture(5, 2 * super::BATCH_BLOCK + 3).unwrap();
        let views: Vec<_> = frames.iter().map(Frame::view).collect();
        let batch = model.classify_batch(&views);
        let mut session = model.session();
        for (view, batched) in views.iter().zip(&batch) {
            let single = session.classify(view).unwrap().to_classification();
            assert_eq!(&single, batched.as_ref().unwrap());
        }
    }

    #[test]
    fn a_frame_of_another_grid_or_with_nan_is_refused() {
        let (model, frames) = bench_fixture(5, 1).unwrap();
        let mut session = model.session();
        let small = Frame::new(crate::frame::Grid::new(4, 4), vec![0.0; 16]).unwrap();
        assert!(session.classify(&small.view()).is_err());
        let mut values = frames[0].view().values().to_vec();
        values[45 * 3] = f64::NAN;
        let bad = Frame::new(frames[0].view().grid(), values).unwrap();
        assert!(session.classify(&bad.view()).is_err());
        let results = model.classify_batch(&[frames[0].view(), bad.view()]);
        assert!(results[0].is_ok() && results[1].is_err());
    }
}
