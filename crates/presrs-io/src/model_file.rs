//! Trained model files: readable JSON holding the trained pipeline and where it came from.
//!
//! The file is one JSON object `{"format": "presrs-model", "format_version": 1, "presrs_version": ...,
//! "provenance": {...}, "model": {...}}`. The envelope is checked before the model is decoded, so a file
//! of another format version says so instead of failing on some inner field.

use std::collections::BTreeMap;
use std::path::Path;

use presrs_core::online::OnlineProfile;
use presrs_core::pipeline::TrainedModel;
use serde::{Deserialize, Serialize};

use crate::atomic::write_atomic;
use crate::error::IoError;

/// The `format` field every model file carries.
pub const MODEL_FORMAT: &str = "presrs-model";
/// The envelope version this build writes and reads.
pub const MODEL_FORMAT_VERSION: u32 = 1;

/// Where a model came from: enough to trace it back to its data and settings.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    /// The manifest trained from, as given on the command line.
    pub manifest: Option<String>,
    /// SHA-256 of the manifest's bytes.
    pub manifest_sha256: Option<String>,
    /// Seed of the random choices (sample selection, splits).
    pub seed: Option<u64>,
    /// The condition training was restricted to, if any.
    pub train_condition: Option<String>,
    /// Training and validation images per class.
    pub train_counts: BTreeMap<String, usize>,
    pub validation_counts: BTreeMap<String, usize>,
    /// The command line that made the model.
    pub command: Option<String>,
    /// Seconds since the Unix epoch when the model was written.
    pub created_unix_s: Option<u64>,
    /// Whether dead sensels were filled in the training recordings (absent in files written before
    /// the correction existed, whose recordings were used as read).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dead_sensels: Option<DeadSenselProvenance>,
}

/// How the training recordings' dead sensels were treated.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct DeadSenselProvenance {
    /// Whether they were found and filled (`false`: `--keep-dead-sensels`).
    pub corrected: bool,
    /// Sensels filled, and in how many recordings.
    pub sensels: usize,
    pub recordings: usize,
}

/// A model file's content.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ModelFile {
    pub format: String,
    pub format_version: u32,
    /// The presrs version that wrote the file.
    pub presrs_version: String,
    pub provenance: Provenance,
    pub model: TrainedModel,
    /// How to run the model online (`presrs stream`): detector settings, calibration and the
    /// terrain-to-gait table. Optional and additive: version-1 files without it read as before.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub online: Option<OnlineProfile>,
}

impl ModelFile {
    pub fn new(model: TrainedModel, provenance: Provenance) -> Self {
        Self {
            format: MODEL_FORMAT.to_owned(),
            format_version: MODEL_FORMAT_VERSION,
            presrs_version: env!("CARGO_PKG_VERSION").to_owned(),
            provenance,
            model,
            online: None,
        }
    }
}

/// Writes a model file atomically (a temporary file renamed into place).
pub fn save_model(path: &Path, file: &ModelFile) -> Result<(), IoError> {
    write_atomic(path, |w| {
        serde_json::to_writer_pretty(&mut *w, file).map_err(std::io::Error::from)?;
        writeln!(w)
    })
}

/// Reads a model file, checking its envelope first.
pub fn load_model(path: &Path) -> Result<ModelFile, IoError> {
    let bytes = std::fs::read(path).map_err(|source| IoError::io("read", path, source))?;
    parse_model(&bytes, &path.display().to_string())
}

/// How many of a file's first bytes tell a model file ([`looks_like_model`]).
const MODEL_HEAD_BYTES: usize = 512;

/// Whether the file at `path` is a presrs model file, from its first bytes (the rest is not read).
pub fn is_model_file(path: &Path) -> Result<bool, IoError> {
    Ok(looks_like_model(&crate::read_head(path, MODEL_HEAD_BYTES)?))
}

/// Whether `bytes` (a file's first bytes are enough) start a presrs model file: a JSON object whose
/// `format` field, which [`save_model`] writes first, is [`MODEL_FORMAT`].
pub fn looks_like_model(bytes: &[u8]) -> bool {
    let head = crate::textutil::decode_text(&bytes[..bytes.len().min(MODEL_HEAD_BYTES)]);
    let Some(object) = head.trim_start().strip_prefix('{') else {
        return false;
    };
    let Some(after_key) = object.trim_start().strip_prefix("\"format\"") else {
        return false;
    };
    after_key
        .trim_start()
        .strip_prefix(':')
        .is_some_and(|value| {
            value
                .trim_start()
                .starts_with(&format!("\"{MODEL_FORMAT}\""))
        })
}

/// What a model file given where a recording was expected is told (words every face can show).
pub const MODEL_NOT_RECORDING: &str = "a presrs model file, not a recording: give it where a model is \
     asked for, and recordings where data are (`presrs inspect` describes a model file, as \
     `Model.load(path).describe()` does in Python)";

/// How to get a model, said when a file is not one (words every face can show).
const TRAIN_ONE: &str =
    "train one with `presrs train` (or `presrs.Model.train` and `save` in Python)";

/// What a file that is not JSON holds, when its first bytes say so: a recording (NumPy, PNG, MCAP,
/// TekScan, a text matrix) or a data set's manifest given where a model was expected. `None` for
/// anything else, which a damaged model file (cut short, overwritten) is.
fn other_format(bytes: &[u8]) -> Option<&'static str> {
    let magic = [
        (crate::npy::NPY_MAGIC, "a NumPy array (.npy) file"),
        (crate::png::PNG_MAGIC, "a PNG image"),
        (crate::mcap::MCAP_MAGIC, "an MCAP file (a ROS 2 bag)"),
    ];
    if let Some((_, kind)) = magic.iter().find(|(magic, _)| bytes.starts_with(magic)) {
        return Some(kind);
    }
    let text = crate::textutil::decode_text(&bytes[..bytes.len().min(64 * 1024)]);
    if crate::tekscan::looks_like_tekscan(&text) {
        return Some("a TekScan ASCII recording");
    }
    let first_line = text.lines().find(|line| !line.trim().is_empty())?;
    let fields: Vec<&str> = first_line.split(',').map(str::trim).collect();
    if fields.len() > 1 && fields.contains(&"path") {
        return Some("a CSV manifest (a data set to train on)");
    }
    let numbers_only = text
        .chars()
        .all(|c| c.is_ascii_digit() || c.is_ascii_whitespace() || ".,;+-eE".contains(c));
    (numbers_only && text.chars().any(|c| c.is_ascii_digit()))
        .then_some("a text matrix (a recording)")
}

/// Parses model-file bytes; `file` names the source in errors.
pub fn parse_model(bytes: &[u8], file: &str) -> Result<ModelFile, IoError> {
    let not_model = |why: String| {
        IoError::format(
            file,
            format!("a JSON file, not a presrs model file ({why}); {TRAIN_ONE}"),
        )
    };
    let value: serde_json::Value =
        serde_json::from_slice(bytes).map_err(|err| match other_format(bytes) {
            Some(kind) => IoError::format(
                file,
                format!("{kind}, not a presrs model file; {TRAIN_ONE}"),
            ),
            None => IoError::parse(file, err.line(), format!("corrupted model file: {err}")),
        })?;
    match value.get("format") {
        Some(serde_json::Value::String(format)) if format == MODEL_FORMAT => {}
        Some(format) => {
            return Err(not_model(format!(
                "its format is {format}, expected \"{MODEL_FORMAT}\""
            )));
        }
        None => return Err(not_model("it has no format field".to_owned())),
    }
    let version = value
        .get("format_version")
        .and_then(serde_json::Value::as_u64);
    if version != Some(u64::from(MODEL_FORMAT_VERSION)) {
        let written_by = value
            .get("presrs_version")
            .and_then(serde_json::Value::as_str)
            .unwrap_or("an unknown version");
        return Err(IoError::unsupported(
            file,
            format!(
                "model format version {} (written by presrs {written_by}) is not supported: this presrs \
                 ({}) reads version {MODEL_FORMAT_VERSION}; retrain the model with this version",
                version.map_or_else(|| "missing".to_owned(), |v| v.to_string()),
                env!("CARGO_PKG_VERSION"),
            ),
        ));
    }
    serde_json::from_value(value)
        .map_err(|err| IoError::format(file, format!("corrupted model file: {err}")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use presrs_core::testing::bench_fixture;

    fn model_bytes() -> Vec<u8> {
        let (model, _) = bench_fixture(3, 0).unwrap();
        let file = ModelFile::new(
            model,
            Provenance {
                seed: Some(3),
                ..Provenance::default()
            },
        );
        serde_json::to_vec(&file).unwrap()
    }

    /// A model file is recognised from its first bytes, compact or pretty-printed, and so is nothing
    /// else: other JSON, a manifest, a text matrix; read as a recording, it is named as a model.
    #[test]
    fn a_model_file_is_recognised_from_its_first_bytes_and_refused_as_a_recording() {
        let compact = model_bytes();
        assert!(looks_like_model(&compact));
        let file: ModelFile = serde_json::from_slice(&compact).unwrap();
        let pretty = serde_json::to_vec_pretty(&file).unwrap();
        assert!(looks_like_model(&pretty[..100]));
        for other in [
            &b"{\"format\": \"presrs-eval-draws\"}"[..],
            b"{\"model\": {\"format\": \"presrs-model\"}}",
            b"path,label\na.asf,wood\n",
            b"1 2 3\n4 5 6\n",
            b"",
        ] {
            assert!(
                !looks_like_model(other),
                "{}",
                String::from_utf8_lossy(other)
            );
        }
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("model.json");
        std::fs::write(&path, &pretty).unwrap();
        let err = crate::read_recording(&path).unwrap_err().to_string();
        assert!(
            err.starts_with(&format!(
                "{}: a presrs model file, not a recording",
                path.display()
            )),
            "{err}"
        );
    }

    #[test]
    fn round_trips_through_a_file_and_classifies_the_same() {
        let (model, frames) = bench_fixture(5, 8).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("model.json");
        save_model(&path, &ModelFile::new(model.clone(), Provenance::default())).unwrap();
        let loaded = load_model(&path).unwrap();
        assert_eq!(loaded.format_version, MODEL_FORMAT_VERSION);
        let (mut a, mut b) = (model.session(), loaded.model.session());
        for frame in &frames {
            let pa = a.classify(&frame.view()).unwrap().to_classification();
            let pb = b.classify(&frame.view()).unwrap().to_classification();
            assert_eq!(pa, pb);
        }
    }

    #[test]
    fn files_without_dead_sensel_provenance_still_load() {
        let mut value: serde_json::Value = serde_json::from_slice(&model_bytes()).unwrap();
        assert!(value["provenance"].get("dead_sensels").is_none());
        let old = parse_model(&serde_json::to_vec(&value).unwrap(), "m.json").unwrap();
        assert_eq!(old.provenance.dead_sensels, None);
        value["provenance"]["dead_sensels"] =
            serde_json::json!({"corrected": true, "sensels": 3, "recordings": 2});
        let new = parse_model(&serde_json::to_vec(&value).unwrap(), "m.json").unwrap();
        assert_eq!(
            new.provenance.dead_sensels,
            Some(DeadSenselProvenance {
                corrected: true,
                sensels: 3,
                recordings: 2
            })
        );
    }

    #[test]
    fn files_that_are_no_model_are_named_for_what_they_are() {
        let mut npy = Vec::new();
        crate::npy::write_npy_f64(&mut npy, &[2, 2], &[0.0; 4]).unwrap();
        let mut png = crate::png::PNG_MAGIC.to_vec();
        png.extend_from_slice(&[0; 16]);
        let cases: [(&[u8], &str); 6] = [
            (&npy, "a NumPy array (.npy) file"),
            (&png, "a PNG image"),
            (
                b"SENSOR_TYPE 5051\nROWS 2\nCOLS 2\nASCII_DATA @@\nFrame 1\n1,2\n3,4\n",
                "a TekScan ASCII recording",
            ),
            (b"path,label\nwalk.npy,grass\n", "a CSV manifest"),
            (b"1 2 3\n4 5 6\n", "a text matrix (a recording)"),
            (b"{\"params\": {}}", "a JSON file"),
        ];
        for (bytes, kind) in cases {
            let err = parse_model(bytes, "walk.x").unwrap_err().to_string();
            assert!(
                err.starts_with(&format!("walk.x: {kind}"))
                    && err.contains("not a presrs model file")
                    && err.contains("presrs train"),
                "{kind}: {err}"
            );
            assert!(!err.contains("corrupted"), "{kind}: {err}");
        }
        // A damaged model (cut short, or bytes of nothing known) is still corrupted.
        let model = model_bytes();
        for bytes in [&model[..model.len() / 3], b"\x00\x01garbage{" as &[u8], b""] {
            let err = parse_model(bytes, "m.json").unwrap_err().to_string();
            assert!(err.contains("corrupted model file"), "{err}");
        }
    }

    #[test]
    fn other_versions_and_corruption_are_clear_errors() {
        let bytes = model_bytes();
        let mut value: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
        value["format_version"] = serde_json::json!(99);
        let err = parse_model(&serde_json::to_vec(&value).unwrap(), "m.json")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("format version 99") && err.contains("retrain"),
            "{err}"
        );

        let err = parse_model(&bytes[..bytes.len() / 2], "m.json")
            .unwrap_err()
            .to_string();
        assert!(err.contains("m.json") && err.contains("corrupted"), "{err}");

        let err = parse_model(b"{\"a\": 1}", "m.json")
            .unwrap_err()
            .to_string();
        assert!(err.contains("not a presrs model file"), "{err}");

        value["format_version"] = serde_json::json!(MODEL_FORMAT_VERSION);
        value["model"]["class_names"] = serde_json::json!(["only-one"]);
        let err = parse_model(&serde_json::to_vec(&value).unwrap(), "m.json")
            .unwrap_err()
            .to_string();
        assert!(err.contains("class names"), "{err}");
    }
}
