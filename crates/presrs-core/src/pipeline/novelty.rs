//! A trained model's novelty score, fitted on the vectors its classifier sees of its own training and
//! validation images ([`crate::novelty`]).

use rayon::prelude::*;

use crate::error::Result;
use crate::features::contact::ContactConfig;
use crate::novelty::{LabelledVectors, NoveltyModel};
use crate::pipeline::contact_check::check_contact;
use crate::pipeline::extract::LabeledImage;
use crate::pipeline::model::TrainedModel;
use crate::pipeline::train::class_indices;
use crate::projection::Pca;

/// The most values a vector may have for the novelty score's discriminant space as they are: it needs a
/// `dims x dims` covariance. A classifier that reads more (a model without a PCA step, ridge on
/// thousands of random-convolution features) has its vectors reduced to [`NOVELTY_COMPONENTS`]
/// principal components of their own first.
pub const MAX_NOVELTY_DIMS: usize = 512;

/// Principal components the novelty score of a wide classifier reads: the pipeline's default PCA size
/// (the paper's 51), not tuned for novelty.
pub const NOVELTY_COMPONENTS: usize = 51;

/// The most training vectors that wide reduction is fitted on, evenly spaced over the training images:
/// their `n x dims` matrix is held at once (2,000 x 10,000 values: 160 MB), while the rest are reduced
/// one image at a time.
pub const NOVELTY_PCA_SAMPLES: usize = 2000;

impl TrainedModel {
    /// This model with a novelty score fitted on `images` (its training and validation images, with their
    /// groups: the threshold is calibrated by leaving groups out, and needs three or more), set to
    /// reject `rejection` of held-out known vectors.
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
        let classes = class_indices(self.class_names(), images)?;
        let n_classes = self.class_names().len();
        let novelty = if dims > MAX_NOVELTY_DIMS {
            let (pca, vectors) = self.novelty_reduction(images)?;
            let data =
                LabelledVectors::new(&vectors, &classes, groups, n_classes, pca.n_components())?;
            NoveltyModel::fit(data, rejection)?.with_reduction(pca)?
        } else {
            let vectors = self.reduced_vectors(images)?;
            let data = LabelledVectors::new(&vectors, &classes, groups, n_classes, dims)?;
            // A frame model's score reads the contact's geometry when its own classes, left out
            // inside the training data, are told apart better with it (`contact_check`).
            let (raw, check) = if self.sample().is_frame() {
                let config = ContactConfig::default();
                let raw = self.raw_contact(&config, images)?;
                let check = check_contact(&config, data, &raw)?;
                (Some((config, raw)), check)
            } else {
                (None, None)
            };
            match raw {
                Some((config, raw)) if check.is_some_and(|check| check.taken) => {
                    NoveltyModel::fit_with_contact(&config, data, &raw, rejection)?
                }
                _ => NoveltyModel::fit(data, rejection)?,
            }
            .with_contact_check(check)
        };
        self.with_novelty_model(novelty)
    }

    /// The raw contact measures of `config` of every image's prepared image (`n x measures`).
    fn raw_contact(&self, config: &ContactConfig, images: &[LabeledImage<'_>]) -> Result<Vec<f64>> {
        let measures = config.measures();
        let mut raw = vec![0.0; images.len() * measures];
        raw.par_chunks_mut(measures.max(1))
            .zip(images.par_iter())
            .try_for_each_init(
                || self.session(),
                |session, (out, image)| session.raw_contact_into(config, &image.frame, out),
            )?;
        Ok(raw)
    }

    /// Principal components of the classifier's vectors of at most [`NOVELTY_PCA_SAMPLES`] of
    /// `images`, evenly spaced (no random draw: the same images give the same reduction), and every
    /// image's vector reduced by them (`n x components`): the fitted vectors projected when they are
    /// every image's, else each image's features computed again, one image at a time.
    fn novelty_reduction(&self, images: &[LabeledImage<'_>]) -> Result<(Pca, Vec<f64>)> {
        let step = images.len().div_ceil(NOVELTY_PCA_SAMPLES).max(1);
        let sample: Vec<LabeledImage<'_>> = images.iter().step_by(step).copied().collect();
        let dims = self.classifier_dims();
        let sampled = self.reduced_vectors(&sample)?;
        let pca = Pca::fit(&sampled, dims, NOVELTY_COMPONENTS)?;
        let components = pca.n_components();
        // (projected as scoring projects a sample, `project_into`)
        let vectors = if step == 1 {
            let mut vectors = vec![0.0; images.len() * components];
            for (x, out) in sampled
                .chunks_exact(dims.max(1))
                .zip(vectors.chunks_exact_mut(components.max(1)))
            {
                pca.project_into(x, out)?;
            }
            vectors
        } else {
            drop(sampled);
            self.vectors_by(images, components, |x, out| pca.project_into(x, out))?
        };
        Ok((pca, vectors))
    }

    /// The vectors the classifier sees of `images` (`n x classifier_dims`, row-major), as a session
    /// computes them.
    pub fn reduced_vectors(&self, images: &[LabeledImage<'_>]) -> Result<Vec<f64>> {
        self.vectors_by(images, self.classifier_dims(), |x, out| {
            out.copy_from_slice(x);
            Ok(())
        })
    }

    /// `width` values of each image (`n x width`, row-major), `write` filling them from the vector the
    /// classifier sees, in parallel (a session per worker).
    fn vectors_by(
        &self,
        images: &[LabeledImage<'_>],
        width: usize,
        write: impl Fn(&[f64], &mut [f64]) -> Result<()> + Sync,
    ) -> Result<Vec<f64>> {
        let mut vectors = vec![0.0; images.len() * width];
        vectors
            .par_chunks_mut(width.max(1))
            .zip(images.par_iter())
            .try_for_each_init(
                || self.session(),
                |session, (out, image)| write(session.reduce(&image.frame)?, out),
            )?;
        Ok(vectors)
    }
}

#[cfg(test)]
mod tests {
    use super::{MAX_NOVELTY_DIMS, NOVELTY_COMPONENTS};
    use crate::classifier::ClassifierKind;
    use crate::frame::Frame;
    use crate::novelty::{LabelledVectors, NoveltyModel};
    use crate::pipeline::train::class_indices;
    use crate::pipeline::{LabeledImage, TrainConfig, TrainedModel, train};
    use crate::projection::Pca;
    use crate::testing::labeled_set;

    /// The images of `set` but its fourth class, from five recordings each holding every class.
    fn known_images<'a>(set: &'a [(Frame, &'static str)]) -> Vec<LabeledImage<'a>> {
        let groups = ["r0", "r1", "r2", "r3", "r4"];
        set.iter()
            .filter(|(_, label)| *label != set[3].1)
            .enumerate()
            .map(|(i, (frame, label))| LabeledImage {
                group: Some(groups[i % 5]),
                ..LabeledImage::new(frame.view(), label)
            })
            .collect()
    }

    /// A model of three of the four synthetic classes with a novelty score, and test frames of all four.
    fn model_without_the_fourth() -> (TrainedModel, Vec<(Frame, &'static str)>) {
        let set = labeled_set(30, 1);
        let images = known_images(&set);
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
    fn a_classifier_of_every_feature_gets_a_score_of_its_own_principal_components() {
        let set = labeled_set(30, 1);
        let images = known_images(&set);
        let config = TrainConfig {
            classifier: ClassifierKind::RIDGE_RAW.default_config(),
            ..TrainConfig::default()
        }
        .check()
        .unwrap();
        let model = train(&images, &[], &config)
            .unwrap()
            .with_novelty(&images, 0.05)
            .unwrap();
        assert!(model.pca().is_none() && model.classifier_dims() > MAX_NOVELTY_DIMS);
        assert_eq!(
            model.describe_projection(),
            format!("no PCA: {} features as they are", model.n_features())
        );
        let novelty = model.novelty().expect("a score for the wide classifier");
        assert_eq!(novelty.dims(), model.classifier_dims());
        assert!(
            novelty.describe().contains("principal components"),
            "{}",
            novelty.describe()
        );
        assert_eq!(NOVELTY_COMPONENTS, TrainConfig::default().dims);
        // The oracle: the reduction fitted by hand on every image (fewer than the sample cap), a
        // score fitted on its projections, the two put together.
        let vectors = model.reduced_vectors(&images).unwrap();
        let pca = Pca::fit(&vectors, model.classifier_dims(), NOVELTY_COMPONENTS).unwrap();
        let projected: Vec<f64> = vectors
            .chunks_exact(model.classifier_dims())
            .flat_map(|row| pca.project(row).unwrap())
            .collect();
        let classes = class_indices(model.class_names(), &images).unwrap();
        let groups: Vec<Option<&str>> = images.iter().map(|image| image.group).collect();
        let components = pca.n_components();
        let oracle = NoveltyModel::fit(
            LabelledVectors::new(&projected, &classes, &groups, 3, components).unwrap(),
            0.05,
        )
        .unwrap()
        .with_reduction(pca)
        .unwrap();
        assert_eq!(novelty, &oracle);
        let test = labeled_set(10, 2);
        let mut session = model.session();
        let (mut novel, mut known) = (Vec::new(), Vec::new());
        for (frame, label) in &test {
            let decided = session.classify(&frame.view()).unwrap().novelty.unwrap();
            if *label == set[3].1 {
                novel.push(decided.score);
            } else {
                known.push(decided.score);
            }
        }
        let median = |v: &mut Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        assert!(
            median(&mut novel) > median(&mut known),
            "{novel:?} against {known:?}"
        );
        let json = serde_json::to_value(&model).unwrap();
        let back: TrainedModel = serde_json::from_value(json).unwrap();
        assert_eq!(
            back.session().classify(&test[0].0.view()).unwrap().novelty,
            model.session().classify(&test[0].0.view()).unwrap().novelty
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

    /// A score with the contact part (forced, whatever the check says): the session, the batch path and
    /// an oracle (the reduced vector and the raw measures of the prepared image, scored by the part
    /// directly) agree, the model file keeps the part, and the check's figures reach `describe`.
    #[test]
    fn a_score_with_the_contact_part_is_the_same_on_every_path_and_kept_in_the_file() {
        use crate::features::contact::ContactConfig;
        let (model, test) = model_without_the_fourth();
        let set = labeled_set(30, 1);
        let images = known_images(&set);
        let groups: Vec<Option<&str>> = images.iter().map(|image| image.group).collect();
        let classes = class_indices(model.class_names(), &images).unwrap();
        let config = ContactConfig::default();
        let vectors = model.reduced_vectors(&images).unwrap();
        let raw = model.raw_contact(&config, &images).unwrap();
        let dims = model.classifier_dims();
        let check = crate::pipeline::contact_check::check_contact(
            &config,
            LabelledVectors::new(&vectors, &classes, &groups, 3, dims).unwrap(),
            &raw,
        )
        .unwrap();
        let scorer = NoveltyModel::fit_with_contact(
            &config,
            LabelledVectors::new(&vectors, &classes, &groups, 3, dims).unwrap(),
            &raw,
            0.05,
        )
        .unwrap()
        .with_contact_check(check);
        let model = model.with_novelty_model(scorer).unwrap();
        let novelty = model.novelty().unwrap();
        assert!(novelty.contact().is_some());
        assert!(novelty.describe().contains("contact's geometry"));
        let views: Vec<_> = test.iter().map(|(frame, _)| frame.view()).collect();
        let batch = model.classify_batch(&views);
        let (mut session, mut reducer) = (model.session(), model.session());
        let mut measures = vec![0.0; config.measures()];
        for (view, batched) in views.iter().zip(&batch) {
            let single = session.classify(view).unwrap().to_classification();
            assert_eq!(&single, batched.as_ref().unwrap());
            let reduced = reducer.reduce(view).unwrap().to_vec();
            reducer
                .raw_contact_into(&config, view, &mut measures)
                .unwrap();
            let oracle = novelty
                .score_parts_into(&reduced, Some(&measures), &mut novelty.scratch())
                .unwrap();
            assert_eq!(single.novelty, Some(oracle));
        }
        let text = serde_json::to_string(&model).unwrap();
        let back: TrainedModel = serde_json::from_str(&text).unwrap();
        assert_eq!(back.novelty(), model.novelty());
    }
}
