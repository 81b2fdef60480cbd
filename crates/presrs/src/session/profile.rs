//! The online profile a session runs with: chosen (a profile file, a calibration manifest, the model
//! file's own, or the defaults), changed by the face's options, and checked against the model.

use std::path::Path;

use presrs_core::online::{DecideAt, OnlineProfile};
use presrs_core::pipeline::TrainedModel;
use presrs_core::sample::SampleKind;
use presrs_io::message::{Message, Opt};

use crate::error::{Error, Result};

/// Changes to a profile, applied after it is chosen (the command line's `--sample-offset`, `--fuse`,
/// `--decide-at` and `--gait`).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ProfileOverrides {
    /// Classify the k-th frame after touchdown.
    pub sample_offset: Option<usize>,
    /// Also fuse the posteriors of these offsets after touchdown (empty: keep the profile's).
    pub fuse: Vec<usize>,
    /// Terrain -> recommended gait, added to the profile's table.
    pub gait: Vec<(String, String)>,
    /// A whole-stance model decides K frames after touchdown, or at its first confident decision
    /// point (`auto`), instead of at lift-off.
    pub decide_at: Option<DecideAt>,
}

/// The profile to run with: the JSON file `profile_file`, else one learned from the recordings of the
/// manifest `calibrate`, else the model file's `model_profile`, else the defaults (warm-up
/// calibration); then `overrides`.
pub fn resolve_profile(
    profile_file: Option<&Path>,
    calibrate: Option<&Path>,
    model_profile: Option<&OnlineProfile>,
    overrides: &ProfileOverrides,
) -> Result<OnlineProfile> {
    let mut profile = if let Some(path) = profile_file {
        read_profile(path)?
    } else if let Some(manifest) = calibrate {
        // With the detector settings the model was trained with, if it says; the recordings read as a
        // data set's are (the default options), by the same code.
        let segment = model_profile.map(|profile| profile.segment.clone());
        crate::train::manifest_online_profile(
            manifest,
            &crate::dataset::SampleOptions::default(),
            &segment.unwrap_or_default(),
        )?
    } else {
        model_profile.cloned().unwrap_or_default()
    };
    if let Some(k) = overrides.sample_offset {
        profile.params.sample_offset = k;
    }
    if overrides.decide_at.is_some() {
        profile.params.decide_at = overrides.decide_at;
    }
    if !overrides.fuse.is_empty() {
        profile.params.fusion_offsets.clone_from(&overrides.fuse);
    }
    for (terrain, gait) in &overrides.gait {
        profile.gait_table.insert(terrain.clone(), gait.clone());
    }
    Ok(profile)
}

/// Whether `profile` suits `model` online: `decide_at` is for whole-stance models (a one-frame model
/// decides on its sample frame), and only for a moment the model was trained for
/// ([`TrainedModel::trained_for`]); fusion is for one-frame models. The error names the option.
pub fn check_profile(model: &TrainedModel, profile: &OnlineProfile) -> Result<()> {
    let whole = matches!(model.sample(), SampleKind::Stance { .. });
    if let (false, Some(k)) = (whole, profile.params.decide_at) {
        return Err(Error::invalid(
            Message::from("").opt_is(Opt::DecideAt, k).text(
                " applies to whole-stance models (trained on stance samples); this model \
                     classifies one frame of each stance, chosen by its sample offset",
            ),
        ));
    }
    if let (true, Some(decide_at)) = (whole, profile.params.decide_at)
        && let Err(trained) = model.trained_for(decide_at)
    {
        return Err(Error::invalid(
            Message::from(format!(
                "this model was not trained to decide at {decide_at} (it was trained for \
                 {trained}), and a model decides only at the moments it was trained for: train one \
                 for it with `presrs train`, "
            ))
            .opt_text(Opt::Sample, "stance")
            .text(" and ")
            .then(decide_at_option(decide_at)),
        ));
    }
    if whole && !profile.params.fusion_offsets.is_empty() {
        return Err(Error::invalid(
            "a whole-stance model decides once per stance, on the stance's summary: fusion \
             (of one-frame decisions) does not apply; leave the fusion offsets out",
        ));
    }
    Ok(())
}

/// `decide_at` as the option that asks for it: `--decide-at 12`, `decide_at="auto"` in Python.
fn decide_at_option(decide_at: DecideAt) -> Message {
    match decide_at {
        DecideAt::Frames(k) => Message::new().opt_is(Opt::DecideAt, k),
        DecideAt::Auto(_) => Message::new().opt_text(Opt::DecideAt, "auto"),
    }
}

/// An online profile from its JSON file.
pub fn read_profile(path: &Path) -> Result<OnlineProfile> {
    let text = std::fs::read_to_string(path)
        .map_err(|err| Error::system(format!("cannot read the profile {}", path.display()), err))?;
    serde_json::from_str(&text)
        .map_err(|err| Error::data(format!("invalid online profile {}: {err}", path.display())))
}
