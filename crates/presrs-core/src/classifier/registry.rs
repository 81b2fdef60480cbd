//! The registered classifier families: the built-in ones (one line each, below) and those registered
//! at run time ([`register`]: extensions, tests). [`ClassifierKind`] is a small handle onto one.

use std::sync::RwLock;

use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::erased::{DynFamily, Erased};
use super::family::ClassifierFamily;
use super::gaussian::{LdaFamily, MleFamily};
use super::knn::KnnFamily;
use super::parzen::PweFamily;
use super::ridge::{RidgeFamily, RidgeRawFamily};
use super::svm::SvmFamily;
use crate::error::{CoreError, Result};

/// The built-in families, in the order the automatic choice tries them. One line per family.
const BUILT_IN: [ClassifierKind; 7] = [
    ClassifierKind::PWE,
    ClassifierKind::MLE,
    ClassifierKind::LDA,
    ClassifierKind::SVM,
    ClassifierKind::KNN,
    ClassifierKind::RIDGE,
    ClassifierKind::RIDGE_RAW,
];

/// Families registered at run time, after the built-in ones.
static REGISTERED: RwLock<Vec<ClassifierKind>> = RwLock::new(Vec::new());

/// A classifier family, by name (as the CLI's `--classifier` spells them): a handle onto a registered
/// [`ClassifierFamily`]. Equal when the names are; serialised as the name.
#[derive(Clone, Copy)]
pub struct ClassifierKind(&'static dyn DynFamily);

impl ClassifierKind {
    /// Parzen-window estimator with a Gaussian kernel (the paper's classifier).
    pub const PWE: Self = Self::of::<PweFamily>();
    /// Gaussian class densities, one shrunk full covariance per class (maximum likelihood).
    pub const MLE: Self = Self::of::<MleFamily>();
    /// Gaussian class densities with one shared shrunk covariance (linear discriminant).
    pub const LDA: Self = Self::of::<LdaFamily>();
    /// One-vs-one C-SVC, linear or RBF kernel, chosen on validation.
    pub const SVM: Self = Self::of::<SvmFamily>();
    /// k-nearest neighbours, k chosen on validation.
    pub const KNN: Self = Self::of::<KnnFamily>();
    /// One-vs-rest ridge regression on standardised features, alpha chosen by exact leave-one-out.
    pub const RIDGE: Self = Self::of::<RidgeFamily>();
    /// The same on centred features in their own units (scikit-learn's `RidgeClassifierCV` alone).
    pub const RIDGE_RAW: Self = Self::of::<RidgeRawFamily>();

    /// The handle of family `F` (registered or not: see [`register`]).
    pub const fn of<F: ClassifierFamily>() -> Self {
        Self(Erased::<F>::FAMILY)
    }

    pub(crate) fn from_family(family: &'static dyn DynFamily) -> Self {
        Self(family)
    }

    pub(crate) fn family(self) -> &'static dyn DynFamily {
        self.0
    }

    /// Whether the family takes every feature, without the PCA step
    /// ([`ClassifierFamily::TAKES_ALL_FEATURES`](crate::classifier::ClassifierFamily::TAKES_ALL_FEATURES)).
    pub fn takes_all_features(self) -> bool {
        self.0.takes_all_features()
    }

    /// Every registered family: the built-in ones, then those registered at run time.
    pub fn all() -> Vec<Self> {
        let registered = REGISTERED
            .read()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        BUILT_IN.iter().chain(registered.iter()).copied().collect()
    }

    /// The families the automatic choice tries, in order.
    pub fn auto_candidates() -> Vec<Self> {
        Self::all()
            .into_iter()
            .filter(|kind| kind.0.joins_auto())
            .collect()
    }

    /// The names of every registered family, in order.
    pub fn names() -> Vec<&'static str> {
        Self::all().into_iter().map(Self::as_str).collect()
    }

    pub fn as_str(self) -> &'static str {
        self.0.name()
    }

    /// Whether the automatic choice tries this family.
    pub fn joins_auto(self) -> bool {
        self.0.joins_auto()
    }

    /// Parses a name (case-insensitive).
    pub fn parse(text: &str) -> Result<Self> {
        let wanted = text.trim().to_ascii_lowercase();
        Self::exactly(&wanted).ok_or_else(|| CoreError::Param {
            name: "classifier",
            reason: format!(
                "unknown classifier {text:?}; known: {}",
                Self::names().join(", ")
            ),
        })
    }

    /// The family named exactly `name`, if registered.
    pub(crate) fn exactly(name: &str) -> Option<Self> {
        Self::all().into_iter().find(|kind| kind.as_str() == name)
    }
}

/// Registers family `F` at run time (an extension, a test): from then on it is parsed, trained, stored,
/// loaded and (with [`ClassifierFamily::JOINS_AUTO`]) tried by the automatic choice like a built-in
/// one. Registering the same family again does nothing; another family of a taken name is refused.
pub fn register<F: ClassifierFamily>() -> Result<ClassifierKind> {
    let kind = ClassifierKind::of::<F>();
    let mut registered = REGISTERED
        .write()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    let taken = BUILT_IN
        .iter()
        .chain(registered.iter())
        .find(|k| **k == kind);
    if let Some(taken) = taken {
        if taken.0.family_type() == kind.0.family_type() {
            return Ok(*taken);
        }
        return Err(CoreError::Param {
            name: "classifier",
            reason: format!("a classifier named {:?} is already registered", F::NAME),
        });
    }
    if F::NAME.is_empty() || F::NAME != F::NAME.trim().to_ascii_lowercase() || F::NAME == "auto" {
        return Err(CoreError::Param {
            name: "classifier",
            reason: format!(
                "{:?} cannot name a classifier (lower case, not auto)",
                F::NAME
            ),
        });
    }
    registered.push(kind);
    Ok(kind)
}

impl PartialEq for ClassifierKind {
    fn eq(&self, other: &Self) -> bool {
        self.as_str() == other.as_str()
    }
}

impl Eq for ClassifierKind {}

impl std::hash::Hash for ClassifierKind {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        self.as_str().hash(state);
    }
}

impl std::fmt::Debug for ClassifierKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "ClassifierKind({})", self.as_str())
    }
}

impl std::fmt::Display for ClassifierKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl Serialize for ClassifierKind {
    fn serialize<S: Serializer>(&self, serializer: S) -> std::result::Result<S::Ok, S::Error> {
        serializer.serialize_str(self.as_str())
    }
}

impl<'de> Deserialize<'de> for ClassifierKind {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> std::result::Result<Self, D::Error> {
        let name = String::deserialize(deserializer)?;
        Self::exactly(&name).ok_or_else(|| {
            serde::de::Error::custom(format!(
                "unknown classifier `{name}`, expected one of {}",
                Self::names().join(", ")
            ))
        })
    }
}
