//! The inputs of `presrs simulate` checked before anything is simulated: the configuration, the output
//! folder, height-map terrains, and the terrains and gaits named.

use std::path::Path;

use presrs_io::message::{Message, Opt};
use presrs_sim::dataset::{BUILTIN_TERRAINS, first_repeated};
use presrs_sim::terrain::HeightMap;
use presrs_sim::{DatasetSpec, SimConfig, Simulator};

use crate::error::{Context, Error, Result};

/// The configuration: defaults, overridden by the JSON file if one is given.
pub fn load_config(path: Option<&Path>) -> Result<SimConfig> {
    match path {
        None => Ok(SimConfig::default()),
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("cannot read the configuration {}", path.display()))?;
            SimConfig::from_json(&text)
                .with_context(|| format!("invalid configuration in {}", path.display()))
        }
    }
}

/// Checks, before anything is simulated, that a data set can be written in `out_dir`: a folder (or
/// none yet) that accepts files, and one that holds no data set already (a `manifest.csv`) unless
/// `replace`: a data set someone trains on is not replaced silently.
pub fn check_dataset_out(out_dir: &Path, replace: bool) -> Result<()> {
    presrs_io::output_path::check_output_dir(out_dir)?;
    let manifest = out_dir.join("manifest.csv");
    if manifest.exists() && !replace {
        return Err(Error::invalid(
            Message::new()
                .text(format!(
                    "{} already holds a data set ({}): give another folder, or ",
                    out_dir.display(),
                    manifest.display()
                ))
                .opt(Opt::Force)
                .text(" to replace it"),
        ));
    }
    Ok(())
}

/// Reads `NAME=PNG` as a height map scaled to `[0, 1]` (darkest pixel 0, brightest 1).
pub fn read_terrain_image(name: &str, path: &Path) -> Result<(String, HeightMap)> {
    let rec = presrs_io::png::read_png(path)
        .with_context(|| format!("cannot read the height map {}", path.display()))?;
    let grid = rec.grid();
    let values = rec.data();
    let (lo, hi) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    let span = if hi > lo { hi - lo } else { 1.0 };
    let scaled = values[..grid.len()]
        .iter()
        .map(|&v| ((v - lo) / span) as f32)
        .collect();
    let map = HeightMap::new(grid.cols, grid.rows, scaled)
        .with_context(|| format!("unusable height map {}", path.display()))?;
    Ok((name.to_owned(), map))
}

/// Checks that every gait of `gaits` is one of `config`'s or a variant `BASE@BETA` of one; the error
/// names `option`.
pub fn check_gaits<'a>(
    option: Opt,
    gaits: impl IntoIterator<Item = &'a String>,
    config: &SimConfig,
) -> Result<(), Message> {
    let sim = Simulator::new(config.clone(), 0, Vec::new()).map_err(|e| e.to_string())?;
    for gait in gaits {
        sim.gait(gait.trim()).map_err(|e| {
            let reason = match e {
                presrs_sim::SimError::Param { reason, .. } => reason,
                other => other.to_string(),
            };
            Message::new()
                .opt_text(option, gait)
                .text(format!(": {reason}"))
        })?;
    }
    Ok(())
}

/// The terrains and gaits a data set would simulate, checked against each other and the configuration:
/// each named once, terrains built-in or given as height-map images (`images`, every one used), gaits
/// known. Empty `terrains` or `gaits` mean the paper's (plus the images). The error says what is wrong
/// with which option.
pub fn dataset_names(
    terrains: &[String],
    images: &[&str],
    gaits: &[String],
    config: &SimConfig,
) -> std::result::Result<(Vec<String>, Vec<String>), Message> {
    if let Some(twice) = first_repeated(images) {
        return Err(Message::new().opt(Opt::TerrainImage).text(format!(
            " gives the name {twice} to two images; give each its own"
        )));
    }
    let terrains: Vec<String> = if terrains.is_empty() {
        let mut terrains = DatasetSpec::paper(0).terrains;
        terrains.extend(images.iter().map(|&n| n.to_owned()));
        terrains
    } else {
        terrains.iter().map(|t| t.trim().to_owned()).collect()
    };
    if let Some(twice) = first_repeated(&terrains) {
        return Err(Message::new().opt(Opt::Terrains).text(format!(
            " lists {twice} twice; list each terrain once (a repeated terrain's images would be in \
             the manifest twice, and could be both trained on and tested)"
        )));
    }
    for terrain in &terrains {
        if !BUILTIN_TERRAINS.contains(&terrain.as_str()) && !images.contains(&terrain.as_str()) {
            return Err(Message::new()
                .opt(Opt::Terrains)
                .text(format!(
                    ": unknown terrain {terrain:?}; the built-in terrains are {}, others must be \
                     given as height maps with ",
                    BUILTIN_TERRAINS.join(", ")
                ))
                .opt_is(Opt::TerrainImage, format!("{terrain}=PNG")));
        }
    }
    if let Some(unused) = images.iter().find(|&&n| !terrains.iter().any(|t| t == n)) {
        return Err(Message::new()
            .opt_is(Opt::TerrainImage, unused)
            .text(" is not among ")
            .opt(Opt::Terrains)
            .text("; add it there or leave the image out"));
    }
    let gaits: Vec<String> = if gaits.is_empty() {
        DatasetSpec::paper(0).gaits
    } else {
        gaits.iter().map(|g| g.trim().to_owned()).collect()
    };
    if let Some(twice) = first_repeated(&gaits) {
        return Err(Message::new()
            .opt(Opt::Gaits)
            .text(format!(" lists {twice} twice; list each gait once")));
    }
    check_gaits(Opt::Gaits, &gaits, config)?;
    Ok((terrains, gaits))
}
