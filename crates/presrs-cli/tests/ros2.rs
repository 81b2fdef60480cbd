//! `presrs ros2`'s command line: a bad option value is a usage error (exit 2), before the model is read
//! and before the node joins a graph. The node itself is tested against Cyclone DDS in `tests/ros2/`.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers outside #[test] functions

mod common;
use common::{presrs, stderr};

/// `presrs ros2` with domain id `id`, a model that does not exist, and a topic.
fn ros2_on_domain(id: &str) -> std::process::Output {
    let args = [
        "ros2",
        "--model",
        "no-such.model.json",
        "--input",
        "foot/pressure",
    ];
    presrs(&[&args[..], &["--domain-id", id]].concat())
}

#[test]
fn a_domain_id_outside_ros2_s_range_is_a_usage_error() {
    for bad in ["233", "300", "65536", "-1", "seven"] {
        let out = ros2_on_domain(bad);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{bad}: {err}");
        assert!(
            err.contains("ROS 2 domain ids are 0 to 232"),
            "{bad}: {err}"
        );
        assert!(err.contains("--domain-id"), "{bad}: {err}");
    }
}

#[test]
fn a_domain_id_in_range_goes_on_to_the_model() {
    for good in ["0", "232"] {
        let out = ros2_on_domain(good);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(1), "{good}: {err}");
        assert!(err.contains("no-such.model.json"), "{good}: {err}");
    }
}
