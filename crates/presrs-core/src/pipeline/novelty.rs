//! A trained model's novelty score, fitted on the vectors its classifier sees of its own training and
//! validation images ([`crate::novelty`]).

use rayon::prelude::*;

use crate::error::Result;
use crate::novelty::NoveltyModel;
use crate::pipeline::extract::LabeledImage;
use crate::pipeline::model::TrainedModel;
use crate::pipeline::train::class_indices;

/// The most values a vector may have for the novelty score: its discriminant space needs a
/// `dims x dims` covariance (a model without a PCA step, ridge's thousands of features, has none).
pub const MAX_NOVELTY_DIMS: usize = 512;

impl TrainedModel {
    /// This model with a novelty score fitted on `images` (its training and validation images, with their
    /// groups: the threshold is calibrated by leaving groups out, and needs three or more), set to
    /// reject `rejection` of held-out known vectors. The model is returned unchanged, without a score,
    /// when its classifier takes more than [`MAX_NOVELTY_DIMS`] values.
    pub fn with_novelty(self, images: &[LabeledImage<'_>], rejection: f64) -> Result<Self> {
        let groups: Vec<Option<&str>> = images.iter().map(|image| image.group).collect();
        self.with_novelty_by(images, &groups, rejection)
    }

    /// [`with_novelty`](Self::with_novelty) calibrated by leaving out `groups` (one per image; e.g. the
    /// recording an image came from when the images name no group).
    pub fn with_novelty_by(
        self,
        images: &[LabeledImage<'_>],
        groups: &[Option<&str>],
        rejection: f64,
    ) -> Result<Self> {
        let dims = self.classifier_dims();
        if dims > MAX_NOVELTY_DIMS {
            return Ok(self.without_novelty());
        }
        let classes = class_indices(self.class_names(), images)?;
        let vectors = self.reduced_vectors(images)?;
        let novelty = NoveltyModel::fit(
            &vectors,
            &classes,
            groups,
            self.class_names().len(),
            dims,
            rejection,
        )?;
        self.with_novelty_model(novelty)
    }

    /// The vectors the classifier sees of `images` (`n x classifier_dims`, row-major), as a session
    /// computes them.
    pub fn reduced_vectors(&self, images: &[LabeledImage<'_>]) -> Result<Vec<f64>> {
        let dims = self.classifier_dims();
        let mut vectors = vec![0.0; images.len() * dims];
        vectors
            .par_chunks_mut(dims.max(1))
            .zip(images.par_iter())
            .try_for_each_init(
                || self.session(),
                |session, (out, image)| {
                    out.copy_from_slice(session.reduce(&image.frame)?);
                    Ok(())
                },
            )?;
        Ok(vectors)
    }
}

#[cfg(test)]
mod tests {
    use crate::frame::Frame;
    use crate::pipeline::{LabeledImage, TrainConfig, TrainedModel, train};
    use crate::testing::labeled_set;

    /// A model of three of the four synthetic classes with a novelty score, and test frames of all four.
    fn model_without_the_fourth() -> (TrainedModel, Vec<(Frame, &'static str)>) {
        let set = labeled_set(30, 1);
        let known: Vec<&(Frame, &str)> = set.iter().filter(|(_, l)| *l != set[3].1).collect();
        // Five recordings, each holding every class.
        let groups = ["r0", "r1", "r2", "r3", "r4"];
        let images: Vec<LabeledImage<'_>> = known
            .iter()
            .enumerate()
            .map(|(i, (frame, label))| LabeledImage {
                group: Some(groups[i % 5]),
                ..LabeledImage::new(frame.view(), label)
            })
            .collect();
        let (train_images, validation_images) = images.split_at(60);
        let config = TrainConfig::default().check().unwrap();
        let model = train(train_images, validation_images, &config)
            .unwrap()
            .with_novelty(&images, 0.05)
            .unwrap();
        (model, labeled_set(20, 2))
    }

    #[test]
    fn every_path_gives_the_score_of_the_reduced_vector_and_a_class_never_seen_is_unknown() {
        let (model, test) = model_without_the_fourth();
        let novelty = model.novelty().unwrap();
        let views: Vec<_> = test.iter().map(|(frame, _)| frame.view()).collect();
        let batch = model.classify_batch(&views);
        let mut session = model.session();
        let mut reducer = model.session();
        let (mut novel_unknown, mut known_unknown) = (0, 0);
        for ((view, (_, label)), batched) in views.iter().zip(&test).zip(&batch) {
            let single = session.classify(view).unwrap().to_classification();
            assert_eq!(&single, batched.as_ref().unwrap());
            let oracle = novelty.score(reducer.reduce(view).unwrap()).unwrap();
            assert_eq!(single.novelty, Some(oracle));
            let unknown = usize::from(oracle.unknown);
            if model.class_names().iter().any(|name| name == label) {
                known_unknown += unknown;
            } else {
                novel_unknown += unknown;
            }
        }
        assert!(
            novel_unknown >= 15,
            "{novel_unknown} of 20 novel frames unknown"
        );
        assert!(
            known_unknown <= 6,
            "{known_unknown} of 60 known frames unknown"
        );
    }

    #[test]
    fn the_score_is_stored_dropped_on_request_and_absent_from_older_files() {
        let (model, test) = model_without_the_fourth();
        let json = serde_json::to_value(&model).unwrap();
        let back: TrainedModel = serde_json::from_value(json.clone()).unwrap();
        let frame = test[0].0.view();
        assert_eq!(
            back.session().classify(&frame).unwrap().novelty,
            model.session().classify(&frame).unwrap().novelty
        );
        let mut older = json;
        older.as_object_mut().unwrap().remove("novelty");
        let older: TrainedModel = serde_json::from_value(older).unwrap();
        assert!(older.novelty().is_none());
        assert_eq!(older.session().classify(&frame).unwrap().novelty, None);
        let off = model.clone().without_novelty();
        let (a, b) = (
            off.session().classify(&frame).unwrap().to_classification(),
            model
                .session()
                .classify(&frame)
                .unwrap()
                .to_classification(),
        );
        assert_eq!(
            (a.class, a.posteriors, a.novelty),
            (b.class, b.posteriors, None)
        );
    }
}
