//! The live view's server without a browser: SSE framing, the page and the snapshot, port 0, several
//! viewers, the rate cap, viewers that leave or read nothing (the session must not wait for them), the
//! viewer limit and stopping.

#![allow(clippy::unwrap_used, clippy::expect_used)]

#[path = "../../presrs/tests/common/mod.rs"]
mod common;

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::time::{Duration, Instant};

use presrs::core::Grid;
use presrs::session::{SessionEvent, SessionObserver, Touchdown};
use presrs_stream::live::{LiveHub, LiveInfo, LiveOptions, LiveServer, base64, sse_event};
use serde_json::Value;

fn hub() -> LiveHub {
    LiveHub::new(LiveInfo {
        source: "test".into(),
        units: "kPa".into(),
        classes: vec!["grass".into(), "wood".into()],
    })
}

fn start(hub: &LiveHub, max_fps: f64) -> LiveServer {
    let options = LiveOptions {
        max_fps,
        max_viewers: 4,
        write_timeout: Duration::from_millis(300),
    };
    LiveServer::start("127.0.0.1:0".parse().unwrap(), hub.clone(), options).unwrap()
}

/// A whole response to a plain GET: status line, body.
fn get(addr: SocketAddr, path: &str) -> (String, String) {
    let mut stream = TcpStream::connect(addr).unwrap();
    write!(stream, "GET {path} HTTP/1.1\r\nHost: x\r\n\r\n").unwrap();
    let mut text = String::new();
    stream.read_to_string(&mut text).unwrap();
    let (head, body) = text.split_once("\r\n\r\n").unwrap();
    (head.lines().next().unwrap().to_owned(), body.to_owned())
}

/// An event stream being read: (event name, data) as they come.
struct Viewer {
    reader: BufReader<TcpStream>,
}

impl Viewer {
    fn connect(addr: SocketAddr) -> Self {
        let mut stream = TcpStream::connect(addr).unwrap();
        stream
            .set_read_timeout(Some(Duration::from_secs(5)))
            .unwrap();
        write!(stream, "GET /events HTTP/1.1\r\nHost: x\r\n\r\n").unwrap();
        let mut reader = BufReader::new(stream);
        let mut status = String::new();
        reader.read_line(&mut status).unwrap();
        assert!(status.starts_with("HTTP/1.1 200"), "{status}");
        loop {
            let mut line = String::new();
            reader.read_line(&mut line).unwrap();
            if line == "\r\n" {
                break;
            }
        }
        Self { reader }
    }

    /// The next event (a comment is one with no name), `None` at the end of the stream.
    fn next(&mut self) -> Option<(String, String)> {
        let (mut name, mut data) = (String::new(), Vec::new());
        loop {
            let mut line = String::new();
            if self.reader.read_line(&mut line).ok()? == 0 {
                return None;
            }
            let line = line.trim_end_matches('\n');
            if line.is_empty() {
                return Some((name, data.join("\n")));
            } else if let Some(n) = line.strip_prefix("event: ") {
                name = n.to_owned();
            } else if let Some(d) = line.strip_prefix("data: ") {
                data.push(d.to_owned());
            }
        }
    }

    /// Events for `time`: (frames, load points, lines).
    fn count_for(&mut self, time: Duration) -> (usize, usize, Vec<String>) {
        let end = Instant::now() + time;
        let (mut frames, mut loads, mut lines) = (0, 0, Vec::new());
        while Instant::now() < end {
            let Some((name, data)) = self.next() else {
                break;
            };
            match name.as_str() {
                "frame" => frames += 1,
                "loads" => {
                    loads += serde_json::from_str::<Value>(&data)
                        .unwrap()
                        .as_array()
                        .unwrap()
                        .len()
                }
                "line" => lines.push(data),
                _ => {}
            }
        }
        (frames, loads, lines)
    }
}

fn wait_until(what: &str, mut done: impl FnMut() -> bool) {
    let end = Instant::now() + Duration::from_secs(10);
    while !done() {
        assert!(Instant::now() < end, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(10));
    }
}

#[test]
fn sse_framing_and_base64() {
    let mut out = String::new();
    sse_event(&mut out, "line", "{\"a\":1}");
    sse_event(&mut out, "x", "two\nlines\r\nhere");
    assert_eq!(
        out,
        "event: line\ndata: {\"a\":1}\n\nevent: x\ndata: two\ndata: lines\ndata: here\n\n"
    );
    // RFC 4648's test vectors.
    for (plain, coded) in [
        ("", ""),
        ("f", "Zg=="),
        ("fo", "Zm8="),
        ("foo", "Zm9v"),
        ("foob", "Zm9vYg=="),
        ("fooba", "Zm9vYmE="),
        ("foobar", "Zm9vYmFy"),
    ] {
        assert_eq!(base64(plain.as_bytes()), coded);
    }
    assert_eq!(base64(&[0xff, 0xfe, 0x00]), "//4A");
}

#[test]
fn port_0_serves_the_page_its_files_and_a_snapshot() {
    let hub = hub();
    let server = start(&hub, 30.0);
    let addr = server.local_addr();
    assert_ne!(addr.port(), 0);
    assert_eq!(server.url(), format!("http://{addr}/"));
    let (status, page) = get(addr, "/");
    assert_eq!(status, "HTTP/1.1 200 OK");
    assert!(
        page.contains("<canvas id=\"image\"") && page.contains("/app.js"),
        "{page}"
    );
    // Nothing from elsewhere: no CDN.
    assert!(!page.contains("https://") && !page.contains("//cdn"));
    let (status, script) = get(addr, "/app.js");
    assert_eq!(status, "HTTP/1.1 200 OK");
    assert!(script.contains("EventSource(\"/events\")") && !script.contains("https://"));
    assert_eq!(get(addr, "/style.css").0, "HTTP/1.1 200 OK");
    assert_eq!(get(addr, "/nothing").0, "HTTP/1.1 404 Not Found");
    let mut tap = hub.tap();
    tap.frame(0, Grid::new(1, 2), &[1.0, 2.0], None, None);
    let wood: SessionEvent = serde_json::from_str(
        r#"{"event":"classification","kind":"single","stance":0,"label":"wood","class":1,
            "confidence":0.9,"posteriors":{"clay":0.1,"wood":0.9},"sample_frame":0,"frame":0,
            "frames_used":1,"touchdown_frame":0,"latency_us":1.0,"timestamp_us":null,"gait":null}"#,
    )
    .unwrap();
    tap.event(&wood);
    tap.event(&SessionEvent::error("a later line", false));
    let state: Value = serde_json::from_str(&get(addr, "/state?x=1").1).unwrap();
    assert_eq!(state["frames"], 1);
    assert_eq!(state["units"], "kPa");
    assert_eq!(state["classification"]["label"], "wood");
    // A POST is refused.
    let mut stream = TcpStream::connect(addr).unwrap();
    write!(stream, "POST / HTTP/1.1\r\nHost: x\r\n\r\n").unwrap();
    let mut text = String::new();
    stream.read_to_string(&mut text).unwrap();
    assert!(text.starts_with("HTTP/1.1 405"), "{text}");
    server.stop();
}

/// Frames from a "session" at `rate` a second for `time`, on a thread; returns the frame count and the
/// longest single `frame` call.
fn feed(
    hub: &LiveHub,
    grid: Grid,
    rate: f64,
    time: Duration,
) -> std::thread::JoinHandle<(u64, Duration)> {
    let mut tap = hub.tap();
    std::thread::spawn(move || {
        let mut values = vec![0.0; grid.len()];
        let start = Instant::now();
        let (mut n, mut longest) = (0u64, Duration::ZERO);
        while start.elapsed() < time {
            values[(n as usize) % grid.len()] = n as f64;
            let t = Instant::now();
            tap.frame(n, grid, &values, None, None);
            if n % 50 == 0 {
                tap.event(&SessionEvent::Touchdown(Touchdown {
                    stance: n / 50,
                    touchdown_frame: n,
                    frame: n,
                    partial: false,
                }));
            }
            longest = longest.max(t.elapsed());
            n += 1;
            let due = start + Duration::from_secs_f64(n as f64 / rate);
            if let Some(wait) = due.checked_duration_since(Instant::now()) {
                std::thread::sleep(wait);
            }
        }
        (n, longest)
    })
}

#[test]
fn several_viewers_get_every_load_and_line_but_frames_at_the_capped_rate() {
    let hub = hub();
    let server = start(&hub, 20.0);
    let mut viewers: Vec<Viewer> = (0..3)
        .map(|_| Viewer::connect(server.local_addr()))
        .collect();
    for viewer in &mut viewers {
        let (name, data) = viewer.next().unwrap();
        assert_eq!(name, "hello");
        let hello: Value = serde_json::from_str(&data).unwrap();
        assert_eq!(
            (hello["units"].as_str(), hello["classes"][1].as_str()),
            (Some("kPa"), Some("wood"))
        );
    }
    wait_until("3 viewers", || hub.viewers() == 3);
    let feeder = feed(&hub, Grid::new(44, 44), 500.0, Duration::from_secs(2));
    let counts: Vec<_> = std::thread::scope(|scope| {
        let handles: Vec<_> = viewers
            .iter_mut()
            .map(|viewer| scope.spawn(move || viewer.count_for(Duration::from_millis(2600))))
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    let (sent, _) = feeder.join().unwrap();
    for (frames, loads, lines) in counts {
        // 20 frames/s for about 2 s: far fewer than the 1000 sent, and not none.
        assert!(
            (10..=60).contains(&frames),
            "{frames} frames sent to a viewer"
        );
        assert_eq!(
            loads as u64, sent,
            "every frame's total load reaches every viewer"
        );
        assert_eq!(lines.len() as u64, sent.div_ceil(50));
    }
    server.stop();
}

#[test]
fn viewers_that_leave_or_read_nothing_are_dropped_and_never_slow_the_session() {
    let hub = hub();
    let server = start(&hub, 200.0);
    let addr = server.local_addr();
    // One reads, one leaves at once, one reads nothing.
    let mut reader = Viewer::connect(addr);
    drop(Viewer::connect(addr));
    let mut stalled = TcpStream::connect(addr).unwrap();
    write!(stalled, "GET /events HTTP/1.1\r\nHost: x\r\n\r\n").unwrap();
    // Large frames, so that the socket of the viewer that reads nothing fills within the test.
    let feeder = feed(&hub, Grid::new(256, 256), 2000.0, Duration::from_secs(3));
    let (frames, ..) = reader.count_for(Duration::from_millis(2500));
    // The one that left and the one that reads nothing (within the write timeout) are gone.
    wait_until("the stalled viewers to be dropped", || hub.viewers() == 1);
    let (sent, longest) = feeder.join().unwrap();
    assert!(frames >= 50, "the reading viewer got {frames} frames");
    assert!(sent > 1000, "the session fed only {sent} frames in 3 s");
    // The session never waited for a viewer: no frame took anywhere near the write timeout.
    assert!(
        longest < Duration::from_millis(150),
        "a frame took {longest:?}"
    );
    drop(reader);
    drop(stalled);
    let t = Instant::now();
    server.stop();
    assert!(
        t.elapsed() < Duration::from_secs(3),
        "stop took {:?}",
        t.elapsed()
    );
}

#[test]
fn viewers_over_the_limit_get_503_and_stop_ends_the_streams() {
    let hub = hub();
    let server = start(&hub, 30.0);
    let addr = server.local_addr();
    let mut viewers: Vec<Viewer> = (0..4).map(|_| Viewer::connect(addr)).collect();
    wait_until("4 viewers", || hub.viewers() == 4);
    assert_eq!(get(addr, "/events").0, "HTTP/1.1 503 Service Unavailable");
    let t = Instant::now();
    server.stop();
    assert!(
        t.elapsed() < Duration::from_secs(2),
        "stop took {:?}",
        t.elapsed()
    );
    for viewer in &mut viewers {
        // hello, then the end of the stream.
        while viewer.next().is_some() {}
    }
    assert_eq!(hub.viewers(), 0);
    assert!(TcpStream::connect(addr).is_err() || get_fails(addr));
}

/// After stop nothing answers (the port may still accept on some systems until it is reused).
fn get_fails(addr: SocketAddr) -> bool {
    let Ok(mut stream) = TcpStream::connect(addr) else {
        return true;
    };
    stream
        .set_read_timeout(Some(Duration::from_millis(500)))
        .unwrap();
    let _ = write!(stream, "GET / HTTP/1.1\r\n\r\n");
    let mut buf = [0u8; 16];
    !matches!(stream.read(&mut buf), Ok(n) if n > 0)
}

/// A whole-stance model's decisions reach the live view with what they waited for: `decided_at` and
/// `decided_at_frame` in the classification lines every viewer gets and in `/state`, and the page
/// shows them. A `jiku-walk` movie (one foot contact, read in place from the shared data folder) is
/// replayed through the session `presrs view` runs, decided at lift-off and at frame 12.
#[test]
fn a_whole_stance_models_decisions_show_what_they_waited_for() {
    use presrs::core::classifier::ClassifierKind;
    use presrs::core::online::{DecideAt, OnlineParams, OnlineProfile};
    use presrs::core::sample::SampleKind;
    use presrs::core::stance::summary::SummaryConfig;
    use presrs_stream::live::{ReplayOptions, replay_recording};

    let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/real");
    let options = presrs::SampleOptions {
        one_sample_per_file: true,
        kind: SampleKind::Stance {
            summary: SummaryConfig::default(),
            length: None,
        },
        // A model decides only where it was trained to: frame 12 after touchdown too.
        decision_points: vec![12],
        ..presrs::SampleOptions::default()
    };
    let manifest = data.join("jiku-walk/manifest.csv");
    let dataset = presrs::Dataset::load(&manifest, &options, &presrs::Quiet).unwrap();
    let model = common::small_rocket_model(&dataset, ClassifierKind::LDA, 20, options.kind);
    let model = common::with_points(model, &dataset);
    let path = data.join("jiku-walk").join(&dataset.samples[0].source);
    let (read, _) =
        presrs::dataset::read_corrected(&path, &options.read, options.dead_sensels.as_ref())
            .unwrap();
    let recording = read.recording;
    let last = recording.frame_count() - 1;
    for (decide_at, said, frame) in [
        (None, "liftoff", last),
        (Some(DecideAt::Frames(12)), "offset", 12),
    ] {
        let profile = OnlineProfile {
            params: OnlineParams {
                decide_at,
                ..OnlineParams::default()
            },
            segment: options.segment_params(),
            ..OnlineProfile::default()
        };
        let hub = LiveHub::new(LiveInfo {
            source: "replay".into(),
            units: "raw".into(),
            classes: model.class_names().to_vec(),
        });
        let server = start(&hub, 30.0);
        let replay = ReplayOptions {
            speed: 1000.0,
            ..ReplayOptions::default()
        };
        let mut output = Vec::new();
        replay_recording(
            &recording,
            "s00",
            Some((&model, &profile)),
            &hub,
            &mut output,
            &replay,
            &|_| {},
        )
        .unwrap();
        let lines: Vec<Value> = hub
            .recent_lines()
            .iter()
            .map(|l| serde_json::from_str(l).unwrap())
            .filter(|l: &Value| l["event"] == "classification")
            .collect();
        let [line] = lines.as_slice() else {
            panic!(
                "{decide_at:?}: one decision, got {lines:?}; hub {:?}; output {}",
                hub.recent_lines(),
                String::from_utf8_lossy(&output)
            );
        };
        assert_eq!(line["kind"], "stance");
        assert_eq!(line["decided_at"], said);
        assert_eq!(line["decided_at_frame"], frame);
        let state: Value = serde_json::from_str(&get(server.local_addr(), "/state").1).unwrap();
        assert_eq!(state["classification"]["decided_at"], said);
        assert_eq!(state["classification"]["decided_at_frame"], frame);
        server.stop();
    }
    // the page says what a decision waited for
    let script = include_str!("../src/live/page/app.js");
    assert!(script.contains("e.decided_at_frame"));
}
