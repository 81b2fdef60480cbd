//! `presrs plot` and `presrs report` end to end: files are written, decode, have the stated size, are not
//! blank, and the HTML references only files that exist.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

fn presrs() -> Command {
    Command::new(env!("CARGO_BIN_EXE_presrs"))
}

fn run_ok(cmd: &mut Command) -> String {
    let output = cmd.output().unwrap();
    assert!(
        output.status.success(),
        "{:?} failed:\nstdout: {}\nstderr: {}",
        cmd,
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    String::from_utf8(output.stdout).unwrap()
}

/// A small simulated data set shared by the tests (2 terrains x 2 gaits, a few hops each).
fn sim_dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap().keep();
        let config = dir.join("small.json");
        // Only the experiment size is changed; everything else is the simulator's default.
        let printed = run_ok(presrs().args(["simulate", "--print-config"]));
        let mut value: serde_json::Value = serde_json::from_str(&printed).unwrap();
        value["experiment"]["hops_per_gait"] = serde_json::json!(24);
        value["experiment"]["hops_per_trial"] = serde_json::json!(12);
        std::fs::write(&config, serde_json::to_string(&value).unwrap()).unwrap();
        run_ok(presrs().args([
            "simulate",
            "--out",
            dir.to_str().unwrap(),
            "--config",
            config.to_str().unwrap(),
        ]));
        dir
    })
}

/// Decodes a PNG: (width, height, RGB(A) pixels as RGB triples).
fn decode_png(path: &Path) -> (u32, u32, Vec<[u8; 3]>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let channels = info.color_type.samples();
    let pixels = buf[..info.buffer_size()]
        .chunks_exact(channels)
        .map(|p| [p[0], p[1 % channels], p[2 % channels]])
        .collect();
    (info.width, info.height, pixels)
}

/// Not blank: the pixels vary and there are several colours.
fn assert_not_blank(path: &Path, pixels: &[[u8; 3]]) {
    let n = pixels.len() as f64;
    let mean: f64 = pixels
        .iter()
        .map(|p| f64::from(p[0]) + f64::from(p[1]) + f64::from(p[2]))
        .sum::<f64>()
        / n;
    let variance: f64 = pixels
        .iter()
        .map(|p| (f64::from(p[0]) + f64::from(p[1]) + f64::from(p[2]) - mean).powi(2))
        .sum::<f64>()
        / n;
    assert!(
        variance > 100.0,
        "{}: pixel variance {variance}",
        path.display()
    );
    let mut colours: Vec<[u8; 3]> = pixels.to_vec();
    colours.sort_unstable();
    colours.dedup();
    assert!(
        colours.len() >= 8,
        "{}: only {} colours",
        path.display(),
        colours.len()
    );
    // Some colour that is not grey (a colour map or category colours).
    assert!(
        pixels
            .iter()
            .any(|p| p.iter().max().unwrap() - p.iter().min().unwrap() > 60),
        "{}: no coloured pixel",
        path.display()
    );
}

fn first_recording(dir: &Path) -> PathBuf {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir.join("recordings"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    files.into_iter().next().unwrap()
}

#[test]
fn plot_png_has_the_sensor_aspect_and_is_not_blank() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("frame.png");
    let stdout = run_ok(presrs().args([
        "plot",
        first_recording(sim_dir()).to_str().unwrap(),
        "--stance",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]));
    assert!(stdout.contains("wrote"));
    let (w, h, pixels) = decode_png(&out);
    assert_eq!(pixels.len(), (w * h) as usize);
    assert_eq!(h, 600, "the default figure height");
    assert!((420..1200).contains(&w), "width {w}");
    assert_not_blank(&out, &pixels);
}

#[test]
fn plot_svg_and_movie_gif() {
    let dir = tempfile::tempdir().unwrap();
    let recording = first_recording(sim_dir());
    let svg = dir.path().join("frame.svg");
    run_ok(presrs().args([
        "plot",
        recording.to_str().unwrap(),
        "--frame",
        "3",
        "--out",
        svg.to_str().unwrap(),
    ]));
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.starts_with("<svg"), "{}", &text[..text.len().min(80)]);
    assert!(text.contains("<rect") && text.contains("frame 3"));
    assert!(text.trim_end().ends_with("</svg>"));

    let gif = dir.path().join("movie.gif");
    let stdout = run_ok(presrs().args([
        "plot",
        recording.to_str().unwrap(),
        "--movie",
        "--max-frames",
        "12",
        "--out",
        gif.to_str().unwrap(),
    ]));
    assert!(
        stdout.contains("12 frames") || stdout.contains("frames)"),
        "{stdout}"
    );
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let mut decoder = options
        .read_info(std::fs::File::open(&gif).unwrap())
        .unwrap();
    let (w, h) = (u32::from(decoder.width()), u32::from(decoder.height()));
    let mut frames = 0;
    let mut first: Option<Vec<u8>> = None;
    let mut changed = false;
    while let Some(frame) = decoder.read_next_frame().unwrap() {
        frames += 1;
        assert_eq!((u32::from(frame.width), u32::from(frame.height)), (w, h));
        let pixels: Vec<[u8; 3]> = frame
            .buffer
            .chunks_exact(4)
            .map(|p| [p[0], p[1], p[2]])
            .collect();
        assert_not_blank(&gif, &pixels);
        match &first {
            None => first = Some(frame.buffer.to_vec()),
            Some(f) => changed |= *f != frame.buffer.to_vec(),
        }
    }
    assert!((2..=12).contains(&frames), "{frames} frames");
    assert!(changed, "the movie does not move");
}

#[test]
fn plot_rejects_bad_requests() {
    let dir = tempfile::tempdir().unwrap();
    let recording = first_recording(sim_dir());
    let cases: [(&[&str], &str); 3] = [
        (&["--frame", "100000", "--out", "a.png"], "frame"),
        (&["--out", "a.jpg"], ".png"),
        (&["--out", "a.gif"], "--movie"),
    ];
    for (args, message) in cases {
        let output = presrs()
            .current_dir(dir.path())
            .arg("plot")
            .arg(&recording)
            .args(args)
            .output()
            .unwrap();
        assert!(!output.status.success(), "{args:?} succeeded");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(stderr.contains(message), "{args:?}: {stderr}");
    }
    assert!(
        std::fs::read_dir(dir.path()).unwrap().next().is_none(),
        "no file is left behind"
    );
}

#[test]
fn report_writes_every_figure_and_only_links_existing_files() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("report");
    let manifest = sim_dir().join("manifest.csv");
    let stdout = run_ok(presrs().args([
        "report",
        "--manifest",
        manifest.to_str().unwrap(),
        "--per-class",
        "10",
        "--validation",
        "4",
        "--repeats",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]));
    assert!(stdout.contains("index.html"), "{stdout}");
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    let mut referenced = Vec::new();
    for part in html
        .split("src=\"")
        .skip(1)
        .chain(html.split("href=\"").skip(1))
    {
        let target = &part[..part.find('"').unwrap()];
        if !target.starts_with('#') {
            referenced.push(target.to_owned());
        }
    }
    assert!(!referenced.is_empty());
    for target in &referenced {
        assert!(
            !target.contains("://"),
            "{target}: the page must open offline"
        );
        assert!(
            out.join(target).is_file(),
            "{target} is referenced but missing"
        );
    }
    for figure in [
        "fig5_pressure_images.png",
        "fig6_spectra.png",
        "load_curves.png",
        "pca.png",
        "validation.png",
        "confusion.png",
        "accuracy.png",
        "reliability.png",
        "table1_velocity.png",
        "hopper.png",
    ] {
        assert!(
            referenced.iter().any(|r| r == figure),
            "{figure} not in the page"
        );
        let path = out.join(figure);
        let (w, h, pixels) = decode_png(&path);
        // The page states each figure's size.
        assert!(
            html.contains(&format!("src=\"{figure}\" width=\"{w}\" height=\"{h}\"")),
            "{figure}: {w} x {h} not stated"
        );
        assert_not_blank(&path, &pixels);
    }
    for heading in [
        "Fig. 5",
        "Fig. 6",
        "Table I",
        "Confusion",
        "Accuracy per condition",
        "How far the confidences can be trusted",
    ] {
        assert!(html.contains(heading), "no {heading} section");
    }
    // The reliability table: a row per evaluation, with a calibration error in [0, 1].
    let table = &html[html
        .find("<th>calibration error</th>")
        .expect("reliability table")..];
    let row = &table[table.find("<tr><td>").unwrap()..table.find("</table>").unwrap()];
    let error: f64 = row
        .trim_end_matches("</td></tr>")
        .rsplit("<td>")
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!((0.0..=1.0).contains(&error), "{row}");
    // No temporary files left behind.
    for entry in std::fs::read_dir(&out).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        assert!(!name.ends_with(".tmp"), "{name}");
    }
}

#[test]
fn report_with_a_model_file() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = sim_dir().join("manifest.csv");
    let model = dir.path().join("model.json");
    run_ok(presrs().args([
        "train",
        "--manifest",
        manifest.to_str().unwrap(),
        "--out",
        model.to_str().unwrap(),
    ]));
    let out = dir.path().join("report");
    run_ok(presrs().args([
        "report",
        "--manifest",
        manifest.to_str().unwrap(),
        "--model",
        model.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]));
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.contains("model "), "the evaluation names the model");
    for figure in ["validation.png", "confusion.png", "pca.png"] {
        let (_, _, pixels) = decode_png(&out.join(figure));
        assert_not_blank(&out.join(figure), &pixels);
    }
}

/// With the default options (20 per class, 7 validating) on a data set with fewer images per class,
/// the draw shrinks as a whole: the validation count becomes the same fraction of what is drawn.
/// `presrs report` with its default options and one repeat of each evaluation on a small simulation of
/// wood and carpet at `gaits` (6 hops each): the exit status and stderr.
fn default_report_on_a_small_simulation(dir: &Path, gaits: &str) -> (bool, String) {
    let sim = dir.join("sim");
    run_ok(presrs().args([
        "simulate",
        "--out",
        sim.to_str().unwrap(),
        "--seed",
        "7",
        "--hops-per-gait",
        "6",
        "--terrains",
        "wood,carpet",
        "--gaits",
        gaits,
    ]));
    let output = presrs()
        .args([
            "report",
            "--manifest",
            sim.join("manifest.csv").to_str().unwrap(),
            "--out",
            dir.join("report").to_str().unwrap(),
            "--repeats",
            "1",
            "--fault-repeats",
            "1",
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    (output.status.success(), stderr)
}

#[test]
fn report_with_default_options_on_a_small_data_set() {
    let dir = tempfile::tempdir().unwrap();
    let (ok, err) = default_report_on_a_small_simulation(dir.path(), "G1,G2");
    assert!(ok, "{err}");
    assert!(
        err.contains("fewer than --per-class 20") && err.contains("a fraction 0.35"),
        "{err}"
    );
    assert!(dir.path().join("report/index.html").is_file());
}

/// One condition and fewer images than --per-class: training on every image would leave nothing to test
/// on, so the evaluations hold a third of each class out (this failed with "no sample is left to test
/// on" before), and the report is written.
#[test]
fn report_on_one_condition_with_few_images_tests_on_held_out_images() {
    let dir = tempfile::tempdir().unwrap();
    let (ok, err) = default_report_on_a_small_simulation(dir.path(), "G2");
    assert!(ok, "{err}");
    assert!(
        err.contains("the evaluations draw") && err.contains("and test on the rest"),
        "{err}"
    );
    let html = std::fs::read_to_string(dir.path().join("report/index.html")).unwrap();
    assert!(
        html.contains("trained on G2"),
        "the evaluation is in the report"
    );
}

/// The headline `presrs report` prints (`NAME, N repeat(s): A % +- S`), split into its name and figures.
fn headline(stdout: &str) -> (String, String) {
    let line = stdout
        .lines()
        .find(|l| l.contains(" repeat(s): "))
        .unwrap_or_else(|| panic!("no headline in {stdout}"));
    let (name, figures) = line.split_once(": ").unwrap();
    (name.to_owned(), figures.to_owned())
}

/// The report evaluates what `presrs eval` evaluates with the same options: the same figures, the
/// protocol named, the model shown is the evaluation's first, and the report says when, by what and how.
#[test]
fn report_agrees_with_eval_and_states_its_provenance() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("report");
    let manifest = sim_dir().join("manifest.csv");
    let options = [
        "--leave-one-out",
        "group",
        "--features",
        "fft1d",
        "--classifier",
        "pwe",
        "--per-class",
        "8",
        "--validation",
        "3",
        "--repeats",
        "2",
    ];
    let stdout = run_ok(
        presrs()
            .args(["report", "--manifest", manifest.to_str().unwrap()])
            .args(options)
            .args(["--fault-repeats", "0", "--out", out.to_str().unwrap()]),
    );
    let json = run_ok(
        presrs()
            .args(["eval", "--manifest", manifest.to_str().unwrap(), "--json"])
            .args(options),
    );
    let doc: serde_json::Value = serde_json::from_str(&json).unwrap();
    let (name, figures) = headline(&stdout);
    assert_eq!(name, "leave one group out, 2 repeat(s)");
    let expected = format!(
        "{:.2} % +- {:.2}",
        100.0 * doc["overall_accuracy"].as_f64().unwrap(),
        100.0 * doc["overall_accuracy_std"].as_f64().unwrap()
    );
    assert_eq!(figures, expected, "report and eval disagree");
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(
        html.contains("leave one group out"),
        "the protocol is named"
    );
    assert!(
        html.contains("first model (leave one group out, seed 1, holding out"),
        "the model shown is the evaluation's first"
    );
    assert!(html.contains(&format!("Made by presrs {}", env!("CARGO_PKG_VERSION"))));
    assert!(
        html.contains("report --manifest"),
        "the command line is stated"
    );
    assert!(html.contains(" UTC"), "the date is stated");
}

/// Without options, a data set with groups (and no G2 condition) is evaluated leaving one group out,
/// with the automatic choice, and the report shows what it chose.
#[test]
fn default_report_on_groups_leaves_one_group_out_with_the_automatic_choice() {
    let dir = tempfile::tempdir().unwrap();
    let sim = sim_dir();
    // The simulator's manifest with its gaits renamed (no G2: not the paper's experiment), beside it so
    // that its relative paths still resolve.
    let text = std::fs::read_to_string(sim.join("manifest.csv")).unwrap();
    let manifest = sim.join("renamed-gaits.csv");
    std::fs::write(
        &manifest,
        text.replace(",G1,", ",slow,").replace(",G2,", ",fast,"),
    )
    .unwrap();
    let out = dir.path().join("report");
    let stdout = run_ok(presrs().args([
        "report",
        "--manifest",
        manifest.to_str().unwrap(),
        "--per-class",
        "6",
        "--validation",
        "2",
        "--repeats",
        "1",
        "--fault-repeats",
        "0",
        "--out",
        out.to_str().unwrap(),
    ]));
    let (name, _) = headline(&stdout);
    assert_eq!(name, "leave one group out, 1 repeat(s)");
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(
        html.contains("Chosen automatically"),
        "the auto choice is shown"
    );
}
