//! What a model file holds, in a few lines a person reads: the classifier and its classes, the image
//! path from crop to classifier, the automatic choice if there was one, the online profile and where
//! the model came from.

use std::fmt::Write;

use presrs_core::TrainedModel;
use presrs_core::features::{FeatureConfig, minirocket_draws};
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
    if let Some(sampling) = sampling_summary(model) {
        line(sampling);
    }
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
        if let Some(best) = selection.best_above_chosen() {
            line(format!(
                "  {} validated higher ({:.2} %), within one standard error: the earlier candidate \
                 was kept (the one-standard-error rule)",
                best.method(),
                100.0 * best.accuracy.mean
            ));
        }
    }
    if let Some(early) = early_summary(model) {
        line(early);
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
            " ({trained} training + {validated} validation {})",
            model.sample().nouns()
        );
    }
    if let Some(seed) = provenance.seed {
        let _ = write!(origin, ", seed {seed}");
    }
    line(origin);
    text
}

/// How the model's samples were taken, in one line, when it says: the sample kind and sensor, then
/// how stances were found (what `presrs classify` does too unless told otherwise).
pub fn sampling_summary(model: &TrainedModel) -> Option<String> {
    let kind = model.sample();
    let sensor = model.sensor().map(|grid| match kind {
        presrs_core::sample::SampleKind::Series { .. } => {
            format!(" of {} channels x {} time steps", grid.rows, grid.cols)
        }
        _ => format!(" of {grid} frames"),
    });
    let sampling = model.sampling();
    if sensor.is_none() && sampling.is_none() {
        return None;
    }
    let mut text = format!("samples: {}{}", kind.name(), sensor.unwrap_or_default());
    if let Some(sampling) = sampling {
        if sampling.one_sample_per_file {
            text.push_str(", one per file (each recording one contact)");
        } else {
            let _ = write!(
                text,
                ", stances found from the {} baseline",
                sampling.segment.params().baseline
            );
            if kind.is_frame() {
                let _ = write!(text, ", frame {} of each", sampling.stance_frame);
            }
            if sampling.include_partial {
                text.push_str(", partial stances included");
            }
        }
    }
    Some(text)
}

/// A whole-stance model's early decisions in one line (`None` without decision points): the points,
/// and `auto`'s rule with what validation measured of it.
pub fn early_summary(model: &TrainedModel) -> Option<String> {
    let early = model.early()?;
    let frames: Vec<String> = early.frames().iter().map(usize::to_string).collect();
    let mut text = format!(
        "decision points: {} frames after touchdown",
        frames.join(", ")
    );
    if let Some(auto) = &early.auto {
        let threshold = if auto.threshold > 1.0 {
            "no point confident enough".to_owned()
        } else {
            format!("threshold {:.3}", auto.threshold)
        };
        let deadline = auto.deadline.map_or_else(
            || "no deadline (else at lift-off)".to_owned(),
            |k| format!("else at the deadline point {k}"),
        );
        let _ = write!(
            text,
            "; auto: {threshold}, {deadline}; on {} held-out training stances{} {:.1} % (whole \
             stance {:.1} %), deciding at {:.1} frames on average ({:.0} % of each stance)",
            auto.validation_stances,
            auto.validated_by
                .map_or_else(String::new, |by| format!(" ({})", by.describe())),
            100.0 * auto.auto_accuracy,
            100.0 * auto.whole_accuracy,
            auto.mean_decision_frame,
            100.0 * auto.mean_decision_share
        );
    }
    if let Some(cost) = &early.cost {
        let of = if cost.rule_stances < cost.stances {
            format!(
                " of a stratified subsample of {} of the {} stances",
                cost.rule_stances, cost.stances
            )
        } else {
            String::new()
        };
        let _ = write!(
            text,
            "; trained in {:.1} s (the points' classifiers {:.1} s; auto's rule {:.1} s, {} \
             classifiers in {} inner folds{of})",
            cost.total_seconds(),
            cost.points_seconds,
            cost.rule_seconds,
            cost.inner_models,
            cost.inner_folds
        );
    }
    Some(text)
}

/// The features' name, with MiniRocket's draws when there are several (`rocket_unscaled, 4 draws`).
fn features_name(features: &FeatureConfig) -> String {
    match minirocket_draws(features) {
        1 => features.name(),
        draws => format!("{}, {draws} draws", features.name()),
    }
}

/// The image path of `model` in one line: crop, the sample's size in its kind's terms (`38x41 image`,
/// `12 channels x 83 frames`), preprocessing, features, PCA or none (and the Parzen window's sigma).
pub fn pipeline_summary(model: &TrainedModel) -> String {
    format!(
        "crop {} -> {}, preprocessing {}, {} features ({}), {}{}",
        model.crop(),
        model.sample().shape_text(model.image_grid()),
        model.preprocess(),
        model.n_features(),
        features_name(model.features()),
        model.describe_projection(),
        model
            .sigma()
            .map_or_else(String::new, |s| format!(", sigma {s:.4}"))
    )
}
