//! The prior an automatic choice falls back on when its validation cannot rank the best candidates.

use presrs_core::classifier::ClassifierKind;
use presrs_core::features::FeatureKind;
use presrs_core::pipeline::CheckedTrainConfig;

/// The method a tie for the best validation score goes to, when it is among the tied candidates:
/// MiniRocket on scaled channels with the SVM on its principal components. A prior, for when the
/// validation cannot rank (inside one walker of `jiku-walk` most candidates score 100 %): of the
/// random-convolution methods, it has the best mean over the three shared whole-sample sets
/// (`jiku-walk`, `icub20`, the simulator's stances) and the best worst set (bench/real/RESULTS.md, "A
/// prior for ties"). Without it, ties go to the earlier candidate. Scoring keeps the candidates' order (the cheap ones first).
pub const PREFERRED_ON_TIE: (FeatureKind, ClassifierKind) =
    (FeatureKind::ROCKET, ClassifierKind::SVM);

/// The index in `candidates` of [`PREFERRED_ON_TIE`] (its first candidate), if it is one.
pub(super) fn preferred_on_tie(candidates: &[CheckedTrainConfig]) -> Option<usize> {
    let (features, classifier) = PREFERRED_ON_TIE;
    candidates.iter().position(|candidate| {
        let config = candidate.config();
        config.features.kind() == Some(features) && config.classifier.kind() == classifier
    })
}
