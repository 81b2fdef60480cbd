//! `presrs features`: the feature vector of one frame (or of each stance's sample frame), as CSV.

use std::io::Write;
use std::path::PathBuf;

use presrs::frame_features::{FrameFeatures, feature_frames};
use presrs_core::features::FeatureKind;

use super::common::{CropArg, SampleArgs};
use crate::printer::feature_csv;

/// Print feature vectors as CSV: a header `frame,` and the features' names, then one row per frame.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "The header names each column: fft1d_binK (|FFT| at frequency bin K), fft2d_rK_cL (2-D \
|FFT| at row frequency bin K, column frequency bin L), fft2d_polar_ringI and fft2d_polar_wedgeJ (sums \
over ring I and wedge J of the 2-D |FFT|), glcm_ATTRIBUTE_dD (a co-occurrence attribute at distance D, \
averaged over the angles).

Examples:
  presrs features walk.asf --frame 40 --features fft1d > f.csv
  presrs features walk.asf --features fft2d_polar+glcm > f.csv"
)]
pub struct FeaturesArgs {
    /// A recording file (TekScan ASCII, .npy, greyscale .png, text matrix or MCAP).
    pub file: PathBuf,
    /// The 0-based frame; by default every stance phase's sample frame (`--stance-frame`), or the only
    /// frame of a one-frame file.
    #[arg(long)]
    pub frame: Option<usize>,
    /// Feature family, as train takes it (auto aside: there is nothing to choose from here): fft1d
    /// (the paper's |FFT| of the row-major, zero-padded image: 1025 values for 38x41), fft2d (half 2-D
    /// |FFT|), fft2d_polar (ring and wedge sums of the 2-D |FFT|), glcm (co-occurrence texture
    /// attributes); join several with + (fft1d+glcm): each part scaled to unit norm, as in a model.
    /// (contact and the rocket families are learned from training images: only a model computes them.)
    // `std::vec::Vec`: one value holding several families, not a repeatable option
    #[arg(long, default_value = "fft1d", value_parser = parse_features)]
    pub features: std::vec::Vec<FeatureKind>,
    #[command(flatten)]
    pub crop: CropArg,
    #[command(flatten)]
    pub samples: SampleArgs,
}

pub fn run(args: &FeaturesArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let mut fills = presrs::dataset::DeadSenselFills::default();
    let recording = &args.samples.read(&args.file, &mut fills)?;
    super::common::note_dead_sensels(&fills);
    let name = args.file.display().to_string();
    let samples = &args.samples;
    let frames = feature_frames(
        recording,
        &name,
        args.frame,
        samples.stance_frame(),
        samples.include_partial,
    )?;
    let table = FrameFeatures::new(recording, &name, args.crop.crop, &args.features)?;
    let mut header_written = false;
    for index in frames {
        let Some(features) = table.row(index)? else {
            continue;
        };
        if !header_written {
            writeln!(out, "{}", feature_csv::header(&table.names))?;
            header_written = true;
        }
        writeln!(out, "{}", feature_csv::row(index, &features))?;
    }
    Ok(())
}

/// `--features`: what train takes, but `auto`, which chooses while training.
fn parse_features(text: &str) -> Result<Vec<FeatureKind>, String> {
    if text.trim().eq_ignore_ascii_case("auto") {
        return Err(format!(
            "auto chooses the features while training a model; here name the families to print ({}, \
             or several joined with +)",
            FeatureKind::names().join(", ")
        ));
    }
    presrs::method::parse_feature_kinds(text)
}
