//! The model file `presrs train` writes, made in one pass ([`train_model_file`]): the data set read
//! once, the model trained on it, and the online profile learned from the recordings already read, under
//! the same options; whether a profile is learned (by default when the training samples come from
//! movies), and its terrain-to-gait table (measured with the simulator or given).

use std::collections::BTreeMap;
use std::path::Path;

use presrs_core::online::OnlineProfile;
use presrs_core::sample::SampleChoice;
use presrs_core::stance::ValidSegmentParams;
use presrs_io::model_file::ModelFile;

use crate::dataset::{Dataset, SampleOptions};
use crate::error::{Context, Error, Result};
use crate::progress::Progress;
use crate::sim::gait::{GaitSweep, MeasuredGaitTable, measure_gait_table};
use crate::train::early::DecisionPoints;
use crate::train::sample_race::{SampleRace, WholeSample, train_racing_samples};
use crate::train::{
    TrainOptions, Training, learn_online_profile, train_with_progress, trained_on_movies,
};

/// What `presrs train` is asked: the data set (a manifest, its files read and sampled as `samples`
/// says, the sample kind chosen by `sample`), the training and the online profile.
#[derive(Clone, Debug)]
pub struct TrainRequest<'a> {
    pub manifest: &'a Path,
    /// The sample kind, or `auto`: one frame raced against the whole sample `whole`.
    pub sample: SampleChoice,
    /// How the manifest's files are read and sampled (their kind is `sample`'s).
    pub samples: SampleOptions,
    /// The whole sample `auto` races.
    pub whole: WholeSample,
    pub train: TrainOptions,
    /// The decision points before lift-off a whole-stance model is trained for.
    pub decide_at: DecisionPoints,
    pub profile: ProfileRequest<'a>,
    /// The command line stored in the model's provenance.
    pub command: Option<String>,
}

/// A model file and how it was made.
#[derive(Debug)]
pub struct TrainedFile {
    /// The model, its provenance and its online profile.
    pub file: ModelFile,
    /// The data set it was trained on (the race's winner with `auto`).
    pub dataset: Dataset,
    pub training: Training,
    /// With `auto`: the race of the sample kinds.
    pub race: Option<SampleRace>,
    /// Why no profile was learned, and a simulated gait table's measurement (the profile itself is
    /// the file's).
    pub profile: ModelProfile,
}

/// Reads the data set of `request.manifest` (each recording once), trains on it (racing the sample
/// kinds with `auto`) and learns the online profile from the recordings already read, under the same
/// options (`--axes`, topics, frame period, leniency, dead sensels): the model file `presrs train`
/// writes. `data_read` is shown the data set as soon as it is read (with `auto`, once the race is
/// run, with the race), before training or the profile can fail: a face says its warnings then.
pub fn train_model_file(
    request: &TrainRequest<'_>,
    progress: &dyn Progress,
    data_read: &mut dyn FnMut(&Dataset, Option<&SampleRace>),
) -> Result<TrainedFile> {
    let whole_stance = matches!(
        request.sample,
        SampleChoice::Kind(presrs_core::sample::SampleKind::Stance { .. })
    );
    if request.decide_at != DecisionPoints::Whole && !whole_stance {
        return Err(Error::invalid(
            presrs_io::message::Message::new()
                .opt(presrs_io::message::Opt::DecideAt)
                .text(" trains decision points before lift-off for a whole-stance model: use ")
                .opt_is(presrs_io::message::Opt::Sample, "stance"),
        ));
    }
    let (dataset, training, race) = match request.sample {
        SampleChoice::Auto => {
            let raced = train_racing_samples(
                request.manifest,
                &request.samples,
                request.whole,
                &request.train,
                progress,
            )?;
            data_read(&raced.dataset, Some(&raced.race));
            (raced.dataset, raced.training, Some(raced.race))
        }
        SampleChoice::Kind(kind) => {
            let options = SampleOptions {
                kind,
                ..request.samples.clone()
            };
            let dataset =
                load_with_points(request.manifest, options, &request.decide_at, progress)?;
            data_read(&dataset, None);
            progress.start("training", None);
            let training = train_with_progress(&dataset, &request.train, progress);
            progress.finish();
            (dataset, training?, None)
        }
    };
    let mut file = training.model_file(
        &dataset,
        &request.train,
        request.samples.dead_sensels.is_some(),
        request.command.clone(),
    );
    let mut profile = model_profile(
        &dataset,
        &request.samples.segment_params(),
        training.model.class_names(),
        &request.profile,
        progress,
    )?;
    file.online = profile.profile.take();
    Ok(TrainedFile {
        file,
        dataset,
        training,
        race,
        profile,
    })
}

/// The data set of `manifest` read with `options`, its stances also cut at the decision points
/// `points` (`auto`'s resolved from the stances' lengths, read first).
pub fn load_with_points(
    manifest: &Path,
    mut options: SampleOptions,
    points: &DecisionPoints,
    progress: &dyn Progress,
) -> Result<Dataset> {
    let stance_frames = match points {
        DecisionPoints::Whole => return Dataset::load(manifest, &options, progress),
        DecisionPoints::Frames(_) => Vec::new(),
        DecisionPoints::Auto => {
            Dataset::load(manifest, &options, progress)?
                .stances
                .stance_frames
        }
    };
    options.decision_points = points.resolve(&stance_frames);
    Dataset::load(manifest, &options, progress)
}

/// Whether a model file gets an online profile.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ProfileChoice {
    /// When the training samples come from movies (learned from them as read); a profile that cannot be
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

/// The online profile of a model of `class_names` trained on `dataset`, learned by offline segmentation
/// with `params` (those of training) of the movies as the data set read them, as `request` says, with
/// its terrain-to-gait table.
pub fn model_profile(
    dataset: &Dataset,
    params: &ValidSegmentParams,
    class_names: &[String],
    request: &ProfileRequest<'_>,
    progress: &dyn Progress,
) -> Result<ModelProfile> {
    let mut learned = learn_profile(dataset, params, request.choice)?;
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
    params: &ValidSegmentParams,
    choice: ProfileChoice,
) -> Result<ModelProfile> {
    let manifest = dataset.path();
    let learn = || learn_online_profile(&dataset.movie_loads, params);
    match choice {
        ProfileChoice::Never => Ok(ModelProfile::default()),
        ProfileChoice::WhenMovies if !trained_on_movies(dataset) => Ok(ModelProfile::default()),
        ProfileChoice::WhenMovies => Ok(match learn() {
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
            let profile = learn().with_context(|| {
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
            let config = crate::sim::load_config(sim.config)?;
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
