//! `presrs stream` and `presrs replay` end to end: stdin, several TCP clients at once, and faults
//! (malformed, oversized and wrong-size frames, a client that disconnects mid-frame) that must not
//! affect the other clients. Every server is started with `--exit-after N` and stops by itself; the
//! test kills it (by its own child handle) only if it failed to.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{Shutdown, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

use presrs_io::frame_protocol::{Dtype, encode_frame};
use serde_json::Value;

fn presrs() -> Command {
    Command::new(env!("CARGO_BIN_EXE_presrs"))
}

fn run_ok(args: &[&str]) -> String {
    let out = presrs().args(args).output().unwrap();
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// A small simulated data set and a model trained on it (built once per test binary).
fn fixture() -> &'static (PathBuf, PathBuf) {
    static FIXTURE: OnceLock<(PathBuf, PathBuf)> = OnceLock::new();
    FIXTURE.get_or_init(|| {
        // (under cargo's target/tmp, not the system's temp dir: a static is never dropped, so it
        // cannot hold a self-removing temp dir, and these used to pile up in /tmp)
        let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
            .join(format!("presrs-stream-test-{}", std::process::id()));
        let dir_s = dir.to_str().unwrap();
        run_ok(&[
            "simulate",
            "--out",
            dir_s,
            "--seed",
            "5",
            "--gaits",
            "G2",
            "--hops-per-gait",
            "12",
        ]);
        let manifest = dir.join("manifest.csv");
        let model = dir.join("model.json");
        run_ok(&[
            "train",
            "--manifest",
            manifest.to_str().unwrap(),
            "--out",
            model.to_str().unwrap(),
            "--per-class",
            "8",
            "--validation",
            "4",
            "--dims",
            "10",
            // These tests show the warm-up: a model without a profile.
            "--no-online-profile",
        ]);
        (dir, model)
    })
}

fn recording(terrain: &str) -> PathBuf {
    fixture().0.join(format!("recordings/{terrain}_G2_000.asf"))
}

fn json_lines(text: &str) -> Vec<Value> {
    text.lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
        .collect()
}

fn count(events: &[Value], kind: &str) -> usize {
    events.iter().filter(|e| e["event"] == kind).count()
}

/// Offline complete stances of a recording.
fn offline_stances(path: &Path) -> usize {
    let rec = presrs_io::read_recording(path).unwrap();
    let seg = presrs_core::stance::segment(
        &rec.total_per_frame(),
        &presrs_core::stance::ValidSegmentParams::default(),
    )
    .unwrap();
    seg.complete().count()
}

/// `--decide-at` is for whole-stance models: with a one-frame model it is an error saying why, before
/// any frame is read.
#[test]
fn decide_at_with_a_one_frame_model_is_refused() {
    let (_, model) = fixture();
    let output = presrs()
        .args([
            "stream",
            "--model",
            model.to_str().unwrap(),
            "--decide-at",
            "5",
        ])
        .stdin(Stdio::null())
        .output()
        .unwrap();
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("--decide-at 5") && stderr.contains("whole-stance"),
        "{stderr}"
    );
    assert!(output.stdout.is_empty(), "no event before the refusal");
}

#[test]
fn stdin_tekscan_gives_one_decision_per_stance() {
    let (dir, model) = fixture();
    let path = recording("grass");
    let mut child = presrs()
        .args(["stream", "--model", model.to_str().unwrap(), "--calibrate"])
        .arg(dir.join("manifest.csv"))
        .args(["--fuse", "5,6,7", "--gait", "grass=G3"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Write the movie in small pieces, as a live writer would.
    let bytes = std::fs::read(&path).unwrap();
    let mut stdin = child.stdin.take().unwrap();
    let writer = std::thread::spawn(move || {
        for chunk in bytes.chunks(7919) {
            stdin.write_all(chunk).unwrap();
        }
    });
    let out = child.wait_with_output().unwrap();
    writer.join().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let events = json_lines(&String::from_utf8(out.stdout).unwrap());
    let stances = offline_stances(&path);
    assert!(stances >= 10);
    let singles: Vec<&Value> = events
        .iter()
        .filter(|e| e["event"] == "classification" && e["kind"] == "single")
        .collect();
    assert_eq!(singles.len(), stances);
    assert_eq!(count(&events, "liftoff"), stances);
    assert_eq!(count(&events, "touchdown"), stances);
    let fused = events.iter().filter(|e| e["kind"] == "fused").count();
    assert_eq!(fused, stances);
    let grass = singles.iter().filter(|e| e["label"] == "grass").count();
    assert!(grass * 10 >= stances * 7, "{grass}/{stances} grass");
    for e in &singles {
        assert!(e["latency_us"].as_f64().unwrap() >= 0.0);
        assert!(e["posteriors"]["grass"].is_number());
        if e["label"] == "grass" {
            assert_eq!(e["gait"], "G3");
        }
    }
    assert_eq!(events.last().unwrap()["event"], "end");
}

struct Server {
    child: Child,
    addr: String,
}

impl Server {
    fn start(extra: &[&str]) -> Self {
        let (dir, _) = fixture();
        let manifest = dir.join("manifest.csv");
        Self::start_with(&[&["--calibrate", manifest.to_str().unwrap()], extra].concat())
    }

    /// A server without `--calibrate`: each connection calibrates on its first frames (warm-up).
    fn start_with(extra: &[&str]) -> Self {
        let (_, model) = fixture();
        let mut child = presrs()
            .args(["stream", "--model", model.to_str().unwrap()])
            .args(["--listen", "127.0.0.1:0"])
            .args(extra)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut first = String::new();
        BufReader::new(child.stdout.as_mut().unwrap())
            .read_line(&mut first)
            .unwrap();
        let v: Value = serde_json::from_str(&first).unwrap();
        assert_eq!(v["event"], "listening");
        let addr = v["addr"].as_str().unwrap().to_owned();
        assert!(addr.starts_with("127.0.0.1:"));
        Self { child, addr }
    }

    /// Waits (bounded) for the server to exit by itself; returns its stderr.
    fn finish(mut self) -> String {
        let deadline = Instant::now() + Duration::from_secs(60);
        loop {
            if let Some(status) = self.child.try_wait().unwrap() {
                let mut err = String::new();
                self.child
                    .stderr
                    .take()
                    .unwrap()
                    .read_to_string(&mut err)
                    .unwrap();
                assert!(status.success(), "server failed: {err}");
                return err;
            }
            if Instant::now() > deadline {
                let _ = self.child.kill();
                panic!("the server did not stop by itself");
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}

fn replay(addr: &str, path: &Path) -> Vec<Value> {
    let out = presrs()
        .args(["replay"])
        .arg(path)
        .args(["--connect", addr, "--rate", "max"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    json_lines(&String::from_utf8(out.stdout).unwrap())
}

fn frame_bytes(rows: usize, cols: usize, dtype: Dtype, values: &[f64]) -> Vec<u8> {
    let mut buf = Vec::new();
    encode_frame(&mut buf, rows, cols, dtype, 0, values).unwrap();
    buf
}

fn read_all_lines(stream: TcpStream) -> Vec<Value> {
    stream
        .set_read_timeout(Some(Duration::from_secs(30)))
        .unwrap();
    let mut text = String::new();
    BufReader::new(stream).read_to_string(&mut text).unwrap();
    json_lines(&text)
}

#[test]
fn a_servers_messages_name_the_connection() {
    // No calibration given: the connection's warm-up note goes to stderr, under the client's address
    // (with several clients, whose stream it is about).
    let server = Server::start_with(&["--exit-after", "1"]);
    let events = replay(&server.addr, &recording("wood"));
    assert_eq!(events.last().unwrap()["event"], "end");
    let log = server.finish();
    let note = log
        .lines()
        .find(|line| line.contains("warm-up calibration"))
        .unwrap_or_else(|| panic!("no warm-up note: {log}"));
    let client = note
        .strip_prefix("presrs stream: 127.0.0.1:")
        .and_then(|rest| rest.split_once(": "))
        .map(|(port, _)| port);
    assert!(
        client.is_some_and(|port| port.parse::<u16>().is_ok()),
        "{note}"
    );
}

#[test]
fn several_clients_at_once_and_faulty_clients_do_not_disturb_them() {
    // Two good clients, one sending bad frames then a fatal one, one disconnecting mid-frame.
    let server = Server::start(&["--exit-after", "4"]);
    let addr = server.addr.clone();
    let (wood, grass) = (recording("wood"), recording("grass"));
    let good = {
        let (addr, wood, grass) = (addr.clone(), wood.clone(), grass.clone());
        std::thread::spawn(move || {
            let a = std::thread::spawn({
                let addr = addr.clone();
                move || replay(&addr, &wood)
            });
            let b = replay(&addr, &grass);
            (a.join().unwrap(), b)
        })
    };

    // Faulty client 1: good frames, a wrong-size frame, an unknown dtype, a NaN, then an oversized
    // declaration (fatal).
    let mut bad = TcpStream::connect(&addr).unwrap();
    let zeros = vec![0.0; 44 * 44];
    bad.write_all(&frame_bytes(44, 44, Dtype::U8, &zeros))
        .unwrap();
    bad.write_all(&frame_bytes(4, 4, Dtype::U8, &[0.0; 16]))
        .unwrap();
    let mut unknown = frame_bytes(44, 44, Dtype::U8, &zeros);
    unknown[12] = 77;
    bad.write_all(&unknown).unwrap();
    let mut nan = zeros.clone();
    nan[5] = f64::NAN;
    bad.write_all(&frame_bytes(44, 44, Dtype::F64, &nan))
        .unwrap();
    bad.write_all(&frame_bytes(44, 44, Dtype::U8, &zeros))
        .unwrap();
    let mut huge = frame_bytes(1, 1, Dtype::U8, &[0.0]);
    huge[4..8].copy_from_slice(&u32::MAX.to_le_bytes());
    bad.write_all(&huge).unwrap();
    let bad_events = read_all_lines(bad);
    let errors: Vec<&Value> = bad_events
        .iter()
        .filter(|e| e["event"] == "error")
        .collect();
    assert_eq!(errors.len(), 4, "{bad_events:?}");
    assert!(errors[0]["message"].as_str().unwrap().contains("4x4"));
    assert!(
        errors[1]["message"]
            .as_str()
            .unwrap()
            .contains("unknown dtype 77")
    );
    assert!(
        errors[2]["message"]
            .as_str()
            .unwrap()
            .contains("not finite")
    );
    assert!(
        errors[3]["message"]
            .as_str()
            .unwrap()
            .contains("exceeds the limit")
    );
    assert_eq!(errors[3]["fatal"], true);
    let end = bad_events.last().unwrap();
    assert_eq!(
        (end["event"].as_str(), end["frames"].as_u64()),
        (Some("end"), Some(2))
    );
    // The wrong size, the unknown dtype and the NaN frame were rejected; with the fatal one, 4 errors.
    assert_eq!(
        (end["rejected_frames"].as_u64(), end["errors"].as_u64()),
        (Some(3), Some(4))
    );

    // Faulty client 2: half a frame, then gone.
    let mut cut = TcpStream::connect(&addr).unwrap();
    let frame = frame_bytes(44, 44, Dtype::U8, &zeros);
    cut.write_all(&frame[..frame.len() / 2]).unwrap();
    cut.shutdown(Shutdown::Write).unwrap();
    let cut_events = read_all_lines(cut);
    assert!(
        cut_events.iter().any(|e| e["event"] == "error"
            && e["message"]
                .as_str()
                .unwrap()
                .contains("ended inside a message")),
        "{cut_events:?}"
    );

    let (wood_events, grass_events) = good.join().unwrap();
    for (events, path) in [(&wood_events, &wood), (&grass_events, &grass)] {
        let stances = offline_stances(path);
        let singles = events
            .iter()
            .filter(|e| e["event"] == "classification" && e["kind"] == "single")
            .count();
        assert_eq!(singles, stances, "{}", path.display());
        assert_eq!(count(events, "error"), 0);
        let end = events.last().unwrap();
        assert_eq!(end["event"], "end");
        assert_eq!(end["dropped_events"], 0);
        assert!(
            events
                .iter()
                .all(|e| e["event"] != "classification" || e["timestamp_us"].is_u64())
        );
    }
    let log = server.finish();
    assert!(log.contains("ended inside a message"), "{log}");
    assert!(log.contains("exceeds the limit"), "{log}");
}

#[test]
fn clients_over_the_limit_are_refused_and_non_loopback_is_rejected() {
    let server = Server::start(&["--exit-after", "2", "--max-clients", "1"]);
    let first = TcpStream::connect(&server.addr).unwrap();
    // Give the server time to register the first client.
    std::thread::sleep(Duration::from_millis(300));
    let second = read_all_lines(TcpStream::connect(&server.addr).unwrap());
    assert!(
        second[0]["message"]
            .as_str()
            .unwrap()
            .contains("server full"),
        "{second:?}"
    );
    first.shutdown(Shutdown::Write).unwrap();
    let events = read_all_lines(first);
    assert_eq!(events.last().unwrap()["frames"], 0);
    server.finish();

    let (_, model) = fixture();
    let out = presrs()
        .args([
            "stream",
            "--model",
            model.to_str().unwrap(),
            "--listen",
            "0.0.0.0:0",
        ])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("only loopback"));
}

#[test]
fn malformed_tekscan_on_stdin_is_reported_and_skipped() {
    let (_, model) = fixture();
    let text = std::fs::read_to_string(recording("wood")).unwrap();
    // Break one data row (too few values) in frame 3.
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    let frame3 = lines.iter().position(|l| l == "Frame 3").unwrap();
    lines[frame3 + 2] = "1,2,3".to_owned();
    let mut child = presrs()
        .args(["stream", "--model", model.to_str().unwrap()])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    let body = lines.join("\n");
    let writer = std::thread::spawn(move || stdin.write_all(body.as_bytes()));
    let out = child.wait_with_output().unwrap();
    writer.join().unwrap().unwrap();
    // The rest was classified, and the exit code says the input was bad.
    let log = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{log}");
    assert!(log.contains("1 rejected frames, 1 errors"), "{log}");
    assert!(
        log.contains("error: stdin: 1 rejected frame(s), 1 error(s)"),
        "{log}"
    );
    let events = json_lines(&String::from_utf8(out.stdout).unwrap());
    let errors: Vec<&Value> = events.iter().filter(|e| e["event"] == "error").collect();
    assert_eq!(errors.len(), 1, "{errors:?}");
    assert!(
        errors[0]["message"]
            .as_str()
            .unwrap()
            .contains("frame 3 row 2 has 3 values")
    );
    let end = events.last().unwrap();
    let frames = presrs_io::read_recording(&recording("wood"))
        .unwrap()
        .frame_count();
    assert_eq!(end["frames"].as_u64().unwrap() as usize, frames - 1);
    assert_eq!(
        (end["rejected_frames"].as_u64(), end["errors"].as_u64()),
        (Some(1), Some(1))
    );
    assert!(count(&events, "classification") > 0);
}

/// `presrs stream --model MODEL` (+ `extra`) on `input` as stdin: exit code, JSON events, stderr.
fn stream_stdin(extra: &[&str], input: Vec<u8>) -> (Option<i32>, Vec<Value>, String) {
    let (_, model) = fixture();
    let mut child = presrs()
        .args(["stream", "--model", model.to_str().unwrap()])
        .args(extra)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    let writer = std::thread::spawn(move || stdin.write_all(&input));
    let out = child.wait_with_output().unwrap();
    // A stream that stops on a fatal error reads no further: the rest may not be written.
    let _ = writer.join().unwrap();
    let events = json_lines(&String::from_utf8(out.stdout).unwrap());
    (
        out.status.code(),
        events,
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn a_good_stream_exits_0_and_says_what_the_warm_up_took() {
    let text = std::fs::read(recording("wood")).unwrap();
    let (code, events, log) = stream_stdin(&[], text);
    assert_eq!(code, Some(0), "{log}");
    assert!(
        log.contains("warm-up calibration done on the first 128 frames: stances before frame 128 were not classified"),
        "{log}"
    );
    assert!(log.contains("0 rejected frames, 0 errors"), "{log}");
    assert_eq!(count(&events, "error"), 0);
    // With a calibration there is no warm-up, and no note.
    let (dir, _) = fixture();
    let manifest = dir.join("manifest.csv");
    let text = std::fs::read(recording("wood")).unwrap();
    let (code, _, log) = stream_stdin(&["--calibrate", manifest.to_str().unwrap()], text);
    assert_eq!(code, Some(0), "{log}");
    assert!(!log.contains("warm-up"), "{log}");
}

#[test]
fn a_truncated_last_frame_or_a_bad_cell_on_stdin_exits_1_after_the_rest() {
    let text = std::fs::read_to_string(recording("wood")).unwrap();
    // Cut inside the last frame's rows (5 of its 44 rows, no end marker).
    let lines: Vec<&str> = text.lines().collect();
    let last = lines.iter().rposition(|l| l.starts_with("Frame ")).unwrap();
    let cut = lines[..=last + 5].join("\n");
    let (code, events, log) = stream_stdin(&[], cut.into_bytes());
    assert_eq!(code, Some(1), "{log}");
    assert!(count(&events, "classification") > 0);
    let end = events.last().unwrap();
    assert_eq!(end["event"], "end");
    assert_eq!(end["errors"].as_u64(), Some(count(&events, "error") as u64));
    assert!(end["errors"].as_u64().unwrap() >= 1, "{log}");
    // A non-numeric cell in frame 5.
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    let frame5 = lines.iter().position(|l| l == "Frame 5").unwrap();
    lines[frame5 + 3] = lines[frame5 + 3].replacen('0', "x", 1);
    let (code, events, log) = stream_stdin(&[], lines.join("\n").into_bytes());
    assert_eq!(code, Some(1), "{log}");
    let end = events.last().unwrap();
    assert_eq!(
        (end["rejected_frames"].as_u64(), end["errors"].as_u64()),
        (Some(1), Some(1))
    );
    assert!(count(&events, "classification") > 0);
}

#[test]
fn a_stream_the_model_cannot_use_gets_one_error_and_stops() {
    // A 60x21 foot-scan recording; the model was trained on 44x44 images.
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/tekscan/FrasP01L.asf");
    let Ok(text) = std::fs::read(&path) else {
        eprintln!("skipped: {} is not there", path.display());
        return;
    };
    let (code, events, log) = stream_stdin(&[], text);
    assert_eq!(code, Some(1), "{log}");
    // One fatal error, not one per frame (205 of them).
    let errors: Vec<&Value> = events.iter().filter(|e| e["event"] == "error").collect();
    assert_eq!(errors.len(), 1, "{errors:?}");
    assert_eq!(errors[0]["fatal"], true);
    let message = errors[0]["message"].as_str().unwrap();
    assert!(
        message.starts_with("input frame 0 rejected: a 60x21 frame") && message.contains("stops"),
        "{message}"
    );
    assert_eq!(count(&events, "classification"), 0);
    let end = events.last().unwrap();
    assert_eq!(
        (
            end["frames"].as_u64(),
            end["rejected_frames"].as_u64(),
            end["errors"].as_u64()
        ),
        (Some(0), Some(1), Some(1))
    );
    assert!(log.contains("1 rejected frames, 1 errors"), "{log}");
}

#[test]
fn two_tekscan_files_on_stdin_are_one_stream_or_a_clear_error() {
    let wood = std::fs::read_to_string(recording("wood")).unwrap();
    let grass = std::fs::read_to_string(recording("grass")).unwrap();
    let frames = |path: &Path| presrs_io::read_recording(path).unwrap().frame_count() as u64;
    let (code, events, log) = stream_stdin(&[], format!("{wood}{grass}").into_bytes());
    assert_eq!(code, Some(0), "{log}");
    let end = events.last().unwrap();
    assert_eq!(
        end["frames"].as_u64(),
        Some(frames(&recording("wood")) + frames(&recording("grass"))),
        "{end}"
    );
    let labels: Vec<&str> = events
        .iter()
        .filter(|e| e["event"] == "classification")
        .filter_map(|e| e["label"].as_str())
        .collect();
    assert!(labels.contains(&"grass"), "{labels:?}");

    // A second file of another size: a fatal error naming both sizes, after the first file's frames.
    let small = "ROWS 4\nCOLS 4\nASCII_DATA @@\nFrame 1\n0,0,0,0\n0,0,0,0\n0,0,0,0\n0,0,0,0\n@@\n";
    let (code, events, log) = stream_stdin(&[], format!("{wood}{small}").into_bytes());
    assert_eq!(code, Some(1), "{log}");
    let errors: Vec<&Value> = events.iter().filter(|e| e["event"] == "error").collect();
    assert_eq!(errors.len(), 1, "{errors:?}");
    assert_eq!(errors[0]["fatal"], true);
    let message = errors[0]["message"].as_str().unwrap();
    assert!(
        message.contains("4x4 frames where the first had 44x44"),
        "{message}"
    );
    assert_eq!(
        events.last().unwrap()["frames"].as_u64(),
        Some(frames(&recording("wood")))
    );
}

#[test]
fn a_client_whose_stream_ends_in_the_warm_up_is_told_why() {
    let server = Server::start_with(&["--exit-after", "1"]);
    let mut client = TcpStream::connect(&server.addr).unwrap();
    let zeros = vec![0.0; 44 * 44];
    for _ in 0..20 {
        client
            .write_all(&frame_bytes(44, 44, Dtype::U8, &zeros))
            .unwrap();
    }
    client.shutdown(Shutdown::Write).unwrap();
    let events = read_all_lines(client);
    let end = events.last().unwrap();
    assert_eq!(
        (end["event"].as_str(), end["decisions"].as_u64()),
        (Some("end"), Some(0))
    );
    assert_eq!(end["warmup_frames"].as_u64(), Some(20), "{end}");
    let note = end["note"].as_str().unwrap_or_default();
    assert!(
        note.contains("ended during the warm-up calibration (20 frames)"),
        "{end}"
    );
    server.finish();
}

/// Sends `signal` (INT or TERM) to `child`.
fn send_signal(child: &Child, signal: &str) {
    let status = Command::new("kill")
        .args([&format!("-{signal}"), &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
}

#[test]
fn sigint_on_stdin_writes_the_end_line_and_exits_cleanly() {
    let (_, model) = fixture();
    let mut child = presrs()
        .args(["stream", "--model", model.to_str().unwrap()])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // A whole movie, with the input left open (a live sensor that goes on).
    let mut stdin = child.stdin.take().unwrap();
    stdin
        .write_all(&std::fs::read(recording("wood")).unwrap())
        .unwrap();
    let mut stdout = BufReader::new(child.stdout.take().unwrap());
    let mut first = String::new();
    stdout.read_line(&mut first).unwrap();
    assert!(first.contains("\"event\""), "{first}");
    send_signal(&child, "INT");
    let mut rest = String::new();
    stdout.read_to_string(&mut rest).unwrap();
    let status = child.wait().unwrap();
    drop(stdin);
    let mut log = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut log)
        .unwrap();
    assert_eq!(status.code(), Some(0), "{log}");
    let events = json_lines(&rest);
    let end = events.last().unwrap();
    assert_eq!(end["event"], "end", "{rest}");
    assert!(end["frames"].as_u64().unwrap() > 0);
    assert!(log.contains("stopped by SIGINT"), "{log}");
}

#[test]
fn sigterm_stops_the_server_with_a_final_summary() {
    let mut server = Server::start_with(&[]);
    let events = replay(&server.addr, &recording("wood"));
    assert_eq!(events.last().unwrap()["event"], "end");
    send_signal(&server.child, "TERM");
    let mut rest = String::new();
    server
        .child
        .stdout
        .take()
        .unwrap()
        .read_to_string(&mut rest)
        .unwrap();
    let stopped = json_lines(&rest);
    let last = stopped.last().unwrap();
    assert_eq!(
        (last["event"].as_str(), last["signal"].as_str()),
        (Some("stopped"), Some("SIGTERM")),
        "{rest}"
    );
    assert_eq!(last["connections"].as_u64(), Some(1));
    server.finish();
}

#[test]
fn bad_addresses_gait_entries_and_limits_are_bad_usage() {
    for args in [
        &["stream", "--model", "m.json", "--listen", "nonsense"][..],
        &["stream", "--model", "m.json", "--listen", "0.0.0.0:7700"],
        &["stream", "--model", "m.json", "--gait", "wood"],
        &["replay", "walk.asf", "--connect", "nonsense"],
        &[
            "replay",
            "walk.asf",
            "--connect",
            "127.0.0.1:1",
            "--rate",
            "0",
        ],
        &["stream", "--model", "m.json", "--max-clients", "0"],
        &["stream", "--model", "m.json", "--queue", "0"],
        &["stream", "--model", "m.json", "--max-frame-bytes", "0"],
        &["stream", "--model", "m.json", "--idle-timeout", "0"],
        &["stream", "--model", "m.json", "--idle-timeout", "1e30"],
        &[
            "replay",
            "walk.asf",
            "--connect",
            "127.0.0.1:1",
            "--timeout=-1",
        ],
    ] {
        let out = presrs().args(args).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains("invalid value"), "{args:?}: {err}");
    }
    let help = presrs().args(["replay", "--help"]).output().unwrap();
    let help = String::from_utf8_lossy(&help.stdout);
    assert_eq!(help.matches("[default: 100]").count(), 1, "{help}");
}

#[test]
fn a_closed_stdout_ends_a_live_stream() {
    // `presrs stream ... | head`: the input stays open (a live sensor), the reader of the decisions
    // goes away; presrs must end by itself, quietly.
    let (_, model) = fixture();
    let mut child = presrs()
        .args(["stream", "--model", model.to_str().unwrap()])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let mut stdin = child.stdin.take().unwrap();
    // presrs may be gone before all is written: that is the point.
    let _ = stdin.write_all(&std::fs::read(recording("wood")).unwrap());
    let deadline = Instant::now() + Duration::from_secs(30);
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("presrs stream went on with nobody reading its output");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    drop(stdin);
    let mut log = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut log)
        .unwrap();
    assert_eq!(status.code(), Some(0), "{log}");
    assert!(!log.contains("error:"), "{log}");
}

/// The stance settings of training (`--stance-threshold`, `--stance-hysteresis`) are stored in the
/// model's online profile, and `stream` segments with them: its stances are those of the offline
/// segmentation with the same settings, not with the defaults.
#[test]
fn a_model_trained_with_stance_options_streams_with_them() {
    let (dir, _) = fixture();
    let model = dir.join("model-stance-options.json");
    run_ok(&[
        "train",
        "--manifest",
        dir.join("manifest.csv").to_str().unwrap(),
        "--out",
        model.to_str().unwrap(),
        "--per-class",
        "8",
        "--validation",
        "4",
        "--dims",
        "10",
        "--online-profile",
        "--stance-threshold",
        "0.5",
        "--stance-hysteresis",
        "0.3",
    ]);
    let file: Value = serde_json::from_str(&std::fs::read_to_string(&model).unwrap()).unwrap();
    let stored = &file["online"]["segment"];
    assert_eq!(stored["on_fraction"], 0.5, "{stored}");
    assert_eq!(stored["off_fraction"], 0.3, "{stored}");
    assert_eq!(stored["baseline"], "auto", "{stored}");

    let path = recording("grass");
    let out = presrs()
        .args(["stream", "--model", model.to_str().unwrap()])
        .stdin(std::fs::File::open(&path).unwrap())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let events = json_lines(&String::from_utf8(out.stdout).unwrap());
    let online: Vec<(u64, u64)> = events
        .iter()
        .filter(|e| e["event"] == "liftoff" && e["partial"] != true)
        .map(|e| {
            let start = e["touchdown_frame"].as_u64().unwrap();
            (start, e["len"].as_u64().unwrap_or(0))
        })
        .collect();
    let rec = presrs_io::read_recording(&path).unwrap();
    let offline = |params: &presrs_core::stance::SegmentParams| -> Vec<(u64, u64)> {
        presrs_core::stance::segment(&rec.total_per_frame(), &params.check().unwrap())
            .unwrap()
            .complete()
            .map(|s| (s.start as u64, s.len as u64))
            .collect()
    };
    let trained = offline(&presrs_core::stance::SegmentParams {
        on_fraction: 0.5,
        off_fraction: 0.3,
        ..Default::default()
    });
    let default = offline(&Default::default());
    assert!(trained.len() >= 10);
    assert_ne!(
        trained[1..],
        default[1..],
        "the options must change the stances"
    );
    assert_eq!(online.len(), trained.len(), "{online:?} vs {trained:?}");
    // From the second stance on: before the first, the online load range is the calibration's prior
    // (half the trained range), so the first touchdown may come a frame or two early.
    for (&(start, len), &(want_start, want_len)) in online.iter().zip(&trained).skip(1) {
        assert!(
            start.abs_diff(want_start) <= 1 && (start + len).abs_diff(want_start + want_len) <= 1,
            "online {online:?} vs offline with the trained options {trained:?}"
        );
    }
}

/// `train` on movies, without flags, writes the online profile: a stream started with the fresh model
/// classifies every complete stance of a movie, its first one included, with no warm-up.
#[test]
fn a_model_trained_on_movies_streams_from_its_first_stance() {
    let (dir, _) = fixture();
    let model = dir.join("fresh.model.json");
    run_ok(&[
        "train",
        "--manifest",
        dir.join("manifest.csv").to_str().unwrap(),
        "--out",
        model.to_str().unwrap(),
        "--features",
        "fft1d",
        "--classifier",
        "lda",
        "--per-class",
        "8",
        "--dims",
        "10",
    ]);
    let file: Value = serde_json::from_str(&std::fs::read_to_string(&model).unwrap()).unwrap();
    assert!(
        file["online"]["calibration"].is_object(),
        "{}",
        file["online"]
    );
    let path = recording("clay");
    let out = presrs()
        .args(["stream", "--model", model.to_str().unwrap()])
        .stdin(std::fs::File::open(&path).unwrap())
        .output()
        .unwrap();
    let log = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{log}");
    assert!(!log.contains("warm-up"), "{log}");
    let events = json_lines(&String::from_utf8(out.stdout).unwrap());
    let singles = events
        .iter()
        .filter(|e| e["event"] == "classification" && e["kind"] == "single")
        .count();
    assert_eq!(singles, offline_stances(&path), "{events:?}");
    assert_eq!(events.last().unwrap()["warmup_frames"], 0, "{events:?}");
}

/// `--record` with `--listen`: one bag per connection (OUT-1.mcap, OUT-2.mcap in the order the clients
/// connected), each holding what its client sent at the sender's times, its metadata naming the client.
#[test]
fn a_server_records_one_bag_per_connection() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("session.mcap");
    let server = Server::start(&["--exit-after", "2", "--record", out.to_str().unwrap()]);
    let (wood, grass) = (recording("wood"), recording("grass"));
    replay(&server.addr, &wood);
    replay(&server.addr, &grass);
    let err = server.finish();
    for (n, path) in [(1, &wood), (2, &grass)] {
        let bag = dir.path().join(format!("session-{n}.mcap"));
        assert!(err.contains(&bag.display().to_string()), "{err}");
        let sent = presrs_io::read_recording(path).unwrap();
        let back = presrs_io::read_recording(&bag).unwrap();
        assert_eq!(back.frame_count(), sent.frame_count(), "{}", bag.display());
        assert_eq!(back.data(), sent.data(), "{}", bag.display());
        let bytes = std::fs::read(&bag).unwrap();
        let has = |text: &str| bytes.windows(text.len()).any(|w| w == text.as_bytes());
        assert!(
            has("presrs.recording") && has("127.0.0.1:"),
            "{}",
            bag.display()
        );
    }
    assert!(!out.exists(), "no bag under the name given: {err}");
}
