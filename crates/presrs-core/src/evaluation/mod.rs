//! The evaluation engine: train on one part of a dataset, test on the rest, repeat with new seeds.
//!
//! Two protocols (see `docs/interface.md`):
//! - [`Protocol::TrainCondition`], the paper's: draw `per_class` random images per class from one
//!   condition (a gait), `validation` of them for hyper-parameters, and test on every other sample of every
//!   condition. Accuracy is reported per tested condition (the training condition's held-out remainder
//!   included) and overall (over every tested sample).
//! - [`Protocol::LeaveOneOut`]: for every value of a grouping column, train on all samples with another
//!   value and test on the held-out ones (leave-one-subject-out, leave-one-gait-out).
//!
//! Every repeat draws with its own seed (`seed + repeat`), so a run is reproducible and repeats differ.
//! Results are means and standard deviations over the repeats; the confusion matrix sums all repeats.
//!
//! ```text
//! protocol   how training and test sets are formed; capped draws, labels no training set holds
//! folds      one repeat's training, validation and test sets (and Draw, their public record)
//! run        the engine: Evaluation trains each fold's model and tests it under each perturbation
//! tally      one perturbation's outcomes, fold by fold and repeat by repeat
//! report     RepeatResult and EvalReport: each repeat, and their summary
//! compare    several configurations evaluated on the same draws
//! ```

mod compare;
mod folds;
mod protocol;
mod report;
mod run;
mod tally;
#[cfg(test)]
mod tests;

pub use compare::ComparisonRow;
pub use folds::Draw;
pub use protocol::{Protocol, labels_never_trained, per_class_capped};
pub use report::{EvalReport, RepeatResult};
pub use run::{
    Evaluated, Evaluation, FirstModel, FoldModel, FoldSets, Models, TestTransform, Trainer,
};

// The summaries an [`EvalReport`] is made of, nameable from here as before they moved to the leaf module.
pub use crate::metrics::{Confusion, MeanStd};
