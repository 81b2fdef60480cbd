//! The line `presrs train` prints about the online profile it wrote into the model file.

use presrs_core::online::OnlineProfile;

/// One line on a model's online profile: its sample frame, calibration and terrain-to-gait table.
pub fn profile_summary(profile: &OnlineProfile) -> String {
    let table: Vec<String> = profile
        .gait_table
        .iter()
        .map(|(t, g)| format!("{t}={g}"))
        .collect();
    format!(
        "online profile: sample frame k = {}, {}, gait table {}",
        profile.params.sample_offset,
        if profile.calibration.is_some() {
            "calibrated"
        } else {
            "warm-up calibration"
        },
        if table.is_empty() {
            "empty".to_owned()
        } else {
            table.join(",")
        }
    )
}
