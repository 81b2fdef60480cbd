//! What a model file holds, in a few lines a person reads: the classifier and its classes, the image
//! path from crop to classifier, the automatic choice if there was one, the online profile and where
//! the model came from.

use std::fmt::Write;

use presrs_core::TrainedModel;
use presrs_io::model_file::ModelFile;

/// A description of `file`, one fact a line.
pub fn describe_model(file: &ModelFile) -> String {
    let model = &file.model;
    let mut text = String::new();
    let mut line = |fact: String| {
        text.push_str(&fact);
        text.push('\n');
    };
    line(format!(
        "{} classifier ({}) over {} classes: {}",
        model.classifier().kind(),
        model.classifier().describe(),
        model.class_names().len(),
        model.class_names().join(", ")
    ));
    line(pipeline_summary(model));
    if let Some(selection) = model.selection()
        && let Some(chosen) = selection.chosen()
    {
        line(format!(
            "chosen automatically ({}): {} + {}, validation accuracy {:.2} % +- {:.2} over {} \
             candidates",
            selection.method,
            chosen.features,
            chosen.classifier,
            100.0 * chosen.accuracy.mean,
            100.0 * chosen.accuracy.std,
            selection.scores.len()
        ));
    }
    line(match model.novelty() {
        Some(novelty) => format!("novelty: {}", novelty.describe()),
        None => "novelty: none (every decision is one of the classes)".to_owned(),
    });
    match &file.online {
        Some(profile) => line(format!(
            "online profile: sample frame k = {}, {}",
            profile.params.sample_offset,
            if profile.calibration.is_some() {
                "calibrated"
            } else {
                "warm-up calibration"
            }
        )),
        None => line("online profile: none (a stream calibrates during warm-up)".to_owned()),
    }
    let provenance = &file.provenance;
    let mut origin = format!("written by presrs {}", file.presrs_version);
    if let Some(manifest) = &provenance.manifest {
        let _ = write!(origin, ", trained on {manifest}");
    }
    let trained: usize = provenance.train_counts.values().sum();
    let validated: usize = provenance.validation_counts.values().sum();
    if trained > 0 {
        let _ = write!(
            origin,
            " ({trained} training + {validated} validation images)"
        );
    }
    if let Some(seed) = provenance.seed {
        let _ = write!(origin, ", seed {seed}");
    }
    line(origin);
    text
}

/// The image path of `model` in one line: crop, image size, preprocessing, features, PCA or none (and
/// the Parzen window's sigma).
pub fn pipeline_summary(model: &TrainedModel) -> String {
    format!(
        "crop {} -> {} image, preprocessing {}, {} features ({}), {}{}",
        model.crop(),
        model.image_grid(),
        model.preprocess(),
        model.n_features(),
        model.features().name(),
        model.describe_projection(),
        model
            .sigma()
            .map_or_else(String::new, |s| format!(", sigma {s:.4}"))
    )
}
