//! A fuzz-style harness that runs in plain `cargo test` (the libFuzzer targets in `fuzz/` go deeper but
//! need nightly): every reader gets many seeded mutations of valid inputs (the real TekScan exports in
//! `shared/data/tekscan/`, read in place, and small generated NPY/PNG/text/manifest/model/stream files)
//! plus hand-written hostile values. Every call must return (no panic) quickly, and a recording that is
//! returned can never hold more values than the input had bytes (a claimed size is never trusted).
//!
//! Inputs that once crashed a reader (found by the fuzzers) live in `tests/fuzz_regressions/<target>/`
//! and are replayed by [`regressions_stay_fixed`].

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use presrs_core::testing::{SYNTHETIC_CLASSES, bench_fixture};
use presrs_core::{Frame, Grid, Recording, SensorMeta};
use presrs_core::{LabeledImage, TrainConfig};
use presrs_io::ReadOptions;
use presrs_io::frame_protocol::{Dtype, FrameReader, encode_frame};
use presrs_io::model_file::{ModelFile, Provenance, parse_model};
use presrs_io::tekscan::TekscanStream;

/// SplitMix64: a tiny seeded generator, so that every run mutates the same way.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Values that readers tend to trust too much.
const HOSTILE_TOKENS: &[&str] = &[
    "0",
    "-1",
    "-0",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e308",
    "1e309",
    "4294967296",
    "18446744073709551616",
    "99999999999999999999",
    "2147483647",
    "65535",
    "1.5",
    "B",
    "",
    ",",
    "@@",
    "\u{feff}",
    "\u{0}",
    "é",
    "\r",
    "(99999999999, 99999999999)",
    "'<f8'",
    "'|O'",
    "null",
    "[]",
    "{}",
    "true",
];

fn mutate(seed: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut data = seed.to_vec();
    for _ in 0..1 + rng.below(4) {
        let len = data.len();
        match rng.below(9) {
            // Flip a bit.
            0 if len > 0 => {
                let at = rng.below(len);
                data[at] ^= 1 << rng.below(8);
            }
            // An interesting byte.
            1 if len > 0 => {
                let at = rng.below(len);
                data[at] = [0u8, 0xff, 0x7f, 0x80, b'\n', b',', b' ', b'9'][rng.below(8)];
            }
            // Truncate.
            2 => data.truncate(rng.below(len + 1)),
            // Delete a range.
            3 if len > 0 => {
                let at = rng.below(len);
                let end = (at + 1 + rng.below(64)).min(len);
                data.drain(at..end);
            }
            // Insert random bytes.
            4 => {
                let at = rng.below(len + 1);
                let n = 1 + rng.below(16);
                let bytes: Vec<u8> = (0..n).map(|_| rng.next() as u8).collect();
                data.splice(at..at, bytes);
            }
            // Duplicate a chunk.
            5 if len > 0 => {
                let at = rng.below(len);
                let end = (at + 1 + rng.below(256)).min(len);
                let chunk = data[at..end].to_vec();
                let to = rng.below(len + 1);
                data.splice(to..to, chunk);
            }
            // Replace a run of digits (a number, a dimension, a count) with a hostile token.
            6 | 7 => {
                let digits: Vec<usize> = data
                    .iter()
                    .enumerate()
                    .filter(|(_, b)| b.is_ascii_digit())
                    .map(|(i, _)| i)
                    .collect();
                if let Some(&start) = digits.get(rng.below(digits.len())) {
                    let end = data[start..]
                        .iter()
                        .position(|b| !b.is_ascii_digit() && *b != b'.')
                        .map_or(data.len(), |n| start + n);
                    let token = HOSTILE_TOKENS[rng.below(HOSTILE_TOKENS.len())];
                    data.splice(start..end, token.bytes());
                }
            }
            // Overwrite with a little-endian integer of an interesting size (binary formats).
            _ if len >= 8 => {
                let at = rng.below(len - 7);
                let value: u64 = [
                    0,
                    1,
                    u64::MAX,
                    u64::from(u32::MAX),
                    1 << 31,
                    0x7fff_ffff_ffff,
                ][rng.below(6)];
                let n = [1, 2, 4, 8][rng.below(4)];
                data[at..at + n].copy_from_slice(&value.to_le_bytes()[..n]);
            }
            _ => {}
        }
    }
    data
}

/// Runs `parse` on `input`; a panic or a slow call fails the test after saving the input (under the
/// target directory) so that it can be replayed and added to `tests/fuzz_regressions/`.
fn check(target: &str, input: &[u8], parse: &dyn Fn(&[u8]) -> Option<usize>) {
    let start = Instant::now();
    let outcome = catch_unwind(AssertUnwindSafe(|| parse(input)));
    let elapsed = start.elapsed();
    let problem = match &outcome {
        Err(_) => Some("panicked".to_owned()),
        Ok(_) if elapsed > Duration::from_secs(5) => Some(format!("took {elapsed:?}")),
        // A recording cannot hold more values than the input had bytes (plus a little for tiny files).
        Ok(Some(values)) if *values > input.len() + 16 => Some(format!(
            "returned {values} values from {} bytes",
            input.len()
        )),
        Ok(_) => None,
    };
    if let Some(problem) = problem {
        let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("fuzz-failures");
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(format!("{target}-{:016x}", fxhash(input)));
        std::fs::write(&path, input).unwrap();
        panic!("{target} {problem} on {} (saved)", path.display());
    }
}

fn fxhash(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

fn values(rec: &Recording) -> usize {
    rec.data().len()
}

type Parser = fn(&[u8]) -> Option<usize>;

fn tekscan(input: &[u8]) -> Option<usize> {
    let text = String::from_utf8_lossy(input);
    let strict = presrs_io::parse_tekscan(&text, "f.asf", &ReadOptions::default());
    let lenient = presrs_io::parse_tekscan(&text, "f.asf", &ReadOptions::lenient());
    if let (Ok(a), Ok(b)) = (&strict, &lenient) {
        assert_eq!(
            a.recording, b.recording,
            "lenient reading changed a clean file"
        );
    }
    let a = strict.ok().map(|p| values(&p.recording));
    let b = lenient.ok().map(|p| values(&p.recording));
    a.max(b)
}

fn tekscan_stream(input: &[u8]) -> Option<usize> {
    let mut stream = TekscanStream::new(std::io::Cursor::new(input), "f.asf");
    let (mut v, mut p) = (Vec::new(), Vec::new());
    let mut total = 0;
    for _ in 0..100_000 {
        match stream.next_frame(&mut v, &mut p) {
            Ok(Some(_)) => total += v.len(),
            Ok(None) => return Some(total),
            Err(_) if stream.header().is_none() => return None,
            Err(_) => {}
        }
    }
    panic!("TekscanStream did not finish within 100000 calls");
}

fn npy(input: &[u8]) -> Option<usize> {
    presrs_io::npy::parse_npy(input, "f.npy")
        .ok()
        .map(|r| values(&r))
}

fn png(input: &[u8]) -> Option<usize> {
    // PNG compresses: a small file can legitimately hold a large image (the png crate caps it).
    presrs_io::png::parse_png(input, "f.png")
        .ok()
        .map(|r| values(&r).min(input.len()))
}

fn text(input: &[u8]) -> Option<usize> {
    presrs_io::text::parse_text_matrix(&String::from_utf8_lossy(input), "f.txt")
        .ok()
        .map(|r| values(&r))
}

fn manifest(input: &[u8]) -> Option<usize> {
    presrs_io::manifest::parse_manifest(input, Path::new("m.csv"), Path::new("/nonexistent"))
        .ok()
        .map(|m| m.rows.len())
}

fn model(input: &[u8]) -> Option<usize> {
    let file = parse_model(input, "m.json").ok()?;
    let mut session = file.model.session();
    for grid in [file.model.image_grid(), Grid::new(44, 44)] {
        if grid.len() <= 1 << 16 {
            let values: Vec<f64> = (0..grid.len()).map(|i| (i % 17) as f64).collect();
            if let Ok(frame) = Frame::new(grid, values) {
                let _ = session.classify(&frame.view());
            }
        }
    }
    None
}

fn frames(input: &[u8]) -> Option<usize> {
    let mut reader = FrameReader::new("fuzz", 1 << 16);
    let mut cursor = std::io::Cursor::new(input);
    let mut values = Vec::new();
    let mut total = 0;
    loop {
        match reader.read_frame(&mut cursor, &mut values) {
            Ok(Some(header)) => {
                assert_eq!(values.len(), header.rows * header.cols);
                total += values.len();
            }
            Ok(None) => return Some(total),
            Err(err) if err.is_fatal() => return None,
            Err(_) => {}
        }
    }
}

fn shared(name: &str) -> Vec<u8> {
    std::fs::read(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../../shared/data/tekscan")
            .join(name),
    )
    .unwrap()
}

fn small_recording() -> Recording {
    let data: Vec<f64> = (0..2 * 3 * 4).map(|i| f64::from(i * 7 % 11)).collect();
    Recording::new(
        Grid::new(3, 4),
        Some(0.01),
        data,
        None,
        SensorMeta::default(),
    )
    .unwrap()
}

/// A small but complete model file (2 components, 12 training images): quick to parse many times.
fn small_model() -> Vec<u8> {
    let (_, frames) = bench_fixture(1, 20).unwrap();
    let images: Vec<LabeledImage<'_>> = frames
        .iter()
        .enumerate()
        .map(|(i, f)| LabeledImage::new(f.view(), SYNTHETIC_CLASSES[i % 4]))
        .collect();
    let config = TrainConfig {
        dims: 2,
        ..TrainConfig::default()
    }
    .check()
    .unwrap();
    let model = presrs_core::train(&images[..12], &images[12..], &config).unwrap();
    serde_json::to_vec(&ModelFile::new(model, Provenance::default())).unwrap()
}

fn seeds(target: &str) -> Vec<Vec<u8>> {
    let rec = small_recording();
    match target {
        "tekscan" | "tekscan_stream" => {
            let mut small = Vec::new();
            presrs_io::write_tekscan(&rec, &mut small).unwrap();
            vec![shared("example3.asf"), small]
        }
        "npy" => {
            let mut a = Vec::new();
            presrs_io::npy::write_npy_f64(&mut a, &[2, 3, 4], rec.data()).unwrap();
            let mut b = Vec::new();
            let bytes: Vec<u8> = rec.data().iter().map(|&v| v as u8).collect();
            presrs_io::npy::write_npy_u8(&mut b, &[6, 4], &bytes).unwrap();
            vec![a, b]
        }
        "png" => {
            let mut a = Vec::new();
            let pixels: Vec<u8> = (0..12).map(|i| i * 20).collect();
            presrs_io::png::write_png_gray8(&mut a, Grid::new(3, 4), &pixels).unwrap();
            vec![a]
        }
        "text" => vec![
            b"1 2 3\n4 5 6\n".to_vec(),
            b"# c\n0.5, B, 1e3,\n-2, 0, 7,\n".to_vec(),
        ],
        "manifest" => {
            vec![
            b"path,label,condition,group,frame,load\na.asf,wood,G1,t0,3,1.5\nb.png,grass,G2,,,\n"
                .to_vec(),
            "\u{feff}path,label,extra\n\"q,uoted.txt\",x,1\n".as_bytes().to_vec(),
        ]
        }
        "model" => vec![small_model()],
        "frames" => {
            let mut all = Vec::new();
            let mut one = Vec::new();
            for (k, dtype) in [Dtype::U8, Dtype::U16, Dtype::F32, Dtype::F64]
                .into_iter()
                .enumerate()
            {
                encode_frame(&mut one, 3, 4, dtype, k as u64, &rec.data()[..12]).unwrap();
                all.extend_from_slice(&one);
            }
            vec![all]
        }
        _ => unreachable!("unknown target {target}"),
    }
}

fn parser(target: &str) -> Parser {
    match target {
        "tekscan" => tekscan,
        "tekscan_stream" => tekscan_stream,
        "npy" => npy,
        "png" => png,
        "text" => text,
        "manifest" => manifest,
        "model" => model,
        "frames" => frames,
        _ => unreachable!("unknown target {target}"),
    }
}

/// Mutation rounds per seed; a few seconds in all in a debug build.
fn rounds(target: &str) -> usize {
    match target {
        "model" => 400,
        "tekscan" | "tekscan_stream" => 300,
        _ => 1500,
    }
}

fn fuzz(target: &str, seed: u64) {
    let parse = parser(target);
    let mut rng = Rng(seed);
    for input in seeds(target) {
        assert!(
            parse(&input).is_some() || matches!(target, "model"),
            "{target} seed does not parse"
        );
        check(target, &input, &parse);
        for _ in 0..rounds(target) {
            let mutated = mutate(&input, &mut rng);
            check(target, &mutated, &parse);
        }
    }
    // Inputs that are not mutations of anything: empty, garbage, UTF-16.
    let mut garbage = vec![0u8; 4096];
    garbage.iter_mut().for_each(|b| *b = rng.next() as u8);
    let utf16: Vec<u8> = "\u{feff}ROWS 2\nCOLS 2\n1 2\n3 4\n"
        .encode_utf16()
        .flat_map(u16::to_le_bytes)
        .collect();
    for input in [&b""[..], b"\n\n", b"\0", &garbage, &utf16] {
        check(target, input, &parse);
    }
}

#[test]
fn fuzz_tekscan() {
    fuzz("tekscan", 1);
}

#[test]
fn fuzz_tekscan_stream() {
    fuzz("tekscan_stream", 2);
}

#[test]
fn fuzz_npy() {
    fuzz("npy", 3);
}

#[test]
fn fuzz_png() {
    fuzz("png", 4);
}

#[test]
fn fuzz_text_matrix() {
    fuzz("text", 5);
}

#[test]
fn fuzz_manifest() {
    fuzz("manifest", 6);
}

#[test]
fn fuzz_model() {
    fuzz("model", 7);
}

#[test]
fn fuzz_frame_protocol() {
    fuzz("frames", 8);
}

/// The large real export, mutated a few times (each parse reads 205 frames).
#[test]
fn fuzz_tekscan_large_real_file() {
    let input = shared("FrasP01L.asf");
    let mut rng = Rng(9);
    for _ in 0..8 {
        check("tekscan", &mutate(&input, &mut rng), &(tekscan as Parser));
    }
}

/// Replays every input under `tests/fuzz_regressions/<target>/` (crashes found by fuzzing, fixed since).
/// Folder names are the libFuzzer target names in `fuzz/`.
#[test]
fn regressions_stay_fixed() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_regressions");
    let mut replayed = 0;
    for (folder, target) in [
        ("parse_tekscan", "tekscan"),
        ("tekscan_stream", "tekscan_stream"),
        ("parse_npy", "npy"),
        ("parse_png", "png"),
        ("parse_text_matrix", "text"),
        ("parse_manifest", "manifest"),
        ("parse_model", "model"),
        ("frame_protocol", "frames"),
    ] {
        let Ok(entries) = std::fs::read_dir(root.join(folder)) else {
            continue;
        };
        for entry in entries {
            let path = entry.unwrap().path();
            let input = std::fs::read(&path).unwrap();
            // The libFuzzer npy/png targets prepend the magic bytes; replay both ways.
            let mut prefixed = match folder {
                "parse_npy" => presrs_io::npy::NPY_MAGIC.to_vec(),
                "parse_png" => presrs_io::png::PNG_MAGIC.to_vec(),
                _ => Vec::new(),
            };
            prefixed.extend_from_slice(&input);
            check(target, &prefixed, &parser(target));
            check(target, &input, &parser(target));
            replayed += 1;
        }
    }
    eprintln!("replayed {replayed} regression inputs");
}

/// The model files in `tests/fuzz_regressions/parse_model/` (valid files with one field corrupted) used
/// to load and then panic, give NaN posteriors or plan a 2^32-point FFT; each is now refused on load with
/// an error naming the file and the field.
#[test]
fn corrupted_model_files_are_refused_on_load() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_regressions/parse_model");
    let expected = [
        ("knn-k-0", "`k`"),
        ("knn-class-out-of-range", "`classes`"),
        ("mle-empty-factors", "`factors`"),
        ("lda-zero-temperature", "`temperature`"),
        ("svm-no-machines", "`machines`"),
        ("svm-support-out-of-range", "`machines[0].support`"),
        ("pwe-sigma-1e-160", "`sigma`"),
        ("image-grid-65536x65536", "image_grid"),
        ("fft-len-2-40", "fft_len"),
    ];
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|entry| entry.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    let mut listed: Vec<&str> = expected.iter().map(|(name, _)| *name).collect();
    listed.sort_unstable();
    assert_eq!(
        names,
        listed,
        "every file in {} is listed here",
        dir.display()
    );
    for (name, field) in expected {
        let err = presrs_io::model_file::load_model(&dir.join(name))
            .map(|_| ())
            .unwrap_err()
            .to_string();
        assert!(err.contains(name) && err.contains(field), "{name}: {err}");
    }
}

/// CRC-32 (IEEE), as PNG chunks use.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xedb8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// The inputs libFuzzer found allocating gigabytes (`-malloc_limit_mb`) are now errors before any
/// allocation.
#[test]
fn claimed_sizes_are_checked_before_allocating() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_regressions");
    let read = |p: &str| std::fs::read(root.join(p)).unwrap();
    let npy = [
        presrs_io::npy::NPY_MAGIC,
        &read("parse_npy/v2-header-length-4gb"),
    ]
    .concat();
    let err = presrs_io::npy::parse_npy(&npy, "h.npy")
        .unwrap_err()
        .to_string();
    assert!(err.contains("h.npy") && err.contains("truncated"), "{err}");
    // libFuzzer builds of the png crate skip CRC checks; fix the IHDR CRC so that this build gets as
    // far as the size check.
    let mut png = [
        presrs_io::png::PNG_MAGIC,
        &read("parse_png/claims-4x1694498819-pixels"),
    ]
    .concat();
    let crc = crc32(&png[12..29]).to_be_bytes();
    png[29..33].copy_from_slice(&crc);
    let err = presrs_io::png::parse_png(&png, "h.png")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("h.png") && err.contains("4 x 1694498819"),
        "{err}"
    );
}

/// Writes the seed inputs as libFuzzer corpora when `PRESRS_FUZZ_SEEDS` names a folder (used to start
/// `cargo fuzz run`; see `fuzz/README.md`). Does nothing otherwise.
#[test]
fn write_fuzz_seed_corpora() {
    let Some(dir) = std::env::var_os("PRESRS_FUZZ_SEEDS") else {
        return;
    };
    for (folder, target, strip) in [
        ("parse_tekscan", "tekscan", 0),
        ("tekscan_stream", "tekscan_stream", 0),
        ("parse_npy", "npy", presrs_io::npy::NPY_MAGIC.len()),
        ("parse_png", "png", presrs_io::png::PNG_MAGIC.len()),
        ("parse_text_matrix", "text", 0),
        ("parse_manifest", "manifest", 0),
        ("parse_model", "model", 0),
        ("frame_protocol", "frames", 0),
    ] {
        let out = Path::new(&dir).join(folder);
        std::fs::create_dir_all(&out).unwrap();
        for (i, seed) in seeds(target).into_iter().enumerate() {
            std::fs::write(out.join(format!("seed{i}")), &seed[strip..]).unwrap();
        }
    }
}
