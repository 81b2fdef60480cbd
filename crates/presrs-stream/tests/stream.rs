//! The stream server embedded in a program: bound on 127.0.0.1:0 in a thread, fed synthetic stances in
//! the binary protocol by clients, stopped through its handle. Also one session over in-memory bytes.
//! Every socket has a read timeout, and the server is stopped even when a check fails, so a fault ends
//! the test instead of hanging it.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::io::{BufRead, BufReader, Write};
use std::net::{Shutdown, SocketAddr, TcpStream};
use std::sync::Mutex;
use std::time::Duration;

use presrs::Method;
use presrs::core::online::{Calibration, OnlineProfile};
use presrs::core::pipeline::{LabeledImage, TrainedModel, train};
use presrs::core::{Frame, Grid};
use presrs::io::frame_protocol::{Dtype, encode_frame};
use presrs::session::{SessionEvent, SessionObserver};
use presrs_stream::{
    ConnectionOptions, InputFormat, ServerNotice, ServerOptions, ShutdownHandle, StreamServer,
    run_connection, run_connection_observed,
};
use serde_json::Value;

const GRID: Grid = Grid { rows: 16, cols: 16 };

/// Ridges along the rows on one terrain, along the columns on the other (as in the README example).
fn image(terrain: &str, k: usize) -> Vec<f64> {
    (0..256)
        .map(|i| {
            let (r, c) = (i / 16, i % 16);
            let along = if terrain == "ridges" { r } else { c };
            50.0 + 40.0 * ((along + k) % 4) as f64 + ((i * 7 + k * 13) % 5) as f64
        })
        .collect()
}

fn model() -> TrainedModel {
    let frames: Vec<(Frame, &str)> = ["ridges", "furrows"]
        .into_iter()
        .flat_map(|terrain| {
            (0..12).map(move |k| (Frame::new(GRID, image(terrain, k)).unwrap(), terrain))
        })
        .collect();
    let images = |keep: fn(usize) -> bool| -> Vec<LabeledImage<'_>> {
        frames
            .iter()
            .enumerate()
            .filter(|(i, _)| keep(i % 12))
            .map(|(_, (frame, label))| LabeledImage::new(frame.view(), label))
            .collect()
    };
    let config = Method::paper().train_config(GRID).unwrap();
    train(&images(|k| k < 8), &images(|k| k >= 8), &config).unwrap()
}

/// Calibrated (no warm-up), so the first stance is classified; ridges recommend gait G3.
fn profile() -> OnlineProfile {
    let load: f64 = image("ridges", 0).iter().sum();
    let mut profile = OnlineProfile {
        calibration: Some(Calibration {
            baseline: 0.0,
            noise: 1.0,
            load_range: load,
        }),
        ..OnlineProfile::default()
    };
    profile.gait_table.insert("ridges".into(), "G3".into());
    profile
}

/// `stances` stances on `terrain` (2 frames up, 10 flat, 2 down) with 20 unloaded frames before each,
/// then 20 more, encoded in the binary protocol (`u8` exactly holds every value).
fn stream_bytes(terrain: &str, stances: usize) -> (Vec<u8>, usize) {
    let envelope = [
        0.3, 0.7, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 0.7, 0.3,
    ];
    let mut loads = Vec::new();
    for _ in 0..stances {
        loads.extend([0.0; 20]);
        loads.extend(envelope);
    }
    loads.extend([0.0; 20]);
    let (mut bytes, mut frame) = (Vec::new(), Vec::new());
    for (t, &scale) in loads.iter().enumerate() {
        let values: Vec<f64> = image(terrain, 1)
            .iter()
            .map(|v| (v * scale).round())
            .collect();
        encode_frame(&mut frame, 16, 16, Dtype::U8, t as u64 * 10_000, &values).unwrap();
        bytes.extend_from_slice(&frame);
    }
    (bytes, loads.len())
}

fn events(text: &[u8]) -> Vec<Value> {
    String::from_utf8_lossy(text)
        .lines()
        .map(|line| serde_json::from_str(line).unwrap())
        .collect()
}

fn count(events: &[Value], kind: &str) -> usize {
    events.iter().filter(|e| e["event"] == kind).count()
}

/// A client: every frame of `bytes` sent, then (if `hang_up`) the sending side closed; reads lines
/// until the server closes, or (without hanging up) until `decisions` classifications came.
fn client(
    addr: SocketAddr,
    bytes: &[u8],
    hang_up: bool,
    decisions: usize,
) -> (TcpStream, Vec<Value>) {
    let mut stream = TcpStream::connect_timeout(&addr, Duration::from_secs(5)).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_secs(20)))
        .unwrap();
    stream.write_all(bytes).unwrap();
    if hang_up {
        stream.shutdown(Shutdown::Write).unwrap();
    }
    let mut received = Vec::new();
    let mut lines = BufReader::new(stream.try_clone().unwrap()).lines();
    while hang_up || count(&received, "classification") < decisions {
        let Some(line) = lines.next() else { break };
        received.push(serde_json::from_str(&line.unwrap()).unwrap());
    }
    (stream, received)
}

#[test]
fn an_embedded_server_classifies_clients_and_stops_on_request() {
    let options = ServerOptions {
        idle_timeout: Duration::from_secs(20),
        ..ServerOptions::default()
    };
    let addr: SocketAddr = "127.0.0.1:0".parse().unwrap();
    let server = StreamServer::bind(addr, model(), profile(), options).unwrap();
    let (addr, handle) = (server.local_addr(), server.shutdown_handle());
    let notices = Mutex::new(Vec::new());
    let record = |notice: &ServerNotice<'_>| notices.lock().unwrap().push(format!("{notice:?}"));
    let (ridges, ridge_frames) = stream_bytes("ridges", 3);
    let (furrows, furrow_frames) = stream_bytes("furrows", 2);
    let (summary, checked) = std::thread::scope(|scope| {
        let serving = scope.spawn(|| server.serve(&record));
        let checked = std::panic::catch_unwind(|| {
            // One client sends its stances and hangs up: its session ends by itself.
            let (_, done) = client(addr, &ridges, true, 0);
            // Another stays connected: the stop ends its session, which still sends its `end`.
            let (stream, mut open) = client(addr, &furrows, false, 2);
            handle.stop();
            let lines = BufReader::new(stream).lines();
            open.extend(lines.map(|line| serde_json::from_str::<Value>(&line.unwrap()).unwrap()));
            (done, open)
        });
        // Stopped whatever happened above, so that a failed check cannot leave the server running.
        handle.stop();
        (serving.join().unwrap(), checked)
    });
    let (done, open) = checked.unwrap_or_else(|panic| std::panic::resume_unwind(panic));
    let summary = summary.unwrap();

    let labels = |events: &[Value]| -> Vec<Value> {
        events
            .iter()
            .filter(|e| e["event"] == "classification")
            .map(|e| e["label"].clone())
            .collect()
    };
    assert_eq!(count(&done, "touchdown"), 3, "{done:?}");
    assert_eq!(labels(&done), vec!["ridges"; 3], "{done:?}");
    assert!(
        done.iter()
            .filter(|e| e["event"] == "classification")
            .all(|e| e["gait"] == "G3")
    );
    assert_eq!(count(&done, "liftoff"), 3);
    let end = done.last().unwrap();
    assert_eq!(
        (end["event"].as_str(), end["frames"].as_u64()),
        (Some("end"), Some(ridge_frames as u64))
    );
    assert_eq!(end["errors"], 0);

    assert_eq!(labels(&open), vec!["furrows"; 2], "{open:?}");
    let end = open.last().unwrap();
    assert_eq!(
        (end["event"].as_str(), end["frames"].as_u64()),
        (Some("end"), Some(furrow_frames as u64))
    );

    assert_eq!(
        (summary.connections, summary.with_errors, summary.failed),
        (2, 0, 0)
    );
    let notices = notices.into_inner().unwrap();
    assert_eq!(
        notices
            .iter()
            .filter(|n| n.starts_with("Connected"))
            .count(),
        2,
        "{notices:?}"
    );
    assert_eq!(
        notices.iter().filter(|n| n.starts_with("Ended")).count(),
        2,
        "{notices:?}"
    );
}

#[test]
fn a_session_runs_over_any_reader_and_writer() {
    let (bytes, frames) = stream_bytes("furrows", 2);
    // The last frame cut short: a fatal error after everything before it was classified.
    let input = &bytes[..bytes.len() - 10];
    let options = ConnectionOptions {
        format: InputFormat::Binary,
        name: "memory".into(),
        ..ConnectionOptions::default()
    };
    let notices = Mutex::new(Vec::new());
    let mut output = Vec::new();
    let summary = run_connection(
        &model(),
        &profile(),
        input,
        &mut output,
        &options,
        &|notice| {
            notices.lock().unwrap().push(notice.clone());
        },
    )
    .unwrap();
    let events = events(&output);
    assert_eq!(count(&events, "classification"), 2, "{events:?}");
    assert_eq!(summary.stats.frames, frames as u64 - 1);
    assert!(summary.fatal && summary.had_errors());
    assert_eq!(summary.errors, 1);
    let error = events.iter().find(|e| e["event"] == "error").unwrap();
    assert_eq!(error["fatal"], true);
    assert!(
        error["message"].as_str().unwrap().contains("memory"),
        "{error}"
    );
    assert_eq!(notices.into_inner().unwrap().len(), 1);
    assert_eq!(events.last().unwrap()["event"], "end");
}

#[test]
fn a_frame_cut_by_a_stop_is_the_end_not_an_error() {
    // The same cut input, read after a stop (a signal ended the input mid-frame).
    let (bytes, frames) = stream_bytes("furrows", 2);
    let input = &bytes[..bytes.len() - 10];
    let stop = ShutdownHandle::default();
    stop.stop();
    let options = ConnectionOptions {
        format: InputFormat::Binary,
        name: "memory".into(),
        stop: Some(stop),
        ..ConnectionOptions::default()
    };
    let mut output = Vec::new();
    let summary =
        run_connection(&model(), &profile(), input, &mut output, &options, &|_| {}).unwrap();
    let events = events(&output);
    assert_eq!(summary.stats.frames, frames as u64 - 1);
    assert!(!summary.had_errors(), "{events:?}");
    assert_eq!(count(&events, "error"), 0);
    assert_eq!(events.last().unwrap()["event"], "end");
}

/// Keeps what a tap saw.
#[derive(Default)]
struct Seen {
    frames: Vec<(u64, Grid, Vec<f64>)>,
    lines: Vec<String>,
}

impl SessionObserver for Seen {
    fn frame(
        &mut self,
        index: u64,
        grid: Grid,
        values: &[f64],
        _: Option<&[bool]>,
        _: Option<u64>,
    ) {
        self.frames.push((index, grid, values.to_vec()));
    }
    fn event(&mut self, event: &SessionEvent) -> bool {
        self.lines.push(event.to_line());
        true
    }
}

#[test]
fn a_tap_sees_every_frame_and_exactly_the_lines_written() {
    let (bytes, frames) = stream_bytes("ridges", 2);
    let options = ConnectionOptions {
        format: InputFormat::Binary,
        name: "memory".into(),
        ..ConnectionOptions::default()
    };
    let mut output = Vec::new();
    let mut seen = Seen::default();
    let (model, profile) = (model(), profile());
    let summary = run_connection_observed(
        &model,
        &profile,
        &bytes[..],
        &mut output,
        &options,
        &|_| {},
        &mut seen,
    )
    .unwrap();
    assert_eq!(seen.frames.len(), frames);
    assert_eq!(summary.stats.frames, frames as u64);
    let indices: Vec<u64> = seen.frames.iter().map(|(index, _, _)| *index).collect();
    assert_eq!(indices, (0..frames as u64).collect::<Vec<_>>());
    assert!(
        seen.frames
            .iter()
            .all(|(_, grid, values)| *grid == GRID && values.len() == 256)
    );
    let written: Vec<String> = String::from_utf8(output)
        .unwrap()
        .lines()
        .map(str::to_owned)
        .collect();
    assert_eq!(seen.lines, written);
    assert!(
        seen.lines
            .iter()
            .any(|line| line.contains("\"classification\""))
    );
}

/// Presses on a standing preload (the foot never leaves the sensor after the first): 20 unloaded frames,
/// then `presses` presses (2 frames up, 10 at full load, 2 down) from a preload at 35% of the full load,
/// `rest` frames at the preload after each.
fn preload_loads(presses: usize, rest: usize) -> Vec<f64> {
    let press = [
        0.5, 0.8, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 0.8, 0.5,
    ];
    let mut loads = vec![0.0; 20];
    for _ in 0..presses {
        loads.extend(press);
        loads.extend(std::iter::repeat_n(0.35, rest));
    }
    loads
}

fn encode_loads(terrain: &str, loads: &[f64]) -> (Vec<u8>, Vec<f64>) {
    let (mut bytes, mut frame, mut totals) = (Vec::new(), Vec::new(), Vec::new());
    for (t, &scale) in loads.iter().enumerate() {
        let values: Vec<f64> = image(terrain, 1)
            .iter()
            .map(|v| (v * scale).round())
            .collect();
        totals.push(values.iter().sum());
        encode_frame(&mut frame, 16, 16, Dtype::U8, t as u64 * 10_000, &values).unwrap();
        bytes.extend_from_slice(&frame);
    }
    (bytes, totals)
}

/// A profile learned (as `train` learns it) from a preload recording stores the floor mode, and a stream
/// of presses on a preload through a session classifies every press; with the baseline mode the same
/// stream is one long stance.
#[test]
fn a_floor_profile_classifies_every_press_on_a_preload() {
    use presrs::core::stance::{BaselineMode, SegmentParams, ValidSegmentParams, segment};
    let (_, training) = encode_loads("ridges", &preload_loads(6, 9));
    let auto = ValidSegmentParams::default();
    let offline = segment(&training, &auto).unwrap();
    assert_eq!(
        offline.mode,
        BaselineMode::Floor,
        "{:?}",
        offline.mode_reason
    );
    assert_eq!(offline.complete().count(), 6);
    let mut profile = OnlineProfile::learn_with(&[offline], &auto);
    assert_eq!(profile.segment.params().baseline, BaselineMode::Floor);
    profile.gait_table.insert("ridges".into(), "G3".into());

    let (bytes, _) = encode_loads("ridges", &preload_loads(9, 7));
    let options = ConnectionOptions {
        format: InputFormat::Binary,
        name: "preload".into(),
        ..ConnectionOptions::default()
    };
    let mut output = Vec::new();
    let summary = run_connection(
        &model(),
        &profile,
        &bytes[..],
        &mut output,
        &options,
        &|_| {},
    )
    .unwrap();
    assert!(!summary.had_errors());
    let found = events(&output);
    assert_eq!(count(&found, "classification"), 9, "{found:?}");
    assert!(
        found
            .iter()
            .filter(|e| e["event"] == "classification")
            .all(|e| e["label"] == "ridges"),
        "{found:?}"
    );

    // The same stream judged from one baseline: the presses never unload, so they are not 9 stances.
    let drifting = SegmentParams {
        baseline: BaselineMode::Drifting,
        ..SegmentParams::default()
    }
    .check()
    .unwrap();
    let baseline_profile = OnlineProfile {
        segment: drifting,
        ..profile
    };
    let mut output = Vec::new();
    run_connection(
        &model(),
        &baseline_profile,
        &bytes[..],
        &mut output,
        &options,
        &|_| {},
    )
    .unwrap();
    assert!(count(&events(&output), "classification") < 9);
}
