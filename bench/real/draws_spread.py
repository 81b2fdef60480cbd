#!/usr/bin/env python3
"""How much of a MiniRocket + ridge accuracy is the luck of one kernel draw (issue #44, "Methods").

On presrs's exported draws (`presrs eval --export-draws DIR`, as rocket_peer.py reads them), aeon's
`MiniRocket(random_state=seed)` + scikit-learn's `RidgeClassifierCV(alphas=np.logspace(-3, 3, 10))` on
the raw features (the peer's pairing), for seeds 0..N-1, and what the ideas for reducing that spread give:

* `single`: each seed alone (the peer is seed 0), and the mean over the seeds;
* `vote K`: K seeds, each its own ridge, their decisions (each over its standard deviation) summed;
* `concat K`: K seeds' features side by side, one ridge;
* `kernels N` (with `--kernels N`): one MiniRocket of N features per seed;
* `input NAME` (with `--inputs`): the samples transformed before the convolutions: `noarea` (stance
  summaries without their `area` row, row 1), `log` (sign(x) log(1 + |x|)), `sample_max` (each sample's
  channel over its own largest magnitude), `sample_z` (each sample's channel standardised over time).

Every row: accuracy per repeat pooled over the repeat's folds, then the mean over repeats; for seeds,
the mean over seeds too. bench/real/RESULTS.md gives the figures. aeon is a bench-only dependency
(bench/rocket/README.md).

    python draws_spread.py --export DIR --seeds 16 --vote 2,4,8 --concat 4 --kernels 40000 --inputs noarea,log
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from aeon.transformations.collection.convolution_based import MiniRocket
from sklearn.linear_model import RidgeClassifierCV

ALPHAS = np.logspace(-3, 3, 10)


def sample_max(x):
    m = np.abs(x).max(axis=2, keepdims=True)
    m[m == 0] = 1
    return x / m


def sample_z(x):
    s = x.std(axis=2, keepdims=True)
    s[s == 0] = 1
    return (x - x.mean(axis=2, keepdims=True)) / s


INPUTS = {
    "noarea": lambda x: np.delete(x, 1, axis=1),
    "log": lambda x: np.sign(x) * np.log1p(np.abs(x)),
    "sample_max": sample_max,
    "sample_z": sample_z,
}


class Draws:
    def __init__(self, export: Path):
        doc = json.loads((export / "draws.json").read_text())
        x = np.load(export / doc["images"]).astype(np.float64)
        self.x = x.reshape(x.shape[0], x.shape[1], -1)
        self.y = np.array(doc["labels"])
        self.folds = [
            (d["repeat"], np.array(d["train"] + d["validation"]), np.array(d["test"]))
            for d in doc["draws"]
        ]

    def decisions(self, seed, kernels=10000, x=None):
        """For every fold, the ridge's normalised decisions on the test samples, and its classes."""
        x = self.x if x is None else x
        out = []
        for _, fit, test in self.folds:
            rocket = MiniRocket(n_kernels=kernels, random_state=seed, n_jobs=1).fit(x[fit])
            model = RidgeClassifierCV(alphas=ALPHAS).fit(rocket.transform(x[fit]), self.y[fit])
            d = model.decision_function(rocket.transform(x[test]))
            d = d.reshape(len(test), -1)
            out.append((d / np.std(d), model.classes_))
        return out

    def concatenated(self, seeds):
        hits = {}
        for repeat, fit, test in self.folds:
            parts = [MiniRocket(n_kernels=10000, random_state=s, n_jobs=1).fit(self.x[fit]) for s in seeds]
            f = np.hstack([p.transform(self.x[fit]) for p in parts])
            t = np.hstack([p.transform(self.x[test]) for p in parts])
            model = RidgeClassifierCV(alphas=ALPHAS).fit(f, self.y[fit])
            right, total = hits.get(repeat, (0, 0))
            hits[repeat] = (right + int((model.predict(t) == self.y[test]).sum()), total + len(test))
        return 100 * np.mean([r / t for r, t in hits.values()])

    def accuracy(self, decision_sets):
        """Accuracy of the summed decisions of several draws' `decisions`."""
        hits = {}
        for k, (repeat, _, test) in enumerate(self.folds):
            summed = sum(ds[k][0] for ds in decision_sets)
            classes = decision_sets[0][k][1]
            predicted = classes[summed.argmax(axis=1)] if summed.shape[1] > 1 else classes[(summed[:, 0] > 0).astype(int)]
            right, total = hits.get(repeat, (0, 0))
            hits[repeat] = (right + int((predicted == self.y[test]).sum()), total + len(test))
        return 100 * np.mean([r / t for r, t in hits.values()])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--export", type=Path, required=True)
    parser.add_argument("--seeds", type=int, default=6)
    parser.add_argument("--vote", default="", help="ensemble sizes, e.g. 2,4,8")
    parser.add_argument("--concat", default="", help="ensemble sizes, e.g. 4")
    parser.add_argument("--kernels", type=int, default=0)
    parser.add_argument("--inputs", default="", help=",".join(INPUTS))
    args = parser.parse_args()
    draws = Draws(args.export)
    seeds = range(args.seeds)
    decisions = [draws.decisions(s) for s in seeds]
    singles = [draws.accuracy([d]) for d in decisions]
    print(f"single: mean {np.mean(singles):.1f} over {len(singles)} seeds, {[round(a, 1) for a in singles]}", flush=True)
    for k in (int(k) for k in args.vote.split(",") if k):
        votes = [draws.accuracy(decisions[j:j + k]) for j in range(0, len(decisions) - k + 1, k)]
        print(f"vote {k}: mean {np.mean(votes):.1f}, {[round(a, 1) for a in votes]}", flush=True)
    for k in (int(k) for k in args.concat.split(",") if k):
        sets = [draws.concatenated(list(seeds[j:j + k])) for j in range(0, len(seeds) - k + 1, k)]
        print(f"concat {k}: mean {np.mean(sets):.1f}, {[round(a, 1) for a in sets]}", flush=True)
    if args.kernels:
        more = [draws.accuracy([draws.decisions(s, args.kernels)]) for s in seeds]
        print(f"kernels {args.kernels}: mean {np.mean(more):.1f}, {[round(a, 1) for a in more]}", flush=True)
    for name in (n for n in args.inputs.split(",") if n):
        x = INPUTS[name](draws.x)
        accs = [draws.accuracy([draws.decisions(s, x=x)]) for s in seeds]
        print(f"input {name}: mean {np.mean(accs):.1f}, {[round(a, 1) for a in accs]}", flush=True)


if __name__ == "__main__":
    main()
