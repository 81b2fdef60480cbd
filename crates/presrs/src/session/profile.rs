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
        return Err(Error::invalid(fusion_with_a_whole_stance_model(
            &profile.params.fusion_offsets,
        )));
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

/// Why fusion does not apply to a whole-stance model: the profile's `fusion_offsets` (which `--fuse`
/// sets), named with the option.
fn fusion_with_a_whole_stance_model(offsets: &[usize]) -> Message {
    Message::new()
        .text(format!(
            "the profile's fusion offsets {} (set by ",
            offsets_text(offsets)
        ))
        .opt(Opt::Fuse)
        .text(
            ") fuse one-frame decisions, but a whole-stance model decides once per stance, on the \
             stance's summary: leave them out",
        )
}

/// `4,5,6`: offsets as `--fuse` takes them.
fn offsets_text(offsets: &[usize]) -> String {
    let offsets: Vec<String> = offsets.iter().map(ToString::to_string).collect();
    offsets.join(",")
}

/// Whether the options a face was given (`overrides`) suit `model`, before any profile is chosen:
/// each names itself in the error. Every one is refused when it does nothing with the model, as
/// [`check_profile`] refuses a profile that does: the model is known when they are given, and a
/// setting silently ignored would leave the user reading decisions made otherwise than they asked
/// (a whole-stance model decides at lift-off, not on the frame `sample_offset` names).
pub fn check_overrides(model: &TrainedModel, overrides: &ProfileOverrides) -> Result<()> {
    let whole = matches!(model.sample(), SampleKind::Stance { .. });
    if let (true, Some(k)) = (whole, overrides.sample_offset) {
        return Err(Error::invalid(
            Message::new()
                .opt_is(Opt::SampleOffset, k)
                .text(
                    " picks the frame a one-frame model classifies; this model classifies whole \
                     stances (it was trained on stance samples), at lift-off: leave it out, or give ",
                )
                .opt_is(Opt::DecideAt, k)
                .text(" to decide on the stance so far, that many frames after touchdown"),
        ));
    }
    if whole && !overrides.fuse.is_empty() {
        return Err(Error::invalid(
            Message::new()
                .opt_is(Opt::Fuse, offsets_text(&overrides.fuse))
                .text(
                    " fuses one-frame decisions, but a whole-stance model decides once per stance, \
                     on the stance's summary: leave it out (with ",
                )
                .opt_is(Opt::DecideAt, "K")
                .text(" it decides K frames after touchdown instead of at lift-off)"),
        ));
    }
    let profile = OnlineProfile {
        params: presrs_core::online::OnlineParams {
            decide_at: overrides.decide_at,
            ..Default::default()
        },
        ..Default::default()
    };
    check_profile(model, &profile)
}

/// An online profile from its JSON file ([`parse_profile`]).
pub fn read_profile(path: &Path) -> Result<OnlineProfile> {
    let text = std::fs::read_to_string(path)
        .map_err(|err| Error::system(format!("cannot read the profile {}", path.display()), err))?;
    parse_profile(&text, &path.display().to_string())
}

/// The fields a profile file may hold; `params` is required (every profile written holds it).
const PROFILE_FIELDS: [&str; 5] = [
    "params",
    "segment",
    "typical_stance_frames",
    "calibration",
    "gait_table",
];

/// An online profile from its JSON text, `file` naming it in errors: a JSON object of the fields a
/// model file's `online` object holds (`params` at least), and no other. A model file is named as
/// such: it is given with `--model`.
pub fn parse_profile(text: &str, file: &str) -> Result<OnlineProfile> {
    let invalid = |why: String| Error::data(format!("{file}: not an online profile: {why}"));
    let value: serde_json::Value =
        serde_json::from_str(text).map_err(|err| invalid(format!("invalid JSON: {err}")))?;
    let Some(object) = value.as_object() else {
        return Err(invalid(format!(
            "a profile is a JSON object of {}, got {value}",
            PROFILE_FIELDS.join(", ")
        )));
    };
    let format = object.get("format").and_then(serde_json::Value::as_str);
    if format == Some(presrs_io::model_file::MODEL_FORMAT) || object.contains_key("model") {
        return Err(Error::invalid(format!(
            "{file} is a model file, not an online profile: give it with --model (its own online \
             profile, when it has one, is used by default)"
        )));
    }
    if let Some(unknown) = object
        .keys()
        .find(|key| !PROFILE_FIELDS.contains(&key.as_str()))
    {
        return Err(invalid(format!(
            "unknown field `{unknown}` (a profile holds {})",
            PROFILE_FIELDS.join(", ")
        )));
    }
    if !object.contains_key("params") {
        return Err(invalid(
            "missing field `params` (the detector's sample offset and warm-up; a model file's \
             `online` object is a profile)"
                .to_owned(),
        ));
    }
    serde_json::from_value(value).map_err(|err| invalid(err.to_string()))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn profile_fields_are_those_a_profile_serialises() {
        let value = serde_json::to_value(OnlineProfile::default()).unwrap();
        let mut written: Vec<&str> = value
            .as_object()
            .unwrap()
            .keys()
            .map(String::as_str)
            .collect();
        let mut known = PROFILE_FIELDS.to_vec();
        written.sort_unstable();
        known.sort_unstable();
        assert_eq!(written, known);
        let text = serde_json::to_string(&OnlineProfile::default()).unwrap();
        assert_eq!(
            parse_profile(&text, "p.json").unwrap(),
            OnlineProfile::default()
        );
    }

    #[test]
    fn profiles_with_unknown_or_missing_fields_and_model_files_are_refused() {
        let err = parse_profile(r#"{"foo": 1}"#, "p.json")
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("p.json: not an online profile: unknown field `foo`"),
            "{err}"
        );
        let err = parse_profile(r#"{"gait_table": {}}"#, "p.json")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("p.json") && err.contains("missing field `params`"),
            "{err}"
        );
        let err = parse_profile(r#"{"params": {"sample_offest": 3}}"#, "p.json")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("p.json") && err.contains("sample_offest"),
            "{err}"
        );
        let err = parse_profile("[1]", "p.json").unwrap_err().to_string();
        assert!(err.contains("a profile is a JSON object"), "{err}");
        let model = r#"{"format": "presrs-model", "format_version": 1, "model": {}}"#;
        let err = parse_profile(model, "m.json").unwrap_err().to_string();
        assert!(
            err.starts_with("m.json is a model file, not an online profile: give it with --model"),
            "{err}"
        );
    }
}
