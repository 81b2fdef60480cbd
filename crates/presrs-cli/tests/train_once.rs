//! `presrs train` reads each recording once: the online profile written into the model is learned from
//! the recordings as training read them (`--axes`, `--topic`, a manifest's `topic` column), not from a
//! second reading with the default options. Small synthetic movies written to a temporary folder.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;
use std::process::{Command, Output};

use presrs_core::Grid;
use presrs_io::mcap::{BagWriter, ImageEncoding};
use serde_json::Value;

const GRID: Grid = Grid { rows: 12, cols: 10 };
const CLASSES: [&str; 3] = ["grass", "gravel", "wood"];

fn presrs(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_presrs"))
        .args(args)
        .output()
        .unwrap()
}

fn s(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// A movie of one class, frames x rows x cols (row-major), integer loads (a bag's mono16 keeps them
/// exactly): 3 stances of 14 frames (half-sine load on the class's print, `scale` times its height)
/// between 10 unloaded frames, each movie's print a little different (`seed`).
fn movie(class: usize, seed: u64, scale: f64) -> Vec<f64> {
    let mut state = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
    let mut noise = move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 33) as f64 / f64::from(u32::MAX)
    };
    let print: Vec<f64> = (0..GRID.rows)
        .flat_map(|r| (0..GRID.cols).map(move |c| (r, c)))
        .map(|(r, c)| {
            let stripe = if (r + c * class) % (class + 2) == 0 {
                1.6
            } else {
                1.0
            };
            let (dr, dc) = (r as f64 - 5.5 - class as f64, c as f64 - 4.5);
            let dome = (30.0 - dr * dr - dc * dc).max(0.0);
            (dome * stripe * 20.0) * (0.9 + 0.2 * noise())
        })
        .collect();
    let mut data = vec![0.0; 10 * GRID.len()];
    for _ in 0..3 {
        for k in 0..14 {
            let height = scale * (std::f64::consts::PI * (k as f64 + 0.5) / 14.0).sin();
            data.extend(print.iter().map(|v| (v * height).round()));
        }
        data.extend(std::iter::repeat_n(0.0, 10 * GRID.len()));
    }
    data
}

/// `data` (frames x rows x cols) laid out as rows x cols x frames.
fn time_last(data: &[f64]) -> Vec<f64> {
    let frames = data.len() / GRID.len();
    let mut out = Vec::with_capacity(data.len());
    for index in 0..GRID.len() {
        out.extend((0..frames).map(|f| data[f * GRID.len() + index]));
    }
    out
}

fn write_npy(path: &Path, shape: &[usize], data: &[f64]) {
    let file = std::fs::File::create(path).unwrap();
    presrs_io::npy::write_npy_f64(std::io::BufWriter::new(file), shape, data).unwrap();
}

/// The movies of a data set, two of each class: `(label, group, movie)`.
fn movies(scale: f64) -> Vec<(&'static str, String, Vec<f64>)> {
    (0..6)
        .map(|i| {
            let class = i % CLASSES.len();
            (
                CLASSES[class],
                format!("t{}", i / CLASSES.len()),
                movie(class, i as u64, scale),
            )
        })
        .collect()
}

/// Trains on `manifest` with a fixed method and `extra` options; returns the model file's JSON.
fn train(manifest: &Path, out: &Path, extra: &[&str]) -> Value {
    let mut args = vec![
        "train",
        "--manifest",
        s(manifest),
        "--out",
        s(out),
        "--features",
        "fft1d",
        "--classifier",
        "lda",
        "--dims",
        "4",
    ];
    args.extend_from_slice(extra);
    let run = presrs(&args);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{args:?}: {stderr}");
    assert!(!stderr.contains("no online profile written"), "{stderr}");
    serde_json::from_str(&std::fs::read_to_string(out).unwrap()).unwrap()
}

/// The model and its online profile, calibrated.
fn model_and_profile(file: &Value) -> (&Value, &Value) {
    let online = &file["online"];
    assert!(online["calibration"].is_object(), "{online}");
    (&file["model"], online)
}

#[test]
fn movies_saved_time_last_train_the_same_model_and_profile_with_their_axes() {
    let dir = tempfile::tempdir().unwrap();
    let mut default = String::from("path,label,group\n");
    let mut transposed = default.clone();
    for (i, (label, group, data)) in movies(1.0).iter().enumerate() {
        let frames = data.len() / GRID.len();
        write_npy(
            &dir.path().join(format!("m{i}.npy")),
            &[frames, GRID.rows, GRID.cols],
            data,
        );
        write_npy(
            &dir.path().join(format!("m{i}_rcf.npy")),
            &[GRID.rows, GRID.cols, frames],
            &time_last(data),
        );
        default.push_str(&format!("m{i}.npy,{label},{group}\n"));
        transposed.push_str(&format!("m{i}_rcf.npy,{label},{group}\n"));
    }
    let (default_manifest, transposed_manifest) =
        (dir.path().join("frames.csv"), dir.path().join("rcf.csv"));
    std::fs::write(&default_manifest, default).unwrap();
    std::fs::write(&transposed_manifest, transposed).unwrap();

    let by_default = train(&default_manifest, &dir.path().join("a.json"), &[]);
    let time_last = train(
        &transposed_manifest,
        &dir.path().join("b.json"),
        &["--axes", "rows,cols,frames"],
    );
    let (model, profile) = model_and_profile(&by_default);
    let (model_rcf, profile_rcf) = model_and_profile(&time_last);
    assert_eq!(model, model_rcf);
    assert_eq!(profile, profile_rcf);
}

/// Writes a bag of two image topics: `/left` holds `left`, `/right` holds `right`.
fn write_bag(path: &Path, left: &[f64], right: &[f64]) {
    let file = std::fs::File::create(path).unwrap();
    let mut bag = BagWriter::new(std::io::BufWriter::new(file), s(path)).unwrap();
    for (topic, data) in [("/left", left), ("/right", right)] {
        let channel = bag.add_image_topic(topic).unwrap();
        for (index, frame) in data.chunks(GRID.len()).enumerate() {
            let time = index as u64 * 10_000_000;
            bag.write_image(channel, time, GRID, frame, ImageEncoding::Mono16)
                .unwrap();
        }
    }
    bag.finish().unwrap();
}

#[test]
fn a_topic_of_two_trains_the_profile_of_its_own_frames() {
    let dir = tempfile::tempdir().unwrap();
    let mut npy = String::from("path,label,group\n");
    let mut bags = npy.clone();
    let mut bags_by_column = String::from("path,label,group,topic\n");
    // The other topic carries three times the load: a profile learned from it is calibrated apart.
    for (i, ((label, group, left), (_, _, right))) in
        movies(1.0).iter().zip(movies(3.0).iter().rev()).enumerate()
    {
        let frames = left.len() / GRID.len();
        write_npy(
            &dir.path().join(format!("m{i}.npy")),
            &[frames, GRID.rows, GRID.cols],
            left,
        );
        write_bag(&dir.path().join(format!("m{i}.mcap")), left, right);
        npy.push_str(&format!("m{i}.npy,{label},{group}\n"));
        bags.push_str(&format!("m{i}.mcap,{label},{group}\n"));
        bags_by_column.push_str(&format!("m{i}.mcap,{label},{group},/left\n"));
    }
    let manifests = ["npy.csv", "bags.csv", "topics.csv"].map(|name| dir.path().join(name));
    for (path, text) in manifests.iter().zip([npy, bags, bags_by_column]) {
        std::fs::write(path, text).unwrap();
    }

    let from_npy = train(&manifests[0], &dir.path().join("npy.json"), &[]);
    let by_option = train(
        &manifests[1],
        &dir.path().join("bag.json"),
        &["--topic", "/left"],
    );
    let by_column = train(&manifests[2], &dir.path().join("column.json"), &[]);
    let (model, profile) = model_and_profile(&from_npy);
    for trained in [&by_option, &by_column] {
        let (bag_model, bag_profile) = model_and_profile(trained);
        assert_eq!(model, bag_model);
        assert_eq!(profile, bag_profile);
    }
}
