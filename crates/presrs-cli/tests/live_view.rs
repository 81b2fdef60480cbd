//! The live view in a real browser: `presrs stream --http 127.0.0.1:0` fed one terrain then another on
//! stdin while headless Chromium shows the page; the page must draw the image and its label must follow
//! the terrain. A screenshot is kept in `target/live-view/live-view.png`.
//!
//! Needs Debian's `chromium` (`.ci/run` installs it). Without it the test fails when `CI` is set and is
//! skipped, saying so, otherwise.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

use serde_json::Value;

fn presrs() -> Command {
    Command::new(env!("CARGO_BIN_EXE_presrs"))
}

fn run_ok(args: &[&str]) {
    let out = presrs().args(args).output().unwrap();
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The browser, or `None` (after saying why) when the test cannot run here.
fn chromium() -> Option<PathBuf> {
    let found = ["chromium", "chromium-browser"].iter().find_map(|name| {
        std::env::var_os("PATH").and_then(|paths| {
            std::env::split_paths(&paths)
                .map(|dir| dir.join(name))
                .find(|path| path.is_file())
        })
    });
    if found.is_none() {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI is set but chromium is not installed: the live view cannot be tested (.ci/run installs it)"
        );
        eprintln!("live_view: skipped, chromium is not installed (apt-get install chromium)");
    }
    found
}

/// `target/live-view/` (the test binary is in `target/<profile>/deps/`).
fn output_dir() -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    let target = exe.ancestors().nth(3).unwrap().to_path_buf();
    let dir = target.join("live-view");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn headless(browser: &Path, profile: &Path) -> Command {
    let mut command = Command::new(browser);
    command.args([
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--virtual-time-budget=5000",
    ]);
    command.arg(format!("--user-data-dir={}", profile.display()));
    command.stdin(Stdio::null()).stderr(Stdio::null());
    command
}

/// Waits for `child` to exit within `limit`, killing it (by its own handle) when it does not.
fn wait_for(child: &mut Child, what: &str, limit: Duration) {
    let end = Instant::now() + limit;
    while child.try_wait().unwrap().is_none() {
        if Instant::now() > end {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{what} did not finish within {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// A small simulated data set and a model trained on it (with its online profile), once per binary.
fn fixture() -> &'static (PathBuf, PathBuf) {
    static FIXTURE: std::sync::OnceLock<(PathBuf, PathBuf)> = std::sync::OnceLock::new();
    FIXTURE.get_or_init(|| {
        // (under cargo's target/tmp, not the system's temp dir: a static is never dropped, so it
        // cannot hold a self-removing temp dir, and these used to pile up in /tmp)
        let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
            .join(format!("presrs-live-test-{}", std::process::id()));
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
        let model = dir.join("model.json");
        let manifest = dir.join("manifest.csv");
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
        ]);
        (dir, model)
    })
}

/// The URL a command prints on stderr (`... live view: URL`), read on a thread that drains the rest.
fn live_url(stderr: std::process::ChildStderr) -> String {
    let (url_tx, url_rx) = channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            if let Some(url) = line.split("live view: ").nth(1) {
                let _ = url_tx.send(url.to_owned());
            }
        }
    });
    let url = url_rx
        .recv_timeout(Duration::from_secs(60))
        .expect("the live view's URL on stderr");
    assert!(
        url.starts_with("http://127.0.0.1:") && !url.ends_with(":0/"),
        "{url}"
    );
    url
}

fn get_state(url: &str) -> Value {
    let addr = url.trim_start_matches("http://").trim_end_matches('/');
    let mut stream = TcpStream::connect(addr).unwrap();
    write!(stream, "GET /state HTTP/1.1\r\nHost: x\r\n\r\n").unwrap();
    let mut text = String::new();
    stream.read_to_string(&mut text).unwrap();
    serde_json::from_str(text.split_once("\r\n\r\n").unwrap().1).unwrap()
}

/// Writes a recording to the stream's stdin in `chunks` pieces over about `time` (a live sensor).
fn feed(stdin: &mut impl Write, path: &Path, chunks: usize, time: Duration) {
    let bytes = std::fs::read(path).unwrap();
    for piece in bytes.chunks(bytes.len().div_ceil(chunks)) {
        stdin.write_all(piece).unwrap();
        stdin.flush().unwrap();
        std::thread::sleep(time / chunks as u32);
    }
}

/// Labels from the stream's classification lines until `want` comes (or 30 s pass).
fn labels_until(lines: &Receiver<Value>, seen: &mut Vec<String>, want: &str) {
    let end = Instant::now() + Duration::from_secs(30);
    while seen.last().is_none_or(|l| l != want) {
        let left = end.saturating_duration_since(Instant::now());
        let line = lines
            .recv_timeout(left)
            .unwrap_or_else(|_| panic!("no {want} decision; saw {seen:?}"));
        if line["event"] == "classification" {
            seen.push(line["label"].as_str().unwrap().to_owned());
        }
    }
}

fn attribute(dom: &str, name: &str) -> String {
    let body = &dom[dom.find("<body").expect("a body")..];
    let body = &body[..body.find('>').unwrap()];
    let key = format!("{name}=\"");
    let start = body
        .find(&key)
        .unwrap_or_else(|| panic!("no {name} in {body}"))
        + key.len();
    body[start..start + body[start..].find('"').unwrap()].to_owned()
}

#[test]
fn the_live_page_draws_the_image_and_its_label_follows_the_terrain() {
    let Some(browser) = chromium() else { return };
    let (dir, model) = fixture();
    let dir = dir.as_path();

    let mut stream = presrs()
        .args([
            "stream",
            "--model",
            model.to_str().unwrap(),
            "--http",
            "127.0.0.1:0",
            "--units",
            "kPa",
        ])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdin = stream.stdin.take().unwrap();
    let url = live_url(stream.stderr.take().unwrap());
    let stdout = BufReader::new(stream.stdout.take().unwrap());
    let (lines_tx, lines) = channel();
    std::thread::spawn(move || {
        for line in stdout.lines().map_while(Result::ok) {
            let _ = lines_tx.send(serde_json::from_str::<Value>(&line).unwrap());
        }
    });

    // The browser watches from before the first frame until the page has shown wood.
    let mut page = headless(&browser, &dir.join("browser"))
        .arg("--dump-dom")
        .arg(format!("{url}?frames=20&until=wood"))
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let end = Instant::now() + Duration::from_secs(30);
    while get_state(&url)["viewers"] == 0 {
        assert!(Instant::now() < end, "the browser never connected");
        std::thread::sleep(Duration::from_millis(50));
    }
    let mut seen = Vec::new();
    let recordings = dir.join("recordings");
    feed(
        &mut stdin,
        &recordings.join("grass_G2_000.asf"),
        40,
        Duration::from_secs(2),
    );
    labels_until(&lines, &mut seen, "grass");
    feed(
        &mut stdin,
        &recordings.join("wood_G2_000.asf"),
        40,
        Duration::from_secs(2),
    );
    labels_until(&lines, &mut seen, "wood");
    wait_for(&mut page, "chromium --dump-dom", Duration::from_secs(60));
    let mut dom = String::new();
    page.stdout
        .take()
        .unwrap()
        .read_to_string(&mut dom)
        .unwrap();
    std::fs::write(output_dir().join("live-view.html"), &dom).unwrap();

    assert_eq!(
        attribute(&dom, "data-image"),
        "44x44",
        "the image was drawn"
    );
    let drawn: u64 = attribute(&dom, "data-frames-drawn").parse().unwrap();
    assert!(drawn >= 20, "{drawn} frames drawn");
    assert_eq!(attribute(&dom, "data-label"), "wood");
    // The page showed the labels the stream decided, in order, from grass to wood.
    let mut decided = seen.clone();
    decided.dedup();
    let shown = attribute(&dom, "data-labels");
    assert_eq!(shown, decided.join(","), "page vs stdout");
    assert!(
        shown.starts_with("grass") && shown.ends_with("wood"),
        "{shown}"
    );
    assert!(
        dom.contains("<div id=\"terrain\" data-label=\"wood\" data-unknown=\"false\">wood</div>"),
        "terrain element (a known terrain: the model scores novelty and wood is near its training)"
    );

    // A screenshot of the page as it is now, for people.
    let shot = output_dir().join("live-view.png");
    let _ = std::fs::remove_file(&shot);
    let mut camera = headless(&browser, &dir.join("browser"))
        .arg(format!("--screenshot={}", shot.display()))
        .arg("--window-size=1200,1000")
        // No frame comes any more: the page closes after the one it is given first.
        .arg(format!("{url}?frames=1"))
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    wait_for(
        &mut camera,
        "chromium --screenshot",
        Duration::from_secs(60),
    );
    let png = std::fs::read(&shot).unwrap();
    assert!(
        png.starts_with(b"\x89PNG") && png.len() > 10_000,
        "{} bytes",
        png.len()
    );

    drop(stdin);
    wait_for(&mut stream, "presrs stream", Duration::from_secs(30));
    assert!(stream.wait().unwrap().success());
    eprintln!("live_view: screenshot in {}", shot.display());
}

#[test]
fn view_replays_a_file_through_the_classifier_and_serves_the_page() {
    let (dir, model) = fixture();
    let file = dir.join("recordings/wood_G2_000.asf");
    let mut view = presrs()
        .args([
            "view",
            file.to_str().unwrap(),
            "--model",
            model.to_str().unwrap(),
        ])
        .args(["--http", "127.0.0.1:0", "--speed", "4", "--delay", "0.5"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let url = live_url(view.stderr.take().unwrap());
    let state = get_state(&url);
    assert_eq!(state["classes"].as_array().unwrap().len(), 4, "{state}");
    assert!(
        state["source"]
            .as_str()
            .unwrap()
            .ends_with("wood_G2_000.asf"),
        "{state}"
    );
    let mut out = String::new();
    view.stdout
        .take()
        .unwrap()
        .read_to_string(&mut out)
        .unwrap();
    wait_for(&mut view, "presrs view", Duration::from_secs(60));
    assert!(view.wait().unwrap().success());
    let lines: Vec<Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let labels: Vec<&str> = lines
        .iter()
        .filter(|l| l["event"] == "classification")
        .map(|l| l["label"].as_str().unwrap())
        .collect();
    assert!(labels.len() >= 5, "{out}");
    assert!(
        labels.iter().filter(|&&l| l == "wood").count() * 2 > labels.len(),
        "{labels:?}"
    );
    assert_eq!(lines.last().unwrap()["event"], "end");
}

#[test]
fn a_servers_clients_are_shown_and_non_loopback_is_refused() {
    let (dir, model) = fixture();
    let mut server = presrs()
        .args([
            "stream",
            "--model",
            model.to_str().unwrap(),
            "--listen",
            "127.0.0.1:0",
        ])
        .args(["--http", "127.0.0.1:0", "--exit-after", "2"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let url = live_url(server.stderr.take().unwrap());
    let mut stdout = BufReader::new(server.stdout.take().unwrap());
    let mut first = String::new();
    stdout.read_line(&mut first).unwrap();
    let addr = serde_json::from_str::<Value>(&first).unwrap()["addr"]
        .as_str()
        .unwrap()
        .to_owned();
    let file = dir.join("recordings/grass_G2_000.asf");
    let replay = || {
        let out = presrs()
            .args([
                "replay",
                file.to_str().unwrap(),
                "--connect",
                &addr,
                "--rate",
                "max",
            ])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    replay();
    let state = get_state(&url);
    assert_eq!(state["frames"], 620, "{state}");
    assert!(
        state["source"].as_str().unwrap().starts_with("127.0.0.1:"),
        "{state}"
    );
    assert_eq!(
        state["classification"]["event"], "classification",
        "{state}"
    );
    replay();
    wait_for(
        &mut server,
        "presrs stream --listen",
        Duration::from_secs(60),
    );
    assert!(server.wait().unwrap().success());

    let out = presrs()
        .args([
            "stream",
            "--model",
            model.to_str().unwrap(),
            "--http",
            "0.0.0.0:0",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("only loopback"));
}
