#!/usr/bin/env python3
"""The paper's pipeline in numpy and in scikit-learn, timed next to presrs on the same inputs.

Reads what `presrs bench --export DIR` wrote (the trained model file, the test images, presrs's features,
reduced vectors, predictions and timings), runs the same pipeline -- crop 44x44 -> 38x41, 1-D |FFT|
(eqs. 3-5: row-major vectorisation, zero padding to N = 2048, |rfft|, 1025 values), PCA to 51 dims with
presrs's trained mean and axes, Parzen window with presrs's stored vectors and sigma, equal class priors,
posteriors calibrated by presrs's temperature (softmax of log class densities / temperature) --
checks every stage against presrs, times one call per image and one vectorised call on a batch, and prints
the ratios. Two peers:

* numpy: the pipeline as a competent numpy engineer writes it for speed -- np.fft.rfft, one matrix product
  for the projection, squared distances by |x|^2 + |p|^2 - 2 p.x, log-sum-exp per class with
  np.maximum.reduceat / np.add.reduceat. The targets are judged against this one (the faster peer).
* scikit-learn: sklearn.decomposition.PCA carrying presrs's trained mean and axes (.transform) and one
  sklearn.neighbors.KernelDensity(kernel="gaussian", bandwidth=sigma) per class (.score_samples), the
  library way of writing a Parzen-window classifier.

Only the standard library, numpy and scikit-learn (with threadpoolctl, which it depends on) are used.
"""

from __future__ import annotations

import argparse
import datetime
import gc
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import sklearn
from sklearn.decomposition import PCA
from sklearn.neighbors import KernelDensity
from threadpoolctl import threadpool_info

# --------------------------------------------------------------------------------------------------------
# The trained state, from presrs's model file


class State:
    """presrs's trained pipeline (model.json of the export), as numpy arrays."""

    def __init__(self, model_path: Path):
        document = json.loads(model_path.read_text())
        if document.get("format") != "presrs-model":
            raise SystemExit(f"{model_path}: not a presrs model file")
        model = document["model"]
        features = model["features"]
        classifier = model["classifier"]
        if features.get("kind") != "fft1d" or classifier.get("kind") != "pwe":
            raise SystemExit(
                f"{model_path}: the peer implements the paper's method (fft1d + pwe), "
                f"this model is {features.get('kind')} + {classifier.get('kind')}"
            )
        preprocess = model.get("preprocess") or {}
        if preprocess.get("normalise_load") or preprocess.get("fill_absent"):
            raise SystemExit(f"{model_path}: preprocessing {preprocess} is not implemented by the peer")
        self.class_names = list(model["class_names"])
        self.rows = model["image_grid"]["rows"]
        self.cols = model["image_grid"]["cols"]
        self.crop = model["crop"]
        # eq. 3-4: N is the next power of two holding rows * cols sensels unless the model fixes it
        self.fft_len = features.get("fft_len") or 1 << (self.rows * self.cols - 1).bit_length()
        pca = model["pca"]
        self.n_features = pca["n_features"]
        self.mean = np.asarray(pca["mean"], dtype=np.float64)
        self.basis = np.asarray(pca["basis"], dtype=np.float64).reshape(-1, self.n_features)
        self.explained_variance = np.asarray(pca["explained_variance"], dtype=np.float64)
        self.dims = classifier["dims"]
        self.sigma = float(classifier["sigma"])
        # posteriors = softmax(log class densities / temperature); model files before calibration: 1
        self.temperature = float(classifier.get("temperature", 1.0))
        self.vectors = np.asarray(classifier["vectors"], dtype=np.float64).reshape(-1, self.dims)
        self.class_starts = np.asarray(classifier["class_starts"], dtype=np.intp)
        assert self.basis.shape == (self.dims, self.n_features)
        assert self.fft_len // 2 + 1 == self.n_features

    def window(self, image_rows: int, image_cols: int) -> tuple[slice, slice]:
        """The crop's rows and columns on an image_rows x image_cols image (presrs's Crop::window)."""
        crop = self.crop
        if crop["kind"] == "margins":
            row0, col0 = crop["top"], crop["left"]
            rows = image_rows - crop["top"] - crop["bottom"]
            cols = image_cols - crop["left"] - crop["right"]
        else:
            row0, col0, rows, cols = crop["row0"], crop["col0"], crop["rows"], crop["cols"]
        if (rows, cols) != (self.rows, self.cols):
            raise SystemExit(f"a {image_rows}x{image_cols} image does not crop to {self.rows}x{self.cols}")
        return slice(row0, row0 + rows), slice(col0, col0 + cols)


# --------------------------------------------------------------------------------------------------------
# Peer 1: numpy


class NumpyPeer:
    """The pipeline in numpy, written for speed.

    Algebraically the same as presrs: projection `basis @ (f - mean)` in float32 as presrs's
    classification path does it, squared distances `|z|^2 + |p|^2 - 2 p.z` with the |z|^2 term dropped (it is the same for
    every stored vector, so it cancels in the posteriors), and the class densities shifted by the largest
    kernel exponent before exp (log-sum-exp with one shift for all classes: the best class's density is
    at least 1/count, so nothing that matters underflows). With a calibrated model (temperature T != 1,
    posteriors = softmax(log densities / T)) the other classes' densities matter even where they underflow,
    so the log densities are formed with one shift per class, as presrs does then.
    """

    name = "numpy"

    def __init__(self, state: State, image_shape: tuple[int, int]):
        self.rs, self.cs = state.window(*image_shape)
        self.n = state.fft_len
        # presrs classifies with an f32 copy of the PCA axes (the centred features rounded to f32, f32
        # accumulation: half the bytes to stream); this peer does the same, which is also faster in numpy.
        self.mean = state.mean
        self.basis32 = np.ascontiguousarray(state.basis, dtype=np.float32)  # dims x n_features
        inv_two_var = 0.5 / (state.sigma * state.sigma)
        # kernel exponent -|z - p|^2 / (2 sigma^2) + |z|^2 / (2 sigma^2) = a @ z - b
        self.a = np.ascontiguousarray(state.vectors * (2.0 * inv_two_var))
        self.b = np.einsum("ij,ij->i", state.vectors, state.vectors) * inv_two_var
        self.starts = state.class_starts[:-1]
        self.inv_counts = 1.0 / np.diff(state.class_starts)
        self.temperature = state.temperature

        self.counts = np.diff(state.class_starts)

    def log_densities(self, z: np.ndarray) -> np.ndarray:
        """Log class densities (up to one constant per image), log-sum-exp shifted per class: with a
        temperature the posteriors are exp(log density / T), and a class hundreds of units below the best
        one, whose density underflows, still gets a posterior that counts."""
        exponent = z @ self.a.T - self.b
        top = np.maximum.reduceat(exponent, self.starts, axis=-1)
        kernel = np.exp(exponent - np.repeat(top, self.counts, axis=-1))
        return top + np.log(np.add.reduceat(kernel, self.starts, axis=-1) * self.inv_counts)

    def tempered(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        scores = self.log_densities(z)
        posteriors = np.exp((scores - scores.max(axis=-1, keepdims=True)) / self.temperature)
        return np.argmax(scores, axis=-1), posteriors / posteriors.sum(axis=-1, keepdims=True)

    def features(self, images: np.ndarray) -> np.ndarray:
        """eqs. 3-5 on one image or a stack: crop, row-major vectorisation, |rfft| zero-padded to N."""
        x = images[..., self.rs, self.cs].reshape(*images.shape[:-2], -1)
        return np.abs(np.fft.rfft(x, n=self.n, axis=-1))

    def reduce(self, features: np.ndarray) -> np.ndarray:
        """PCA: basis . (f - mean) in float32, for one vector or a stack of rows."""
        return (features - self.mean).astype(np.float32) @ self.basis32.T

    def densities(self, z: np.ndarray) -> np.ndarray:
        """Class densities (mean kernel value per class), up to one positive factor per image."""
        exponent = z @ self.a.T - self.b
        kernel = np.exp(exponent - exponent.max(axis=-1, keepdims=True))
        return np.add.reduceat(kernel, self.starts, axis=-1) * self.inv_counts

    def classify(self, image: np.ndarray) -> tuple[int, np.ndarray]:
        """One 44x44 image -> (class index, posteriors)."""
        z = self.reduce(self.features(image))
        if self.temperature != 1.0:
            best, posteriors = self.tempered(z)
            return int(best), posteriors
        density = self.densities(z)
        return int(np.argmax(density)), density / density.sum()

    def classify_batch(self, images: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """n x 44 x 44 images -> (class indices, n x classes posteriors), one vectorised pass."""
        z = self.reduce(self.features(images))
        if self.temperature != 1.0:
            return self.tempered(z)
        density = self.densities(z)
        return np.argmax(density, axis=1), density / density.sum(axis=1, keepdims=True)


# --------------------------------------------------------------------------------------------------------
# Peer 1b: presrs's own Python package


class PresrsPythonPeer:
    """presrs's Python package (`pip install ./python`): the same Rust code behind a Python call, so its
    figures are what a Python robot loop pays on top of presrs (argument checks, the numpy array in, the
    posteriors out)."""

    name = "presrs (Python)"

    def __init__(self, model_path: Path):
        import presrs  # noqa: PLC0415 - optional: the table leaves this row out without it

        self.presrs = presrs
        self.model = presrs.Model.load(model_path)

    def classify(self, image: np.ndarray) -> tuple[int, np.ndarray]:
        posteriors = self.model.predict_proba(image)
        return int(posteriors.argmax()), posteriors

    def classify_batch(self, images: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        posteriors = self.model.predict_proba(images)
        return posteriors.argmax(axis=1), posteriors

    def features(self, images: np.ndarray) -> np.ndarray:
        return self.presrs.features(images)


# --------------------------------------------------------------------------------------------------------
# Peer 2: scikit-learn


class SklearnPeer:
    name = "scikit-learn"

    def __init__(self, state: State, image_shape: tuple[int, int]):
        self.rs, self.cs = state.window(*image_shape)
        self.n = state.fft_len
        # A PCA carrying presrs's fitted state (not refitted: the same trained state is compared).
        pca = PCA(n_components=state.dims, whiten=False)
        pca.components_ = state.basis
        pca.mean_ = state.mean
        pca.explained_variance_ = state.explained_variance
        pca.n_components_ = state.dims
        pca.n_features_in_ = state.n_features
        self.pca = pca
        # One Gaussian KDE per class on that class's stored vectors, exact (atol = rtol = 0). score_samples
        # gives log(mean kernel) - (d/2) log(2 pi sigma^2); the constant is the same for every class.
        self.temperature = state.temperature
        self.kdes = [
            KernelDensity(kernel="gaussian", bandwidth=state.sigma).fit(state.vectors[start:end])
            for start, end in zip(state.class_starts[:-1], state.class_starts[1:])
        ]

    def features(self, images: np.ndarray) -> np.ndarray:
        x = images[..., self.rs, self.cs].reshape(*images.shape[:-2], -1)
        return np.abs(np.fft.rfft(x, n=self.n, axis=-1))

    def classify(self, image: np.ndarray) -> tuple[int, np.ndarray]:
        z = self.pca.transform(self.features(image)[None, :])
        scores = np.array([kde.score_samples(z)[0] for kde in self.kdes])
        best = int(np.argmax(scores))
        posteriors = np.exp((scores - scores[best]) / self.temperature)
        return best, posteriors / posteriors.sum()

    def classify_batch(self, images: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        z = self.pca.transform(self.features(images))
        scores = np.stack([kde.score_samples(z) for kde in self.kdes], axis=1)
        best = np.argmax(scores, axis=1)
        posteriors = np.exp((scores - scores.max(axis=1, keepdims=True)) / self.temperature)
        return best, posteriors / posteriors.sum(axis=1, keepdims=True)


# --------------------------------------------------------------------------------------------------------
# Timing


def time_single(peer, images: np.ndarray, iterations: int) -> dict:
    """One call per image, cycling through the images, each call timed on its own (warm)."""
    n = len(images)
    frames = list(images)  # one C-contiguous 2-D array per image, as a sensor driver would hand them over
    for frame in frames:  # warm-up: caches, lazily initialised library state
        peer.classify(frame)
    times = np.empty(iterations, dtype=np.int64)
    clock = time.perf_counter_ns
    classify = peer.classify
    for i in range(iterations):
        frame = frames[i % n]
        start = clock()
        classify(frame)
        times[i] = clock() - start
    times.sort()
    return {
        "median_ns": int(np.median(times)),
        "p99_ns": int(times[min(iterations - 1, round((iterations - 1) * 0.99))]),
        "min_ns": int(times[0]),
        "iterations": iterations,
    }


def time_batch(peer, images: np.ndarray, batch: int, runs: int) -> dict:
    """One vectorised call on `batch` images (the test images cycled, as presrs's batch), median of runs."""
    stack = np.ascontiguousarray(images[np.arange(batch) % len(images)])
    peer.classify_batch(stack[: len(images)])  # warm-up
    rates = []
    for _ in range(runs):
        start = time.perf_counter()
        peer.classify_batch(stack)
        rates.append(batch / (time.perf_counter() - start))
    return {"images_per_s": float(np.median(rates)), "runs_images_per_s": rates, "batch": batch}


# --------------------------------------------------------------------------------------------------------
# Checks against presrs


def agreement(peer, images, presrs, features, reduced) -> dict:
    """Every stage of the peer against presrs's exported results, one call per image and batched."""
    n = len(images)
    expected = np.asarray(presrs["predictions"])
    expected_post = np.asarray(presrs["posteriors"])
    single = [peer.classify(image) for image in images]
    single_pred = np.array([c for c, _ in single])
    single_post = np.array([p for _, p in single])
    batch_pred, batch_post = peer.classify_batch(images)
    result = {
        "images": n,
        "single_agreement": float(np.mean(single_pred == expected)),
        "batch_agreement": float(np.mean(batch_pred == expected)),
        "max_posterior_diff": float(
            max(np.abs(single_post - expected_post).max(), np.abs(batch_post - expected_post).max())
        ),
        "disagreements": [int(i) for i in np.flatnonzero((single_pred != expected) | (batch_pred != expected))],
    }
    peer_features = peer.features(images)
    result["features_max_rel_diff"] = float(np.abs(peer_features - features).max() / np.abs(features).max())
    if hasattr(peer, "reduce"):
        peer_reduced = peer.reduce(peer_features)
    elif hasattr(peer, "pca"):
        peer_reduced = peer.pca.transform(peer_features)
    else:  # presrs's own package: its PCA is presrs's
        result["reduced_max_rel_diff"] = 0.0
        return result
    result["reduced_max_rel_diff"] = float(np.abs(peer_reduced - reduced).max() / np.abs(reduced).max())
    return result


# --------------------------------------------------------------------------------------------------------
# The machine


def machine() -> dict:
    cpu = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        cpu = platform.processor() or "unknown"
    flags = set()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("flags"):
                flags = set(line.split(":", 1)[1].split())
                break
    except OSError:
        pass
    mhz = None
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("cpu MHz"):
                mhz = float(line.split(":", 1)[1])
                break
    except (OSError, ValueError):
        pass
    return {
        "cpu": cpu,
        "cpu_mhz": mhz,
        "simd": [f for f in ("sse4_2", "avx", "avx2", "fma", "avx512f") if f in flags],
        "logical_cpus": os.cpu_count(),
        "usable_cpus": len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count(),
        "os": f"{platform.system()} {platform.release()}",
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scikit_learn": sklearn.__version__,
        "blas": [
            {k: info.get(k) for k in ("internal_api", "version", "num_threads", "architecture")}
            for info in threadpool_info()
        ],
    }


def load_average() -> list[float]:
    try:
        return [round(x, 2) for x in os.getloadavg()]
    except OSError:
        return []


# --------------------------------------------------------------------------------------------------------


def fmt_ns(ns: float) -> str:
    return f"{ns / 1e3:.1f} us"


def presrs_timing(presrs: Path, export: Path, seed: int, iterations: int, batch_runs: int) -> dict:
    """One run of `presrs bench` on the exported model (the same test images: same seed), as JSON."""
    command = [
        str(presrs), "bench", "--model", str(export / "model.json"), "--seed", str(seed),
        "--iterations", str(iterations), "--batch-runs", str(batch_runs), "--json",
    ]
    done = subprocess.run(command, check=True, capture_output=True, text=True)
    return json.loads(done.stdout)


def median(values):
    return float(np.median(np.asarray(values, dtype=np.float64)))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--export", type=Path, required=True, help="folder written by presrs bench --export")
    parser.add_argument("--presrs", type=Path, required=True, help="the presrs binary (release build)")
    parser.add_argument("--seed", type=int, default=1, help="the seed the export was made with")
    parser.add_argument("--rounds", type=int, default=3, help="rounds of presrs, numpy, scikit-learn timings")
    parser.add_argument("--iterations", type=int, default=20000, help="timed single-image calls (presrs, numpy)")
    parser.add_argument(
        "--sklearn-iterations", type=int, default=2000, help="timed single-image calls (scikit-learn)"
    )
    parser.add_argument("--batch-runs", type=int, default=5, help="timed batch calls; the median is reported")
    parser.add_argument("--out", type=Path, help="write the results as JSON here")
    parser.add_argument("--markdown", type=Path, help="write the results as Markdown here")
    parser.add_argument("--load-before", default="", help="load average before the run (from the script)")
    parser.add_argument("--presrs-commit", default="", help="git describe of the presrs build")
    args = parser.parse_args()

    exported = json.loads((args.export / "presrs.json").read_text())
    images = np.load(args.export / exported["images"])
    features = np.load(args.export / exported["features"])
    reduced = np.load(args.export / exported["reduced"])
    state = State(args.export / exported["model_file"])
    image_shape = images.shape[1:]
    batch = exported["timing"]["batch"]

    peers = [NumpyPeer(state, image_shape), SklearnPeer(state, image_shape)]
    try:
        peers.append(PresrsPythonPeer(args.export / exported["model_file"]))
    except ImportError:
        print("(the presrs Python package is not installed here: its row is left out)", file=sys.stderr)
    results = {
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "machine": machine(),
        "presrs_commit": args.presrs_commit,
        "load_average_before": args.load_before,
        "setup": {
            "test_images": len(images),
            "image_shape": list(image_shape),
            "cropped_shape": [state.rows, state.cols],
            "fft_len": state.fft_len,
            "features": state.n_features,
            "pca_dims": state.dims,
            "parzen_vectors": len(state.vectors),
            "sigma": state.sigma,
            "classes": state.class_names,
            "batch": batch,
            "rounds": args.rounds,
            "batch_runs": args.batch_runs,
        },
        "rounds": [],
    }
    truth = exported.get("truth") or []
    if truth:
        names = state.class_names
        results["presrs_accuracy"] = float(
            np.mean([names[p] == t for p, t in zip(exported["predictions"], truth)])
        )

    results["agreement"] = {}
    for peer in peers:
        check = agreement(peer, images, exported, features, reduced)
        results["agreement"][peer.name] = check
        print(
            f"{peer.name}: agreement with presrs {100 * check['single_agreement']:.1f} % one by one, "
            f"{100 * check['batch_agreement']:.1f} % batched (max posterior difference "
            f"{check['max_posterior_diff']:.1e}; features {check['features_max_rel_diff']:.1e}, "
            f"PCA {check['reduced_max_rel_diff']:.1e} of the largest value)",
            file=sys.stderr,
        )

    # Rounds of presrs, numpy, scikit-learn back to back, so each ratio compares timings taken under the
    # same machine load; the reported figures are medians over the rounds.
    for index in range(args.rounds):
        presrs = presrs_timing(args.presrs, args.export, args.seed, args.iterations, args.batch_runs)
        if presrs.get("test_images") != len(images):
            raise SystemExit("presrs bench did not run on the exported test images (another seed?)")
        entry = {"load_average": load_average(), "presrs": presrs, "peers": {}}
        for peer in peers:
            iterations = args.sklearn_iterations if peer.name == "scikit-learn" else args.iterations
            gc.collect()
            single = time_single(peer, images, iterations)
            gc.collect()
            batched = time_batch(peer, images, batch, args.batch_runs)
            entry["peers"][peer.name] = {
                "single_image": single,
                "batch": batched,
                "single_ratio": single["median_ns"] / presrs["single_image_median_ns"],
                "batch_ratio": presrs["batch_images_per_s"] / batched["images_per_s"],
            }
        results["rounds"].append(entry)
        print(
            f"round {index + 1}/{args.rounds}: presrs {fmt_ns(presrs['single_image_median_ns'])}, "
            + ", ".join(
                f"{name} {fmt_ns(p['single_image']['median_ns'])} ({p['single_ratio']:.1f}x), "
                f"batch {p['batch_ratio']:.1f}x"
                for name, p in entry["peers"].items()
            ),
            file=sys.stderr,
        )
    rounds = results["rounds"]
    results["presrs"] = {
        "single_image_median_ns": median([r["presrs"]["single_image_median_ns"] for r in rounds]),
        "single_image_p99_ns": median([r["presrs"]["single_image_p99_ns"] for r in rounds]),
        "batch_images_per_s": median([r["presrs"]["batch_images_per_s"] for r in rounds]),
        "batch_threads": rounds[0]["presrs"]["batch_threads"],
    }
    results["peers"] = {}
    for peer in peers:
        per_round = [r["peers"][peer.name] for r in rounds]
        results["peers"][peer.name] = {
            "single_image_median_ns": median([p["single_image"]["median_ns"] for p in per_round]),
            "single_image_p99_ns": median([p["single_image"]["p99_ns"] for p in per_round]),
            "batch_images_per_s": median([p["batch"]["images_per_s"] for p in per_round]),
            "single_ratio": median([p["single_ratio"] for p in per_round]),
            "single_ratio_range": [min(p["single_ratio"] for p in per_round), max(p["single_ratio"] for p in per_round)],
            "batch_ratio": median([p["batch_ratio"] for p in per_round]),
            "batch_ratio_range": [min(p["batch_ratio"] for p in per_round), max(p["batch_ratio"] for p in per_round)],
        }
    results["load_average_after"] = load_average()

    table = markdown(results)
    print(table)
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(results, indent=2) + "\n")
    if args.markdown:
        args.markdown.parent.mkdir(parents=True, exist_ok=True)
        args.markdown.write_text(table)
    agreed = all(
        a["single_agreement"] == 1.0 and a["batch_agreement"] == 1.0 for a in results["agreement"].values()
    )
    return 0 if agreed else 3


def markdown(results: dict) -> str:
    presrs = results["presrs"]
    numpy_peer = results["peers"]["numpy"]
    m = results["machine"]
    s = results["setup"]
    loads = " / ".join(" ".join(map(str, r["load_average"][:1])) for r in results["rounds"])
    lines = [
        "# presrs next to numpy and scikit-learn: measured figures",
        "",
        "Written by `bench/side_by_side.sh --record`; what is compared and how: `bench/README.md`. A ratio is",
        "the peer's median time per image over presrs's (one image per call), or presrs's batch throughput over",
        "the peer's (one call on the whole batch); each is the median over the rounds of the ratio measured",
        "within a round (range over the rounds in brackets).",
        "",
        f"- Machine: {m['cpu']}, {m['usable_cpus']} usable of {m['logical_cpus']} logical CPUs at "
        f"{m['cpu_mhz']:.0f} MHz ({', '.join(m['simd'])}), {m['os']}; shared with other work: load average "
        f"(1 min) {results['load_average_before'].split(' ')[0] if results['load_average_before'] else '?'} before, "
        f"{loads} at the start of each round, {results['load_average_after'][0]} after.",
        f"- Software: presrs {results['presrs_commit'] or '?'} (release build); Python {m['python']}, "
        f"numpy {m['numpy']}, scikit-learn {m['scikit_learn']}; "
        + ", ".join(f"{b['internal_api']} {b['version']} ({b['num_threads']} threads)" for b in m["blas"])
        + ".",
        f"- Inputs: {s['test_images']} simulated mid-stance images ({s['image_shape'][0]}x{s['image_shape'][1]}, "
        f"cropped to {s['cropped_shape'][0]}x{s['cropped_shape'][1]}); |rfft| with N = {s['fft_len']} -> "
        f"{s['features']} features, PCA {s['pca_dims']}, Parzen window over {s['parzen_vectors']} vectors "
        f"(sigma {s['sigma']:.4g}); batch of {s['batch']} images; {s['rounds']} round(s).",
        "",
        "| implementation | agreement with presrs | one image per call: median (p99) | presrs faster by "
        "| batch: images/s | presrs faster by |",
        "| --- | --- | --- | --- | --- | --- |",
        f"| presrs (Rust) | - | {fmt_ns(presrs['single_image_median_ns'])} ({fmt_ns(presrs['single_image_p99_ns'])}) "
        f"| - | {presrs['batch_images_per_s']:,.0f} ({presrs['batch_threads']} threads) | - |",
    ]
    for name, peer in results["peers"].items():
        a = results["agreement"][name]
        lo, hi = peer["single_ratio_range"]
        blo, bhi = peer["batch_ratio_range"]
        lines.append(
            f"| {name} | {100 * a['single_agreement']:.1f} % of {a['images']} images "
            f"| {fmt_ns(peer['single_image_median_ns'])} ({fmt_ns(peer['single_image_p99_ns'])}) "
            f"| **{peer['single_ratio']:.1f}x** ({lo:.1f}-{hi:.1f}) "
            f"| {peer['batch_images_per_s']:,.0f} | **{peer['batch_ratio']:.1f}x** ({blo:.1f}-{bhi:.1f}) |"
        )
    single_ok = numpy_peer["single_ratio"] >= 20
    batch_ok = numpy_peer["batch_ratio"] >= 5
    lines += [
        "",
        f"Targets of issue #8, against the faster peer (numpy): one image per call at least 20x faster: "
        f"{'met' if single_ok else '**missed**'} ({numpy_peer['single_ratio']:.1f}x); batch at least 5x the "
        f"throughput: {'met' if batch_ok else '**missed**'} ({numpy_peer['batch_ratio']:.1f}x).",
    ]
    python_peer = results["peers"].get("presrs (Python)")
    if python_peer:
        per_call_us = python_peer["single_image_median_ns"] / 1e3
        batch_share = python_peer["batch_images_per_s"] / presrs["batch_images_per_s"]
        lines.append(
            f"Targets of issue #21, presrs's Python package: `model.predict_proba(image)` at most 10 µs per "
            f"call: {'met' if per_call_us <= 10 else '**missed**'} ({per_call_us:.1f} µs, "
            f"{numpy_peer['single_image_median_ns'] / python_peer['single_image_median_ns']:.1f}x faster "
            f"than numpy); batch throughput within 20 % of Rust's: "
            f"{'met' if batch_share >= 0.8 else '**missed**'} ({100 * batch_share:.0f} %)."
        )
    if "presrs_accuracy" in results:
        lines.append(
            f"Predictions agree image by image; presrs's (and so the peers') accuracy on these test images is "
            f"{100 * results['presrs_accuracy']:.1f} %."
        )
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    sys.exit(main())
