//! Options and helpers shared by several subcommands.

use std::io::IsTerminal;
use std::path::Path;

use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use presrs_core::Crop;
use presrs_core::classifier::ClassifierKind;
use presrs_core::features::FeatureKind;
use presrs_core::pipeline::{CheckedTrainConfig, TrainConfig};
use presrs_core::stance::SampleFrame;
use presrs_io::ReadOptions;
use presrs_io::dataset::{LoadedSamples, SampleOptions, load_samples};
use presrs_io::manifest::{Manifest, read_manifest};

/// How the pipeline is built: crop, features, reduction, classifier.
#[derive(Debug, Clone, clap::Args)]
pub struct PipelineArgs {
    /// Feature family: fft1d (the paper's 1-D |FFT| of the row-major image).
    #[arg(long, default_value = "fft1d", value_parser = parse_features)]
    pub features: FeatureKind,
    /// Classifier: pwe (Parzen window, sigma chosen on the validation set).
    #[arg(long, default_value = "pwe", value_parser = parse_classifier)]
    pub classifier: ClassifierKind,
    /// Principal components kept (at most the number of training images minus one).
    #[arg(long, default_value_t = 51)]
    pub dims: usize,
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

impl PipelineArgs {
    /// The checked training configuration these options describe, for images of `grid`.
    pub fn train_config(&self, grid: presrs_core::Grid) -> anyhow::Result<CheckedTrainConfig> {
        let config = TrainConfig {
            crop: self.crop.resolve(grid),
            features: self.features.default_config(),
            dims: self.dims,
            classifier: self.classifier.default_config(),
        };
        Ok(config.check()?)
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
    /// Accept a TekScan file whose last frame is truncated (the frame is dropped with a warning).
    #[arg(long)]
    pub lenient: bool,
}

impl SampleArgs {
    pub fn options(&self) -> SampleOptions {
        SampleOptions {
            sample: self.stance_frame,
            include_partial: self.include_partial,
            read: ReadOptions {
                lenient: self.lenient,
            },
            ..SampleOptions::default()
        }
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
        eprintln!("warning: {warning}");
    }
    if loaded.samples.is_empty() {
        anyhow::bail!("{}: the manifest gives no samples", path.display());
    }
    Ok((manifest, loaded))
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

fn parse_features(text: &str) -> Result<FeatureKind, String> {
    FeatureKind::parse(text).map_err(|err| err.to_string())
}

fn parse_classifier(text: &str) -> Result<ClassifierKind, String> {
    ClassifierKind::parse(text).map_err(|err| err.to_string())
}

fn parse_crop_arg(text: &str) -> Result<CropChoice, String> {
    if text.trim().eq_ignore_ascii_case("auto") {
        return Ok(CropChoice::Auto);
    }
    Crop::parse(text)
        .map(CropChoice::Fixed)
        .map_err(|err| err.to_string())
}

fn parse_sample_frame(text: &str) -> Result<SampleFrame, String> {
    text.parse::<SampleFrame>().map_err(|err| err.to_string())
}
