//! The online profile `presrs train` writes into a model file: whether it is learned (by default when
//! the training samples come from movies), and its terrain-to-gait table (measured with the simulator
//! or given).

use std::collections::BTreeMap;
use std::path::Path;

use presrs_core::online::OnlineProfile;
use presrs_core::stance::ValidSegmentParams;

use crate::dataset::Dataset;
use crate::error::{Context, Error, Result};
use crate::gait::{GaitSweep, MeasuredGaitTable, measure_gait_table};
use crate::progress::Progress;
use crate::train::{learn_online_profile, trained_on_movies};

/// Whether a model file gets an online profile.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ProfileChoice {
    /// When the training samples come from movies (it reads them once more); a profile that cannot be
    /// learned is a warning, and the model is written without one.
    #[default]
    WhenMovies,
    /// Always; a profile that cannot be learned is an error.
    Required,
    /// Never.
    Never,
}

/// What a model file's online profile is asked to be.
#[derive(Clone, Copy, Debug)]
pub struct ProfileRequest<'a> {
    pub choice: ProfileChoice,
    /// The terrain-to-gait table's source (`--gait-table`: `sim` or `TERRAIN=GAIT,...`), with a profile.
    pub gait_table: Option<&'a str>,
    /// How a `sim` table is measured.
    pub sim: GaitTableSim<'a>,
}

/// The profile [`model_profile`] learned, or what the user should know when it learned none.
#[derive(Clone, Debug, Default)]
pub struct ModelProfile {
    pub profile: Option<OnlineProfile>,
    /// Why no profile was written although the default asked for one.
    pub warning: Option<String>,
    /// The measurement of a simulated terrain-to-gait table.
    pub measured: Option<MeasuredGaitTable>,
}

/// The online profile of a model of `class_names` trained on `dataset` (read from `manifest`), learned
/// by offline segmentation with `params` (those of training) as `request` says, with its
/// terrain-to-gait table.
pub fn model_profile(
    dataset: &Dataset,
    manifest: &Path,
    params: &ValidSegmentParams,
    class_names: &[String],
    request: &ProfileRequest<'_>,
    progress: &dyn Progress,
) -> Result<ModelProfile> {
    let mut learned = learn_profile(dataset, manifest, params, request.choice)?;
    if let (Some(profile), Some(source)) = (&mut learned.profile, request.gait_table) {
        let (table, measured) = gait_table(
            &source.parse::<GaitTableSource>()?,
            class_names,
            request.sim,
            progress,
        )?;
        profile.gait_table = table;
        learned.measured = measured;
    }
    Ok(learned)
}

/// The profile alone, as `choice` says.
fn learn_profile(
    dataset: &Dataset,
    manifest: &Path,
    params: &ValidSegmentParams,
    choice: ProfileChoice,
) -> Result<ModelProfile> {
    match choice {
        ProfileChoice::Never => Ok(ModelProfile::default()),
        ProfileChoice::WhenMovies if !trained_on_movies(dataset) => Ok(ModelProfile::default()),
        ProfileChoice::WhenMovies => Ok(match learn_online_profile(manifest, params) {
            Ok(profile) => ModelProfile {
                profile: Some(profile),
                ..ModelProfile::default()
            },
            Err(err) => ModelProfile {
                warning: Some(format!(
                    "{}: no online profile written (a stream will warm up first): {err}",
                    manifest.display()
                )),
                ..ModelProfile::default()
            },
        }),
        ProfileChoice::Required => {
            let profile = learn_online_profile(manifest, params).with_context(|| {
                format!("{}: cannot learn the online profile", manifest.display())
            })?;
            Ok(ModelProfile {
                profile: Some(profile),
                ..ModelProfile::default()
            })
        }
    }
}

/// Where a terrain-to-gait table comes from (`--gait-table`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum GaitTableSource {
    /// Measured with the simulator (`sim`).
    Simulated,
    /// Given as `TERRAIN=GAIT,...`.
    Given(BTreeMap<String, String>),
}

impl std::str::FromStr for GaitTableSource {
    type Err = Error;

    /// `sim`, or `TERRAIN=GAIT` entries separated by commas (empty entries skipped).
    fn from_str(text: &str) -> Result<Self> {
        if text.trim() == "sim" {
            return Ok(Self::Simulated);
        }
        let mut table = BTreeMap::new();
        for entry in text.split(',').filter(|e| !e.trim().is_empty()) {
            let (terrain, gait) = entry
                .split_once('=')
                .filter(|(t, g)| !t.trim().is_empty() && !g.trim().is_empty())
                .ok_or_else(|| {
                    Error::invalid(format!(
                        "--gait-table expects sim or TERRAIN=GAIT,..., got {entry:?}"
                    ))
                })?;
            table.insert(terrain.trim().to_owned(), gait.trim().to_owned());
        }
        Ok(Self::Given(table))
    }
}

/// How a simulated terrain-to-gait table is measured.
#[derive(Clone, Copy, Debug)]
pub struct GaitTableSim<'c> {
    /// The simulator configuration file (`None`: the built-in one); its gaits are the candidates.
    pub config: Option<&'c Path>,
    pub seed: u64,
    pub sweep: GaitSweep,
}

/// The terrain-to-gait table for a model of `class_names`, and the measurement when it was simulated.
pub fn gait_table(
    source: &GaitTableSource,
    class_names: &[String],
    sim: GaitTableSim<'_>,
    progress: &dyn Progress,
) -> Result<(BTreeMap<String, String>, Option<MeasuredGaitTable>)> {
    match source {
        GaitTableSource::Given(table) => Ok((table.clone(), None)),
        GaitTableSource::Simulated => {
            let config = crate::simulation::load_config(sim.config)?;
            let measured = measure_gait_table(&config, sim.seed, class_names, sim.sweep, progress)?;
            Ok((measured.table.best.clone(), Some(measured)))
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn gait_tables_are_sim_or_terrain_gait_pairs() {
        assert_eq!(
            " sim".parse::<GaitTableSource>().unwrap(),
            GaitTableSource::Simulated
        );
        let given = "wood = G3,, grass=G1@0.6"
            .parse::<GaitTableSource>()
            .unwrap();
        let expected =
            [("grass", "G1@0.6"), ("wood", "G3")].map(|(t, g)| (t.to_owned(), g.to_owned()));
        assert_eq!(given, GaitTableSource::Given(BTreeMap::from(expected)));
        for bad in ["wood", "wood=", "=G1", "wood=G1,clay"] {
            let err = bad.parse::<GaitTableSource>().unwrap_err().to_string();
            assert!(err.starts_with("--gait-table expects sim"), "{bad}: {err}");
        }
    }
}
