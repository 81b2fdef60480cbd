//! Helpers shared by the CLI test binaries (each binary uses a subset).
#![allow(dead_code, clippy::unwrap_used)]

use std::process::{Command, Output, Stdio};

/// Runs the `presrs` binary with `args` and no standard input.
pub fn presrs(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_presrs"))
        .args(args)
        .stdin(Stdio::null())
        .output()
        .expect("the presrs binary runs")
}

pub fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).into_owned()
}

pub fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// Trains a whole-stance model (rocket + ridge) of the one-contact trials of `manifest` into `model`,
/// asserting that training succeeded.
pub fn train_one_contact_stance_model(manifest: &std::path::Path, model: &std::path::Path) {
    let out = presrs(&[
        "train",
        "--manifest",
        manifest.to_str().unwrap(),
        "--out",
        model.to_str().unwrap(),
        "--sample",
        "stance",
        "--one-sample-per-file",
        "--features",
        "rocket",
        "--classifier",
        "ridge",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
}

/// Writes a labelled image set of `rows x cols` NPY images under `dir` and returns its manifest: `n`
/// images per class of `classes` textures (stripes of a class-specific frequency and orientation, with
/// noise), in `groups` groups (`g0`, `g1`, ...) taken in turn; `group_shift` scales a per-group offset
/// of the stripes' phase and amplitude (0: groups alike). Deterministic in `seed`.
pub fn write_image_set(
    dir: &std::path::Path,
    (rows, cols): (usize, usize),
    classes: usize,
    n: usize,
    groups: usize,
    group_shift: f64,
    seed: u64,
) -> std::path::PathBuf {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut manifest = String::from("path,label,condition,group\n");
    for class in 0..classes {
        for i in 0..n {
            let group = i % groups.max(1);
            let shift = group_shift * group as f64;
            let (fr, fc) = (0.15 + 0.2 * class as f64, 0.1 + 0.05 * class as f64);
            let data: Vec<f64> = (0..rows * cols)
                .map(|k| {
                    let (r, c) = ((k / cols) as f64, (k % cols) as f64);
                    (1.0 + 0.5 * shift) * (10.0 + 5.0 * (fr * r + fc * c + shift).sin())
                        + rng.random_range(0.0..2.0)
                })
                .collect();
            let name = format!("c{class}_{i}.npy");
            let file = std::fs::File::create(dir.join(&name)).unwrap();
            presrs_io::npy::write_npy_f64(file, &[rows, cols], &data).unwrap();
            manifest.push_str(&format!("{name},t{class},press,g{group}\n"));
        }
    }
    let path = dir.join("manifest.csv");
    std::fs::write(&path, manifest).unwrap();
    path
}
