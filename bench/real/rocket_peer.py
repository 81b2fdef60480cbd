#!/usr/bin/env python3
"""aeon's MiniRocket + scikit-learn's RidgeClassifierCV on presrs's own draws (issue #33's peer).

Reads what `presrs eval --export-draws DIR` wrote -- `images.npy` (samples x rows x cols: the samples as
presrs evaluates them; for `--sample stance` each stance's summary, channels x frames padded to one
length; for `--sample series` the taxels x time array) and `draws.json` (every repeat's folds: training,
validation and test indices) -- and evaluates, on exactly those sets, each sample's rows read as channels
over time:

* `aeon MiniRocket + RidgeClassifierCV`: the issue's peer. aeon's `MiniRocket(n_kernels=10000,
  random_state=0)` fitted on the training + validation samples, then `RidgeClassifierCV(alphas=
  np.logspace(-3, 3, 10))` on its features;
* `... + StandardScaler + RidgeClassifierCV`: the same with the features standardised first, as aeon's
  own `MiniRocketClassifier` pipeline (`StandardScaler(with_mean=False)`);
* `... + PCA(51) + StandardScaler + RidgeClassifierCV` (with `--pca`): presrs's path before ridge saw the
  full features (the 51 principal components, each standardised), to measure what the PCA step costs;
* `aeon MiniRocket on presrs's input (channels / spread) + StandardScaler + RidgeClassifierCV` (with
  `--channel-scaled`): each channel divided by its standard deviation over the samples MiniRocket is
  fitted on, as presrs's rocket family does before its convolutions; the same input and classifier as
  presrs's rocket + ridge, so the two MiniRockets are compared alone;
* `aeon MultiRocket + RidgeClassifierCV` and `... + StandardScaler + RidgeClassifierCV` (with
  `--multirocket`): aeon's `MultiRocket(n_kernels=1250, random_state=0)` (9,408 features: presrs's
  `multirocket`; aeon's default is 6,250 kernels, 49,728 features), the same two classifiers.

Ridge has nothing to validate outside its own leave-one-out, so every peer trains on training +
validation at once: the images presrs's models learn from. Accuracy per repeat is pooled over the
repeat's folds; the rows give the mean and sample standard deviation over the repeats, as peers.py.

aeon is a bench-only dependency, in a venv of its own (bench/rocket/README.md); never in the product or
CI. bench/real/run.sh runs this with `ROCKET_PYTHON` (default /work/wt/rocket-venv/bin/python).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from aeon.transformations.collection.convolution_based import MiniRocket, MultiRocket
from sklearn.decomposition import PCA
from sklearn.linear_model import RidgeClassifierCV
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler

ALPHAS = np.logspace(-3, 3, 10)


def ridge():
    return RidgeClassifierCV(alphas=ALPHAS)


def scaled_ridge():
    return make_pipeline(StandardScaler(with_mean=False), RidgeClassifierCV(alphas=ALPHAS))


def pca_ridge():
    return make_pipeline(PCA(n_components=51, random_state=0), StandardScaler(), RidgeClassifierCV(alphas=ALPHAS))


PEERS = [
    ("aeon MiniRocket + RidgeClassifierCV", ridge),
    ("aeon MiniRocket + StandardScaler + RidgeClassifierCV", scaled_ridge),
]
SCALED_PEER = (
    "aeon MiniRocket on presrs's input (channels / spread) + StandardScaler + RidgeClassifierCV",
    scaled_ridge,
)
PCA_PEER = ("aeon MiniRocket + PCA(51) + StandardScaler + RidgeClassifierCV", pca_ridge)
MULTI_PEERS = [
    ("aeon MultiRocket + RidgeClassifierCV", ridge),
    ("aeon MultiRocket + StandardScaler + RidgeClassifierCV", scaled_ridge),
]


def minirocket(threads: int):
    return MiniRocket(n_kernels=10_000, random_state=0, n_jobs=threads)


def multirocket(threads: int):
    return MultiRocket(n_kernels=1_250, random_state=0, n_jobs=threads)


def load(export: Path) -> tuple[np.ndarray, dict]:
    document = json.loads((export / "draws.json").read_text())
    if document.get("format") != "presrs-eval-draws":
        raise SystemExit(f"{export / 'draws.json'}: not a presrs draws export")
    images = np.load(export / document["images"])
    if images.ndim != 3 or len(images) != len(document["labels"]):
        raise SystemExit(f"{export}: images of shape {images.shape} for {len(document['labels'])} labels")
    return images.astype(np.float64), document


def channel_scaled(images: np.ndarray, fit_on: np.ndarray) -> np.ndarray:
    """`images` with each channel (row) divided by its standard deviation over every value of the
    samples `fit_on` (1 for a constant channel): presrs's rocket family's input."""
    channels = images.shape[1]
    spread = images[fit_on].transpose(1, 0, 2).reshape(channels, -1).std(axis=1)
    spread[~(np.isfinite(spread) & (spread > 0))] = 1.0
    return images / spread[None, :, None]


def evaluate(
    images: np.ndarray, document: dict, peers, threads: int, scale: bool = False, transform=minirocket
) -> list[dict]:
    labels = np.array(document["labels"])
    draws = document["draws"]
    repeats = sorted({d["repeat"] for d in draws})
    results = {name: {"accuracies": [], "train": [], "classify": 0.0} for name, _ in peers}
    n_classified = 0
    transform_seconds = 0.0
    for repeat in repeats:
        hits = {name: 0 for name, _ in peers}
        total = 0
        for draw in (d for d in draws if d["repeat"] == repeat):
            tr, va, te = (np.array(draw[k], dtype=int) for k in ("train", "validation", "test"))
            fit_on = np.concatenate([tr, va])
            x = channel_scaled(images, fit_on) if scale else images
            start = time.perf_counter()
            rocket = transform(threads).fit(x[fit_on])
            x_fit = np.asarray(rocket.transform(x[fit_on]))
            fit_seconds = time.perf_counter() - start
            start = time.perf_counter()
            x_test = np.asarray(rocket.transform(x[te]))
            test_seconds = time.perf_counter() - start
            transform_seconds += test_seconds
            for name, make in peers:
                start = time.perf_counter()
                model = make().fit(x_fit, labels[fit_on])
                results[name]["train"].append(fit_seconds + time.perf_counter() - start)
                start = time.perf_counter()
                predicted = model.predict(x_test)
                results[name]["classify"] += test_seconds + time.perf_counter() - start
                hits[name] += int(np.sum(predicted == labels[te]))
            total += len(te)
            n_classified += len(te)
        for name, _ in peers:
            results[name]["accuracies"].append(hits[name] / total)
    rows = []
    for name, _ in peers:
        accuracies = results[name]["accuracies"]
        rows.append(
            {
                "method": name,
                "accuracy": float(np.mean(accuracies)),
                "accuracy_std": float(np.std(accuracies, ddof=1)) if len(accuracies) > 1 else 0.0,
                "accuracies": accuracies,
                # MiniRocket's fit and the transform of the training samples, then the classifier's fit
                "train_seconds_per_model": float(np.mean(results[name]["train"])),
                # the test samples' transform (shared by the peers) and prediction, in batches
                "classify_us_per_image": 1e6 * results[name]["classify"] / max(n_classified, 1),
            }
        )
    return rows


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--export", type=Path, required=True, help="the folder `presrs eval --export-draws` wrote")
    parser.add_argument("--out", type=Path, help="write the rows as JSON here (default: stdout)")
    parser.add_argument("--pca", action="store_true", help="also the PCA(51) variant")
    parser.add_argument("--channel-scaled", action="store_true", help="also the peer on presrs's scaled channels")
    parser.add_argument("--multirocket", action="store_true", help="also aeon's MultiRocket with both ridges")
    parser.add_argument("--threads", type=int, default=2, help="aeon's n_jobs (default 2)")
    args = parser.parse_args()
    images, document = load(args.export)
    peers = PEERS + ([PCA_PEER] if args.pca else [])
    rows = evaluate(images, document, peers, args.threads)
    if args.channel_scaled:
        scaled = evaluate(images, document, [SCALED_PEER], args.threads, scale=True)
        rows += scaled
    if args.multirocket:
        rows += evaluate(images, document, MULTI_PEERS, args.threads, transform=multirocket)
    text = json.dumps({"manifest": document.get("manifest"), "shape": list(images.shape[1:]), "peers": rows}, indent=1)
    if args.out:
        args.out.write_text(text + "\n")
    else:
        print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
