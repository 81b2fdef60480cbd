//! ROS 2 bags (MCAP) through the command line: recordings converted to bags train, classify and stream
//! exactly as the TekScan files they came from; `stream --record` writes the frames and the decisions;
//! `inspect` lists a bag's topics; bad bags and bad options are clear errors.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::OnceLock;

use presrs_io::mcap::{BagFrames, list_topics};
use serde_json::Value;

fn presrs() -> Command {
    Command::new(env!("CARGO_BIN_EXE_presrs"))
}

fn run(args: &[&str]) -> Output {
    presrs().args(args).output().unwrap()
}

fn run_ok(args: &[&str]) -> String {
    let out = run(args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

fn s(path: &Path) -> &str {
    path.to_str().unwrap()
}

fn fixture_bag(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../presrs-io/tests/fixtures/mcap")
        .join(name)
}

/// A simulated data set, every recording also converted to a bag, with a manifest of each.
struct Data {
    dir: PathBuf,
    asf_manifest: PathBuf,
    bag_manifest: PathBuf,
}

fn data() -> &'static Data {
    static DATA: OnceLock<Data> = OnceLock::new();
    DATA.get_or_init(|| {
        // (under cargo's target/tmp, not the system's temp dir: a static is never dropped, so it
        // cannot hold a self-removing temp dir, and these used to pile up in /tmp)
        let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
            .join(format!("presrs-mcap-test-{}", std::process::id()));
        run_ok(&[
            "simulate",
            "--out",
            s(&dir),
            "--seed",
            "5",
            "--gaits",
            "G2",
            "--hops-per-gait",
            "8",
        ]);
        let asf_manifest = dir.join("manifest.csv");
        let text = std::fs::read_to_string(&asf_manifest).unwrap();
        for entry in std::fs::read_dir(dir.join("recordings")).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "asf") {
                let out = run_ok(&["convert", s(&path), s(&path.with_extension("mcap"))]);
                assert!(out.contains("(mono16,"), "{out}");
            }
        }
        let bag_manifest = dir.join("manifest_mcap.csv");
        std::fs::write(&bag_manifest, text.replace(".asf,", ".mcap,")).unwrap();
        Data {
            dir,
            asf_manifest,
            bag_manifest,
        }
    })
}

fn train(manifest: &Path, out: &Path) {
    run_ok(&[
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
        "10",
        "--seed",
        "3",
    ]);
}

fn results(model: &Path, files: &[PathBuf]) -> Vec<Value> {
    let mut args = vec!["classify", "--model", s(model), "--json"];
    args.extend(files.iter().map(|f| s(f)));
    let doc: Value = serde_json::from_str(&run_ok(&args)).unwrap();
    doc["results"].as_array().unwrap().clone()
}

fn recordings(ext: &str) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(data().dir.join("recordings"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == ext))
        .collect();
    files.sort();
    files
}

#[test]
fn bags_train_and_classify_like_the_tekscan_files() {
    let d = data();
    let (asf_model, bag_model) = (d.dir.join("asf.model.json"), d.dir.join("bag.model.json"));
    train(&d.asf_manifest, &asf_model);
    train(&d.bag_manifest, &bag_model);
    let asf = results(&asf_model, &recordings("asf"));
    let bag = results(&bag_model, &recordings("mcap"));
    assert!(asf.len() >= 8, "{}", asf.len());
    assert_eq!(asf.len(), bag.len());
    for (a, b) in asf.iter().zip(&bag) {
        assert_eq!(a["frame"], b["frame"]);
        assert_eq!(a["label"], b["label"]);
        assert_eq!(a["posteriors"], b["posteriors"], "{a} vs {b}");
    }
    // The bag's frame period is the file's.
    let inspect: Value =
        serde_json::from_str(&run_ok(&["inspect", s(&recordings("mcap")[0]), "--json"])).unwrap();
    let asf_inspect: Value =
        serde_json::from_str(&run_ok(&["inspect", s(&recordings("asf")[0]), "--json"])).unwrap();
    assert_eq!(inspect["frame_period_s"], asf_inspect["frame_period_s"]);
    assert_eq!(inspect["stances"], asf_inspect["stances"]);
    assert_eq!(inspect["topic"], "/presrs/frames");
}

fn stream(model: &Path, extra: &[&str], input: Vec<u8>) -> (Output, Vec<Value>) {
    let mut child = presrs()
        .args(["stream", "--model", s(model)])
        .args(extra)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    let writer = std::thread::spawn(move || stdin.write_all(&input));
    let out = child.wait_with_output().unwrap();
    let _ = writer.join().unwrap();
    let lines = String::from_utf8(out.stdout.clone())
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    (out, lines)
}

/// The decisions of a stream, without what depends on the clock.
fn decisions(lines: &[Value]) -> Vec<Value> {
    lines
        .iter()
        .filter(|l| l["event"] != "end")
        .map(|l| {
            let mut l = l.clone();
            if let Some(o) = l.as_object_mut() {
                o.remove("latency_us");
                o.remove("timestamp_us");
            }
            l
        })
        .collect()
}

#[test]
fn bags_stream_like_the_tekscan_files_and_sessions_are_recorded() {
    let d = data();
    let model = d.dir.join("stream.model.json");
    train(&d.asf_manifest, &model);
    let asf = recordings("asf")[1].clone();
    let bag = asf.with_extension("mcap");
    let (out, from_asf) = stream(&model, &[], std::fs::read(&asf).unwrap());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let record = d.dir.join("session.mcap");
    let (out, from_bag) = stream(
        &model,
        &["--format", "mcap", "--record", s(&record)],
        std::fs::read(&bag).unwrap(),
    );
    let log = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{log}");
    let decided = decisions(&from_asf);
    assert!(decided.iter().any(|l| l["event"] == "classification"));
    assert_eq!(decided, decisions(&from_bag));
    // Frames carry the bag's stamps: timestamp_us counts frame periods.
    let stamped: Vec<&Value> = from_bag
        .iter()
        .filter(|l| l["event"] == "classification")
        .collect();
    assert!(stamped.iter().all(|l| l["timestamp_us"].is_u64()));

    // The recorded bag: every frame as read, every line as written.
    assert!(log.contains("recorded"), "{log}");
    let topics = list_topics(std::fs::File::open(&record).unwrap(), "session.mcap").unwrap();
    let counts: Vec<(&str, &str, u64)> = topics
        .iter()
        .map(|t| (t.topic.as_str(), t.schema.as_str(), t.messages))
        .collect();
    let original = presrs_io::read_recording(&asf).unwrap();
    assert_eq!(
        counts,
        [
            (
                "/presrs/decisions",
                "presrs/Decision",
                from_bag.len() as u64
            ),
            (
                "/presrs/frames",
                "sensor_msgs/msg/Image",
                original.frame_count() as u64
            ),
        ]
    );
    let mut frames = BagFrames::new(
        std::fs::File::open(&record).unwrap(),
        "session.mcap",
        Some("/presrs/frames"),
    );
    let mut values = Vec::new();
    let mut index = 0;
    while let Some(frame) = frames.next_frame(&mut values).unwrap() {
        assert_eq!(frame.grid, original.grid());
        assert_eq!(values, original.frame(index).unwrap().values());
        index += 1;
    }
    assert_eq!(index, original.frame_count());
    assert!(
        !std::fs::read_dir(&d.dir).unwrap().any(|e| e
            .unwrap()
            .file_name()
            .to_string_lossy()
            .ends_with(".tmp")),
        "no temporary file is left"
    );
}

#[test]
fn inspect_lists_the_topics_of_a_bag() {
    let bag = fixture_bag("two_topics.mcap");
    let text = run_ok(&["inspect", s(&bag)]);
    assert!(
        text.contains("topic          /left  sensor_msgs/msg/Image  6 messages (described below)"),
        "{text}"
    );
    assert!(
        text.contains("/right  std_msgs/msg/UInt16MultiArray  6 messages (frames: --topic"),
        "{text}"
    );
    assert!(
        text.contains("/status  std_msgs/msg/String  6 messages\n"),
        "{text}"
    );
    let doc: Value = serde_json::from_str(&run_ok(&[
        "inspect",
        s(&bag),
        "--topic",
        "/right",
        "--json",
    ]))
    .unwrap();
    assert_eq!(doc["topic"], "/right");
    assert_eq!(
        (doc["rows"].as_u64(), doc["cols"].as_u64()),
        (Some(2), Some(3))
    );
    assert_eq!(doc["topics"].as_array().unwrap().len(), 3);
    // Another command asks for a topic (and writes nothing).
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("x.png");
    let out = run(&["plot", s(&bag), "--out", s(&png)]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("several topics (/left, /right"), "{err}");
    assert!(!png.exists());
}

#[test]
fn bad_bags_and_outputs_are_clear_errors_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.mcap");
    let cases: [(PathBuf, &[&str], &str); 4] = [
        (
            fixture_bag("size_change.mcap"),
            &[],
            "topic /foot message 3: a 3x4 frame, the earlier ones are 3x3",
        ),
        (
            fixture_bag("bad_encoding.mcap"),
            &[],
            "topic /camera message 0: image encoding \"rgb8\" is not supported",
        ),
        (
            fixture_bag("two_topics.mcap"),
            &["--topic", "/status"],
            "topic /status holds std_msgs/msg/String messages, not frames",
        ),
        (
            fixture_bag("gap.mcap"),
            &["--topic", "/nothing"],
            "no messages on topic /nothing",
        ),
    ];
    for (input, extra, expected) in cases {
        let mut args = vec!["convert", s(&input), s(&out)];
        args.extend_from_slice(extra);
        let result = run(&args);
        let err = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(1), "{err}");
        assert!(err.contains(expected), "{err}");
        assert!(err.contains(s(&input)), "the error names the file: {err}");
        assert!(!out.exists());
    }
    let result = run(&[
        "convert",
        s(&fixture_bag("gap.mcap")),
        s(&dir.path().join("x.npy")),
    ]);
    assert_eq!(result.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&result.stderr).contains("must be an MCAP file"));
    // A bag converted again keeps its values and period.
    let text = run_ok(&["convert", s(&fixture_bag("gap.mcap")), s(&out)]);
    assert!(text.contains("9 frames of 3x3"), "{text}");
    let back = presrs_io::read_recording(&out).unwrap();
    let original = presrs_io::read_recording(&fixture_bag("gap.mcap")).unwrap();
    assert_eq!(back.data(), original.data());
    assert_eq!(back.frame_period_s(), Some(0.01));
}

#[test]
fn classify_writes_its_frames_and_decisions_to_a_bag() {
    let d = data();
    let model = d.dir.join("classify.model.json");
    train(&d.asf_manifest, &model);
    let files: Vec<PathBuf> = recordings("asf").into_iter().take(2).collect();
    let bag = d.dir.join("classified.mcap");
    let mut args = vec![
        "classify",
        "--model",
        s(&model),
        "--json",
        "--mcap",
        s(&bag),
    ];
    args.extend(files.iter().map(|f| s(f)));
    let doc: Value = serde_json::from_str(&run_ok(&args)).unwrap();
    let results = doc["results"].as_array().unwrap().len() as u64;
    assert!(results >= 2);
    let frames: usize = files
        .iter()
        .map(|f| presrs_io::read_recording(f).unwrap().frame_count())
        .sum();
    let stances: usize = files
        .iter()
        .map(|f| {
            let rec = presrs_io::read_recording(f).unwrap();
            presrs_core::stance::segment_recording(
                &rec,
                &presrs_core::stance::ValidSegmentParams::default(),
            )
            .unwrap()
            .stances
            .len()
        })
        .sum();
    let topics = list_topics(std::fs::File::open(&bag).unwrap(), "classified.mcap").unwrap();
    let counts: Vec<(&str, u64)> = topics
        .iter()
        .map(|t| (t.topic.as_str(), t.messages))
        .collect();
    assert_eq!(
        counts,
        [
            ("/presrs/decisions", results + 2 * stances as u64),
            ("/presrs/frames", frames as u64)
        ]
    );
    // The frames follow each other: the first file's, then the second's.
    let back = presrs_io::read_recording(&bag).unwrap();
    let first = presrs_io::read_recording(&files[0]).unwrap();
    assert_eq!(back.frame_count(), frames);
    assert_eq!(&back.data()[..first.data().len()], first.data());
}

/// What a recorded bag's metadata says of its frame times (`presrs.recording`, `frame_times`): the
/// record is written outside the compressed chunks, so its strings can be found in the file's bytes.
fn frame_times(bag: &Path) -> &'static str {
    let bytes = std::fs::read(bag).unwrap();
    let has = |text: &str| bytes.windows(text.len()).any(|w| w == text.as_bytes());
    assert!(
        has("presrs.recording") && has("frame_times"),
        "{}",
        bag.display()
    );
    ["input", "wall_clock", "mixed"]
        .into_iter()
        .find(|t| has(t))
        .unwrap()
}

/// `stream --record` of a TekScan file stamps its frames with the file's own period (not the wall
/// clock, which read back as thousands of Hz with gaps); a file that states none takes --frame-period,
/// else the wall clock; the bag's metadata says which.
#[test]
fn recorded_bags_keep_the_input_s_frame_times() {
    let d = data();
    let model = d.dir.join("times.model.json");
    train(&d.asf_manifest, &model);
    let asf = recordings("asf")[0].clone();
    let text = std::fs::read_to_string(&asf).unwrap();
    assert!(
        text.contains("SECONDS_PER_FRAME 0.01"),
        "the simulator states its period"
    );
    let untimed: String = text
        .lines()
        .filter(|l| !l.starts_with("SECONDS_PER_FRAME"))
        .map(|l| format!("{l}\n"))
        .collect();
    for (case, input, extra, times) in [
        ("stated", text.clone(), &[][..], "input"),
        ("none", untimed.clone(), &[][..], "wall_clock"),
        ("given", untimed, &["--frame-period", "0.01"][..], "input"),
    ] {
        let record = d.dir.join(format!("times-{case}.mcap"));
        let mut args = vec!["--record", s(&record)];
        args.extend_from_slice(extra);
        let (out, lines) = stream(&model, &args, input.into_bytes());
        let log = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{case}: {log}");
        assert!(
            log.contains(&format!("(frame times: {times})")),
            "{case}: {log}"
        );
        assert_eq!(frame_times(&record), times, "{case}");
        if times == "input" {
            let back: Value =
                serde_json::from_str(&run_ok(&["inspect", s(&record), "--json"])).unwrap();
            let period = back["frame_period_s"].as_f64().unwrap();
            assert!((period - 0.01).abs() < 1e-9, "{case}: {back}");
            assert_eq!(back["warnings"], serde_json::json!([]), "{case}: {back}");
            let classified = lines.iter().filter(|l| l["event"] == "classification");
            assert!(classified.clone().count() > 0);
            assert!(
                classified.into_iter().all(|l| l["timestamp_us"].is_u64()),
                "{case}"
            );
        }
    }
}
