//! The object-safe face of a [`ClassifierFamily`]: what the registry, the stored configuration and the
//! stored model hold (`&'static dyn DynFamily`, `Box<dyn DynConfig>`, `Box<dyn DynModel>`), one
//! generic adapter each, so that a family only implements the typed trait.

use std::any::{Any, TypeId};
use std::fmt::Debug;
use std::marker::PhantomData;

use super::family::{ClassifierFamily, FitData, FitRows};
use crate::error::{CoreError, Result};

/// A registered family, by its name.
pub(crate) trait DynFamily: Send + Sync {
    fn name(&self) -> &'static str;
    /// The family's own type: two registrations of one name are the same family only if it matches.
    fn family_type(&self) -> TypeId;
    fn joins_auto(&self) -> bool;
    fn takes_all_features(&self) -> bool;
    fn default_config(&self) -> Box<dyn DynConfig>;
    fn config_from_value(&self, value: serde_json::Value) -> Result<Box<dyn DynConfig>>;
    fn model_from_value(&self, value: serde_json::Value) -> Result<Box<dyn DynModel>>;
}

/// Hyper-parameters of some family.
pub(crate) trait DynConfig: Debug + Send + Sync {
    fn family(&self) -> &'static dyn DynFamily;
    fn check(&self) -> Result<()>;
    fn needs_validation(&self) -> bool;
    fn fit(&self, data: FitData<'_>) -> Result<Box<dyn DynModel>>;
    fn reads_single(&self) -> bool;
    fn fit_single(&self, data: FitData<'_, f32>) -> Result<Box<dyn DynModel>>;
    fn reads_rows(&self) -> bool;
    fn fit_rows(&self, data: FitRows<'_>) -> Result<Box<dyn DynModel>>;
    fn pins(&self) -> bool;
    /// `None` too when `model` belongs to another family.
    fn pinned(&self, model: &dyn DynModel) -> Option<Box<dyn DynConfig>>;
    fn clone_box(&self) -> Box<dyn DynConfig>;
    fn as_any(&self) -> &dyn Any;
    fn fields(&self) -> &dyn erased_serde::Serialize;
}

/// A trained classifier of some family.
pub(crate) trait DynModel: Debug + Send + Sync {
    fn family(&self) -> &'static dyn DynFamily;
    fn dims(&self) -> usize;
    fn n_classes(&self) -> usize;
    fn describe(&self) -> String;
    fn scratch(&self) -> Box<dyn Any + Send>;
    /// `None` when `scratch` belongs to another family.
    fn classify_into(
        &self,
        x: &[f64],
        scratch: &mut (dyn Any + Send),
        posteriors: &mut [f64],
    ) -> Option<Result<usize>>;
    fn clone_box(&self) -> Box<dyn DynModel>;
    fn as_any(&self) -> &dyn Any;
    fn fields(&self) -> &dyn erased_serde::Serialize;
}

/// The adapter of family `F` (a zero-sized value: registering one allocates nothing).
pub(crate) struct Erased<F>(PhantomData<fn() -> F>);

impl<F: ClassifierFamily> Erased<F> {
    pub(crate) const FAMILY: &'static dyn DynFamily = &Erased::<F>(PhantomData);
}

/// Family `F`'s hyper-parameters, as a [`DynConfig`].
pub(crate) struct ConfigOf<F: ClassifierFamily>(pub(crate) F::Config);

/// Family `F`'s trained state, as a [`DynModel`].
pub(crate) struct ModelOf<F: ClassifierFamily>(pub(crate) F::Model);

impl<F: ClassifierFamily> Debug for ConfigOf<F> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.fmt(f)
    }
}

impl<F: ClassifierFamily> Debug for ModelOf<F> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.fmt(f)
    }
}

fn from_value<T: serde::de::DeserializeOwned>(
    family: &'static str,
    value: serde_json::Value,
) -> Result<T> {
    serde_json::from_value(value).map_err(|err| CoreError::Param {
        name: "classifier",
        reason: format!("{family}: {err}"),
    })
}

impl<F: ClassifierFamily> DynFamily for Erased<F> {
    fn name(&self) -> &'static str {
        F::NAME
    }

    fn family_type(&self) -> TypeId {
        TypeId::of::<F>()
    }

    fn joins_auto(&self) -> bool {
        F::JOINS_AUTO
    }

    fn takes_all_features(&self) -> bool {
        F::TAKES_ALL_FEATURES
    }

    fn default_config(&self) -> Box<dyn DynConfig> {
        Box::new(ConfigOf::<F>(F::Config::default()))
    }

    fn config_from_value(&self, value: serde_json::Value) -> Result<Box<dyn DynConfig>> {
        Ok(Box::new(ConfigOf::<F>(from_value(F::NAME, value)?)))
    }

    fn model_from_value(&self, value: serde_json::Value) -> Result<Box<dyn DynModel>> {
        Ok(Box::new(ModelOf::<F>(from_value(F::NAME, value)?)))
    }
}

impl<F: ClassifierFamily> DynConfig for ConfigOf<F> {
    fn family(&self) -> &'static dyn DynFamily {
        Erased::<F>::FAMILY
    }

    fn check(&self) -> Result<()> {
        F::check(&self.0)
    }

    fn needs_validation(&self) -> bool {
        F::needs_validation(&self.0)
    }

    fn fit(&self, data: FitData<'_>) -> Result<Box<dyn DynModel>> {
        Ok(Box::new(ModelOf::<F>(F::fit(&self.0, data)?)))
    }

    fn reads_single(&self) -> bool {
        F::READS_SINGLE
    }

    fn fit_single(&self, data: FitData<'_, f32>) -> Result<Box<dyn DynModel>> {
        Ok(Box::new(ModelOf::<F>(F::fit_single(&self.0, data)?)))
    }

    fn reads_rows(&self) -> bool {
        F::READS_ROWS
    }

    fn fit_rows(&self, data: FitRows<'_>) -> Result<Box<dyn DynModel>> {
        Ok(Box::new(ModelOf::<F>(F::fit_rows(&self.0, data)?)))
    }

    fn pins(&self) -> bool {
        F::PINS
    }

    fn pinned(&self, model: &dyn DynModel) -> Option<Box<dyn DynConfig>> {
        let model = model.as_any().downcast_ref::<ModelOf<F>>()?;
        let pinned = F::pinned(&self.0, &model.0)?;
        Some(Box::new(ConfigOf::<F>(pinned)))
    }

    fn clone_box(&self) -> Box<dyn DynConfig> {
        Box::new(Self(self.0.clone()))
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn fields(&self) -> &dyn erased_serde::Serialize {
        &self.0
    }
}

impl<F: ClassifierFamily> DynModel for ModelOf<F> {
    fn family(&self) -> &'static dyn DynFamily {
        Erased::<F>::FAMILY
    }

    fn dims(&self) -> usize {
        F::dims(&self.0)
    }

    fn n_classes(&self) -> usize {
        F::n_classes(&self.0)
    }

    fn describe(&self) -> String {
        F::describe(&self.0)
    }

    fn scratch(&self) -> Box<dyn Any + Send> {
        Box::new(F::scratch(&self.0))
    }

    fn classify_into(
        &self,
        x: &[f64],
        scratch: &mut (dyn Any + Send),
        posteriors: &mut [f64],
    ) -> Option<Result<usize>> {
        let scratch = scratch.downcast_mut::<F::Scratch>()?;
        Some(F::classify_into(&self.0, x, scratch, posteriors))
    }

    fn clone_box(&self) -> Box<dyn DynModel> {
        Box::new(Self(self.0.clone()))
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn fields(&self) -> &dyn erased_serde::Serialize {
        &self.0
    }
}
