//! Training: the classes of a training set, its features, the PCA (unless the classifier takes every
//! feature) and the classifier, into a model.

use crate::classifier::{ClassifierConfig, ClassifierModel, LabeledVectors};
use crate::error::{CoreError, Result};
use crate::features::Precision;
use crate::pipeline::config::CheckedTrainConfig;
use crate::pipeline::extract::{LabeledImage, features_of, fitted_config, preprocessor_for};
use crate::pipeline::model::{FORMAT_VERSION, ModelFields, TrainedModel, TrainingSummary};
use crate::projection::pca::Pca;
use crate::sample::SampleKind;

/// Trains the pipeline (see the module documentation). Classes are the distinct training labels, sorted;
/// every validation label must be one of them.
pub fn train(
    train: &[LabeledImage<'_>],
    validation: &[LabeledImage<'_>],
    config: &CheckedTrainConfig,
) -> Result<TrainedModel> {
    train_searching(train, validation, config, None).map(|(model, _)| model)
}

/// [`train`], with the classifier's hyper-parameters searched on the images `search` only (indices
/// into the training images followed by the validation images, each keeping its role) when its family
/// pins them ([`ClassifierConfig::pins`](crate::classifier::ClassifierConfig::pins)): the classifier
/// is fitted (with its search and calibration) on those images' vectors, and the configuration it
/// chose, pinned, is fitted on every vector. The features and the PCA are every image's either way.
/// Also says whether the search was run on `search` (`false`: the family pins nothing, the search
/// failed on `search`, or no `search` was given, and the classifier was trained as [`train`] trains
/// it).
pub(crate) fn train_searching(
    train: &[LabeledImage<'_>],
    validation: &[LabeledImage<'_>],
    config: &CheckedTrainConfig,
    search: Option<&[usize]>,
) -> Result<(TrainedModel, bool)> {
    let config = config.config();
    let first = train
        .first()
        .ok_or_else(|| CoreError::NotEnoughData("no training images".into()))?;
    let class_names = class_names_of(train)?;
    let train_classes = class_indices(&class_names, train)?;
    let validation_classes = class_indices(&class_names, validation)?;

    let fitted = fitted_config(config, train)?;
    let preprocessor = preprocessor_for(&fitted, first.frame.grid())?;
    let image_grid = preprocessor.image_grid();
    let n_features = preprocessor.extractor.output_len();
    // A classifier that takes every feature and reads them in single precision gets them so: the
    // feature table (`n x` thousands) is the largest thing training holds.
    let single = config.pca_dims().is_none() && config.classifier.reads_single();
    let (pca, classifier, searched_on_subset) = if single {
        let train_features = features_of::<f32>(train, &preprocessor, Precision::Exact)?;
        let validation_features = features_of::<f32>(validation, &preprocessor, Precision::Exact)?;
        let sets = Sets::of(
            (&train_features, &train_classes),
            (&validation_features, &validation_classes),
            class_names.len(),
            n_features,
        );
        let (classifier, searched) = fit_searching(&config.classifier, sets, search)?;
        (None, classifier, searched)
    } else {
        let train_features = features_of::<f64>(train, &preprocessor, Precision::Exact)?;
        let validation_features = features_of::<f64>(validation, &preprocessor, Precision::Exact)?;
        let (pca, train_vectors, validation_vectors) = match config.pca_dims() {
            Some(dims) => {
                let pca = Pca::fit(&train_features, n_features, dims)?;
                let train_vectors = project_rows(&pca, &train_features)?;
                let validation_vectors = project_rows(&pca, &validation_features)?;
                // The features (`n x` thousands) are not needed past the projection: gone before
                // the classifier's fit, which may hold an `n x n` kernel matrix of its own.
                drop((train_features, validation_features));
                (Some(pca), train_vectors, validation_vectors)
            }
            // The classifier takes every feature (and standardises them itself).
            None => (None, train_features, validation_features),
        };
        let sets = Sets::of(
            (&train_vectors, &train_classes),
            (&validation_vectors, &validation_classes),
            class_names.len(),
            pca.as_ref().map_or(n_features, Pca::n_components),
        );
        let (classifier, searched) = fit_searching(&config.classifier, sets, search)?;
        (pca, classifier, searched)
    };

    let count = |classes: &[usize]| {
        let mut counts = vec![0; class_names.len()];
        for &class in classes {
            counts[class] += 1;
        }
        counts
    };
    let summary = TrainingSummary {
        config: config.clone(),
        train_per_class: count(&train_classes),
        validation_per_class: count(&validation_classes),
        searched_on: search.filter(|_| searched_on_subset).map(<[usize]>::len),
    };
    let model = TrainedModel::try_from(ModelFields {
        format_version: FORMAT_VERSION,
        crop: config.crop,
        preprocess: config.preprocess,
        image_grid,
        features: fitted.features,
        pca,
        classifier,
        class_names,
        summary,
        selection: None,
        sample: SampleKind::Frame,
        sensor: None,
        sampling: None,
        early: None,
        novelty: None,
    })?;
    Ok((model, searched_on_subset))
}

/// A training set's vectors in one precision, with their shape.
struct Sets<'a, T> {
    train: LabeledVectors<'a, T>,
    validation: LabeledVectors<'a, T>,
    n_classes: usize,
    dims: usize,
}

impl<'a, T> Sets<'a, T> {
    /// The training and validation `(vectors, classes)` of `dims` values each.
    fn of(
        train: (&'a [T], &'a [usize]),
        validation: (&'a [T], &'a [usize]),
        n_classes: usize,
        dims: usize,
    ) -> Self {
        Self {
            train: LabeledVectors {
                vectors: train.0,
                classes: train.1,
            },
            validation: LabeledVectors {
                vectors: validation.0,
                classes: validation.1,
            },
            n_classes,
            dims,
        }
    }
}

/// The precisions a classifier is fitted in: double for every family, single for those that read it.
trait Element: Copy + Send + Sync {
    fn fit(
        classifier: &ClassifierConfig,
        sets: &Sets<'_, Self>,
        train: LabeledVectors<'_, Self>,
        validation: LabeledVectors<'_, Self>,
    ) -> Result<ClassifierModel>;
}

impl Element for f64 {
    fn fit(
        classifier: &ClassifierConfig,
        sets: &Sets<'_, f64>,
        train: LabeledVectors<'_, f64>,
        validation: LabeledVectors<'_, f64>,
    ) -> Result<ClassifierModel> {
        classifier.fit(train, validation, sets.n_classes, sets.dims)
    }
}

impl Element for f32 {
    fn fit(
        classifier: &ClassifierConfig,
        sets: &Sets<'_, f32>,
        train: LabeledVectors<'_, f32>,
        validation: LabeledVectors<'_, f32>,
    ) -> Result<ClassifierModel> {
        classifier.fit_single(train, validation, sets.n_classes, sets.dims)
    }
}

/// `classifier` fitted on `sets`, its hyper-parameters searched on the rows `search` first when its
/// family pins them (see [`train_searching`]); also whether they were.
fn fit_searching<T: Element>(
    classifier: &ClassifierConfig,
    sets: Sets<'_, T>,
    search: Option<&[usize]>,
) -> Result<(ClassifierModel, bool)> {
    let pinned = match search.filter(|_| classifier.pins()) {
        Some(rows) => {
            let (sub_train, sub_validation) = split_rows(rows, &sets);
            // (a subsample the search cannot be run on, e.g. missing a class in its training
            // part, leaves the search to every vector, as without one)
            T::fit(classifier, &sets, sub_train.view(), sub_validation.view())
                .ok()
                .and_then(|searched| classifier.pinned(&searched))
        }
        None => None,
    };
    let model = T::fit(
        pinned.as_ref().unwrap_or(classifier),
        &sets,
        sets.train,
        sets.validation,
    )?;
    Ok((model, pinned.is_some()))
}

/// Rows of labelled vectors, owned.
struct OwnedVectors<T> {
    vectors: Vec<T>,
    classes: Vec<usize>,
}

impl<T> OwnedVectors<T> {
    fn view(&self) -> LabeledVectors<'_, T> {
        LabeledVectors {
            vectors: &self.vectors,
            classes: &self.classes,
        }
    }
}

/// The training and validation rows of `rows` (indices into the training vectors followed by the
/// validation vectors, in order), each in its own role.
fn split_rows<T: Copy>(rows: &[usize], sets: &Sets<'_, T>) -> (OwnedVectors<T>, OwnedVectors<T>) {
    let (n_train, dims) = (sets.train.classes.len(), sets.dims);
    let pick = |set: LabeledVectors<'_, T>, indices: &mut dyn Iterator<Item = usize>| {
        let mut out = OwnedVectors {
            vectors: Vec::new(),
            classes: Vec::new(),
        };
        for i in indices {
            out.vectors
                .extend_from_slice(&set.vectors[i * dims..(i + 1) * dims]);
            out.classes.push(set.classes[i]);
        }
        out
    };
    let sub_train = pick(
        sets.train,
        &mut rows.iter().copied().filter(|&i| i < n_train),
    );
    let sub_validation = pick(
        sets.validation,
        &mut rows
            .iter()
            .copied()
            .filter(|&i| i >= n_train && i - n_train < sets.validation.classes.len())
            .map(|i| i - n_train),
    );
    (sub_train, sub_validation)
}

/// The classes of a training set: its distinct labels, sorted; at least two.
pub(crate) fn class_names_of(train: &[LabeledImage<'_>]) -> Result<Vec<String>> {
    let mut class_names: Vec<String> = train.iter().map(|image| image.label.to_owned()).collect();
    class_names.sort();
    class_names.dedup();
    if class_names.len() < 2 {
        return Err(CoreError::NotEnoughData(format!(
            "training needs at least two classes, got {class_names:?}"
        )));
    }
    Ok(class_names)
}

/// The class index of every image; a label outside `class_names` is an error.
pub(crate) fn class_indices(
    class_names: &[String],
    images: &[LabeledImage<'_>],
) -> Result<Vec<usize>> {
    images
        .iter()
        .map(|image| {
            class_names
                .binary_search_by(|name| name.as_str().cmp(image.label))
                .map_err(|_| CoreError::Param {
                    name: "validation label",
                    reason: format!(
                        "{:?} is not among the training classes {class_names:?}",
                        image.label
                    ),
                })
        })
        .collect()
}

/// Projects feature rows (`n x pca.n_features()`) with the PCA's fixed-point projection: the one a
/// session uses, so that training and classification see the same vectors.
pub(crate) fn project_rows(pca: &Pca, features: &[f64]) -> Result<Vec<f64>> {
    let n_features = pca.n_features();
    let dims = pca.n_components();
    let mut reduced = vec![0.0; features.len() / n_features * dims];
    let mut scratch = pca.scratch();
    for (x, out) in features
        .chunks_exact(n_features)
        .zip(reduced.chunks_exact_mut(dims))
    {
        pca.project_fast_into(x, &mut scratch, out)?;
    }
    Ok(reduced)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::{Frame, Grid};

    #[test]
    fn classes_are_sorted_distinct_labels_and_unknown_ones_are_refused() {
        let frame = Frame::new(Grid::new(2, 2), vec![1.0; 4]).unwrap();
        let image = |label| LabeledImage::new(frame.view(), label);
        let set = [image("b"), image("a"), image("b")];
        let names = class_names_of(&set).unwrap();
        assert_eq!(names, ["a", "b"]);
        assert_eq!(class_indices(&names, &set).unwrap(), [1, 0, 1]);
        assert!(class_indices(&names, &[image("c")]).is_err());
        assert!(matches!(
            class_names_of(&[image("a"), image("a")]),
            Err(CoreError::NotEnoughData(_))
        ));
    }
}
