//! [`ClassifierConfig`], [`ClassifierModel`] and [`ClassifierScratch`]: any registered family behind one
//! type each, stored tagged by the family's name (`{"kind": "pwe", ...its fields}`, as the enums they
//! replace were).

use std::any::Any;

use serde::de::Error as _;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::common::LabeledVectors;
use super::erased::{ConfigOf, DynConfig, DynFamily, DynModel, ModelOf};
use super::family::{ClassifierFamily, FitData};
use super::parzen::PweFamily;
use super::registry::ClassifierKind;
use crate::error::{CoreError, Result};

/// A classifier family with its training parameters.
#[derive(Debug)]
pub struct ClassifierConfig(Box<dyn DynConfig>);

/// A trained classifier. Equal when their stored forms are.
#[derive(Debug)]
pub struct ClassifierModel(Box<dyn DynModel>);

/// Reusable buffers of [`ClassifierModel::classify_into`] (the family's own
/// [`ClassifierFamily::Scratch`]).
pub struct ClassifierScratch(Box<dyn Any + Send>);

impl ClassifierKind {
    /// The default training parameters of this family.
    pub fn default_config(self) -> ClassifierConfig {
        ClassifierConfig(self.family().default_config())
    }
}

impl Default for ClassifierConfig {
    fn default() -> Self {
        Self::of::<PweFamily>(Default::default())
    }
}

impl ClassifierConfig {
    /// Family `F` with parameters `config`.
    pub fn of<F: ClassifierFamily>(config: F::Config) -> Self {
        Self(Box::new(ConfigOf::<F>(config)))
    }

    /// The parameters, when the family is `F`.
    pub fn params<F: ClassifierFamily>(&self) -> Option<&F::Config> {
        let config = self.0.as_any().downcast_ref::<ConfigOf<F>>()?;
        Some(&config.0)
    }

    pub fn kind(&self) -> ClassifierKind {
        kind_of(self.0.family())
    }

    /// Whether fitting needs validation vectors (the Parzen window choosing σ on them; the other
    /// classifiers use them when there are some and do without otherwise).
    pub fn needs_validation(&self) -> bool {
        self.0.needs_validation()
    }

    /// Checks the parameters on their own (no data needed).
    pub fn check(&self) -> Result<()> {
        self.0.check()
    }

    /// Trains on reduced vectors. `validation` is used for model selection (the Parzen σ, the SVM's C and
    /// gamma, k, the posterior temperature); every model but the Parzen one is then refitted on training +
    /// validation vectors (the Parzen model stores both, as in the paper).
    pub fn fit(
        &self,
        train: LabeledVectors<'_>,
        validation: LabeledVectors<'_>,
        n_classes: usize,
        dims: usize,
    ) -> Result<ClassifierModel> {
        self.fit_with(train, validation, n_classes, dims, true)
    }

    /// [`fit`](Self::fit), or, without `calibrate`, for counting right answers only: the same
    /// decisions, the posteriors possibly uncalibrated (the SVM skips the cross-validation that fits
    /// its temperature).
    pub(crate) fn fit_with(
        &self,
        train: LabeledVectors<'_>,
        validation: LabeledVectors<'_>,
        n_classes: usize,
        dims: usize,
        calibrate: bool,
    ) -> Result<ClassifierModel> {
        let data = FitData {
            train,
            validation,
            n_classes,
            dims,
            calibrate,
        };
        self.0.fit(data).map(ClassifierModel)
    }

    /// Whether the family trains on vectors in single precision
    /// ([`ClassifierFamily::READS_SINGLE`](crate::classifier::ClassifierFamily::READS_SINGLE)).
    pub fn reads_single(&self) -> bool {
        self.0.reads_single()
    }

    /// [`fit`](Self::fit) on vectors in single precision (an error unless
    /// [`reads_single`](Self::reads_single)).
    pub fn fit_single(
        &self,
        train: LabeledVectors<'_, f32>,
        validation: LabeledVectors<'_, f32>,
        n_classes: usize,
        dims: usize,
    ) -> Result<ClassifierModel> {
        let data = FitData {
            train,
            validation,
            n_classes,
            dims,
            calibrate: true,
        };
        self.0.fit_single(data).map(ClassifierModel)
    }

    /// Whether the family trains on rows held elsewhere
    /// ([`ClassifierFamily::READS_ROWS`](crate::classifier::ClassifierFamily::READS_ROWS)).
    pub(crate) fn reads_rows(&self) -> bool {
        self.0.reads_rows()
    }

    /// [`fit_with`](Self::fit_with) on rows held elsewhere (an error unless
    /// [`reads_rows`](Self::reads_rows)).
    pub(crate) fn fit_rows(
        &self,
        data: crate::classifier::family::FitRows<'_>,
    ) -> Result<ClassifierModel> {
        self.0.fit_rows(data).map(ClassifierModel)
    }

    /// Whether the family can pin the hyper-parameters a model chose
    /// ([`ClassifierFamily::PINS`](crate::classifier::ClassifierFamily::PINS)).
    pub fn pins(&self) -> bool {
        self.0.pins()
    }

    /// This configuration with the hyper-parameters (and calibration) `model`, fitted with it,
    /// chose, fixed: fitting it searches nothing
    /// ([`ClassifierFamily::pinned`](crate::classifier::ClassifierFamily::pinned)). `None` when the
    /// family has nothing to pin or `model` is of another family.
    pub fn pinned(&self, model: &ClassifierModel) -> Option<Self> {
        self.0.pinned(&*model.0).map(Self)
    }
}

impl Clone for ClassifierConfig {
    fn clone(&self) -> Self {
        Self(self.0.clone_box())
    }
}

impl PartialEq for ClassifierConfig {
    fn eq(&self, other: &Self) -> bool {
        self.kind() == other.kind() && stored_form(&*self.0) == stored_form(&*other.0)
    }
}

impl ClassifierModel {
    /// The trained state, when the family is `F`.
    pub fn get<F: ClassifierFamily>(&self) -> Option<&F::Model> {
        let model = self.0.as_any().downcast_ref::<ModelOf<F>>()?;
        Some(&model.0)
    }

    pub fn kind(&self) -> ClassifierKind {
        kind_of(self.0.family())
    }

    /// Length of the vectors this model classifies.
    pub fn dims(&self) -> usize {
        self.0.dims()
    }

    pub fn n_classes(&self) -> usize {
        self.0.n_classes()
    }

    /// The hyper-parameters training chose, in words (for reports).
    pub fn describe(&self) -> String {
        self.0.describe()
    }

    /// Scratch buffers sized for this model.
    pub fn scratch(&self) -> ClassifierScratch {
        ClassifierScratch(self.0.scratch())
    }

    /// Classifies `x`: writes class posteriors into `posteriors` (`n_classes` long) and returns the most
    /// likely class. Does not allocate once `scratch` has been sized by [`scratch`](Self::scratch).
    /// A scratch of another family is replaced by a fresh one (which allocates once).
    pub fn classify_into(
        &self,
        x: &[f64],
        scratch: &mut ClassifierScratch,
        posteriors: &mut [f64],
    ) -> Result<usize> {
        if let Some(result) = self.0.classify_into(x, &mut *scratch.0, posteriors) {
            return result;
        }
        *scratch = self.scratch();
        self.0
            .classify_into(x, &mut *scratch.0, posteriors)
            .unwrap_or_else(|| {
                Err(CoreError::Param {
                    name: "classifier",
                    reason: "the scratch of a model is not of its family".into(),
                })
            })
    }
}

impl Clone for ClassifierModel {
    fn clone(&self) -> Self {
        Self(self.0.clone_box())
    }
}

impl PartialEq for ClassifierModel {
    fn eq(&self, other: &Self) -> bool {
        self.kind() == other.kind() && stored_form(&*self.0) == stored_form(&*other.0)
    }
}

impl std::fmt::Debug for ClassifierScratch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("ClassifierScratch")
    }
}

fn kind_of(family: &'static dyn DynFamily) -> ClassifierKind {
    ClassifierKind::from_family(family)
}

/// Something stored, as the value its fields serialise to (for equality).
trait Stored {
    fn stored_fields(&self) -> &dyn erased_serde::Serialize;
}

impl Stored for dyn DynConfig {
    fn stored_fields(&self) -> &dyn erased_serde::Serialize {
        self.fields()
    }
}

impl Stored for dyn DynModel {
    fn stored_fields(&self) -> &dyn erased_serde::Serialize {
        self.fields()
    }
}

fn stored_form<T: Stored + ?Sized>(item: &T) -> Option<serde_json::Value> {
    serde_json::to_value(item.stored_fields()).ok()
}

/// The stored form: the family's name under `kind`, then the family's own fields.
#[derive(Serialize)]
struct Tagged<'a> {
    kind: &'static str,
    #[serde(flatten)]
    fields: &'a dyn erased_serde::Serialize,
}

impl Serialize for ClassifierConfig {
    fn serialize<S: Serializer>(&self, serializer: S) -> std::result::Result<S::Ok, S::Error> {
        let kind = self.0.family().name();
        Tagged {
            kind,
            fields: self.0.fields(),
        }
        .serialize(serializer)
    }
}

impl Serialize for ClassifierModel {
    fn serialize<S: Serializer>(&self, serializer: S) -> std::result::Result<S::Ok, S::Error> {
        let kind = self.0.family().name();
        Tagged {
            kind,
            fields: self.0.fields(),
        }
        .serialize(serializer)
    }
}

/// The family named by `kind` in a stored object, and the object without it.
fn untag<'de, D: Deserializer<'de>>(
    deserializer: D,
) -> std::result::Result<(ClassifierKind, serde_json::Value), D::Error> {
    let mut fields = serde_json::Map::deserialize(deserializer)?;
    let kind = match fields.remove("kind") {
        Some(serde_json::Value::String(name)) => name,
        Some(other) => {
            return Err(D::Error::custom(format!(
                "`kind` must be a name, got {other}"
            )));
        }
        None => return Err(D::Error::missing_field("kind")),
    };
    let family = ClassifierKind::exactly(&kind).ok_or_else(|| {
        D::Error::custom(format!(
            "unknown variant `{kind}`, expected one of {}",
            ClassifierKind::names().join(", ")
        ))
    })?;
    Ok((family, serde_json::Value::Object(fields)))
}

impl<'de> Deserialize<'de> for ClassifierConfig {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> std::result::Result<Self, D::Error> {
        let (kind, fields) = untag(deserializer)?;
        let config = kind.family().config_from_value(fields);
        config.map(Self).map_err(D::Error::custom)
    }
}

impl<'de> Deserialize<'de> for ClassifierModel {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> std::result::Result<Self, D::Error> {
        let (kind, fields) = untag(deserializer)?;
        let model = kind.family().model_from_value(fields);
        model.map(Self).map_err(D::Error::custom)
    }
}
