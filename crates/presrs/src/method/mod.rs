//! What a model is made of: crop, features, principal components, classifier, preprocessing — fixed,
//! or chosen automatically by validation. The one definition of `auto` and of the paper's method.

use std::str::FromStr;
use std::time::Duration;

use presrs_core::classifier::ClassifierKind;
use presrs_core::features::{FeatureConfig, FeatureKind, RocketFamily, RocketParams};
use presrs_core::pipeline::{CheckedTrainConfig, TrainConfig};
use presrs_core::preprocess::{Intensity, Preprocess};
use presrs_core::sample::SampleKind;
pub use presrs_core::selection::ChoiceRule;
pub use presrs_core::selection::ValidateBy;
use presrs_core::selection::{AutoChoice, CandidateScore, Selection};
use presrs_core::split::ValidationSize;
use presrs_core::{CoreError, Crop, Grid};
use presrs_io::message::{Message, Opt};

use crate::error::{Error, Result};

mod ties;
mod warnings;

pub use ties::PREFERRED_ON_TIE;
use ties::preferred_on_tie;
pub use warnings::{budget_warning, selection_warnings, tie_warning, validation_warning};

/// Principal components kept unless told otherwise (the paper's 51).
pub const DEFAULT_DIMS: usize = 51;

/// How long an automatic choice may score candidates by default, per model trained: the whole default
/// search of a few hundred images fits in it on a 2-core machine; on larger sets it cuts the texture
/// families first (and says so).
pub const DEFAULT_BUDGET: Duration = Duration::from_secs(60);

/// The numbers of principal components the best few candidates of an automatic choice are scored again
/// with, when `--dims` is not given: half and twice the paper's 51 (real sets differ in how many
/// components carry the classes; more than the training images allow are lowered to that).
pub const REFINED_DIMS: [usize; 2] = [25, 102];

/// Every feature family: what a comparison tries, and what an automatic choice tries, the texture ones
/// (glcm, alone or combined: a GLCM image costs 2-3x an FFT one) after the cheap ones and the intensity
/// transforms, so that a time budget cuts them first.
pub const CANDIDATE_FEATURES: [&[FeatureKind]; 5] = [
    &[FeatureKind::FFT1D],
    &[FeatureKind::FFT2D],
    &[FeatureKind::FFT2D_POLAR],
    &[FeatureKind::GLCM],
    &[FeatureKind::FFT2D_POLAR, FeatureKind::GLCM],
];

/// The families an automatic choice races on whole stances and series by default (`full_search`: every
/// family of [`WHOLE_SAMPLE_FEATURES`] and the frame families too): MiniRocket's two presets, each with
/// every classifier. On every shared whole-sample set the inner validation's other winners did worse on
/// the held-out groups than MiniRocket's: on the simulator's stances `fft2d_polar` + pwe (64.6 % on the
/// held-out gait) or, without the frame families, `multirocket_unscaled` + `ridge_raw` (59.6 %), where
/// MiniRocket + `ridge_raw` gives 99.6 %; on `icub20` the frame families' SVMs won validation by 0.5-1
/// point and tested 0.7 below MiniRocket + `ridge_raw`. The race of MiniRocket alone: the simulator
/// 84.7 -> 94.6 %, `jiku-walk` and `icub20` unchanged (98.1, 97.3 %) with fewer candidates to score
/// (bench/real/RESULTS.md, "MiniRocket alone in the default race").
pub const DEFAULT_WHOLE_SAMPLE_FEATURES: [FeatureKind; 2] =
    [FeatureKind::ROCKET_UNSCALED, FeatureKind::ROCKET];

/// The random-convolution families a full search (and a comparison) on whole stances and series adds
/// before the frame families, in order of preference (ties go to the earlier; a time budget cuts from
/// the end), each with whether it is paired with every classifier (or with the ridge classifiers only):
/// MiniRocket before MultiRocket (on the shared sets MultiRocket scored lower, and its features cost
/// about twice MiniRocket's; Tan et al. 2022 report it ahead on the UCR/UEA archives, so a full search
/// validates it; the default race has MiniRocket's alone, [`DEFAULT_WHOLE_SAMPLE_FEATURES`]), and for each the channels
/// in their own units before the channels scaled by their spread (aeon's input; on `jiku-walk` the
/// scaling cost 2-5 points, sensors whose channels differ in units may need it, so both are validated).
pub const WHOLE_SAMPLE_FEATURES: [(FeatureKind, bool); 4] = [
    (FeatureKind::ROCKET_UNSCALED, true),
    (FeatureKind::ROCKET, true),
    (FeatureKind::MULTIROCKET_UNSCALED, false),
    (FeatureKind::MULTIROCKET, false),
];

/// The most MiniRocket draws ([`RocketParams::draws`]) a race on whole samples fits side by side.
pub const MAX_RACE_DRAWS: usize = 4;

/// The MiniRocket feature values (samples x features, all draws) up to which a race on whole samples
/// adds draws: 64 million, 256 MB in single precision, which keeps the scale goals' sets (10^4 samples
/// and more) at one draw.
pub const DRAW_BUDGET_VALUES: usize = 64_000_000;

/// How many MiniRocket draws of `features_per_draw` features a race on `samples` whole samples fits side
/// by side: as many as [`DRAW_BUDGET_VALUES`] allows, 1 to [`MAX_RACE_DRAWS`]. One draw's luck moves
/// the accuracy by tenths of a point on real sets and by points on small ones; four draws side by side
/// scored above the mean single draw on every shared whole-sample set (bench/real/RESULTS.md,
/// "MiniRocket's draws side by side"), at four times the features' cost, so only where that is small.
pub fn race_draws(samples: usize, features_per_draw: usize) -> usize {
    let per_draw = samples.max(1).saturating_mul(features_per_draw.max(1));
    (DRAW_BUDGET_VALUES / per_draw).clamp(1, MAX_RACE_DRAWS)
}

/// [`race_draws`] for MiniRocket's default features (about 10,000 a draw) on `samples` samples.
pub fn race_draws_for(samples: usize) -> usize {
    race_draws(samples, RocketParams::default().config().output_len())
}

/// `features` with `draws` MiniRocket draws when it is MiniRocket's (other families as they are).
fn with_draws(features: FeatureConfig, draws: usize) -> FeatureConfig {
    match features.params::<RocketFamily>() {
        Some(params) => FeatureConfig::of::<RocketFamily>(RocketParams {
            draws,
            ..params.clone()
        }),
        None => features,
    }
}

/// A crop, or `auto`: decided from the image size.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CropChoice {
    /// The paper's crop on a 44 x 44 array, the whole image otherwise.
    #[default]
    Auto,
    Fixed(Crop),
}

impl CropChoice {
    /// The crop for images of `grid`: as given, or resolved from `auto`.
    pub fn resolve(self, grid: Grid) -> Crop {
        match self {
            Self::Fixed(crop) => crop,
            Self::Auto if grid == Grid::new(44, 44) => Crop::PAPER,
            Self::Auto => Crop::NONE,
        }
    }
}

/// Feature families, or `auto`.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub enum FeatureChoice {
    #[default]
    Auto,
    Kinds(Vec<FeatureKind>),
}

/// A classifier family, or `auto`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ClassifierChoice {
    #[default]
    Auto,
    Kind(ClassifierKind),
}

/// How a model is built: crop, features, reduction, classifier and preprocessing. The default is the
/// automatic choice; [`Method::paper`] is the paper's 1-D |FFT| + Parzen window.
#[derive(Debug, Clone, PartialEq)]
pub struct Method {
    pub features: FeatureChoice,
    pub classifier: ClassifierChoice,
    /// With `auto`: score every candidate without a time budget, and on whole samples race every family
    /// (the random-convolution ones and the frame families), not MiniRocket's presets alone.
    pub full_search: bool,
    /// With `auto`: how long scoring the candidates of one model may take (`None`: no limit, every
    /// candidate scored) [default: [`DEFAULT_BUDGET`]].
    pub budget: Option<Duration>,
    /// Principal components kept (at most the training images minus one, and the features) [default:
    /// [`DEFAULT_DIMS`]].
    pub dims: Option<usize>,
    pub preprocess: Preprocess,
    pub crop: CropChoice,
    /// How an automatic choice validates its candidates inside the training data (by group, condition
    /// or stratified splits; `auto`: the most honest the data allow).
    pub validate_by: ValidateBy,
    /// How an automatic choice picks its winner from the validation scores.
    pub choose: Choose,
}

/// How an automatic choice picks its winner: a [`ChoiceRule`], or `auto`, the rule measured best for
/// the race (see [`Choose::rule_for`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Choose {
    #[default]
    Auto,
    Rule(ChoiceRule),
}

impl Choose {
    pub const NAMES: [&'static str; 3] = ["auto", "best", "one-se"];

    /// The rule for a race among `candidates`: `auto` is one standard error where they are the
    /// random-convolution families of whole samples (on icub20 and the scale bench's set the highest
    /// of their close scores was a lucky candidate: bench/real/RESULTS.md, "One standard error by
    /// default"), else the best (on frames it kept the paper's method where the best was better, as
    /// at frames 12 and 18 of jiku-walk's stances).
    pub fn rule_for(self, candidates: &[CheckedTrainConfig]) -> ChoiceRule {
        match self {
            Self::Rule(rule) => rule,
            Self::Auto if candidates.iter().any(is_random_convolution) => {
                ChoiceRule::OneStandardError
            }
            Self::Auto => ChoiceRule::Best,
        }
    }
}

/// Whether `candidate`'s features are a random-convolution family of whole samples (MiniRocket's or
/// MultiRocket's, any preset).
fn is_random_convolution(candidate: &CheckedTrainConfig) -> bool {
    let families = [
        FeatureKind::ROCKET.family_name(),
        FeatureKind::MULTIROCKET.family_name(),
    ];
    candidate
        .config()
        .features
        .kind()
        .is_some_and(|kind| families.contains(&kind.family_name()))
}

impl std::str::FromStr for Choose {
    type Err = String;

    fn from_str(text: &str) -> std::result::Result<Self, String> {
        match text.trim().to_ascii_lowercase().as_str() {
            "auto" => Ok(Self::Auto),
            other => other.parse().map(Self::Rule).map_err(|_| {
                format!(
                    "unknown choice rule {text:?} (known: {})",
                    Self::NAMES.join(", ")
                )
            }),
        }
    }
}

impl Default for Method {
    /// The automatic choice, with the default budget.
    fn default() -> Self {
        Self {
            features: FeatureChoice::Auto,
            classifier: ClassifierChoice::Auto,
            full_search: false,
            budget: Some(DEFAULT_BUDGET),
            dims: None,
            preprocess: Preprocess::default(),
            crop: CropChoice::Auto,
            validate_by: ValidateBy::Auto,
            choose: Choose::Auto,
        }
    }
}

impl Method {
    /// The paper's method: 1-D |FFT| features, Parzen window, 51 components, the paper's crop on a
    /// 44 x 44 array.
    pub fn paper() -> Self {
        Self {
            features: FeatureChoice::Kinds(vec![FeatureKind::FFT1D]),
            classifier: ClassifierChoice::Kind(ClassifierKind::PWE),
            ..Self::default()
        }
    }

    /// Principal components to keep: as given, or the paper's 51.
    pub fn dims(&self) -> usize {
        self.dims.unwrap_or(DEFAULT_DIMS)
    }

    /// Whether features or classifier are to be chosen automatically.
    pub fn is_auto(&self) -> bool {
        self.features == FeatureChoice::Auto || self.classifier == ClassifierChoice::Auto
    }

    /// The checked training configuration for images of `grid`. An `auto` part is the paper's choice
    /// here (fft1d, pwe); [`candidates`](Self::candidates) lists what auto tries.
    pub fn train_config(&self, grid: Grid) -> Result<CheckedTrainConfig> {
        let features = match &self.features {
            FeatureChoice::Kinds(kinds) => FeatureConfig::combined(kinds),
            FeatureChoice::Auto => FeatureKind::FFT1D.default_config(),
        };
        let classifier = match self.classifier {
            ClassifierChoice::Kind(kind) => kind.default_config(),
            ClassifierChoice::Auto => ClassifierKind::PWE.default_config(),
        };
        self.config(grid, features, classifier)
    }

    /// The paper's method (1-D |FFT| features, Parzen window) with this method's crop, dims and
    /// preprocessing: what an automatic choice is shown next to.
    pub fn paper_config(&self, grid: Grid) -> Result<CheckedTrainConfig> {
        self.config(
            grid,
            FeatureKind::FFT1D.default_config(),
            ClassifierKind::PWE.default_config(),
        )
    }

    /// Every configuration an automatic choice tries, in the order it scores them (auto parts run over
    /// the candidates, fixed parts stay), or, with `all`, every feature x classifier combination (for a
    /// comparison). The order: the cheap families (the paper's first), then the intensity transforms
    /// (with the paper's features, or with every cheap family in a full search), then the texture
    /// families (with the transforms in a full search): a time budget cuts from the end.
    pub fn candidates(&self, grid: Grid, all: bool) -> Result<Vec<CheckedTrainConfig>> {
        self.candidates_for(grid, all, &SampleKind::Frame, 1)
    }

    /// [`candidates`](Self::candidates) for samples of `sample`: on whole stances and series an automatic
    /// choice races MiniRocket's presets ([`DEFAULT_WHOLE_SAMPLE_FEATURES`]) alone; with `full_search`
    /// (and in a comparison, `all`) every random-convolution family ([`WHOLE_SAMPLE_FEATURES`]) first,
    /// then the frame families. Each random-convolution family is paired with the ridge classifiers
    /// first (`ridge_raw`, then `ridge`: the pairing the papers use), then, for MiniRocket, with the
    /// others (MultiRocket with the ridges only, unless `all`, to bound the search's cost). MiniRocket
    /// paired with a ridge fits `draws` draws side by side (see [`race_draws`]).
    pub fn candidates_for(
        &self,
        grid: Grid,
        all: bool,
        sample: &SampleKind,
        draws: usize,
    ) -> Result<Vec<CheckedTrainConfig>> {
        let classifiers: Vec<ClassifierKind> = match self.classifier {
            ClassifierChoice::Kind(kind) if !all => vec![kind],
            _ => ClassifierKind::auto_candidates(),
        };
        let families: Vec<FeatureConfig> = match &self.features {
            FeatureChoice::Kinds(kinds) if !all => vec![FeatureConfig::combined(kinds)],
            _ => CANDIDATE_FEATURES
                .iter()
                .map(|kinds| FeatureConfig::combined(kinds))
                .collect(),
        };
        let mut out = Vec::new();
        let whole = !sample.is_frame() && (all || self.features == FeatureChoice::Auto);
        // The default race on whole samples: MiniRocket's presets alone.
        let narrow = whole && !all && !self.full_search;
        if whole {
            let auto_classifier = all || self.classifier == ClassifierChoice::Auto;
            for (kind, every_classifier) in WHOLE_SAMPLE_FEATURES {
                if narrow && !DEFAULT_WHOLE_SAMPLE_FEATURES.contains(&kind) {
                    continue;
                }
                let features = kind.default_config();
                let drawn = with_draws(features.clone(), draws);
                let ridges = [ClassifierKind::RIDGE_RAW, ClassifierKind::RIDGE];
                let paired: Vec<ClassifierKind> = match (auto_classifier, all || every_classifier) {
                    (false, _) => classifiers.clone(),
                    (true, false) => ridges.to_vec(),
                    (true, true) => ridges.iter().chain(&classifiers).copied().collect(),
                };
                for classifier in paired {
                    // The ridges read every feature, where a draw's luck shows; the others read
                    // principal components, which more draws would cost as many times to compute.
                    let features = if ridges.contains(&classifier) {
                        &drawn
                    } else {
                        &features
                    };
                    out.push(self.config(grid, features.clone(), classifier.default_config())?);
                }
            }
        }
        if narrow {
            return Ok(out);
        }
        let given = self.preprocess.intensity;
        let intensities: &[Intensity] =
            if !all && self.features == FeatureChoice::Auto && given.is_none() {
                &Intensity::ALL
            } else {
                std::slice::from_ref(&given)
            };
        for texture in [false, true] {
            for &intensity in intensities {
                let method = Self {
                    preprocess: Preprocess {
                        intensity,
                        ..self.preprocess
                    },
                    ..self.clone()
                };
                // The transforms are raced with every family: the race drops the clear losers, and
                // the texture families come last, where a budget cuts first on large sets.
                for feature in families.iter().filter(|f| f.is_costly() == texture) {
                    for &classifier in &classifiers {
                        out.push(method.config(
                            grid,
                            feature.clone(),
                            classifier.default_config(),
                        )?);
                    }
                }
            }
        }
        Ok(out)
    }

    /// How the automatic choice picks among `candidates` (from [`candidates`](Self::candidates)): this
    /// method's validation and budget, a tie for the best to [`PREFERRED_ON_TIE`] when it is a
    /// candidate, and, unless `dims` is given, the best candidates tried again with [`REFINED_DIMS`]
    /// components.
    pub fn auto_choice<'c>(&self, candidates: &'c [CheckedTrainConfig]) -> AutoChoice<'c> {
        let refine: &'static [usize] = if self.dims.is_none() {
            &REFINED_DIMS
        } else {
            &[]
        };
        AutoChoice::new(candidates, self.validate_by)
            .with_preferred_on_tie(preferred_on_tie(candidates))
            .with_budget(if self.full_search { None } else { self.budget })
            .with_refined_dims(refine)
            .with_rule(self.choose.rule_for(candidates))
    }

    fn config(
        &self,
        grid: Grid,
        features: FeatureConfig,
        classifier: presrs_core::classifier::ClassifierConfig,
    ) -> Result<CheckedTrainConfig> {
        let config = TrainConfig {
            crop: self.crop.resolve(grid),
            features,
            dims: self.dims(),
            classifier,
            preprocess: self.preprocess,
        };
        Ok(config.check()?)
    }

    /// Refuses a draw that leaves no validation images when the classifier needs them: the Parzen
    /// window (pwe) chooses its sigma on them, and no option fixes sigma; an automatic choice of the
    /// classifier tries pwe among the others (and would fail only after scoring every candidate).
    pub fn check_validation_set(
        &self,
        validation: ValidationSize,
        validation_images: usize,
    ) -> Result<()> {
        if validation_images > 0 {
            return Ok(());
        }
        let given = match validation {
            ValidationSize::Count(count) => count.to_string(),
            ValidationSize::Fraction(fraction) => fraction.to_string(),
        };
        let remedy = Message::from("give ").opt(Opt::Validation).text(
            " a count of at least 1 (e.g. 7) or a fraction (e.g. 0.35) with at least 3 images \
                 per class",
        );
        let leaves_none = Message::new()
            .opt_is(Opt::Validation, given)
            .text(" leaves no validation images, and ");
        match self.classifier {
            ClassifierChoice::Kind(kind) if kind == ClassifierKind::PWE => Err(Error::invalid(
                leaves_none
                    .text("the Parzen window (pwe) chooses its sigma on them: ")
                    .then(remedy)
                    .text(", or another ")
                    .opt(Opt::Classifier),
            )),
            ClassifierChoice::Auto => Err(Error::invalid(
                leaves_none
                    .text(
                        "the automatic choice tries the Parzen window (pwe), which chooses its \
                         sigma on them: ",
                    )
                    .then(remedy)
                    .text(", or a ")
                    .opt(Opt::Classifier)
                    .text(" other than pwe or auto"),
            )),
            ClassifierChoice::Kind(_) => Ok(()),
        }
    }
}

/// A time budget from seconds: 0 means no limit; negative, non-finite or absurd values are refused
/// with the reason (the one check the command line and the Python package share).
pub fn budget_from_seconds(seconds: f64) -> std::result::Result<Option<Duration>, String> {
    // (a finite limit: `Duration` holds at most about 1.8e19 s)
    if !seconds.is_finite() || !(0.0..=1e12).contains(&seconds) {
        return Err(format!(
            "the budget must be a number of seconds, 0 or more (0: no limit); got {seconds}"
        ));
    }
    Ok((seconds > 0.0).then(|| Duration::from_secs_f64(seconds)))
}

/// The paper's method (1-D |FFT| + Parzen window, no intensity transform, the candidates' own number
/// of components) among a selection's scores, with its index.
pub fn paper_score(selection: &Selection) -> Option<(usize, &CandidateScore)> {
    let dims = selection.scores.first()?.config.dims;
    selection.scores.iter().enumerate().find(|(_, score)| {
        score.features == FeatureKind::FFT1D.as_str()
            && score.config.classifier.kind() == ClassifierKind::PWE
            && score.config.preprocess.intensity.is_none()
            && score.config.dims == dims
    })
}

/// Feature families joined with `+` or `,` (`fft1d`, `fft2d_polar+glcm`); the error lists the names.
pub fn parse_feature_kinds(text: &str) -> std::result::Result<Vec<FeatureKind>, String> {
    text.split(['+', ','])
        .map(|part| {
            FeatureKind::parse(part).map_err(|_| {
                format!(
                    "unknown feature family {:?} in {text:?}; known: {}, or several joined with + \
                     (fft1d+glcm)",
                    part.trim(),
                    FeatureKind::names().join(", ")
                )
            })
        })
        .collect()
}

impl FromStr for FeatureChoice {
    type Err = String;

    /// `auto`, or families joined with `+`.
    fn from_str(text: &str) -> std::result::Result<Self, String> {
        if text.trim().eq_ignore_ascii_case("auto") {
            return Ok(Self::Auto);
        }
        parse_feature_kinds(text)
            .map(Self::Kinds)
            .map_err(|err| err.replacen("; known: ", "; known: auto, ", 1))
    }
}

impl FromStr for ClassifierChoice {
    type Err = String;

    /// `auto`, or a classifier name.
    fn from_str(text: &str) -> std::result::Result<Self, String> {
        if text.trim().eq_ignore_ascii_case("auto") {
            return Ok(Self::Auto);
        }
        ClassifierKind::parse(text).map(Self::Kind).map_err(|_| {
            format!(
                "unknown classifier {text:?}; known: auto, {}",
                ClassifierKind::names().join(", ")
            )
        })
    }
}

impl FromStr for CropChoice {
    type Err = String;

    /// `auto`, or what [`Crop::parse`] reads; an empty value is refused (it is not `none`).
    fn from_str(text: &str) -> std::result::Result<Self, String> {
        const FORMS: &str =
            "auto, none, paper, margins top,bottom,left,right or a window row0:col0:rows:cols";
        if text.trim().is_empty() {
            return Err(format!("the crop is empty; expected {FORMS}"));
        }
        if text.trim().eq_ignore_ascii_case("auto") {
            return Ok(Self::Auto);
        }
        Crop::parse(text).map(Self::Fixed).map_err(|err| match err {
            CoreError::Param { reason, .. } => match reason.split_once("; expected") {
                Some((why, _)) => format!("{why}; expected {FORMS}"),
                None => reason,
            },
            other => other.to_string(),
        })
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    /// Whole stances of the default summary and length.
    fn whole_stance() -> SampleKind {
        SampleKind::Stance {
            summary: Default::default(),
            length: None,
        }
    }

    /// On whole samples the default race is MiniRocket's two presets with every classifier, ridge
    /// first; the full search adds MultiRocket (with the ridges) and the frame families after them.
    #[test]
    fn whole_stances_and_series_add_rocket_with_ridge_to_the_search() {
        let grid = Grid::new(12, 54);
        let stance = whole_stance();
        let default = Method::default();
        let frame = default.candidates(grid, false).unwrap();
        let learned = |c: &&CheckedTrainConfig| c.config().features.learns();
        assert!(frame.iter().filter(learned).count() == 0);
        let race = default.candidates_for(grid, false, &stance, 1).unwrap();
        let mut every_classifier = vec![ClassifierKind::RIDGE_RAW, ClassifierKind::RIDGE];
        every_classifier.extend(ClassifierKind::auto_candidates());
        let pairs =
            |c: &CheckedTrainConfig| (c.config().features.kind(), c.config().classifier.kind());
        let expected: Vec<_> = DEFAULT_WHOLE_SAMPLE_FEATURES
            .iter()
            .flat_map(|&kind| every_classifier.iter().map(move |&c| (Some(kind), c)))
            .collect();
        assert_eq!(race.iter().map(pairs).collect::<Vec<_>>(), expected);
        assert_eq!(
            expected[0],
            (
                Some(FeatureKind::ROCKET_UNSCALED),
                ClassifierKind::RIDGE_RAW
            )
        );
        let auto = Method {
            full_search: true,
            ..Method::default()
        };
        let whole = auto.candidates_for(grid, false, &stance, 1).unwrap();
        let paired = |kind: FeatureKind| -> Vec<ClassifierKind> {
            whole
                .iter()
                .filter(|c| c.config().features.kind() == Some(kind))
                .map(|c| c.config().classifier.kind())
                .collect()
        };
        let ridges = vec![ClassifierKind::RIDGE_RAW, ClassifierKind::RIDGE];
        let mut every = ridges.clone();
        every.extend(ClassifierKind::auto_candidates());
        // MiniRocket (scaled or not) with the ridges first, then every classifier; MultiRocket with
        // the ridges only.
        for kind in [FeatureKind::ROCKET, FeatureKind::ROCKET_UNSCALED] {
            assert_eq!(paired(kind), every, "{}", kind.as_str());
        }
        for kind in [FeatureKind::MULTIROCKET, FeatureKind::MULTIROCKET_UNSCALED] {
            assert_eq!(paired(kind), ridges, "{}", kind.as_str());
        }
        let added = 2 * every.len() + 2 * ridges.len();
        assert_eq!(whole.len(), frame.len() + added);
        // First, in the order of preference: MiniRocket on the channels as they are, with ridge on
        // the features as they are (aeon's peer).
        let first = whole[0].config();
        assert_eq!(first.features.kind(), Some(FeatureKind::ROCKET_UNSCALED));
        assert_eq!(first.classifier.kind(), ClassifierKind::RIDGE_RAW);
        // Both MiniRockets before either MultiRocket (a budget cuts the costlier family first).
        let family_of = |c: &CheckedTrainConfig| c.config().features.kind();
        let last_minirocket = whole[..added]
            .iter()
            .rposition(|c| family_of(c) == Some(FeatureKind::ROCKET))
            .unwrap();
        assert!(whole[..=last_minirocket].iter().all(|c| {
            [FeatureKind::ROCKET, FeatureKind::ROCKET_UNSCALED].contains(&family_of(c).unwrap())
        }));
        assert_eq!(last_minirocket + 1, 2 * every.len());
        assert!(whole[..added].iter().all(|c| c.config().features.learns()));
        assert!(whole[added..].iter().filter(learned).count() == 0);
        // A fixed classifier pairs with every family of the race (MiniRocket's two by default, all four
        // in a full search, then the frame families); `all` pairs every classifier with every family.
        let svm = Method {
            classifier: ClassifierChoice::Kind(ClassifierKind::SVM),
            ..Method::default()
        };
        let with_svm = svm.candidates_for(grid, false, &stance, 1).unwrap();
        assert_eq!(with_svm.len(), 2);
        assert!(
            with_svm
                .iter()
                .all(|c| c.config().classifier.kind() == ClassifierKind::SVM)
        );
        let full_svm = Method {
            full_search: true,
            ..svm
        };
        let with_svm = full_svm.candidates_for(grid, false, &stance, 1).unwrap();
        assert_eq!(with_svm.iter().filter(learned).count(), 4);
        assert!(with_svm.len() > 4);
        let compare = auto.candidates_for(grid, true, &stance, 1).unwrap();
        assert_eq!(compare.iter().filter(learned).count(), 4 * every.len());
        // A fixed method stays fixed; a series adds rocket too.
        let fixed = Method {
            features: FeatureChoice::Kinds(vec![FeatureKind::FFT1D]),
            ..Method::default()
        };
        assert!(
            fixed
                .candidates_for(grid, false, &stance, 1)
                .unwrap()
                .iter()
                .all(|c| c.config().features.is_fft1d())
        );
        let series = SampleKind::Series {
            time_in_rows: false,
        };
        assert_eq!(
            auto.candidates_for(grid, false, &series, 1).unwrap().len(),
            whole.len()
        );
        assert_eq!(
            default
                .candidates_for(grid, false, &series, 1)
                .unwrap()
                .len(),
            race.len()
        );
    }

    /// The race's ridges read four MiniRocket draws while the features of every draw stay under the
    /// budget (a few thousand samples), fewer above it, one on a robot's logs; the classifiers on
    /// principal components read one draw.
    #[test]
    fn the_race_s_ridges_read_several_draws_on_small_sets_only() {
        let per_draw = RocketParams::default().config().output_len();
        assert_eq!(per_draw, 9996);
        assert_eq!(race_draws(120, per_draw), MAX_RACE_DRAWS);
        assert_eq!(race_draws(1000, per_draw), 4);
        assert_eq!(race_draws(1601, per_draw), 3);
        assert_eq!(race_draws(2500, per_draw), 2);
        assert_eq!(race_draws(11_256, per_draw), 1);
        assert_eq!(race_draws(100_000, per_draw), 1);
        assert_eq!(
            race_draws(0, 0),
            MAX_RACE_DRAWS,
            "no samples: nothing to cost"
        );
        let grid = Grid::new(60, 75);
        let series = SampleKind::Series {
            time_in_rows: false,
        };
        let draws_of = |samples: usize| -> Vec<(String, usize)> {
            Method::default()
                .candidates_for(grid, false, &series, race_draws_for(samples))
                .unwrap()
                .iter()
                .map(|c| {
                    let config = c.config();
                    let draws = config
                        .features
                        .params::<RocketFamily>()
                        .map_or(0, |params| params.draws);
                    (config.classifier.kind().as_str().to_owned(), draws)
                })
                .collect()
        };
        for (classifier, draws) in draws_of(1000) {
            let ridge = classifier.starts_with("ridge");
            assert_eq!(draws, if ridge { 4 } else { 1 }, "{classifier}");
        }
        assert!(draws_of(50_000).iter().all(|(_, draws)| *draws == 1));
        // Frames have no MiniRocket candidate.
        assert!(
            Method::default()
                .candidates(Grid::new(44, 44), false)
                .unwrap()
                .iter()
                .all(|c| c.config().features.params::<RocketFamily>().is_none())
        );
    }

    #[test]
    fn auto_tries_every_family_with_every_classifier_cheap_first_and_paper_is_fft1d_pwe() {
        let grid = Grid::new(44, 44);
        let auto = Method::default();
        assert!(auto.is_auto());
        let candidates = auto.candidates(grid, false).unwrap();
        let n_classifiers = ClassifierKind::auto_candidates().len();
        // every family with the two intensity transforms too
        assert_eq!(
            candidates.len(),
            3 * CANDIDATE_FEATURES.len() * n_classifiers
        );
        // the paper's method first; the texture families last, where a budget cuts
        assert_eq!(candidates[0], auto.paper_config(grid).unwrap());
        let texture = |c: &CheckedTrainConfig| c.config().features.is_costly();
        let first_texture = candidates.iter().position(texture).unwrap();
        assert_eq!(first_texture, candidates.len() - 3 * 2 * n_classifiers);
        assert!(candidates[first_texture..].iter().all(texture));
        let intensities = |method: &Method| -> Vec<Intensity> {
            let mut seen: Vec<Intensity> = method
                .candidates(grid, false)
                .unwrap()
                .iter()
                .map(|c| c.config().preprocess.intensity)
                .collect();
            seen.dedup();
            seen
        };
        // the cheap families under each transform, then the texture ones
        assert_eq!(
            intensities(&auto),
            [Intensity::ALL, Intensity::ALL].concat()
        );
        // a full search tries the same candidates, every one of them: no budget
        let full = Method {
            full_search: true,
            ..Method::default()
        };
        assert_eq!(full.candidates(grid, false).unwrap(), candidates);
        let full_candidates = full.candidates(grid, false).unwrap();
        assert_eq!(full.auto_choice(&full_candidates).budget(), None);
        assert_eq!(auto.auto_choice(&candidates).budget(), Some(DEFAULT_BUDGET));
        // a transform given is kept, not searched; a comparison does not multiply its rows
        let given = Method {
            preprocess: Preprocess {
                intensity: Intensity::Sqrt,
                ..Preprocess::NONE
            },
            ..Method::default()
        };
        assert_eq!(intensities(&given), [Intensity::Sqrt]);
        assert_eq!(
            Method::default().candidates(grid, true).unwrap().len(),
            CANDIDATE_FEATURES.len() * ClassifierKind::auto_candidates().len()
        );
        let paper = Method::paper();
        assert!(!paper.is_auto());
        assert_eq!(paper.candidates(grid, false).unwrap().len(), 1);
        let config = paper.train_config(grid).unwrap();
        assert_eq!(config, paper.paper_config(grid).unwrap());
        assert_eq!(config.config().crop, Crop::PAPER);
        assert_eq!(
            paper.train_config(Grid::new(20, 30)).unwrap().config().crop,
            Crop::NONE
        );
    }

    #[test]
    fn choices_parse_and_bad_names_list_the_known_ones() {
        assert_eq!("AUTO".parse::<FeatureChoice>(), Ok(FeatureChoice::Auto));
        assert_eq!(
            "fft1d+glcm".parse::<FeatureChoice>(),
            Ok(FeatureChoice::Kinds(vec![
                FeatureKind::FFT1D,
                FeatureKind::GLCM
            ]))
        );
        let err = "fft3d".parse::<FeatureChoice>().unwrap_err();
        assert!(err.contains("known: auto, fft1d"), "{err}");
        let err = "tree".parse::<ClassifierChoice>().unwrap_err();
        assert!(err.contains("known: auto, pwe"), "{err}");
        assert!("".parse::<CropChoice>().unwrap_err().contains("empty"));
        assert_eq!(
            "paper".parse::<CropChoice>(),
            Ok(CropChoice::Fixed(Crop::PAPER))
        );
    }

    #[test]
    fn budgets_are_seconds_and_zero_is_no_limit() {
        assert_eq!(budget_from_seconds(0.0), Ok(None));
        assert_eq!(
            budget_from_seconds(1.5),
            Ok(Some(Duration::from_millis(1500)))
        );
        for bad in [-1.0, f64::NAN, f64::INFINITY, 1e13] {
            assert!(
                budget_from_seconds(bad).unwrap_err().contains("0 or more"),
                "{bad}"
            );
        }
    }

    #[test]
    fn no_validation_images_is_refused_only_where_sigma_needs_them() {
        let none = ValidationSize::Count(0);
        assert!(Method::paper().check_validation_set(none, 0).is_err());
        assert!(Method::default().check_validation_set(none, 0).is_err());
        let lda = Method {
            classifier: ClassifierChoice::Kind(ClassifierKind::LDA),
            ..Method::paper()
        };
        assert!(lda.check_validation_set(none, 0).is_ok());
        assert!(Method::paper().check_validation_set(none, 3).is_ok());
    }

    /// A tie for the best goes to MiniRocket on scaled channels with the SVM when it is a candidate
    /// (whole samples, or `--classifier svm`), and to the earlier candidate otherwise (frames).
    #[test]
    fn a_tie_goes_to_the_preferred_method_only_when_it_is_a_candidate() {
        let grid = Grid::new(12, 54);
        let stance = whole_stance();
        let auto = Method::default();
        let whole = auto.candidates_for(grid, false, &stance, 1).unwrap();
        let preferred = auto.auto_choice(&whole).preferred_on_tie.unwrap();
        let config = whole[preferred].config();
        assert_eq!(config.features.kind(), Some(FeatureKind::ROCKET));
        assert_eq!(config.classifier.kind(), ClassifierKind::SVM);
        // scored where the order puts it: the cheap first candidates stay first
        assert!(preferred > 0);
        let frame = auto.candidates(grid, false).unwrap();
        assert_eq!(auto.auto_choice(&frame).preferred_on_tie, None);
        let ridge = Method {
            classifier: ClassifierChoice::Kind(ClassifierKind::RIDGE),
            ..Method::default()
        };
        let with_ridge = ridge.candidates_for(grid, false, &stance, 1).unwrap();
        assert_eq!(ridge.auto_choice(&with_ridge).preferred_on_tie, None);
    }

    /// `auto` picks by one standard error among whole samples' random convolutions (a full search's
    /// too) and by the best among frame families; a rule named is that rule everywhere; the names
    /// parse, and an unknown one lists them.
    #[test]
    fn the_rule_follows_the_race_unless_named() {
        let grid = Grid::new(12, 54);
        let stance = whole_stance();
        let auto = Method::default();
        assert_eq!(auto.choose, Choose::Auto);
        let whole = auto.candidates_for(grid, false, &stance, 1).unwrap();
        let frame = auto.candidates(grid, false).unwrap();
        let full = Method {
            full_search: true,
            ..Method::default()
        };
        let full_whole = full.candidates_for(grid, false, &stance, 1).unwrap();
        assert_eq!(auto.auto_choice(&whole).rule, ChoiceRule::OneStandardError);
        assert_eq!(
            full.auto_choice(&full_whole).rule,
            ChoiceRule::OneStandardError
        );
        assert_eq!(auto.auto_choice(&frame).rule, ChoiceRule::Best);
        // a preset named, the classifier chosen: still MiniRocket's race
        let log = Method {
            features: FeatureChoice::Kinds(vec![FeatureKind::ROCKET_LOG]),
            ..Method::default()
        };
        let log_candidates = log.candidates_for(grid, false, &stance, 1).unwrap();
        assert_eq!(
            log.auto_choice(&log_candidates).rule,
            ChoiceRule::OneStandardError
        );
        for rule in [ChoiceRule::Best, ChoiceRule::OneStandardError] {
            let named = Method {
                choose: Choose::Rule(rule),
                ..Method::default()
            };
            assert_eq!(named.auto_choice(&whole).rule, rule);
            assert_eq!(named.auto_choice(&frame).rule, rule);
        }
        assert_eq!("AUTO".parse::<Choose>(), Ok(Choose::Auto));
        assert_eq!(
            "one-se".parse::<Choose>(),
            Ok(Choose::Rule(ChoiceRule::OneStandardError))
        );
        let err = "median".parse::<Choose>().unwrap_err();
        assert!(err.contains("known: auto, best, one-se"), "{err}");
    }
}
