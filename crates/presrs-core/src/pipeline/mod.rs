//! The trained pipeline: crop -> features -> PCA -> classifier, with training and a reusable classification session.
//!
//! ```text
//! TrainConfig --check--> CheckedTrainConfig --train(train, validation)--> TrainedModel (serde)
//! TrainedModel::session() -> Session::classify(&frame) -> Prediction { class, label, confidence, posteriors }
//! ```
//!
//! Training follows the paper: features of the training images fit the PCA (`dims` components, at most
//! `n_train - 1`), the validation images are projected with that PCA and used to choose the classifier's
//! hyper-parameters (the Parzen σ), and the final classifier stores the reduced training *and* validation
//! vectors. Absent (masked) sensels are read as 0 unless [`Preprocess::fill_absent`](crate::preprocess::Preprocess::fill_absent) fills them from their
//! neighbours; [`Preprocess::normalise_load`](crate::preprocess::Preprocess::normalise_load) divides each cropped image by its total load. Both are part
//! of the configuration and the model, so training and classification preprocess alike. Every image, in
//! training and afterwards, must have the same grid once cropped.

pub(crate) mod config;
pub(crate) mod contact_check;
pub(crate) mod early;
pub(crate) mod extract;
pub(crate) mod model;
pub(crate) mod novelty;
pub(crate) mod session;
pub(crate) mod train;

pub use config::{CheckedTrainConfig, TrainConfig};
pub use early::{
    AUTO_BOUND_Z, AUTO_EARLINESS, AUTO_TOLERANCE, ChoosePoint, HeldOutStance, OfflineDecision,
    RULE_STANCES, StanceImages, classify_held_out, classify_stances, held_out_stances,
    learn_threshold, median_length, point_confidences, train_early, train_like, wilson_lower_bound,
};
pub use extract::{LabeledImage, extract_features, extract_features_many, extract_features_with};
pub use model::{
    AutoRule, AutoThreshold, DecisionPoint, EarlyCost, EarlyDecisions, MAX_MODEL_SENSELS,
    MAX_TRANSFORM_LEN, TrainedModel, TrainingSummary,
};
pub use novelty::{MAX_NOVELTY_DIMS, NOVELTY_COMPONENTS, NOVELTY_PCA_SAMPLES};
pub use session::{BATCH_BLOCK, Classification, Prediction, Session};
pub use train::train;

/// The record of the automatic choice, at its old path; it lives beside the procedure, in
/// [`crate::selection`].
pub use crate::selection::record::{CandidateScore, Selection};
