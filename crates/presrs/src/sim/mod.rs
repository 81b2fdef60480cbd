//! The simulated data set on disk: [`write_dataset`] simulates and writes it (TekScan movies, a
//! manifest, the ground truth, Table I, the configuration), stamped so that [`read_dataset`] reuses a
//! folder only when it holds exactly what would be simulated.
//!
//! Folder layout:
//! - `manifest.csv`: `path,label,condition,group,frame,load` (one row per movie; `frame` empty: every
//!   stance phase in the movie is a sample; `load` is the body mass in kg).
//! - `recordings/<terrain>_<gait>_<trial>.asf`: TekScan ASCII movies, continuous frames at 100 Hz.
//! - `truth/hops.csv`: one row per hop (stance frames, times, angles, forces, velocity).
//! - `truth/trials.json`: per trial, per hop, the full ground truth (including per-frame forces), and
//!   the trial's plan.
//! - `table1.csv`: simulated forward velocity per gait and terrain beside the paper's Table I.
//! - `config.json`: the complete configuration used (feed it back to reproduce).
//! - `stamp.json`, written last: what the data set was made from (presrs version, seed, terrains, gaits,
//!   hops per gait, load, the SHA-256 of the configuration) and the size and SHA-256 of every file
//!   above. A folder without a stamp is an unfinished (or older) data set.

pub mod gait;

use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

use presrs_sim::{
    DatasetSpec, HopRecord, SimConfig, SimulatedDataset, Simulator, TrialOutput, TrialPlan,
    VelocityTable,
};
use rayon::prelude::*;

use crate::error::{Context, Error, Result};
use crate::progress::Progress;

/// `return Err(Error::Data(..))` unless `cond`.
macro_rules! ensure {
    ($cond:expr, $($arg:tt)*) => {
        if !$cond {
            return Err(Error::data(format!($($arg)*)));
        }
    };
}

/// `return Err(Error::Data(..))`.
macro_rules! bail {
    ($($arg:tt)*) => {
        return Err(Error::data(format!($($arg)*)))
    };
}

mod inputs;
mod stamp;

pub use inputs::{check_dataset_out, check_gaits, dataset_names, load_config, read_terrain_image};
pub use stamp::{DatasetKey, DatasetStamp, FileStamp, STAMP_FILE};
use stamp::{STAMP_FORMAT, config_json, read_checked, write_hashed};

/// What [`write_dataset`] wrote.
#[derive(Clone, Debug)]
pub struct DatasetSummary {
    /// The manifest file.
    pub manifest: PathBuf,
    pub trials: usize,
    pub hops: usize,
    pub frames: usize,
    /// Trials that had to be rerun because the hopper fell.
    pub reruns: usize,
    pub velocity: VelocityTable,
    pub mean_stance_s: f64,
}

/// One trial's truth, kept after its movie is written (an element of `truth/trials.json`).
#[derive(Debug, serde::Serialize, serde::Deserialize)]
struct TrialTruth {
    name: String,
    path: String,
    terrain: String,
    gait: String,
    load_kg: f64,
    frames: usize,
    attempts: usize,
    hops: Vec<HopRecord>,
    /// The trial as planned (gait parameters, trial seed).
    plan: TrialPlan,
}

/// Simulates the data set described by `config` and `spec` and writes it under `out_dir` (see the module
/// documentation for the layout). `progress` advances after each trial (from worker threads). Same
/// inputs, same bytes.
pub fn write_dataset(
    config: &SimConfig,
    spec: &DatasetSpec,
    out_dir: &Path,
    progress: &dyn Progress,
) -> Result<DatasetSummary> {
    Ok(write_dataset_with(config, spec, out_dir, false, progress)?.0)
}

/// [`write_dataset`], also returning the simulated trials when `keep` (what
/// [`presrs_sim::simulate_dataset`] would return, without reading the files back).
///
/// The folder's old stamp is removed first and the new one written last (each file atomically), so an
/// interrupted run leaves no stamp that claims a complete data set.
pub fn write_dataset_with(
    config: &SimConfig,
    spec: &DatasetSpec,
    out_dir: &Path,
    keep: bool,
    progress: &dyn Progress,
) -> Result<(DatasetSummary, Option<SimulatedDataset>)> {
    let key = DatasetKey::new(config, spec);
    let sim = Simulator::new(config.clone(), spec.seed, spec.image_terrains.clone())?;
    let stamp_path = out_dir.join(STAMP_FILE);
    let old_files = remove_stamp(&stamp_path)?;
    for dir in [out_dir, &out_dir.join("recordings"), &out_dir.join("truth")] {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create the folder {}", dir.display()))?;
    }
    let (truths, mut files, kept) = write_trials(&sim, spec, out_dir, keep, progress)?;
    let velocity = velocity_table(&truths);
    let mut write_file =
        |rel: &str, write: &dyn Fn(&mut dyn Write) -> std::io::Result<()>| -> Result<()> {
            let file = write_hashed(out_dir, rel, write)?;
            files.insert(rel.to_owned(), file);
            Ok(())
        };
    write_file("manifest.csv", &|w| write_manifest(&truths, w))?;
    write_file("truth/hops.csv", &|w| write_hops(&truths, w))?;
    write_file("truth/trials.json", &|w| {
        serde_json::to_writer(&mut *w, &truths).map_err(std::io::Error::from)?;
        writeln!(w)
    })?;
    write_file("table1.csv", &|w| write_table1(&velocity, w))?;
    write_file("config.json", &|w| {
        w.write_all(config_json(config).as_bytes())
    })?;
    // The stamp, last.
    let frames = truths.iter().map(|t| t.frames).sum();
    let stamp = DatasetStamp {
        format: STAMP_FORMAT,
        made_from: key,
        trials: truths.len(),
        frames,
        files,
    };
    presrs_io::write_atomic(&stamp_path, |w| {
        serde_json::to_writer_pretty(&mut *w, &stamp).map_err(std::io::Error::from)?;
        writeln!(w)
    })?;
    remove_stale(out_dir, old_files, &stamp);
    let summary = DatasetSummary::of(out_dir, &truths, frames, velocity);
    Ok((summary, keep.then_some(SimulatedDataset { trials: kept })))
}

/// Removes the folder's stamp first: until the new one is written, the folder claims no complete data
/// set. Returns the files the old stamp listed (those the new data set lacks go at the end).
fn remove_stamp(stamp_path: &Path) -> Result<Vec<String>> {
    let old_files: Vec<String> = std::fs::read_to_string(stamp_path)
        .ok()
        .and_then(|text| serde_json::from_str::<DatasetStamp>(&text).ok())
        .map(|old| old.files.into_keys().collect())
        .unwrap_or_default();
    match std::fs::remove_file(stamp_path) {
        Err(err) if err.kind() != std::io::ErrorKind::NotFound => Err(err)
            .with_context(|| format!("cannot remove the old stamp {}", stamp_path.display())),
        _ => Ok(old_files),
    }
}

/// The trials' truth and movie files, and the trials themselves with `keep`.
type WrittenTrials = (
    Vec<TrialTruth>,
    BTreeMap<String, FileStamp>,
    Vec<TrialOutput>,
);

/// Simulates every trial of `spec` (in parallel) and writes its movie; returns the truths in plan
/// order, the movies' stamps and (with `keep`) the trials.
fn write_trials(
    sim: &Simulator,
    spec: &DatasetSpec,
    out_dir: &Path,
    keep: bool,
    progress: &dyn Progress,
) -> Result<WrittenTrials> {
    let total = sim.plan(spec)?.len();
    progress.start("simulating trials", Some(total as u64));
    type Written = (TrialTruth, FileStamp, Option<TrialOutput>);
    let written = sim.for_each_trial(spec, |trial| -> Result<Written> {
        let name = trial.plan.name();
        let rel = format!("recordings/{name}.asf");
        let file = write_hashed(out_dir, &rel, |w| {
            presrs_io::write_tekscan(&trial.recording, w)
        })
        .with_context(|| format!("cannot write the movie {}", out_dir.join(&rel).display()))?;
        progress.advance(1);
        let truth = TrialTruth {
            name,
            path: rel,
            terrain: trial.plan.terrain.clone(),
            gait: trial.plan.gait.name.clone(),
            load_kg: trial.plan.load_kg,
            frames: trial.recording.frame_count(),
            attempts: trial.attempts,
            hops: trial.hops.clone(),
            plan: trial.plan.clone(),
        };
        Ok((truth, file, keep.then_some(trial)))
    });
    progress.finish();
    let mut files = BTreeMap::new();
    let mut truths = Vec::new();
    let mut kept = Vec::new();
    for (truth, file, trial) in written? {
        files.insert(truth.path.clone(), file);
        truths.push(truth);
        kept.extend(trial);
    }
    Ok((truths, files, kept))
}

/// `manifest.csv`: one row per movie.
fn write_manifest(truths: &[TrialTruth], w: &mut dyn Write) -> std::io::Result<()> {
    writeln!(w, "path,label,condition,group,frame,load")?;
    for t in truths {
        writeln!(
            w,
            "{},{},{},{},,{}",
            csv_cell(&t.path),
            csv_cell(&t.terrain),
            csv_cell(&t.gait),
            csv_cell(&t.name),
            t.load_kg
        )?;
    }
    Ok(())
}

/// `truth/hops.csv`: one row per hop.
fn write_hops(truths: &[TrialTruth], w: &mut dyn Write) -> std::io::Result<()> {
    writeln!(
        w,
        "path,group,label,condition,hop,touchdown_time_s,liftoff_time_s,stance_duration_s,\
         touchdown_angle_rad,liftoff_angle_rad,first_stance_frame,last_stance_frame,mid_stance_frame,\
         stance_frames,peak_normal_force_n,peak_tangential_force_n,mid_stance_normal_force_n,\
         mean_forward_velocity_m_per_s,apex_height_m,load_kg"
    )?;
    for t in truths {
        for h in &t.hops {
            let opt = |v: Option<usize>| v.map(|v| v.to_string()).unwrap_or_default();
            let mid_force = match (h.mid_stance_frame, h.first_stance_frame) {
                (Some(mid), Some(first)) => h
                    .frame_normal_force_n
                    .get(mid - first)
                    .map(|f| format!("{f}"))
                    .unwrap_or_default(),
                _ => String::new(),
            };
            let tr = &h.truth;
            writeln!(
                w,
                "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                csv_cell(&t.path),
                csv_cell(&t.name),
                csv_cell(&t.terrain),
                csv_cell(&t.gait),
                tr.hop,
                tr.touchdown_time_s,
                tr.liftoff_time_s,
                tr.stance_duration_s,
                tr.touchdown_angle_rad,
                tr.liftoff_angle_rad,
                opt(h.first_stance_frame),
                opt(h.last_stance_frame),
                opt(h.mid_stance_frame),
                h.frame_normal_force_n.len(),
                tr.peak_normal_force_n,
                tr.peak_tangential_force_n,
                mid_force,
                tr.mean_forward_velocity_m_per_s,
                tr.apex_height_m,
                t.load_kg
            )?;
        }
    }
    Ok(())
}

/// `table1.csv`: the simulated velocity per gait and terrain beside the paper's.
fn write_table1(velocity: &VelocityTable, w: &mut dyn Write) -> std::io::Result<()> {
    writeln!(w, "gait,terrain,velocity_m_per_s,paper_m_per_s,hops")?;
    for (gi, (g, row)) in velocity
        .gaits
        .iter()
        .zip(&velocity.velocity_m_per_s)
        .enumerate()
    {
        for (ti, (t, v)) in velocity.terrains.iter().zip(row).enumerate() {
            let paper = VelocityTable::paper_value(g, t)
                .map(|p| p.to_string())
                .unwrap_or_default();
            writeln!(w, "{g},{t},{v},{paper},{}", velocity.hops[gi][ti])?;
        }
    }
    Ok(())
}

/// Removes the files an older data set in the folder had and the new stamp does not list.
fn remove_stale(out_dir: &Path, old_files: Vec<String>, stamp: &DatasetStamp) {
    for rel in old_files {
        // Only plain relative paths inside the folder, as this module writes them.
        let inside = Path::new(&rel)
            .components()
            .all(|c| matches!(c, std::path::Component::Normal(_)));
        if inside && !stamp.files.contains_key(&rel) {
            // A file that cannot be removed is only clutter: the new stamp does not list it.
            let _ = std::fs::remove_file(out_dir.join(&rel));
        }
    }
}

impl DatasetSummary {
    fn of(out_dir: &Path, truths: &[TrialTruth], frames: usize, velocity: VelocityTable) -> Self {
        let hops: usize = truths.iter().map(|t| t.hops.len()).sum();
        let stance_sum: f64 = truths
            .iter()
            .flat_map(|t| t.hops.iter().map(|h| h.truth.stance_duration_s))
            .sum();
        Self {
            manifest: out_dir.join("manifest.csv"),
            trials: truths.len(),
            hops,
            frames,
            reruns: truths.iter().map(|t| t.attempts - 1).sum(),
            velocity,
            mean_stance_s: if hops == 0 {
                f64::NAN
            } else {
                stance_sum / hops as f64
            },
        }
    }
}

/// Reads back the data set `write_dataset` wrote in `dir`, if its stamp says it was made from `wanted`
/// and every file is as the stamp lists it (size and fingerprint). The error says why not, in words
/// that follow "not reusing DIR: ".
pub fn read_dataset(dir: &Path, wanted: &DatasetKey) -> Result<(SimulatedDataset, DatasetStamp)> {
    let stamp_path = dir.join(STAMP_FILE);
    let text = match std::fs::read_to_string(&stamp_path) {
        Ok(text) => text,
        Err(err) if err.kind() == std::io::ErrorKind::NotFound => {
            if dir.exists() {
                bail!(
                    "it has no {STAMP_FILE} (an unfinished data set, or one written before stamps)"
                );
            }
            bail!("there is no data set there yet");
        }
        Err(err) => {
            return Err(err).with_context(|| format!("cannot read {}", stamp_path.display()));
        }
    };
    let stamp: DatasetStamp = serde_json::from_str(&text)
        .with_context(|| format!("{} is corrupt", stamp_path.display()))?;
    ensure!(
        stamp.format == STAMP_FORMAT,
        "{} has format {}, this presrs reads format {STAMP_FORMAT}",
        stamp_path.display(),
        stamp.format
    );
    if let Some(why) = stamp.made_from.mismatch(wanted) {
        return Err(Error::data(why));
    }
    for rel in stamp.files.keys() {
        if !rel.starts_with("recordings/") && rel != "truth/trials.json" {
            read_checked(dir, rel, &stamp)?;
        }
    }
    let truths: Vec<TrialTruth> =
        serde_json::from_slice(&read_checked(dir, "truth/trials.json", &stamp)?)
            .with_context(|| format!("{} is corrupt", dir.join("truth/trials.json").display()))?;
    ensure!(
        truths.len() == stamp.trials,
        "truth/trials.json lists {} trials, the stamp {}",
        truths.len(),
        stamp.trials
    );
    let trials: Vec<TrialOutput> = truths
        .into_par_iter()
        .map(|truth| -> Result<TrialOutput> {
            let path = dir.join(&truth.path);
            let bytes = read_checked(dir, &truth.path, &stamp)?;
            let text = std::str::from_utf8(&bytes).map_err(|err| {
                Error::data(format!("{} is not ASCII text: {err}", path.display()))
            })?;
            let recording = presrs_io::parse_tekscan(
                text,
                &path.display().to_string(),
                &presrs_io::ReadOptions::default(),
            )?
            .recording;
            ensure!(
                recording.frame_count() == truth.frames,
                "{} has {} frames, truth/trials.json says {}",
                path.display(),
                recording.frame_count(),
                truth.frames
            );
            Ok(TrialOutput {
                plan: truth.plan,
                recording,
                hops: truth.hops,
                attempts: truth.attempts,
            })
        })
        .collect::<Result<_>>()?;
    let frames: usize = trials.iter().map(|t| t.recording.frame_count()).sum();
    ensure!(
        frames == stamp.frames,
        "the movies hold {frames} frames, the stamp says {}",
        stamp.frames
    );
    Ok((SimulatedDataset { trials }, stamp))
}

/// Checks that this build's simulator still makes `dataset` (read back from a folder): simulates its first
/// trial again (about 1/50 of the time of the whole data set) and compares the movie and the truth. A
/// simulator changed without a version change (a development build) is caught here; the error says so.
pub fn check_simulator(
    config: &SimConfig,
    spec: &DatasetSpec,
    dataset: &SimulatedDataset,
) -> Result<()> {
    let Some(stored) = dataset.trials.first() else {
        return Ok(());
    };
    let sim = Simulator::new(config.clone(), spec.seed, spec.image_terrains.clone())?;
    let again = sim.run_trial(&stored.plan, spec.seed)?;
    let same = again.plan == stored.plan
        && again.hops == stored.hops
        && again.attempts == stored.attempts
        && again.recording.grid() == stored.recording.grid()
        && again.recording.present() == stored.recording.present()
        && again.recording.data() == stored.recording.data();
    ensure!(
        same,
        "this build's simulator no longer makes its trial {} (presrs changed without a version change)",
        stored.plan.name()
    );
    Ok(())
}

/// Table I from the trials' truth.
fn velocity_table(truths: &[TrialTruth]) -> VelocityTable {
    VelocityTable::from_trials(truths.iter().map(|t| {
        (
            t.gait.clone(),
            t.terrain.clone(),
            t.hops
                .iter()
                .map(|h| h.truth.mean_forward_velocity_m_per_s)
                .collect(),
        )
    }))
}

/// Quotes a CSV cell when it needs it.
fn csv_cell(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_owned()
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]

    use super::stamp::Fingerprint;
    use super::*;
    use crate::progress::Quiet;

    #[test]
    fn fingerprint_is_sha256_the_same_in_pieces_and_changes_with_any_byte() {
        // FIPS 180-2's example: SHA-256("abc").
        assert_eq!(
            Fingerprint::of(b"abc").hex(),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
        let bytes: Vec<u8> = (0..1000u32).map(|i| (i * 7 % 251) as u8).collect();
        let whole = Fingerprint::of(&bytes).hex();
        for cut in [1, 3, 7, 8, 9, 500] {
            let mut pieces = Fingerprint::new();
            for chunk in bytes.chunks(cut) {
                pieces.update(chunk);
            }
            assert_eq!(pieces.hex(), whole, "pieces of {cut}");
        }
        for at in [0, 7, 8, 999] {
            let mut changed = bytes.clone();
            changed[at] ^= 1;
            assert_ne!(Fingerprint::of(&changed).hex(), whole, "byte {at}");
        }
        assert_ne!(Fingerprint::of(&[]).hex(), Fingerprint::of(&[0]).hex());
        assert_ne!(Fingerprint::of(&bytes[..999]).hex(), whole);
    }

    #[test]
    fn written_data_set_reads_back_as_simulated() {
        let dir = tempfile::tempdir().unwrap();
        let config = SimConfig::default();
        let mut spec = DatasetSpec::paper(11);
        spec.terrains = vec!["carpet".into(), "grass".into()];
        spec.gaits = vec!["G2".into()];
        spec.hops_per_gait = Some(2);
        let (summary, kept) = write_dataset_with(&config, &spec, dir.path(), true, &Quiet).unwrap();
        let kept = kept.unwrap();
        assert_eq!(summary.trials, 2);
        let wanted = DatasetKey::new(&config, &spec);
        let (read, stamp) = read_dataset(dir.path(), &wanted).unwrap();
        assert_eq!(stamp.trials, 2);
        assert_eq!(read.trials.len(), kept.trials.len());
        for (a, b) in read.trials.iter().zip(&kept.trials) {
            assert_eq!(a.plan, b.plan);
            assert_eq!(a.hops, b.hops);
            assert_eq!(a.attempts, b.attempts);
            assert_eq!(a.recording.grid(), b.recording.grid());
            assert_eq!(a.recording.present(), b.recording.present());
            assert_eq!(a.recording.frame_period_s(), b.recording.frame_period_s());
            assert!(
                a.recording.data() == b.recording.data(),
                "{}",
                a.plan.name()
            );
        }
        assert_eq!(read.velocity_table(), kept.velocity_table());
        check_simulator(&config, &spec, &read).unwrap();
        let mut stale = read.clone();
        stale.trials[0].hops[0].truth.apex_height_m += 1e-9;
        let err = check_simulator(&config, &spec, &stale).unwrap_err();
        assert!(
            format!("{err:#}").contains("no longer makes its trial carpet_G2_000"),
            "{err:#}"
        );

        // Another seed, load or configuration is not this data set.
        let mut other = spec.clone();
        other.seed = 12;
        let err = read_dataset(dir.path(), &DatasetKey::new(&config, &other)).unwrap_err();
        assert_eq!(format!("{err:#}"), "it was made with seed 11, not 12");
        let mut other = spec.clone();
        other.load_kg = Some(3.0);
        let err = read_dataset(dir.path(), &DatasetKey::new(&config, &other)).unwrap_err();
        assert_eq!(format!("{err:#}"), "it was simulated at 2.5 kg, not 3 kg");
        let mut changed = config.clone();
        changed.realism.sensor_noise_counts += 1.0;
        let err = read_dataset(dir.path(), &DatasetKey::new(&changed, &spec)).unwrap_err();
        assert!(
            format!("{err:#}").contains("another simulator configuration"),
            "{err:#}"
        );

        // A movie changed, even by one digit: not reused; restored: reused.
        let movie = dir.path().join("recordings/grass_G2_000.asf");
        let original = std::fs::read(&movie).unwrap();
        let mut bytes = original.clone();
        let at = bytes.len() / 2
            + bytes[bytes.len() / 2..]
                .iter()
                .position(u8::is_ascii_digit)
                .unwrap();
        bytes[at] = if bytes[at] == b'1' { b'2' } else { b'1' };
        std::fs::write(&movie, &bytes).unwrap();
        let err = read_dataset(dir.path(), &wanted).unwrap_err();
        assert!(
            format!("{err:#}").contains("grass_G2_000.asf has changed since it was written"),
            "{err:#}"
        );
        std::fs::write(&movie, &original).unwrap();
        read_dataset(dir.path(), &wanted).unwrap();

        // The truth file changed: not reused.
        let truth = dir.path().join("truth/trials.json");
        let mut text = std::fs::read_to_string(&truth).unwrap();
        text.push(' ');
        std::fs::write(&truth, text).unwrap();
        let err = read_dataset(dir.path(), &wanted).unwrap_err();
        assert!(
            format!("{err:#}").contains("trials.json has changed"),
            "{err:#}"
        );

        // A smaller data set in the same folder: the old movies it does not have are removed.
        let mut smaller = spec.clone();
        smaller.terrains = vec!["grass".into()];
        write_dataset_with(&config, &smaller, dir.path(), false, &Quiet).unwrap();
        assert!(!dir.path().join("recordings/carpet_G2_000.asf").exists());
        assert!(dir.path().join("recordings/grass_G2_000.asf").exists());
        read_dataset(dir.path(), &DatasetKey::new(&config, &smaller)).unwrap();

        // Rewriting removes the old stamp before anything else: a failure half-way leaves none.
        std::fs::remove_dir_all(dir.path().join("truth")).unwrap();
        std::fs::write(dir.path().join("truth"), "a file where a folder belongs").unwrap();
        assert!(write_dataset_with(&config, &spec, dir.path(), false, &Quiet).is_err());
        assert!(!dir.path().join(STAMP_FILE).exists());
        let err = read_dataset(dir.path(), &wanted).unwrap_err();
        assert!(format!("{err:#}").contains("has no stamp.json"), "{err:#}");
    }
}
