//! Options and helpers shared by several subcommands.

use std::io::IsTerminal;
use std::path::Path;

use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use presrs_core::Crop;
use presrs_core::Recording;
use presrs_core::classifier::ClassifierKind;
use presrs_core::dead_sensels::DeadSenselConfig;
use presrs_core::features::{FeatureConfig, FeatureKind};
use presrs_core::pipeline::{CheckedTrainConfig, TrainConfig};
use presrs_core::preprocess::Preprocess;
use presrs_core::split::ValidationSize;
use presrs_core::stance::SampleFrame;
use presrs_io::ReadOptions;
use presrs_io::dataset::{
    DeadSenselFills, LoadedSamples, SampleOptions, load_samples, read_corrected,
};
use presrs_io::manifest::{Manifest, read_manifest};

/// How the pipeline is built: crop, features, reduction, classifier.
#[derive(Debug, Clone, clap::Args)]
pub struct PipelineArgs {
    /// Feature family: fft1d (the paper's 1-D |FFT| of the row-major image), fft2d (half 2-D |FFT|),
    /// fft2d_polar (ring and wedge sums of the 2-D |FFT|), glcm (co-occurrence texture attributes); join
    /// several with + (fft1d+glcm); or auto (the default: chosen by validation inside the training data,
    /// leave one condition out when it spans several, among fft1d, fft2d and fft2d_polar; --full-search
    /// adds glcm and fft2d_polar+glcm). `--features fft1d --classifier pwe` is the paper's method.
    #[arg(long, default_value = "auto", value_parser = parse_features)]
    pub features: FeatureChoice,
    /// Classifier: pwe (Parzen window, the paper's), mle (Gaussian, shrunk full covariance per class),
    /// lda (shared covariance), svm (one-vs-one, linear or RBF, C and gamma chosen on validation), knn;
    /// or auto (the default: chosen by validation inside the training data among all five).
    #[arg(long, default_value = "auto", value_parser = parse_classifier)]
    pub classifier: ClassifierChoice,
    /// With auto: try every feature family, the slow texture ones (glcm, fft2d_polar+glcm) too (about
    /// twice the time of the default search; they did not win on the simulated data).
    #[arg(long)]
    pub full_search: bool,
    /// Principal components kept, at least 1 (at most the number of training images minus one, and the
    /// number of features: a larger value is lowered to that, with a warning when given) [default: 51].
    #[arg(long, value_name = "DIMS", value_parser = parse_positive)]
    pub dims: Option<usize>,
    /// Divide each cropped image by its total load (sum of its values): features that do not depend on
    /// the robot's load, without knowing it. Stored in the model; off in the paper's method.
    #[arg(long)]
    pub normalise_load: bool,
    /// Fill absent (masked) sensels from their neighbours (mean of the 4-neighbours, relaxed across
    /// clusters) instead of reading them as 0. Stored in the model.
    #[arg(long)]
    pub fill_absent: bool,
    #[command(flatten)]
    pub crop: CropArg,
}

/// The `--crop` option.
#[derive(Debug, Clone, clap::Args)]
pub struct CropArg {
    /// Region of each image used: auto (the paper's crop on a 44x44 array, the whole image otherwise),
    /// paper (drop the bottom 6 rows and first 3 columns: 44x44 -> 38x41), none, margins
    /// top,bottom,left,right, or a window row0:col0:rows:cols.
    #[arg(long = "crop", default_value = "auto", value_parser = parse_crop_arg)]
    pub crop: CropChoice,
}

/// Principal components kept without `--dims` (the paper's 51).
pub const DEFAULT_DIMS: usize = 51;

/// A crop, or `auto`: decided from the image size.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CropChoice {
    Auto,
    Fixed(Crop),
}

impl CropArg {
    /// The crop for images of `grid`: as given, or resolved from `auto`.
    pub fn resolve(&self, grid: presrs_core::Grid) -> Crop {
        match self.crop {
            CropChoice::Fixed(crop) => crop,
            CropChoice::Auto if grid == presrs_core::Grid::new(44, 44) => Crop::PAPER,
            CropChoice::Auto => Crop::NONE,
        }
    }
}

/// `--features`: families, or auto.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum FeatureChoice {
    Auto,
    Kinds(Vec<FeatureKind>),
}

/// `--classifier`: a family, or auto.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ClassifierChoice {
    Auto,
    Kind(ClassifierKind),
}

/// The feature families an automatic choice tries by default: the cheap ones (a GLCM image costs 2-3x
/// an FFT one, and glcm never won on the simulated data).
pub const FAST_CANDIDATE_FEATURES: [&[FeatureKind]; 3] = [
    &[FeatureKind::Fft1d],
    &[FeatureKind::Fft2d],
    &[FeatureKind::Fft2dPolar],
];

/// The feature families a full automatic choice (`--full-search`) or a comparison tries.
pub const CANDIDATE_FEATURES: [&[FeatureKind]; 5] = [
    &[FeatureKind::Fft1d],
    &[FeatureKind::Fft2d],
    &[FeatureKind::Fft2dPolar],
    &[FeatureKind::Glcm],
    &[FeatureKind::Fft2dPolar, FeatureKind::Glcm],
];

impl PipelineArgs {
    /// The preprocessing steps these options ask for.
    pub fn preprocess(&self) -> Preprocess {
        Preprocess {
            normalise_load: self.normalise_load,
            fill_absent: self.fill_absent,
        }
    }

    /// Principal components to keep: `--dims`, or the paper's 51.
    pub fn dims(&self) -> usize {
        self.dims.unwrap_or(DEFAULT_DIMS)
    }

    /// Whether features or classifier are to be chosen automatically.
    pub fn is_auto(&self) -> bool {
        self.features == FeatureChoice::Auto || self.classifier == ClassifierChoice::Auto
    }

    /// The checked training configuration these options describe, for images of `grid`. An `auto`
    /// part is the paper's choice here (fft1d, pwe); [`candidates`](Self::candidates) lists what auto tries.
    pub fn train_config(&self, grid: presrs_core::Grid) -> anyhow::Result<CheckedTrainConfig> {
        let features = match &self.features {
            FeatureChoice::Kinds(kinds) => FeatureConfig::combined(kinds),
            FeatureChoice::Auto => FeatureKind::Fft1d.default_config(),
        };
        let classifier = match self.classifier {
            ClassifierChoice::Kind(kind) => kind.default_config(),
            ClassifierChoice::Auto => ClassifierKind::Pwe.default_config(),
        };
        let config = TrainConfig {
            crop: self.crop.resolve(grid),
            features,
            dims: self.dims(),
            classifier,
            preprocess: self.preprocess(),
        };
        Ok(config.check()?)
    }

    /// The paper's method (1-D |FFT| features, Parzen window) with these options' crop, dims and
    /// preprocessing: what an automatic choice is shown next to. [`train_config`](Self::train_config) is
    /// the same only when both parts are `auto`.
    pub fn paper_config(&self, grid: presrs_core::Grid) -> anyhow::Result<CheckedTrainConfig> {
        let config = TrainConfig {
            crop: self.crop.resolve(grid),
            features: FeatureKind::Fft1d.default_config(),
            dims: self.dims(),
            classifier: ClassifierKind::Pwe.default_config(),
            preprocess: self.preprocess(),
        };
        Ok(config.check()?)
    }

    /// Every configuration an automatic choice tries (auto parts run over the candidates — the cheap
    /// feature families unless `--full-search` — fixed parts stay), or, with `all`, every feature x
    /// classifier combination (for `--compare`).
    pub fn candidates(
        &self,
        grid: presrs_core::Grid,
        all: bool,
    ) -> anyhow::Result<Vec<CheckedTrainConfig>> {
        let features: Vec<FeatureConfig> = match &self.features {
            FeatureChoice::Kinds(kinds) if !all => vec![FeatureConfig::combined(kinds)],
            _ if all || self.full_search => CANDIDATE_FEATURES
                .iter()
                .map(|kinds| FeatureConfig::combined(kinds))
                .collect(),
            _ => FAST_CANDIDATE_FEATURES
                .iter()
                .map(|kinds| FeatureConfig::combined(kinds))
                .collect(),
        };
        let classifiers: Vec<ClassifierKind> = match self.classifier {
            ClassifierChoice::Kind(kind) if !all => vec![kind],
            _ => ClassifierKind::ALL.to_vec(),
        };
        let mut out = Vec::new();
        for feature in &features {
            for &classifier in &classifiers {
                out.push(
                    TrainConfig {
                        crop: self.crop.resolve(grid),
                        features: feature.clone(),
                        dims: self.dims(),
                        classifier: classifier.default_config(),
                        preprocess: self.preprocess(),
                    }
                    .check()?,
                );
            }
        }
        Ok(out)
    }
}

/// Refuses a draw that leaves no validation images when the classifier needs them: the Parzen window
/// (pwe) chooses its sigma on them, and no option fixes sigma; an automatic choice of the classifier
/// tries pwe among the others (and would fail only after scoring every candidate, if pwe won).
pub fn check_validation_set(
    pipeline: &PipelineArgs,
    validation: ValidationSize,
    validation_images: usize,
) -> anyhow::Result<()> {
    if validation_images > 0 {
        return Ok(());
    }
    let given = match validation {
        ValidationSize::Count(count) => count.to_string(),
        ValidationSize::Fraction(fraction) => fraction.to_string(),
    };
    let remedy = "give --validation a count of at least 1 (e.g. 7) or a fraction (e.g. 0.35) with at \
                  least 3 images per class";
    match pipeline.classifier {
        ClassifierChoice::Kind(ClassifierKind::Pwe) => anyhow::bail!(
            "--validation {given} leaves no validation images, and the Parzen window (pwe) chooses its \
             sigma on them: {remedy}, or another --classifier"
        ),
        ClassifierChoice::Auto => anyhow::bail!(
            "--validation {given} leaves no validation images, and the automatic choice tries the \
             Parzen window (pwe), which chooses its sigma on them: {remedy}, or a --classifier other \
             than pwe or auto"
        ),
        ClassifierChoice::Kind(_) => Ok(()),
    }
}

/// How samples are taken from movies.
#[derive(Debug, Clone, clap::Args)]
pub struct SampleArgs {
    /// Which frame of each stance phase is a sample: mid (the paper's mid-stance frame), peak, a frame
    /// offset K after touchdown (0-based), or all.
    #[arg(long, default_value = "mid", value_parser = parse_sample_frame)]
    pub stance_frame: SampleFrame,
    /// Also use stances cut by the start or end of a recording.
    #[arg(long)]
    pub include_partial: bool,
    /// Accept a TekScan file whose last frame is truncated (the frame is dropped with a warning) or whose
    /// frame numbers repeat or go back (the frames are kept, with a warning).
    #[arg(long)]
    pub lenient: bool,
    /// Use recordings as read. By default a sensel that reads 0 in every frame of a movie while its
    /// neighbours carry load around it (in 3 frames or more) is taken for dead and filled, in every
    /// frame, from its live neighbours; single images (PNG, 2-D NPY, text, one-frame files) are never
    /// corrected, as one image cannot tell a dead sensel from a gap in the terrain.
    #[arg(long)]
    pub keep_dead_sensels: bool,
}

impl SampleArgs {
    pub fn options(&self) -> SampleOptions {
        SampleOptions {
            sample: self.stance_frame,
            include_partial: self.include_partial,
            read: ReadOptions {
                lenient: self.lenient,
            },
            dead_sensels: self.dead_sensels(),
            ..SampleOptions::default()
        }
    }

    /// The dead-sensel correction to apply (`None` with `--keep-dead-sensels`).
    pub fn dead_sensels(&self) -> Option<DeadSenselConfig> {
        (!self.keep_dead_sensels).then(DeadSenselConfig::default)
    }

    /// Reads one recording file, its dead sensels filled unless `--keep-dead-sensels` (noted in
    /// `fills`); its warnings go to stderr.
    pub fn read(&self, path: &Path, fills: &mut DeadSenselFills) -> anyhow::Result<Recording> {
        let (parsed, filled) =
            read_corrected(path, &self.read_options(), self.dead_sensels().as_ref())?;
        for warning in &parsed.warnings {
            stderr_line!("warning: {warning}");
        }
        fills.add(path.to_path_buf(), filled);
        Ok(parsed.recording)
    }

    pub fn read_options(&self) -> ReadOptions {
        ReadOptions {
            lenient: self.lenient,
        }
    }
}

/// Reads a manifest and all its samples; warnings go to stderr.
pub fn load_manifest(
    path: &Path,
    samples: &SampleArgs,
) -> anyhow::Result<(Manifest, LoadedSamples)> {
    let manifest = read_manifest(path)?;
    let spinner = spinner(&format!("reading {} files", manifest.rows.len()));
    let loaded = load_samples(&manifest, &samples.options())?;
    spinner.finish_and_clear();
    for warning in &loaded.warnings {
        stderr_line!("warning: {warning}");
    }
    note_dead_sensels(&loaded.dead_sensels);
    if loaded.samples.is_empty() {
        anyhow::bail!("{}: the manifest gives no samples", path.display());
    }
    Ok((manifest, loaded))
}

/// The one-line note on stderr of the dead sensels filled, if any.
pub fn note_dead_sensels(fills: &DeadSenselFills) {
    if let Some(summary) = fills.summary() {
        stderr_line!(
            "note: {summary} (from their neighbours; --keep-dead-sensels to use them as read)"
        );
    }
}

/// A progress bar on stderr when it is a terminal; hidden otherwise (pipes, CI, logs).
pub fn progress_bar(len: u64, message: &str) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(len).with_message(message.to_owned());
    if let Ok(style) =
        ProgressStyle::with_template("{msg:>20} [{bar:40}] {pos}/{len} ({elapsed}, eta {eta})")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}

/// A spinner on stderr when it is a terminal; hidden otherwise.
pub fn spinner(message: &str) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let spinner = ProgressBar::new_spinner().with_message(message.to_owned());
    spinner.enable_steady_tick(std::time::Duration::from_millis(120));
    spinner
}

/// Writes a JSON document followed by a newline.
pub fn write_json(
    out: &mut dyn std::io::Write,
    value: &impl serde::Serialize,
) -> anyhow::Result<()> {
    serde_json::to_writer_pretty(&mut *out, value).context("cannot write JSON")?;
    writeln!(out)?;
    Ok(())
}

/// A whole number of at least 1 (`--dims`, `--per-class`, `--repeats`).
pub fn parse_positive(text: &str) -> Result<usize, String> {
    match text.trim().parse::<usize>() {
        Ok(0) => Err("must be at least 1".to_owned()),
        Ok(n) => Ok(n),
        Err(_) => Err(format!(
            "expected a whole number of at least 1, got {text:?}"
        )),
    }
}

/// Feature families joined with `+` or `,` (`fft1d`, `fft2d_polar+glcm`); the error lists the names.
pub fn parse_feature_kinds(text: &str) -> Result<Vec<FeatureKind>, String> {
    text.split(['+', ','])
        .map(|part| {
            FeatureKind::parse(part).map_err(|_| {
                format!(
                    "unknown feature family {:?} in {text:?}; known: {}, or several joined with + \
                     (fft1d+glcm)",
                    part.trim(),
                    FeatureKind::ALL.map(FeatureKind::as_str).join(", ")
                )
            })
        })
        .collect()
}

fn parse_features(text: &str) -> Result<FeatureChoice, String> {
    if text.trim().eq_ignore_ascii_case("auto") {
        return Ok(FeatureChoice::Auto);
    }
    parse_feature_kinds(text)
        .map(FeatureChoice::Kinds)
        .map_err(|err| err.replacen("; known: ", "; known: auto, ", 1))
}

fn parse_classifier(text: &str) -> Result<ClassifierChoice, String> {
    if text.trim().eq_ignore_ascii_case("auto") {
        return Ok(ClassifierChoice::Auto);
    }
    ClassifierKind::parse(text)
        .map(ClassifierChoice::Kind)
        .map_err(|_| {
            format!(
                "unknown classifier {text:?}; known: auto, {}",
                ClassifierKind::ALL.map(ClassifierKind::as_str).join(", ")
            )
        })
}

/// `--crop`: auto, or what [`Crop::parse`] reads; an empty value is refused (it is not `none`).
pub fn parse_crop_arg(text: &str) -> Result<CropChoice, String> {
    const FORMS: &str =
        "auto, none, paper, margins top,bottom,left,right or a window row0:col0:rows:cols";
    if text.trim().is_empty() {
        return Err(format!("the crop is empty; expected {FORMS}"));
    }
    if text.trim().eq_ignore_ascii_case("auto") {
        return Ok(CropChoice::Auto);
    }
    Crop::parse(text)
        .map(CropChoice::Fixed)
        .map_err(|err| match err {
            presrs_core::CoreError::Param { reason, .. } => match reason.split_once("; expected") {
                Some((why, _)) => format!("{why}; expected {FORMS}"),
                None => reason,
            },
            other => other.to_string(),
        })
}

fn parse_sample_frame(text: &str) -> Result<SampleFrame, String> {
    text.parse::<SampleFrame>().map_err(|err| err.to_string())
}

/// How many frames a recording has and how they are numbered, for errors about `--frame`: "1 frame,
/// frame 0", "205 frames, numbered 0 to 204".
pub fn frames_numbered(count: usize) -> String {
    match count {
        0 => "no frames".to_owned(),
        1 => "1 frame, frame 0".to_owned(),
        n => format!("{n} frames, numbered 0 to {}", n - 1),
    }
}
