//! The registered feature families: the built-in ones (one line each, below) and those registered at
//! run time ([`register`]: extensions, tests). [`FeatureKind`] names one preset of one family, as users
//! name it (`--features fft2d_polar`).

use std::sync::RwLock;

use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::error::{CoreError, Result};
use crate::features::contact::ContactFamily;
use crate::features::erased::{DynFamily, Erased};
use crate::features::family::FeatureFamily;
use crate::features::fft1d::Fft1dFamily;
use crate::features::fft2d::Fft2dFamily;
use crate::features::glcm::GlcmFamily;
use crate::features::rocket::family::RocketFamily;
use crate::features::rocket::multi_family::MultiRocketFamily;

/// The built-in families, in the order users see them. One line per family (every preset of it is a
/// name).
const BUILT_IN: [&dyn DynFamily; 6] = [
    Erased::<Fft1dFamily>::FAMILY,
    Erased::<Fft2dFamily>::FAMILY,
    Erased::<GlcmFamily>::FAMILY,
    Erased::<ContactFamily>::FAMILY,
    Erased::<RocketFamily>::FAMILY,
    Erased::<MultiRocketFamily>::FAMILY,
];

/// Families registered at run time, after the built-in ones.
static REGISTERED: RwLock<Vec<&'static dyn DynFamily>> = RwLock::new(Vec::new());

/// A feature family by a name users give it (`--features NAME`): one preset of a registered
/// [`FeatureFamily`]. Equal when the names are; serialised as the name.
#[derive(Clone, Copy)]
pub struct FeatureKind {
    family: &'static dyn DynFamily,
    preset: usize,
}

impl FeatureKind {
    /// Magnitude of the 1-D FFT of the row-major image (the paper's eqs. 3-5).
    pub const FFT1D: Self = Self::preset::<Fft1dFamily>(0);
    /// The non-redundant half of the 2-D |FFT|.
    pub const FFT2D: Self = Self::preset::<Fft2dFamily>(0);
    /// Ring and wedge sums of the 2-D |FFT| (compact, shift- and rotation-robust).
    pub const FFT2D_POLAR: Self = Self::preset::<Fft2dFamily>(1);
    /// Haralick attributes of grey-level co-occurrence matrices.
    pub const GLCM: Self = Self::preset::<GlcmFamily>(0);
    /// Contact geometry: areas above shares of the peak, the load's moments and radial profile, mean
    /// and peak, standardised over the training images.
    pub const CONTACT: Self = Self::preset::<ContactFamily>(0);
    /// MiniRocket's random convolutions of a series (an image's rows as channels over time), learned
    /// from the training samples.
    pub const ROCKET: Self = Self::preset::<RocketFamily>(0);
    /// MiniRocket on the channels in their own units (no scaling by their spread first).
    pub const ROCKET_UNSCALED: Self = Self::preset::<RocketFamily>(1);
    /// MiniRocket on the signed logs of the channels' values.
    pub const ROCKET_LOG: Self = Self::preset::<RocketFamily>(2);
    /// MiniRocket on the channels in their own units, and the sample's duration as one more feature.
    pub const ROCKET_DURATION: Self = Self::preset::<RocketFamily>(3);
    /// MiniRocket on the signed logs, and the duration.
    pub const ROCKET_LOG_DURATION: Self = Self::preset::<RocketFamily>(4);
    /// MultiRocket (Tan et al. 2022): MiniRocket's kernels on the series and its first differences,
    /// four pooling operators, the channels scaled by their spread.
    pub const MULTIROCKET: Self = Self::preset::<MultiRocketFamily>(0);
    /// MultiRocket on the channels in their own units.
    pub const MULTIROCKET_UNSCALED: Self = Self::preset::<MultiRocketFamily>(1);

    /// Preset `index` of family `F` (registered or not: see [`register`]); a bad index fails to compile
    /// where it is a constant.
    pub const fn preset<F: FeatureFamily>(index: usize) -> Self {
        assert!(index < F::PRESETS.len(), "no such preset");
        Self {
            family: Erased::<F>::FAMILY,
            preset: index,
        }
    }

    /// The default preset of family `F`.
    pub const fn of<F: FeatureFamily>() -> Self {
        Self::preset::<F>(0)
    }

    pub(crate) fn from_parts(family: &'static dyn DynFamily, preset: usize) -> Self {
        Self { family, preset }
    }

    pub(crate) fn family(self) -> &'static dyn DynFamily {
        self.family
    }

    pub(crate) fn preset_index(self) -> usize {
        self.preset
    }

    /// Every name of every registered family: the built-in ones, then those registered at run time.
    pub fn all() -> Vec<Self> {
        families()
            .into_iter()
            .flat_map(|family| {
                (0..family.presets().len()).map(move |preset| Self::from_parts(family, preset))
            })
            .collect()
    }

    /// Every name, in order.
    pub fn names() -> Vec<&'static str> {
        Self::all().into_iter().map(Self::as_str).collect()
    }

    pub fn as_str(self) -> &'static str {
        self.family.presets()[self.preset]
    }

    /// The name the family's parameters are stored under (`fft2d` for `fft2d_polar`).
    pub fn family_name(self) -> &'static str {
        self.family.name()
    }

    /// Whether the family is costly to compute (scored last by the automatic choice).
    pub fn costly(self) -> bool {
        self.family.costly()
    }

    /// Parses a name (case-insensitive).
    pub fn parse(text: &str) -> Result<Self> {
        let wanted = text.trim().to_ascii_lowercase();
        Self::exactly(&wanted).ok_or_else(|| CoreError::Param {
            name: "features",
            reason: format!(
                "unknown feature kind {text:?}; known: {}",
                Self::names().join(", ")
            ),
        })
    }

    /// Parses `fft1d`, `glcm`, `fft1d+glcm`, `fft2d_polar,glcm`, ... into the families named.
    pub fn parse_list(text: &str) -> Result<Vec<Self>> {
        text.split(['+', ',']).map(Self::parse).collect()
    }

    /// The preset named exactly `name`, if registered.
    pub(crate) fn exactly(name: &str) -> Option<Self> {
        Self::all().into_iter().find(|kind| kind.as_str() == name)
    }
}

/// The registered families, built-in first.
pub(crate) fn families() -> Vec<&'static dyn DynFamily> {
    let registered = REGISTERED
        .read()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    BUILT_IN.iter().chain(registered.iter()).copied().collect()
}

/// The family stored under `name`, if registered.
pub(crate) fn family_named(name: &str) -> Option<&'static dyn DynFamily> {
    families().into_iter().find(|family| family.name() == name)
}

/// Registers family `F` at run time (an extension, a test): from then on its presets are parsed, its
/// features extracted, stored, loaded and listed like a built-in family's. Registering the same family
/// again does nothing; another family of a taken name (stored or preset) is refused.
pub fn register<F: FeatureFamily>() -> Result<FeatureKind> {
    let family = Erased::<F>::FAMILY;
    let mut registered = REGISTERED
        .write()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    let known = || BUILT_IN.iter().chain(registered.iter());
    if let Some(same) = known().find(|f| f.family_type() == family.family_type()) {
        return Ok(FeatureKind::from_parts(*same, 0));
    }
    let refuse = |reason: String| {
        Err(CoreError::Param {
            name: "features",
            reason,
        })
    };
    let names = std::iter::once(F::NAME).chain(F::PRESETS.iter().copied());
    for name in names {
        if name.is_empty()
            || name != name.trim().to_ascii_lowercase()
            || name == "auto"
            || name.contains(['+', ','])
        {
            return refuse(format!(
                "{name:?} cannot name a feature family (lower case, no + or comma, not auto)"
            ));
        }
        let taken = known().any(|f| f.name() == name || f.presets().contains(&name));
        if taken {
            return refuse(format!(
                "a feature family named {name:?} is already registered"
            ));
        }
    }
    if F::PRESETS.first() != Some(&F::NAME) {
        return refuse(format!(
            "the first preset of {:?} must be its own name",
            F::NAME
        ));
    }
    registered.push(family);
    Ok(FeatureKind::of::<F>())
}

impl PartialEq for FeatureKind {
    fn eq(&self, other: &Self) -> bool {
        self.as_str() == other.as_str()
    }
}

impl Eq for FeatureKind {}

impl std::hash::Hash for FeatureKind {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        self.as_str().hash(state);
    }
}

impl std::fmt::Debug for FeatureKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "FeatureKind({})", self.as_str())
    }
}

impl std::fmt::Display for FeatureKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl Serialize for FeatureKind {
    fn serialize<S: Serializer>(&self, serializer: S) -> std::result::Result<S::Ok, S::Error> {
        serializer.serialize_str(self.as_str())
    }
}

impl<'de> Deserialize<'de> for FeatureKind {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> std::result::Result<Self, D::Error> {
        let name = String::deserialize(deserializer)?;
        Self::exactly(&name).ok_or_else(|| {
            serde::de::Error::custom(format!(
                "unknown feature kind `{name}`, expected one of {}",
                Self::names().join(", ")
            ))
        })
    }
}
