"""The Python package's per-call costs beside the Rust figures, measured in one run.

One model (the paper's method, trained here by `TerrainClassifier.fit` on simulated mid-stance images)
is timed three ways on the same images: `presrs bench --model` (Rust: `Session::classify` in a Rust
loop), `Model.predict_proba` / `Model.predict` on one image, and `TerrainClassifier.predict` on one
image; then `OnlineClassifier.push` per frame of simulated movies. Medians of warm single calls
(`time.perf_counter_ns`); ratios are Python's median over Rust's, within this run. Prints a Markdown
table; `--json FILE` also writes the raw figures.

    python bench/python/bench.py --cli target/release/presrs [--rounds 3] [--json out.json]
"""

import argparse
import json
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

import presrs
from presrs.sklearn import TerrainClassifier


def median_us(call, inputs, calls):
    """The median time of `call(x)` in microseconds, cycling through `inputs`, after a warm-up."""
    for x in inputs[:50]:
        call(x)
    times = np.empty(calls)
    n = len(inputs)
    for i in range(calls):
        x = inputs[i % n]
        start = time.perf_counter_ns()
        call(x)
        times[i] = time.perf_counter_ns() - start
    return float(np.median(times)) / 1e3


def push_us(model, movies):
    """Median and mean time of `OnlineClassifier.push` per frame over `movies` (frames taken once),
    and the median per kind of frame (what the push returned: nothing, a touchdown, a lift-off, a
    classification), which tells the typical frame from the decision frames."""
    online = presrs.OnlineClassifier(model)
    times, kinds = [], []
    for frames in movies:
        for frame in frames:
            start = time.perf_counter_ns()
            events = online.push(frame)
            times.append(time.perf_counter_ns() - start)
            kinds.append("+".join(sorted(e["event"] for e in events)) or "no event")
    online.finish()
    times = np.array(times[100:]) / 1e3  # after the detector's warm-up
    kinds = kinds[100:]
    by_kind = {
        kind: float(np.median(times[[k == kind for k in kinds]])) for kind in sorted(set(kinds))
    }
    return float(np.median(times)), float(np.mean(times)), len(times), by_kind


def rust_single_us(cli, model_path, images, work):
    """`presrs bench --model M --images MANIFEST`: Rust's median per image on the same images."""
    rows = ["path,label"]
    for i, image in enumerate(images):
        np.save(work / f"image{i:04d}.npy", image)
        rows.append(f"image{i:04d}.npy,x")
    (work / "manifest.csv").write_text("\n".join(rows) + "\n")
    out = subprocess.run(
        [str(cli), "bench", "--model", str(model_path), "--images", str(work / "manifest.csv"),
         "--iterations", "20000", "--batch", "64", "--batch-runs", "1", "--json"],
        check=True, capture_output=True, text=True,
    ).stdout
    return json.loads(out)["single_image_median_ns"] / 1e3


def one_round(cli, est, images, movies, work):
    model = est.model_
    model_path = work / "model.json"
    model.save(model_path)
    figures = {"rust_session_classify": rust_single_us(cli, model_path, images[:200], work)}
    figures["Model.predict_proba"] = median_us(model.predict_proba, images, 20000)
    figures["Model.predict"] = median_us(model.predict, images, 20000)
    figures["TerrainClassifier.predict (one image)"] = median_us(est.predict, images, 20000)
    batches = [images[i : i + 1] for i in range(len(images))]
    figures["TerrainClassifier.predict (batch of 1)"] = median_us(est.predict, batches, 20000)
    median, mean, frames, by_kind = push_us(model, movies)
    figures["OnlineClassifier.push median"] = median
    figures["OnlineClassifier.push mean"] = mean
    for kind, value in by_kind.items():
        figures[f"OnlineClassifier.push median, {kind} frames"] = value
    figures["push frames"] = frames
    return figures


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cli", required=True, help="a release build of presrs")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    trials = presrs.simulate(gaits=["G1", "G2", "G3"], hops=20, seed=1)
    images, labels = [], []
    for trial in trials:
        frames, stances = presrs.stance_images(trial.recording)
        images.append(frames)
        labels += [trial.terrain] * len(stances)
    images, labels = np.concatenate(images), np.array(labels)
    est = TerrainClassifier(features="fft1d", classifier="pwe", seed=1).fit(images, labels)
    movies = [trial.recording.frames for trial in trials]
    rounds = []
    with tempfile.TemporaryDirectory() as work:
        for _ in range(args.rounds):
            rounds.append(one_round(args.cli, est, images, movies, Path(work)))
    rust = [r["rust_session_classify"] for r in rounds]
    lines = [
        f"{len(images)} simulated 44x44 mid-stance images, the paper's method (fft1d + pwe); "
        f"{rounds[0]['push frames']} frames pushed; {args.rounds} rounds, medians of rounds.",
        "",
        "| call | median (us) | / Rust Session::classify |",
        "|---|---:|---:|",
        f"| Rust `Session::classify` (`presrs bench --model`) | {np.median(rust):.2f} | 1.0 |",
    ]
    for key in rounds[0]:
        if key in ("rust_session_classify", "push frames"):
            continue
        values = [r[key] for r in rounds]
        if key.startswith("OnlineClassifier"):
            # A frame's push is stance detection (a classification only at the decision frame):
            # not comparable with one classification.
            lines.append(f"| {key} | {np.median(values):.2f} | - |")
            continue
        ratios = [r[key] / r["rust_session_classify"] for r in rounds]
        lines.append(
            f"| {key} | {np.median(values):.2f} | {np.median(ratios):.1f} "
            f"({min(ratios):.1f}-{max(ratios):.1f}) |"
        )
    print("\n".join(lines))
    if args.json:
        args.json.write_text(json.dumps({"rounds": rounds}, indent=1))


if __name__ == "__main__":
    main()
