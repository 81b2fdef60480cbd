//! The object-safe face of a [`FeatureFamily`]: what the registry, the stored configuration and the
//! extractor hold (`&'static dyn DynFamily`, `Box<dyn DynConfig>`, `Box<dyn DynExtractor>`), one generic
//! adapter each, so that a family only implements the typed trait.

use std::any::{Any, TypeId};
use std::fmt::Debug;
use std::marker::PhantomData;

use crate::error::{CoreError, Result};
use crate::features::family::{FeatureFamily, FitImages};
use crate::frame::Grid;

/// A registered family, by its name.
pub(crate) trait DynFamily: Send + Sync {
    fn name(&self) -> &'static str;
    fn presets(&self) -> &'static [&'static str];
    /// The family's own type: two registrations of one name are the same family only if it matches.
    fn family_type(&self) -> TypeId;
    fn costly(&self) -> bool;
    fn learns(&self) -> bool;
    fn preset(&self, index: usize) -> Box<dyn DynConfig>;
    fn config_from_value(&self, value: serde_json::Value) -> Result<Box<dyn DynConfig>>;
}

/// Parameters of some family.
pub(crate) trait DynConfig: Debug + Send + Sync {
    fn family(&self) -> &'static dyn DynFamily;
    fn preset_of(&self) -> usize;
    fn check(&self) -> Result<()>;
    fn fit(&self, images: FitImages<'_>) -> Result<Box<dyn DynConfig>>;
    fn output_len(&self, grid: Grid) -> Result<usize>;
    fn feature_names(&self, grid: Grid) -> Result<Vec<String>>;
    fn transform_points(&self, grid: Grid) -> Result<usize>;
    fn has_fast_path(&self) -> bool;
    fn extractor(&self, grid: Grid) -> Result<Box<dyn DynExtractor>>;
    fn clone_box(&self) -> Box<dyn DynConfig>;
    fn as_any(&self) -> &dyn Any;
    fn fields(&self) -> &dyn erased_serde::Serialize;
}

/// An extractor of some family.
pub(crate) trait DynExtractor: Debug + Send + Sync {
    fn grid(&self) -> Grid;
    fn len(&self) -> usize;
    fn extract_into(&mut self, image: &[f64], out: &mut [f64]) -> Result<()>;
    fn extract_fast_into(&mut self, image: &[f64], out: &mut [f64]) -> Result<()>;
    fn extract_fast_window(
        &mut self,
        values: &[f64],
        first: usize,
        stride: usize,
    ) -> Option<Result<&[f32]>>;
    fn clone_box(&self) -> Box<dyn DynExtractor>;
    fn as_any(&self) -> &dyn Any;
}

/// The adapter of family `F` (a zero-sized value: registering one allocates nothing).
pub(crate) struct Erased<F>(PhantomData<fn() -> F>);

impl<F: FeatureFamily> Erased<F> {
    pub(crate) const FAMILY: &'static dyn DynFamily = &Erased::<F>(PhantomData);
}

/// Family `F`'s parameters, as a [`DynConfig`].
pub(crate) struct ConfigOf<F: FeatureFamily>(pub(crate) F::Config);

/// Family `F`'s extractor, as a [`DynExtractor`].
pub(crate) struct ExtractorOf<F: FeatureFamily>(pub(crate) F::Extractor);

impl<F: FeatureFamily> Debug for ConfigOf<F> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.fmt(f)
    }
}

impl<F: FeatureFamily> Debug for ExtractorOf<F> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.fmt(f)
    }
}

impl<F: FeatureFamily> DynFamily for Erased<F> {
    fn name(&self) -> &'static str {
        F::NAME
    }

    fn presets(&self) -> &'static [&'static str] {
        F::PRESETS
    }

    fn family_type(&self) -> TypeId {
        TypeId::of::<F>()
    }

    fn costly(&self) -> bool {
        F::COSTLY
    }

    fn learns(&self) -> bool {
        F::LEARNS
    }

    fn preset(&self, index: usize) -> Box<dyn DynConfig> {
        Box::new(ConfigOf::<F>(F::preset(index)))
    }

    fn config_from_value(&self, value: serde_json::Value) -> Result<Box<dyn DynConfig>> {
        let config = serde_json::from_value(value).map_err(|err| CoreError::Param {
            name: "features",
            reason: format!("{}: {err}", F::NAME),
        })?;
        Ok(Box::new(ConfigOf::<F>(config)))
    }
}

impl<F: FeatureFamily> DynConfig for ConfigOf<F> {
    fn family(&self) -> &'static dyn DynFamily {
        Erased::<F>::FAMILY
    }

    fn preset_of(&self) -> usize {
        F::preset_of(&self.0)
    }

    fn check(&self) -> Result<()> {
        F::check(&self.0)
    }

    fn fit(&self, images: FitImages<'_>) -> Result<Box<dyn DynConfig>> {
        Ok(Box::new(Self(F::fit(&self.0, images)?)))
    }

    fn output_len(&self, grid: Grid) -> Result<usize> {
        F::output_len(&self.0, grid)
    }

    fn feature_names(&self, grid: Grid) -> Result<Vec<String>> {
        F::feature_names(&self.0, grid)
    }

    fn transform_points(&self, grid: Grid) -> Result<usize> {
        F::transform_points(&self.0, grid)
    }

    fn has_fast_path(&self) -> bool {
        F::has_fast_path(&self.0)
    }

    fn extractor(&self, grid: Grid) -> Result<Box<dyn DynExtractor>> {
        Ok(Box::new(ExtractorOf::<F>(F::extractor(&self.0, grid)?)))
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

impl<F: FeatureFamily> DynExtractor for ExtractorOf<F> {
    fn grid(&self) -> Grid {
        F::grid(&self.0)
    }

    fn len(&self) -> usize {
        F::len(&self.0)
    }

    fn extract_into(&mut self, image: &[f64], out: &mut [f64]) -> Result<()> {
        F::extract_into(&mut self.0, image, out)
    }

    fn extract_fast_into(&mut self, image: &[f64], out: &mut [f64]) -> Result<()> {
        F::extract_fast_into(&mut self.0, image, out)
    }

    fn extract_fast_window(
        &mut self,
        values: &[f64],
        first: usize,
        stride: usize,
    ) -> Option<Result<&[f32]>> {
        F::extract_fast_window(&mut self.0, values, first, stride)
    }

    fn clone_box(&self) -> Box<dyn DynExtractor> {
        Box::new(Self(self.0.clone()))
    }

    fn as_any(&self) -> &dyn Any {
        self
    }
}
