//! What `presrs train` shows of an automatic choice: every candidate's validation score (the chosen
//! one marked), the choice next to the paper's method, the internal estimate, and why the model keeps
//! fewer principal components than the chosen candidate names, when it does.

use presrs::method::paper_score;
use presrs_core::TrainedModel;
use presrs_core::selection::{CandidateScore, Selection};

/// The table's lines, in order. `n_train` is the number of samples the model was trained on (without
/// the validation ones): what bounds its principal components.
pub fn selection_lines(selection: &Selection, model: &TrainedModel, n_train: usize) -> Vec<String> {
    let mut lines = vec![format!("automatic choice ({}):", selection.method)];
    let folds = selection
        .scores
        .iter()
        .filter(|score| score.is_contender())
        .map(|score| score.per_fold.len())
        .max()
        .unwrap_or(0);
    // (names padded to the longest, at least 40 characters, so the scores stand in one column)
    let width = selection
        .scores
        .iter()
        .map(|score| score.name().len())
        .max()
        .unwrap_or(0)
        .max(40);
    for (i, score) in selection.scores.iter().enumerate() {
        let mark = if i == selection.chosen { "*" } else { " " };
        let name = format!("{:<width$}", score.name());
        lines.push(match &score.error {
            None if score.dropped_early => format!(
                "{mark} {name} {:6.2} % on the first {} of {folds} folds: clearly behind, dropped",
                100.0 * score.accuracy.mean,
                score.per_fold.len()
            ),
            None => format!("{mark} {name} {}", percent(score)),
            Some(err) if score.skipped => format!("{mark} {name} {err}"),
            Some(err) => format!("{mark} {name} failed: {err}"),
        });
    }
    let Some(chosen) = selection.chosen() else {
        return lines;
    };
    lines.push(match paper_score(selection) {
        Some((i, _)) if i == selection.chosen => {
            format!("chosen: {} (the paper's method)", chosen.name())
        }
        Some((_, paper)) if paper.is_contender() => format!(
            "chosen: {}; the paper's method ({}) scored {}",
            chosen.name(),
            paper.name(),
            percent(paper)
        ),
        _ => format!("chosen: {}", chosen.name()),
    });
    lines.extend(higher_scored_note(selection));
    if let Some(note) = components_note(chosen, model, n_train) {
        lines.push(note);
    }
    lines.push(format!(
        "internal estimate: {}, validated by {}",
        percent(chosen),
        selection.method
    ));
    lines.extend(cost_line(selection));
    lines
}

/// Why the chosen candidate is not the highest-scoring one, when it is not (the one-standard-error rule).
fn higher_scored_note(selection: &Selection) -> Option<String> {
    let best = selection.best_above_chosen()?;
    Some(format!(
        "  {} scored higher ({:.2} %), but the chosen one is within one standard error of it and \
         earlier in the search order (--choose one-se, the default on stances and series; --choose best \
         takes the highest)",
        best.name(),
        100.0 * best.accuracy.mean
    ))
}

/// On how many samples the candidates were scored and where the time went: the scoring (what the
/// budget bounds, the features included) and the winner's training on every sample, which comes after
/// the budget (`None` for a model that did not record it).
pub fn cost_line(selection: &Selection) -> Option<String> {
    let cost = selection.cost.as_ref()?;
    let scored = if cost.subsampled() {
        format!(
            "scored on a stratified subsample of {} of the {} samples",
            cost.scored_on, cost.samples
        )
    } else {
        format!("scored on all {} samples", cost.samples)
    };
    let searched = match cost.searched_on {
        Some(on) => format!(" (its hyper-parameters chosen on the subsample of {on})"),
        None => String::new(),
    };
    Some(format!(
        "time: {scored} in {:.1} s (features {:.1} s; {}); training the winner on all {} samples{searched} \
         {:.1} s, not covered by the budget",
        cost.scoring_seconds,
        cost.features_seconds,
        cost.budget_text(),
        cost.samples,
        cost.final_fit_seconds
    ))
}

/// `85.00 % +- 2.00`
fn percent(score: &CandidateScore) -> String {
    format!(
        "{:6.2} % +- {:.2}",
        100.0 * score.accuracy.mean,
        100.0 * score.accuracy.std
    )
}

/// Why the model keeps fewer principal components than the chosen candidate asks for (`None` when it
/// keeps them all, or has no PCA step): a PCA keeps at most one fewer than its training images, and no more than the
/// features.
pub fn components_note(
    chosen: &CandidateScore,
    model: &TrainedModel,
    n_train: usize,
) -> Option<String> {
    let (asked, kept) = (chosen.config.dims, model.pca()?.n_components());
    if kept >= asked {
        return None;
    }
    let features = model.n_features();
    let nouns = model.sample().nouns();
    let bound = if features <= n_train.saturating_sub(1) {
        format!("no more than its {features} features")
    } else {
        format!("at most one fewer than its {n_train} training {nouns}")
    };
    Some(format!(
        "the model keeps {kept} of the {asked} principal components asked for: {bound} (the \
         validation folds, trained on fewer {nouns}, may have kept fewer still)"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use presrs_core::metrics::MeanStd;
    use presrs_core::pipeline::TrainConfig;

    fn scored(classifier: &str, mean: f64) -> CandidateScore {
        CandidateScore {
            features: "rocket_unscaled".into(),
            classifier: classifier.into(),
            config: TrainConfig::default(),
            accuracy: MeanStd { mean, std: 0.01 },
            per_fold: (0..4).map(|k| (format!("f{k}"), mean)).collect(),
            error: None,
            skipped: false,
            dropped_early: false,
        }
    }

    /// A choice below the best says which scored higher and which rule kept the earlier one; the best
    /// chosen says nothing more.
    #[test]
    fn a_choice_below_the_best_names_the_best_and_the_rule() {
        let mut selection = Selection {
            method: "leave one group out".into(),
            chosen: 0,
            scores: vec![scored("ridge_raw", 0.978), scored("svm", 0.982)],
            fallback: None,
            cost: None,
        };
        let note = higher_scored_note(&selection).unwrap();
        assert!(
            note.contains("rocket_unscaled + svm, 51 dims scored higher (98.20 %)"),
            "{note}"
        );
        assert!(note.contains("within one standard error") && note.contains("--choose best"));
        selection.chosen = 1;
        assert_eq!(higher_scored_note(&selection), None);
    }
}
