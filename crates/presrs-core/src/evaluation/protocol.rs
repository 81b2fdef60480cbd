//! The protocols: how training and test sets are formed ([`Protocol`]), and what a protocol's draws
//! cannot give on some samples (capped draws, labels no training set holds).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::pipeline::LabeledImage;
use crate::split::{ValidationSize, per_class_shortfall};

/// How training and test sets are formed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Protocol {
    /// Train on a random draw (from `condition` only, when given); test on everything else.
    TrainCondition {
        condition: Option<String>,
        per_class: Option<usize>,
        validation: ValidationSize,
    },
    /// Hold out each value of the samples' `group` in turn.
    LeaveOneOut {
        /// The column's name (for reports).
        column: String,
        per_class: Option<usize>,
        validation: ValidationSize,
    },
}

impl Protocol {
    /// Models one repeat trains on `samples`: one per held-out group with leave-one-out, else one.
    pub fn models_per_repeat(&self, samples: &[LabeledImage<'_>]) -> usize {
        match self {
            Self::LeaveOneOut { .. } => samples
                .iter()
                .filter_map(|s| s.group)
                .collect::<std::collections::BTreeSet<_>>()
                .len(),
            Self::TrainCondition { .. } => 1,
        }
    }
}

/// The classes whose training pool holds fewer images than the protocol's `per_class`, with how many
/// it holds, by held-out value (leave-one-out) or as `"all"` (a training condition): their draws are
/// capped to what there is. Empty when every draw is as asked.
pub fn per_class_capped(
    samples: &[LabeledImage<'_>],
    protocol: &Protocol,
) -> BTreeMap<String, BTreeMap<String, usize>> {
    let shortfall = |keep: &dyn Fn(&LabeledImage<'_>) -> bool, per_class: Option<usize>| {
        let labels: Vec<&str> = samples
            .iter()
            .filter(|s| keep(s))
            .map(|s| s.label)
            .collect();
        per_class_shortfall(&labels, per_class)
    };
    let mut out = BTreeMap::new();
    match protocol {
        Protocol::TrainCondition {
            condition,
            per_class,
            ..
        } => {
            let short = shortfall(
                &|s| condition.as_deref().is_none_or(|c| s.condition == Some(c)),
                *per_class,
            );
            if !short.is_empty() {
                out.insert("all".to_owned(), short);
            }
        }
        Protocol::LeaveOneOut { per_class, .. } => {
            let values: std::collections::BTreeSet<&str> =
                samples.iter().filter_map(|s| s.group).collect();
            for value in values {
                let short = shortfall(&|s| s.group != Some(value), *per_class);
                if !short.is_empty() {
                    out.insert(value.to_owned(), short);
                }
            }
        }
    }
    out
}

/// The labels a protocol tests that its training sets can never hold, by held-out value (leave-one-out)
/// or as `"all"` (a training condition): such samples are wrong whatever the model, e.g. a group that is
/// one terrain's only trial. Empty when every tested label can be trained. Sorted.
pub fn labels_never_trained(
    samples: &[LabeledImage<'_>],
    protocol: &Protocol,
) -> BTreeMap<String, Vec<String>> {
    let labels_where = |keep: &dyn Fn(&LabeledImage<'_>) -> bool| {
        samples
            .iter()
            .filter(|s| keep(s))
            .map(|s| s.label)
            .collect::<std::collections::BTreeSet<_>>()
    };
    let mut out = BTreeMap::new();
    match protocol {
        Protocol::TrainCondition {
            condition: Some(condition),
            ..
        } => {
            let trainable = labels_where(&|s| s.condition == Some(condition.as_str()));
            let missing: Vec<String> = labels_where(&|_| true)
                .difference(&trainable)
                .map(|&l| l.to_owned())
                .collect();
            if !missing.is_empty() {
                out.insert("all".to_owned(), missing);
            }
        }
        Protocol::TrainCondition {
            condition: None, ..
        } => {}
        Protocol::LeaveOneOut { .. } => {
            let values: std::collections::BTreeSet<&str> =
                samples.iter().filter_map(|s| s.group).collect();
            for value in values {
                let trainable = labels_where(&|s| s.group != Some(value));
                let missing: Vec<String> = labels_where(&|s| s.group == Some(value))
                    .difference(&trainable)
                    .map(|&l| l.to_owned())
                    .collect();
                if !missing.is_empty() {
                    out.insert(value.to_owned(), missing);
                }
            }
        }
    }
    out
}
