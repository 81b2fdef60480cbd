//! What `presrs report` shows and how it makes its model and evaluations.

use std::path::PathBuf;

use presrs_core::split::ValidationSize;

use crate::dataset::SampleOptions;
use crate::method::Method;

/// What `presrs report` shows and how its model and evaluations are made.
#[derive(Clone, Debug)]
pub struct ReportOptions {
    /// A trained model to show (crop, PCA, validation curve) and to test on every image. Without it,
    /// a model is trained on the data set (the paper's protocol) and evaluated with repeats.
    pub model: Option<PathBuf>,
    /// Train on this condition, test on the others (see [`report_holdout`](super::report_holdout) for the default).
    pub train_condition: Option<String>,
    /// Hold out each value of this manifest column in turn (see [`report_holdout`](super::report_holdout) for the default).
    pub leave_one_out: Option<String>,
    /// Images drawn per class for training + validation (fewer if a class has fewer).
    pub per_class: usize,
    pub validation: ValidationSize,
    /// Repeats of the evaluation (0: none).
    pub repeats: usize,
    /// Repeats of the sensor-fault sweep (0: none).
    pub fault_repeats: usize,
    pub seed: u64,
    pub method: Method,
    /// How the data set's samples were taken (the report says which stance frame, and reads movies
    /// for load curves the same way).
    pub samples: SampleOptions,
    /// The command line the report was made with, stated in it.
    pub command_line: Option<String>,
}

impl Default for ReportOptions {
    fn default() -> Self {
        Self {
            model: None,
            train_condition: None,
            leave_one_out: None,
            per_class: 20,
            validation: ValidationSize::Count(7),
            repeats: 5,
            fault_repeats: 3,
            seed: 1,
            method: Method::default(),
            samples: SampleOptions::default(),
            command_line: None,
        }
    }
}
