//! How an automatic choice validates its candidates: by group, by condition, or by stratified splits.

use serde::{Deserialize, Serialize};

/// How the automatic choice validates its candidates inside the training data.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ValidateBy {
    /// Group when the images span 3 or more groups, else condition when they span 2 or more, else
    /// stratified splits; a scheme under which a held-out fold holds a class its training part lacks
    /// is passed over for the next (see [`crate::selection::ValidationFallback`]).
    #[default]
    Auto,
    /// Leave one group out (at least two groups needed).
    Group,
    /// Leave one condition out (at least two conditions needed).
    Condition,
    /// Three stratified 70/30 splits.
    Split,
}

impl ValidateBy {
    pub const NAMES: [&'static str; 4] = ["auto", "group", "condition", "split"];

    pub fn as_str(self) -> &'static str {
        match self {
            Self::Auto => "auto",
            Self::Group => "group",
            Self::Condition => "condition",
            Self::Split => "split",
        }
    }

    /// The scheme in a few words (`leaving one group out`).
    pub fn describe(self) -> &'static str {
        match self {
            Self::Auto => "the automatic validation",
            Self::Group => "leaving one group out",
            Self::Condition => "leaving one condition out",
            Self::Split => "three stratified 70/30 splits",
        }
    }

    /// What `Auto` means for images with these distinct groups and conditions (counts).
    pub fn resolve(self, groups: usize, conditions: usize) -> Self {
        match self {
            Self::Auto if groups >= 3 => Self::Group,
            Self::Auto if conditions >= 2 => Self::Condition,
            Self::Auto => Self::Split,
            other => other,
        }
    }
}

impl std::fmt::Display for ValidateBy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::str::FromStr for ValidateBy {
    type Err = String;

    fn from_str(text: &str) -> std::result::Result<Self, String> {
        match text.trim().to_ascii_lowercase().as_str() {
            "auto" => Ok(Self::Auto),
            "group" => Ok(Self::Group),
            "condition" => Ok(Self::Condition),
            "split" => Ok(Self::Split),
            _ => Err(format!(
                "unknown validation {text:?} (known: {})",
                Self::NAMES.join(", ")
            )),
        }
    }
}
