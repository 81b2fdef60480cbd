//! What the automatic choices of a training or an evaluation warn of: a validation scheme passed
//! over, a time budget that cut candidates, a choice the validation could not make.

use presrs_core::selection::{CandidateScore, Selection, ValidationFallback};
use presrs_io::message::{Message, Opt};

use super::ties::PREFERRED_ON_TIE;

/// The warning for selections whose time budget cut candidates (`None` when none was cut): how many
/// models, which candidates (each feature family with its classifiers), and what to do.
pub fn budget_warning(selections: &[Selection]) -> Option<Message> {
    let cut: Vec<_> = selections
        .iter()
        .filter(|selection| selection.scores.iter().any(|score| score.skipped))
        .collect();
    let first = cut.first()?;
    let skipped: Vec<&CandidateScore> = first.scores.iter().filter(|score| score.skipped).collect();
    // Each feature family (with its transform, and its dims when refined) with its classifiers.
    let mut families: Vec<(String, Vec<&str>)> = Vec::new();
    for score in &skipped {
        let intensity = score.config.preprocess.intensity;
        let mut name = score.features.clone();
        if !intensity.is_none() {
            name.push_str(&format!(" ({intensity})"));
        }
        // (the refinement of the best candidates' dims)
        if score.config.dims != first.scores[0].config.dims {
            name.push_str(&format!(", {} dims", score.config.dims));
        }
        match families.iter_mut().find(|(family, _)| *family == name) {
            Some((_, classifiers)) => classifiers.push(&score.classifier),
            None => families.push((name, vec![&score.classifier])),
        }
    }
    let families: Vec<String> = families
        .into_iter()
        .map(|(family, classifiers)| format!("{family} with {}", classifiers.join(", ")))
        .collect();
    let budget = skipped[0]
        .error
        .as_deref()
        .unwrap_or("the time budget was spent");
    let models = if selections.len() == 1 {
        String::new()
    } else {
        format!("in {} of {} models, ", cut.len(), selections.len())
    };
    let message = Message::from(format!(
        "{models}the automatic choice was cut short ({}): {} of {} candidates not tried ({}); give ",
        budget.trim_start_matches("not tried: "),
        skipped.len(),
        first.scores.len(),
        families.join("; ")
    ));
    Some(
        message
            .opt(Opt::Budget)
            .text(" a larger value in seconds, or ")
            .opt_is(Opt::Budget, 0)
            .text(" for no limit (the choice then does not depend on the machine's speed)"),
    )
}

/// What the automatic choices of `selections` warn of, in order: a validation scheme passed over, a
/// time budget that cut candidates, a choice the validation could not make.
pub fn selection_warnings(selections: &[Selection]) -> Vec<Message> {
    [validation_warning, budget_warning, tie_warning]
        .into_iter()
        .filter_map(|warning| warning(selections))
        .collect()
}

/// The tied methods a warning names before it counts the rest.
const TIES_NAMED: usize = 3;

/// The warning for selections whose chosen candidate scored the same in validation as other methods
/// (`None` when none did): in how many models, the first's score and tied methods, and what lets the
/// validation rank them. Small or homogeneous training data (one walker's stances, where every random
/// convolution candidate is right on every validation sample) leave the choice to a prior:
/// [`PREFERRED_ON_TIE`] when it is among the best, else the candidates' order.
pub fn tie_warning(selections: &[Selection]) -> Option<Message> {
    let tied: Vec<(&Selection, Vec<&CandidateScore>)> = selections
        .iter()
        .map(|selection| (selection, selection.tied()))
        .filter(|(_, tied)| !tied.is_empty())
        .collect();
    let (first, others) = tied.first()?;
    let chosen = first.chosen()?;
    let models = if selections.len() == 1 {
        String::new()
    } else {
        format!("in {} of {} models, ", tied.len(), selections.len())
    };
    let mut names: Vec<String> = others.iter().take(TIES_NAMED).map(|s| s.method()).collect();
    // The prior is named where it was a candidate (whole samples); elsewhere the order alone decides.
    let (features, classifier) = PREFERRED_ON_TIE;
    // (by kind, whatever the intensity transform, as `ties::preferred_on_tie` finds it)
    let preferred_scored = first.scores.iter().any(|score| {
        score.config.features.kind() == Some(features)
            && score.config.classifier.kind() == classifier
    });
    let prior = if preferred_scored {
        format!(
            "a prior, not the data, made the choice (a tie goes to {features} + {} when it is among \
             the best, else to the earlier candidate)",
            classifier.as_str()
        )
    } else {
        "the candidates' order, not the data, made the choice".to_owned()
    };
    if others.len() > TIES_NAMED {
        names.push(format!("and {} more", others.len() - TIES_NAMED));
    }
    Some(
        Message::from(format!(
            "{models}the automatic choice's validation could not rank its best candidates: {} \
             scored {:.2} % and so did {} other method(s) ({}), so {prior}; training data from \
             more groups (walkers, recordings, sessions) let the validation tell them apart, or fix \
             the method with ",
            chosen.method(),
            100.0 * chosen.accuracy.mean,
            others.len(),
            names.join(", ")
        ))
        .opt(Opt::Features)
        .text(" and ")
        .opt(Opt::Classifier),
    )
}

/// The warning for selections whose validation scheme was passed over because a held-out fold held a
/// class its training part lacked (`None` when none was): one line, in how many models, the first
/// class and fold, and what was used instead.
pub fn validation_warning(selections: &[Selection]) -> Option<Message> {
    let fell: Vec<&ValidationFallback> = selections
        .iter()
        .filter_map(|selection| selection.fallback.as_ref())
        .collect();
    let first = fell.first()?;
    let (class, fold) = first.unseen.first()?;
    let models = if selections.len() == 1 {
        String::new()
    } else {
        format!("in {} of {} models, ", fell.len(), selections.len())
    };
    let more = match first.unseen.len() {
        1 => String::new(),
        n => format!(" (and {} other class(es) the same way)", n - 1),
    };
    let what = first.wanted.as_str();
    Some(
        Message::from(format!(
            "{models}the automatic choice validated its candidates by {} instead of {}: holding \
             out {what} {fold} leaves no training image of class {class}{more}, so every candidate \
             would score 0 on it; images of one {what} may now be on both sides of a fold, which \
             makes the internal estimate optimistic (",
            first.used.describe(),
            first.wanted.describe()
        ))
        .opt_text(Opt::ValidateBy, first.used.as_str())
        .text(" chooses this without a warning)"),
    )
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use presrs_core::pipeline::TrainConfig;
    use presrs_io::message::Face;

    /// A candidate of `features` + `classifier` (its words and its configuration) scored `mean` on every
    /// fold.
    fn scored(features: &str, classifier: &str, mean: f64) -> CandidateScore {
        use presrs_core::classifier::ClassifierKind;
        use presrs_core::features::FeatureKind;
        CandidateScore {
            features: features.into(),
            classifier: classifier.into(),
            config: TrainConfig {
                features: FeatureKind::parse(features).unwrap().default_config(),
                classifier: ClassifierKind::parse(classifier).unwrap().default_config(),
                ..TrainConfig::default()
            },
            accuracy: presrs_core::metrics::MeanStd { mean, std: 0.0 },
            per_fold: (0..3).map(|k| (format!("g{k}"), mean)).collect(),
            error: None,
            skipped: false,
            dropped_early: false,
        }
    }

    fn selection(scores: Vec<CandidateScore>) -> Selection {
        Selection {
            method: "three stratified 70/30 splits".into(),
            chosen: 0,
            scores,
            fallback: None,
            cost: None,
        }
    }

    /// A tie in validation is said, with how many models it decided, the tied methods (the first
    /// three, then a count), and the way out in each face's words; a clear winner says nothing.
    #[test]
    fn a_choice_the_validation_could_not_make_is_said() {
        // (the preferred `rocket` + `svm` was a candidate, below the tie)
        let mut tied = selection(
            ["ridge_raw", "ridge", "svm", "lda", "knn"]
                .iter()
                .map(|classifier| scored("rocket_unscaled", classifier, 1.0))
                .collect(),
        );
        tied.scores.push(scored("rocket", "svm", 0.95));
        let clear = selection(vec![
            scored("rocket_unscaled", "ridge_raw", 1.0),
            scored("rocket_unscaled", "svm", 0.9),
        ]);
        assert_eq!(tie_warning(std::slice::from_ref(&clear)), None);
        let warning = tie_warning(&[tied.clone(), clear, tied]).unwrap();
        let cli = warning.render(Face::Cli);
        assert!(
            cli.starts_with(
                "in 2 of 3 models, the automatic choice's validation could not rank its best \
                 candidates: rocket_unscaled + ridge_raw scored 100.00 % and so did 4 other \
                 method(s) (rocket_unscaled + ridge, rocket_unscaled + svm, rocket_unscaled + lda, \
                 and 1 more), so a prior, not the data, made the choice (a tie goes to rocket + svm \
                 when it is among the best, else to the earlier candidate)"
            ),
            "{cli}"
        );
        assert!(
            cli.ends_with("fix the method with --features and --classifier"),
            "{cli}"
        );
        let python = warning.render(Face::Python);
        assert!(
            python.ends_with("fix the method with features= and classifier="),
            "{python}"
        );
        assert_eq!(
            selection_warnings(&[selection(vec![scored("fft1d", "pwe", 0.8)])]),
            []
        );
        // Where the preferred method was no candidate (frames), the order alone is named.
        let frames = selection(vec![
            scored("fft2d_polar", "pwe", 0.8),
            scored("fft2d_polar", "knn", 0.8),
        ]);
        let cli = tie_warning(&[frames]).unwrap().render(Face::Cli);
        assert!(
            cli.contains(
                "and so did 1 other method(s) (fft2d_polar + knn), so the candidates' order, not \
                 the data, made the choice; training data"
            ),
            "{cli}"
        );
    }
}
