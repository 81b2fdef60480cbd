//! `presrs plot`: option values that would draw a meaningless picture are bad usage (exit 2), refused
//! before the recording is read.

#![allow(clippy::expect_used)] // the shared helpers in common/ run the binary outside #[test] functions

mod common;
use common::{presrs, stderr};

#[test]
fn a_colour_scale_or_stride_that_means_nothing_is_bad_usage() {
    let dir = tempfile::tempdir().expect("a temporary folder");
    let out = dir.path().join("x.png");
    let out = out.to_str().expect("a UTF-8 temporary path");
    let gif = dir.path().join("x.gif");
    let gif = gif.to_str().expect("a UTF-8 temporary path");
    for args in [
        &["plot", "walk.asf", "--out", out, "--vmax=-5"][..],
        &["plot", "walk.asf", "--out", out, "--vmax", "nan"],
        &["plot", "walk.asf", "--out", out, "--vmax", "inf"],
        &["plot", "walk.asf", "--out", out, "--vmax", "0"],
        &["plot", "walk.asf", "--out", gif, "--movie", "--stride", "0"],
        &[
            "plot",
            "walk.asf",
            "--out",
            gif,
            "--movie",
            "--max-frames",
            "0",
        ],
    ] {
        let output = presrs(args);
        assert_eq!(
            output.status.code(),
            Some(2),
            "{args:?}: {}",
            stderr(&output)
        );
        assert!(
            stderr(&output).contains("invalid value"),
            "{args:?}: {}",
            stderr(&output)
        );
    }
    assert!(
        std::fs::read_dir(dir.path())
            .expect("the folder")
            .next()
            .is_none()
    );
}
