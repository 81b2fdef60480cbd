//! What a simulated data set's folder was made from and holds: the key (presrs version, seed, terrains,
//! gaits, hops, load, the configuration's fingerprint), the size and SHA-256 of every file, and the
//! reading and writing that check and record them.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::Path;

use presrs_sim::{DatasetSpec, SimConfig};
use sha2::{Digest, Sha256};

use crate::error::{Context, Error, Result};

/// The stamp of a data set folder. It is written last, so its presence claims a complete data set.
pub const STAMP_FILE: &str = "stamp.json";

/// Layout version of [`DatasetStamp`]; a stamp of another format is not trusted (format 1 had 64-bit
/// FNV fingerprints where format 2 has SHA-256).
pub(super) const STAMP_FORMAT: u32 = 2;

/// What a data set was made from. Equal keys, equal data sets: the simulator is deterministic.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DatasetKey {
    pub presrs_version: String,
    pub seed: u64,
    pub terrains: Vec<String>,
    pub gaits: Vec<String>,
    /// Recorded hops per terrain and gait (the configuration's default resolved).
    pub hops_per_gait: usize,
    /// Body mass including payload, kg (the configuration's default resolved).
    pub load_kg: f64,
    /// Fingerprint of the simulator configuration as `config.json` holds it.
    pub config_fingerprint: String,
    /// Terrains given as height-map images: name and fingerprint of the map.
    pub image_terrains: Vec<(String, String)>,
}

impl DatasetKey {
    /// The key of the data set `config` and `spec` describe, made by this version of presrs.
    pub fn new(config: &SimConfig, spec: &DatasetSpec) -> Self {
        let image_terrains = spec
            .image_terrains
            .iter()
            .map(|(name, map)| {
                let mut hash = Fingerprint::new();
                hash.update(&(map.width as u64).to_le_bytes());
                hash.update(&(map.height as u64).to_le_bytes());
                for v in &map.values {
                    hash.update(&v.to_le_bytes());
                }
                (name.clone(), hash.hex())
            })
            .collect();
        Self {
            presrs_version: env!("CARGO_PKG_VERSION").to_owned(),
            seed: spec.seed,
            terrains: spec.terrains.clone(),
            gaits: spec.gaits.clone(),
            hops_per_gait: spec
                .hops_per_gait
                .unwrap_or(config.experiment.hops_per_gait),
            load_kg: spec.load_kg.unwrap_or(config.robot.body_mass_kg),
            config_fingerprint: Fingerprint::of(config_json(config).as_bytes()).hex(),
            image_terrains,
        }
    }

    /// Why a data set made with `self` is not the one `wanted` describes (`None`: it is).
    pub fn mismatch(&self, wanted: &Self) -> Option<String> {
        let list = |v: &[String]| v.join(",");
        if self.presrs_version != wanted.presrs_version {
            Some(format!(
                "it was made by presrs {}, this is presrs {}",
                self.presrs_version, wanted.presrs_version
            ))
        } else if self.seed != wanted.seed {
            Some(format!(
                "it was made with seed {}, not {}",
                self.seed, wanted.seed
            ))
        } else if self.hops_per_gait != wanted.hops_per_gait {
            Some(format!(
                "it has {} hops per terrain and gait, not {}",
                self.hops_per_gait, wanted.hops_per_gait
            ))
        } else if self.load_kg.to_bits() != wanted.load_kg.to_bits() {
            Some(format!(
                "it was simulated at {} kg, not {} kg",
                self.load_kg, wanted.load_kg
            ))
        } else if self.terrains != wanted.terrains {
            Some(format!(
                "its terrains are {}, not {}",
                list(&self.terrains),
                list(&wanted.terrains)
            ))
        } else if self.gaits != wanted.gaits {
            Some(format!(
                "its gaits are {}, not {}",
                list(&self.gaits),
                list(&wanted.gaits)
            ))
        } else if self.config_fingerprint != wanted.config_fingerprint {
            Some(format!(
                "it was made with another simulator configuration (fingerprint {}, not {})",
                self.config_fingerprint, wanted.config_fingerprint
            ))
        } else if self.image_terrains != wanted.image_terrains {
            Some("its height-map terrains differ".to_owned())
        } else {
            None
        }
    }
}

/// Size and fingerprint (64-bit, hexadecimal) of a file of the data set.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct FileStamp {
    pub bytes: u64,
    pub fingerprint: String,
}

/// `stamp.json`: what the data set was made from and every file it consists of.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DatasetStamp {
    pub format: u32,
    pub made_from: DatasetKey,
    pub trials: usize,
    pub frames: usize,
    /// Every file of the data set, by path relative to its folder.
    pub files: BTreeMap<String, FileStamp>,
}

/// The bytes of `dir/rel`, checked against the stamp's size and fingerprint.
pub(super) fn read_checked(dir: &Path, rel: &str, stamp: &DatasetStamp) -> Result<Vec<u8>> {
    let path = dir.join(rel);
    let expected = stamp
        .files
        .get(rel)
        .ok_or_else(|| Error::data(format!("{STAMP_FILE} does not list {rel}")))?;
    let bytes = match std::fs::read(&path) {
        Ok(bytes) => bytes,
        Err(err) if err.kind() == std::io::ErrorKind::NotFound => {
            bail!("{} is missing", path.display())
        }
        Err(err) => return Err(err).with_context(|| format!("cannot read {}", path.display())),
    };
    let actual = FileStamp {
        bytes: bytes.len() as u64,
        fingerprint: Fingerprint::of(&bytes).hex(),
    };
    ensure!(
        actual == *expected,
        "{} has changed since it was written ({} bytes, fingerprint {}; the stamp says {} bytes, {})",
        path.display(),
        actual.bytes,
        actual.fingerprint,
        expected.bytes,
        expected.fingerprint
    );
    Ok(bytes)
}

/// Writes `out_dir/rel` atomically with `write`, returning its size and fingerprint.
pub(super) fn write_hashed(
    out_dir: &Path,
    rel: &str,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<FileStamp> {
    let path = out_dir.join(rel);
    let stamp = presrs_io::write_atomic(&path, |w| {
        let mut hashing = HashingWriter {
            inner: w,
            hash: Fingerprint::new(),
            bytes: 0,
        };
        write(&mut hashing)?;
        Ok(FileStamp {
            bytes: hashing.bytes,
            fingerprint: hashing.hash.hex(),
        })
    })?;
    Ok(stamp)
}

/// The configuration as `config.json` holds it.
pub(super) fn config_json(config: &SimConfig) -> String {
    format!("{}\n", config.to_json_pretty())
}

/// SHA-256 of bytes fed in pieces, as lowercase hex: the fingerprint of a data set's files and of
/// what it was made from.
#[derive(Clone, Debug, Default)]
pub(super) struct Fingerprint(Sha256);

impl Fingerprint {
    pub(super) fn new() -> Self {
        Self::default()
    }

    pub(super) fn of(bytes: &[u8]) -> Self {
        let mut hash = Self::new();
        hash.update(bytes);
        hash
    }

    pub(super) fn update(&mut self, bytes: &[u8]) {
        self.0.update(bytes);
    }

    pub(super) fn hex(self) -> String {
        self.0
            .finalize()
            .iter()
            .map(|byte| format!("{byte:02x}"))
            .collect()
    }
}

/// A writer that fingerprints and counts what passes through it.
struct HashingWriter<'a> {
    inner: &'a mut dyn Write,
    hash: Fingerprint,
    bytes: u64,
}

impl Write for HashingWriter<'_> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.hash.update(&buf[..n]);
        self.bytes += n as u64;
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}
