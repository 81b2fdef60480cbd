//! The online stream: pressure frames in as they come, terrain decisions out as JSON lines.
//!
//! Input is TekScan ASCII text or the binary frame protocol of `docs/stream-protocol.md`
//! ([`presrs_io::frame_protocol`]); output is one JSON object per line (`touchdown`, `classification`,
//! `liftoff`, `error`, `end`). Two ways to run it:
//! - [`run_connection`]: one connection over any reader and writer (stdin and stdout, a pipe, a file);
//! - [`StreamServer`]: binary-protocol clients over TCP on a loopback address, several at once, until
//!   [`ShutdownHandle::stop`] (or a given number of connections).
//!
//! A bad frame (unreadable, non-finite, or of a size the model cannot use) is rejected with an `error`
//! event and the stream goes on; the `end` event and the [`ConnectionSummary`] count it among
//! `rejected_frames` and `errors`. But when the first frame already has a size the model cannot use,
//! the stream comes from another sensor: one fatal `error` ends it instead of one error per frame.
//!
//! Without a calibration (in the [`OnlineProfile`]) the detector calibrates on the stream's first frames
//! (the warm-up, [`OnlineParams::warmup_frames`](presrs_core::online::OnlineParams)); stances in them
//! are not classified, and a [`ConnectionNotice`] says so when the warm-up ends.
//!
//! Each connection has its own causal detector and classifier (`presrs_core::online`); the model is shared
//! read-only. Faults never panic and never grow memory without bound: frame sizes are capped before
//! reading, output to a client goes through a [`BoundedOutput`] (overflow is dropped and counted), the
//! number of clients is capped, idle connections are closed. Nothing here prints: what a person should
//! see comes back through the notice callbacks and the summaries.

mod bag;
mod connection;
mod events;
mod output;
mod server;
mod shutdown;
mod signals;
mod summary;
mod tap;

use std::path::Path;

use presrs_core::online::OnlineProfile;
use presrs_core::pipeline::TrainedModel;
use presrs_core::sample::SampleKind;
use presrs_io::message::{Message, Opt};

use crate::error::{Error, Result};

pub(crate) use bag::DecisionBag;
pub use bag::{
    BagRecorder, BagReport, ConnectionBags, DECISIONS_SCHEMA, DECISIONS_SCHEMA_NAME,
    DECISIONS_TOPIC, FRAME_TIMES_KEY, FRAMES_TOPIC, FrameTimes, RECORDING_METADATA, RecordedBag,
};
pub use connection::{
    ConnectionNotice, ConnectionOptions, ConnectionSummary, Input, InputFormat, MAX_ERROR_NOTICES,
    run_connection, run_connection_tapped, run_frames,
};
pub use events::event_values;
pub use output::BoundedOutput;
pub use server::{ServeSummary, ServerNotice, ServerOptions, StreamServer, TapFactory};
pub use shutdown::ShutdownHandle;
pub use signals::{SignalWatch, StopSignals};
pub use tap::{ConnectionTap, NoTap, OwnedTaps, Taps};

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
    /// A whole-stance model decides K frames after touchdown instead of at lift-off.
    pub decide_at: Option<usize>,
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
/// decides on its sample frame), fusion for one-frame models. The error names the option.
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
    if whole && !profile.params.fusion_offsets.is_empty() {
        return Err(Error::invalid(
            "a whole-stance model decides once per stance, on the stance's summary: fusion \
             (of one-frame decisions) does not apply; leave the fusion offsets out",
        ));
    }
    Ok(())
}

/// An online profile from its JSON file.
pub fn read_profile(path: &Path) -> Result<OnlineProfile> {
    let text = std::fs::read_to_string(path)
        .map_err(|err| Error::system(format!("cannot read the profile {}", path.display()), err))?;
    serde_json::from_str(&text)
        .map_err(|err| Error::data(format!("invalid online profile {}: {err}", path.display())))
}
