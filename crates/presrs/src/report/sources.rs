//! Where a manifest report's extra inputs come from: the sensor and a few movies of the data set, and the
//! velocity table and configuration of a `presrs simulate` folder, and hops traced by the simulator.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use presrs_core::{Recording, SensorMeta};
use presrs_io::read_recording_with;
use presrs_sim::trace::{HopTrace, trace_hops};
use presrs_sim::{SimConfig, VelocityTable};

use crate::dataset::{Dataset, Sample, SampleOptions};
use crate::error::Result;

/// The sensor metadata of the manifest's first file and up to four movies (one per label) for load
/// curves.
pub(super) fn manifest_recordings(
    loaded: &Dataset,
    sample_options: &SampleOptions,
    preferred_condition: Option<&str>,
) -> (Option<SensorMeta>, Vec<(String, Recording)>) {
    let read = sample_options.read.clone();
    let mut sources: Vec<(&Path, Option<&str>, Option<&str>)> = Vec::new();
    let mut periods: BTreeMap<&Path, f64> = BTreeMap::new();
    let mut seen = BTreeSet::new();
    for s in &loaded.samples {
        if seen.insert(s.source.as_path()) {
            sources.push((
                s.source.as_path(),
                s.label.as_deref(),
                s.condition.as_deref(),
            ));
        }
        // The same frame period the samples were read with: the row's column, else the option.
        let period = s
            .columns
            .get("frame_period_s")
            .and_then(|text| text.trim().parse().ok())
            .or(sample_options.frame_period_s);
        if let Some(period) = period {
            periods.entry(s.source.as_path()).or_insert(period);
        }
    }
    let meta = sources
        .first()
        .and_then(|(path, ..)| read_recording_with(path, &read).ok())
        .map(|p| p.recording.meta);
    let mut labels_done = BTreeSet::new();
    let mut movies = Vec::new();
    let preferred: Vec<_> = sources
        .iter()
        .filter(|s| preferred_condition.is_none_or(|c| s.2 == Some(c)))
        .chain(sources.iter())
        .collect();
    for &&(path, label, condition) in &preferred {
        if movies.len() >= 4 {
            break;
        }
        if labels_done.contains(&label) {
            continue;
        }
        let Ok(mut parsed) = read_recording_with(path, &read) else {
            continue;
        };
        if let Some(&period) = periods.get(path) {
            // Already checked when the samples were loaded; a file's own period wins, as there.
            let _ = parsed.recording.set_frame_period_if_unknown(period);
        }
        if parsed.recording.frame_count() < 10 {
            continue;
        }
        labels_done.insert(label);
        let name = format!(
            "{}{}{}",
            path.file_name().map_or_else(
                || path.display().to_string(),
                |n| n.to_string_lossy().into_owned()
            ),
            label.map_or(String::new(), |l| format!(" · {l}")),
            condition.map_or(String::new(), |c| format!(" · {c}")),
        );
        let recording = first_seconds(&parsed.recording, 3.0).unwrap_or(parsed.recording);
        movies.push((name, recording));
    }
    (meta, movies)
}

/// The first `seconds` of a recording (all of it when shorter or without a frame period).
pub(super) fn first_seconds(recording: &Recording, seconds: f64) -> Result<Recording> {
    let keep = recording
        .frame_period_s()
        .map_or(recording.frame_count(), |p| (seconds / p).ceil() as usize)
        .clamp(1, recording.frame_count().max(1));
    if keep >= recording.frame_count() {
        return Ok(recording.clone());
    }
    let len = recording.grid().len() * keep;
    Ok(Recording::new(
        recording.grid(),
        recording.frame_period_s(),
        recording.data()[..len].to_vec(),
        recording.present().map(<[bool]>::to_vec),
        recording.meta.clone(),
    )?)
}

/// Whether `manifest` sits in a `presrs simulate` output folder.
pub(super) fn is_simulate_output(manifest: &Path) -> bool {
    manifest
        .parent()
        .is_some_and(|dir| dir.join("table1.csv").is_file() && dir.join("config.json").is_file())
}

/// Velocity table and config of a `presrs simulate` folder (its `table1.csv` and `config.json`).
pub(super) fn simulate_outputs(dir: &Path) -> Option<(VelocityTable, SimConfig)> {
    let table_text = std::fs::read_to_string(dir.join("table1.csv")).ok()?;
    let config =
        SimConfig::from_json(&std::fs::read_to_string(dir.join("config.json")).ok()?).ok()?;
    let mut rows: Vec<(String, String, f64, usize)> = Vec::new();
    for line in table_text.lines().skip(1) {
        let fields: Vec<&str> = line.split(',').collect();
        if let [gait, terrain, velocity, _, hops, ..] = fields[..] {
            rows.push((
                gait.to_owned(),
                terrain.to_owned(),
                velocity.parse().ok()?,
                hops.parse().ok()?,
            ));
        }
    }
    let mut gaits: Vec<String> = Vec::new();
    let mut terrains: Vec<String> = Vec::new();
    for (g, t, ..) in &rows {
        if !gaits.contains(g) {
            gaits.push(g.clone());
        }
        if !terrains.contains(t) {
            terrains.push(t.clone());
        }
    }
    let mut velocity = vec![vec![f64::NAN; terrains.len()]; gaits.len()];
    let mut hops = vec![vec![0; terrains.len()]; gaits.len()];
    for (g, t, v, n) in &rows {
        let gi = gaits.iter().position(|x| x == g)?;
        let ti = terrains.iter().position(|x| x == t)?;
        velocity[gi][ti] = *v;
        hops[gi][ti] = *n;
    }
    Some((
        VelocityTable {
            gaits,
            terrains,
            velocity_m_per_s: velocity,
            hops,
        },
        config,
    ))
}

/// Four hops on the slowest and the fastest terrain of `table` at `gait` (nothing if tracing fails).
pub(super) fn simulation_traces(
    config: &SimConfig,
    table: &VelocityTable,
    gait: &str,
) -> Vec<HopTrace> {
    let mut terrains: Vec<&str> = Vec::new();
    for preferred in ["wood", "grass"] {
        if table.terrains.iter().any(|t| t == preferred) {
            terrains.push(preferred);
        }
    }
    if terrains.is_empty() {
        terrains.extend(table.terrains.first().map(String::as_str));
    }
    terrains
        .into_iter()
        .filter_map(|t| trace_hops(config, t, gait, 4, 1e-3).ok())
        .collect()
}

/// The condition a report's figures show first: the paper's training gait `G2` when the samples have
/// it, else their first condition in sorted order (`None` without conditions).
pub(super) fn preferred_condition(samples: &[Sample]) -> Option<&str> {
    let conditions: BTreeSet<&str> = samples
        .iter()
        .filter_map(|s| s.condition.as_deref())
        .collect();
    if conditions.contains("G2") {
        Some("G2")
    } else {
        conditions.first().copied()
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use presrs_core::Grid;

    use super::*;
    use crate::progress::Quiet;

    /// A movie of 30 frames of 4 x 3 with one press in the middle, as NPY (which states no period).
    fn write_movie(path: &Path) {
        let grid = Grid::new(4, 3);
        let mut data = Vec::new();
        for f in 0..30 {
            let load = if (8..20).contains(&f) { 50.0 } else { 0.0 };
            data.extend(std::iter::repeat_n(load, grid.len()));
        }
        let recording = Recording::new(grid, None, data, None, SensorMeta::default()).unwrap();
        presrs_io::npy::write_recording_npy(&recording, path).unwrap();
    }

    /// The movies of the report's load curves are read with the period the samples were read with:
    /// the `--frame-period` option, and a row's `frame_period_s` column before it.
    #[test]
    fn movies_keep_the_frame_period_of_the_option_and_the_column() {
        let dir = tempfile::tempdir().unwrap();
        write_movie(&dir.path().join("a.npy"));
        write_movie(&dir.path().join("b.npy"));
        let manifest = dir.path().join("manifest.csv");
        std::fs::write(
            &manifest,
            "path,label,frame_period_s\na.npy,grass,0.02\nb.npy,wood,\n",
        )
        .unwrap();
        let options = SampleOptions {
            frame_period_s: Some(0.01),
            ..SampleOptions::default()
        };
        let loaded = Dataset::load(&manifest, &options, &Quiet).unwrap();
        let (_, movies) = manifest_recordings(&loaded, &options, None);
        let periods: Vec<(String, Option<f64>)> = movies
            .iter()
            .map(|(name, r)| (name.clone(), r.frame_period_s()))
            .collect();
        assert_eq!(periods.len(), 2, "{periods:?}");
        assert!(periods[0].0.starts_with("a.npy"), "{periods:?}");
        assert_eq!(periods[0].1, Some(0.02));
        assert_eq!(periods[1].1, Some(0.01));
    }
}
