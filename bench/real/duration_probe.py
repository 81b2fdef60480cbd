#!/usr/bin/env python3
"""Does a whole stance's duration help MiniRocket + ridge? (issue #44, "Methods", lead 1)

On presrs's exported draws (`presrs eval --export-draws DIR`), aeon's `MiniRocket(random_state=seed)`
+ scikit-learn's `RidgeClassifierCV(alphas=np.logspace(-3, 3, 10))` on the raw features, with the
stance's duration appended as one more feature: the frames before the zero padding (one past the last
frame where any channel is non-zero), standardised over each fold's training samples and multiplied by
`c * sqrt(features)` for each weight `c` given (0: no duration; presrs's `rocket_duration` uses 0.1).
`log` takes sign(x) log(1 + |x|) of every value first. Accuracy per repeat pooled over its folds, then
the mean over repeats; bench/real/RESULTS.md gives the figures. aeon is a bench-only dependency.

    python duration_probe.py DIR SEEDS WEIGHTS [log]    # e.g. DIR 4 0,0.03,0.1,0.3,1
"""

import json
import sys
from pathlib import Path

import numpy as np
from aeon.transformations.collection.convolution_based import MiniRocket
from sklearn.linear_model import RidgeClassifierCV

ALPHAS = np.logspace(-3, 3, 10)


def main() -> None:
    export, seeds = Path(sys.argv[1]), range(int(sys.argv[2]))
    weights = [float(c) for c in sys.argv[3].split(",")]
    doc = json.loads((export / "draws.json").read_text())
    x = np.load(export / doc["images"]).astype(np.float64)
    x = x.reshape(x.shape[0], x.shape[1], -1)
    if len(sys.argv) > 4 and sys.argv[4] == "log":
        x = np.sign(x) * np.log1p(np.abs(x))
    y = np.array(doc["labels"])
    folds = [(d["repeat"], np.array(d["train"] + d["validation"]), np.array(d["test"])) for d in doc["draws"]]
    loaded = np.abs(x).sum(axis=1) != 0
    duration = np.array([np.nonzero(r)[0].max() + 1 if r.any() else 0 for r in loaded], dtype=float)
    results = {c: [] for c in weights}
    for seed in seeds:
        hits = {c: {} for c in weights}
        for repeat, fit, test in folds:
            rocket = MiniRocket(n_kernels=10000, random_state=seed, n_jobs=1).fit(x[fit])
            train_f, test_f = rocket.transform(x[fit]), rocket.transform(x[test])
            mean, spread = duration[fit].mean(), duration[fit].std() or 1.0
            for c in weights:
                w = c * np.sqrt(train_f.shape[1])
                a = np.hstack([train_f, ((duration[fit] - mean) / spread * w)[:, None]]) if c else train_f
                b = np.hstack([test_f, ((duration[test] - mean) / spread * w)[:, None]]) if c else test_f
                model = RidgeClassifierCV(alphas=ALPHAS).fit(a, y[fit])
                right, total = hits[c].get(repeat, (0, 0))
                hits[c][repeat] = (right + int((model.predict(b) == y[test]).sum()), total + len(test))
        for c in weights:
            results[c].append(100 * np.mean([r / t for r, t in hits[c].values()]))
        print("seed", seed, {c: round(results[c][-1], 1) for c in weights}, flush=True)
    for c in weights:
        print(f"weight {c}: mean {np.mean(results[c]):.1f}", [round(a, 1) for a in results[c]])


if __name__ == "__main__":
    main()
