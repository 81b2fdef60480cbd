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

/// Every other bad option value (QoS, depth, node name, namespace, input topic) and a bad
/// `ROS_DOMAIN_ID` (the option's environment stand-in, as clap treats one) are usage errors too, said
/// before the model is read.
#[test]
fn every_bad_option_value_is_a_usage_error() {
    let base = ["ros2", "--model", "no-such.model.json"];
    let cases: [(&[&str], &str); 5] = [
        (
            &["--input", "p", "--input-qos", "fast"],
            "unknown input QoS \"fast\"",
        ),
        (&["--input", "p", "--input-depth", "0"], "depth is 0"),
        (&["--input", "p", "--name", "two words"], "node name"),
        (&["--input", "p", "--namespace", "robot"], "namespace"),
        (&["--input", "a//b"], "topic name"),
    ];
    for (args, says) in cases {
        let out = presrs(&[&base[..], args].concat());
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
        assert!(!err.contains("no-such.model.json"), "{args:?}: {err}");
    }
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_presrs"))
        .args(base)
        .args(["--input", "p"])
        .env("ROS_DOMAIN_ID", "250")
        .output()
        .unwrap();
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("ROS_DOMAIN_ID") && err.contains("250"),
        "{err}"
    );
}

/// A recording (or any file that is not a model) given as the model is named for what it is, with how
/// to get a model; "corrupted" is kept for a damaged model file.
#[test]
fn a_recording_given_as_the_model_is_named_for_what_it_is() {
    let dir = tempfile::tempdir().unwrap();
    let walk = dir.path().join("walk.npy");
    let mut npy = Vec::new();
    presrs_io::npy::write_npy_f64(&mut npy, &[2, 2, 2], &[0.0; 8]).unwrap();
    std::fs::write(&walk, npy).unwrap();
    for command in ["ros2", "classify"] {
        let mut args = vec![command, "--model", walk.to_str().unwrap()];
        args.extend(if command == "ros2" {
            ["--input", "p"]
        } else {
            ["x.npy", "--json"]
        });
        let out = presrs(&args);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(1), "{command}: {err}");
        assert!(
            err.contains("walk.npy: a NumPy array (.npy) file, not a presrs model file")
                && err.contains("presrs train"),
            "{command}: {err}"
        );
        assert!(!err.contains("corrupted"), "{command}: {err}");
    }
}
