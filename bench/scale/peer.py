#!/usr/bin/env python3
"""aeon's MiniRocket + scikit-learn's RidgeClassifierCV on a manifest of series, leaving each group out
(issue #44's scale bench; the peer of `presrs eval --leave-one-out group --sample series`).

    python bench/scale/peer.py MANIFEST [--json OUT]

Reads the manifest (`path,label,...,group`; each path a `.npy` of channels x time), holds out each
group in turn (the folds of `presrs eval --leave-one-out group`: the held-out group tests, every other
sample trains, as presrs's models learn from training + validation), fits aeon's
`MiniRocket(n_kernels=10000, random_state=0)` and `RidgeClassifierCV(alphas=np.logspace(-3, 3, 10))`
(the pairing of bench/real/rocket_peer.py and the MiniRocket paper) and prints the pooled accuracy and
the wall time of the whole run (reading the files included, as presrs's is). Peak memory is measured
around it by `/usr/bin/time -v` (bench/scale/run.sh).

aeon is a bench-only dependency, in a venv of its own (bench/scale/README.md).
"""

from __future__ import annotations

import argparse
import csv
import json
import time
from pathlib import Path

import numpy as np
from aeon.transformations.collection.convolution_based import MiniRocket
from sklearn.linear_model import RidgeClassifierCV


def load(manifest: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    root = manifest.parent
    with manifest.open(newline="") as f:
        rows = list(csv.DictReader(f))
    series = np.stack([np.load(root / row["path"]) for row in rows]).astype(np.float64)
    labels = np.array([row["label"] for row in rows])
    groups = np.array([row["group"] for row in rows])
    return series, labels, groups


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("manifest", type=Path)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    started = time.perf_counter()
    series, labels, groups = load(args.manifest)
    correct = 0
    folds = []
    for group in sorted(set(groups)):
        fold_started = time.perf_counter()
        test = groups == group
        rocket = MiniRocket(n_kernels=10000, random_state=0)
        train_features = rocket.fit_transform(series[~test])
        ridge = RidgeClassifierCV(alphas=np.logspace(-3, 3, 10)).fit(train_features, labels[~test])
        predicted = ridge.predict(rocket.transform(series[test]))
        right = int((predicted == labels[test]).sum())
        correct += right
        folds.append(
            {
                "held_out": group,
                "accuracy": right / int(test.sum()),
                "seconds": time.perf_counter() - fold_started,
            }
        )
    result = {
        "peer": "aeon MiniRocket + RidgeClassifierCV",
        "samples": int(len(labels)),
        "accuracy": correct / len(labels),
        "seconds": time.perf_counter() - started,
        "folds": folds,
    }
    print(json.dumps(result))
    if args.json:
        args.json.write_text(json.dumps(result, indent=1) + "\n")


if __name__ == "__main__":
    main()
