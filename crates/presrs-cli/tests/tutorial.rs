//! `docs/tutorial.md` stays true: every ```sh block is run, in order, in one empty folder with this
//! build's `presrs` first on the PATH (and `CHECKOUT` naming the clone, as the page asks of a user who
//! takes its real recording from beside the checkout), and must succeed; every picture the page shows
//! must be one its commands made.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};
use std::process::Command;

fn docs() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs")
}

/// The ```sh blocks of a markdown text, in order.
fn sh_blocks(markdown: &str) -> Vec<String> {
    let mut blocks = Vec::new();
    let mut current: Option<String> = None;
    for line in markdown.lines() {
        match (&mut current, line.trim_end()) {
            (None, "```sh") => current = Some(String::new()),
            (Some(block), "```") => {
                blocks.push(std::mem::take(block));
                current = None;
            }
            (Some(block), _) => {
                block.push_str(line);
                block.push('\n');
            }
            (None, _) => {}
        }
    }
    assert!(current.is_none(), "an unclosed ```sh block");
    blocks
}

/// The pictures the page shows from `docs/tutorial/`: their file names.
fn pictures(markdown: &str) -> Vec<String> {
    markdown
        .split("](tutorial/")
        .skip(1)
        .map(|rest| rest[..rest.find(')').unwrap()].to_owned())
        .collect()
}

#[test]
fn every_command_of_the_tutorial_runs() {
    let markdown = std::fs::read_to_string(docs().join("tutorial.md")).unwrap();
    let real =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/tekscan/FrasP01L.asf");
    if !real.is_file() {
        eprintln!("skipped: {} is not there", real.display());
        return;
    }
    // An empty folder, as the tutorial asks: its commands fetch the real recording themselves, from
    // where the page says it is (`CHECKOUT`: the clone, as a user sets it).
    let dir = tempfile::tempdir().unwrap();
    let checkout = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let bin = Path::new(env!("CARGO_BIN_EXE_presrs")).parent().unwrap();
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let blocks = sh_blocks(&markdown);
    assert!(blocks.len() >= 8, "{} blocks", blocks.len());
    for block in &blocks {
        let out = Command::new("bash")
            .args(["-euo", "pipefail", "-c", block])
            .current_dir(dir.path())
            .env("PATH", &path)
            .env("CHECKOUT", &checkout)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "this tutorial block failed ({:?}):\n{block}\nstdout:\n{}\nstderr:\n{}",
            out.status,
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let shown = pictures(&markdown);
    assert!(!shown.is_empty());
    for name in shown {
        assert!(
            dir.path().join(&name).is_file(),
            "tutorial/{name} is shown but no command made {name}"
        );
        assert!(
            docs().join("tutorial").join(&name).is_file(),
            "docs/tutorial/{name} is missing"
        );
    }
    // What the page says came out.
    let end = std::fs::read_to_string(dir.path().join("clay.jsonl")).unwrap();
    let end: serde_json::Value = serde_json::from_str(end.lines().last().unwrap()).unwrap();
    assert_eq!(end["event"], "end");
    assert!(end["decisions"].as_u64().unwrap() > 0);
    let header = std::fs::read_to_string(dir.path().join("foot-features.csv")).unwrap();
    assert!(header.starts_with("frame,fft2d_polar_ring0,"));
}
