#!/usr/bin/env python3
"""Hydra (Dempster, Schmidt & Webb 2023) screened on presrs's exported draws (issue #44, "a stronger fast family").

aeon's `HydraTransformer` needs torch, which the bench venv does not carry; this is its forward pass in numpy,
line for line after aeon 1.6.0's `_HydraInternal` (k = 8 kernels per group, g = 64 groups, kernel length 9,
dilations 2^0..2^floor(log2((T - 1) / 8)), the series and its first difference, random channel subsets summed for
multivariate input; per group the soft max counts and hard min counts), then aeon's `_SparseScaler` (sqrt, masked
standardisation) and scikit-learn's `RidgeClassifierCV` (the alphas of rocket_peer.py). `hydra+minirocket` puts
aeon's MiniRocket features (standardised) beside Hydra's, as MultiRocket-Hydra does. Each row: the accuracy per
repeat pooled over the repeat's folds, mean over repeats, for seeds 0..N-1. bench/real/RESULTS.md has the figures.

    presrs eval --manifest SET/manifest.csv ... --export-draws DIR
    python hydra_probe.py DIR 2 hydra,hydra+minirocket
"""
import sys, json, numpy as np
from pathlib import Path
from sklearn.linear_model import RidgeClassifierCV
sys.path.insert(0, '/work/main/bench/real')
from draws_spread import Draws
from aeon.transformations.collection.convolution_based import MiniRocket

class Hydra:
    def __init__(self, n_timepoints, n_channels, k=8, g=64, max_num_channels=8, seed=0):
        rng = np.random.default_rng(seed)
        self.k, self.g = k, g
        max_exponent = np.log2((n_timepoints - 1) / 8)
        self.dilations = 2 ** np.arange(int(max_exponent) + 1)
        self.divisor = min(2, g); self.h = g // self.divisor
        W = rng.standard_normal((len(self.dilations), self.divisor, k * self.h, 9))
        W -= W.mean(-1, keepdims=True); W /= np.abs(W).sum(-1, keepdims=True)
        self.W = W
        per = int(np.clip(n_channels // 2, 2, max_num_channels))
        self.idx = [rng.integers(0, n_channels, (self.divisor, self.h, per)) for _ in self.dilations]
        self.multi = n_channels > 1

    def transform(self, X):
        n, c, t = X.shape
        dX = np.diff(X, axis=2)
        out = []
        for di, d in enumerate(self.dilations):
            p = (8 * d) // 2
            for v in range(self.divisor):
                src = X if v == 0 else dX
                if self.multi:
                    inp = src[:, self.idx[di][v]].sum(2)  # n x h x len
                else:
                    inp = np.repeat(src, self.h, axis=1)
                L = inp.shape[2]
                pad = np.pad(inp, ((0, 0), (0, 0), (p, p)))
                out_len = L + 2 * p - 8 * d
                # conv: for each group h, k kernels on channel h
                Wv = self.W[di, v].reshape(self.h, self.k, 9)
                Z = np.zeros((n, self.h, self.k, out_len))
                for j in range(9):
                    seg = pad[:, :, j * d: j * d + out_len]  # n x h x out
                    Z += Wv[None, :, :, j, None] * seg[:, :, None, :]
                mx = Z.max(2); ai = Z.argmax(2); mi = Z.argmin(2)
                cmax = np.zeros((n, self.h, self.k)); cmin = np.zeros((n, self.h, self.k))
                for kk in range(self.k):
                    cmax[:, :, kk] = np.where(ai == kk, mx, 0).sum(-1)
                    cmin[:, :, kk] = (mi == kk).sum(-1)
                out += [cmax, cmin]
        return np.concatenate(out, 1).reshape(n, -1)

class Sparse:
    def fit(self, X):
        X = np.sqrt(np.clip(X, 0, None)); self.eps = (X == 0).mean(0) ** 4 + 1e-8
        self.mu = X.mean(0); self.sd = X.std(0, ddof=1) + self.eps; return self
    def transform(self, X):
        X = np.sqrt(np.clip(X, 0, None)); return ((X - self.mu) * (X != 0)) / self.sd

ALPHAS = np.logspace(-3, 3, 10)
def run(export, seeds, which):
    d = Draws(Path(export))
    res = {}
    for name in which:
        accs = []
        for s in range(seeds):
            hits = {}
            for repeat, fit, test in d.folds:
                x = d.x
                if name == 'hydra':
                    h = Hydra(x.shape[2], x.shape[1], seed=s)
                    ft, tt = h.transform(x[fit]), h.transform(x[test])
                    sc = Sparse().fit(ft); ft, tt = sc.transform(ft), sc.transform(tt)
                elif name == 'hydra+minirocket':
                    h = Hydra(x.shape[2], x.shape[1], seed=s)
                    ft, tt = h.transform(x[fit]), h.transform(x[test])
                    sc = Sparse().fit(ft); ft, tt = sc.transform(ft), sc.transform(tt)
                    mr = MiniRocket(n_kernels=10000, random_state=s, n_jobs=1).fit(x[fit])
                    mf, mt = mr.transform(x[fit]), mr.transform(x[test])
                    mu, sd = mf.mean(0), mf.std(0) + 1e-8
                    ft = np.hstack([ft, (mf - mu) / sd]); tt = np.hstack([tt, (mt - mu) / sd])
                model = RidgeClassifierCV(alphas=ALPHAS).fit(ft, d.y[fit])
                r, t = hits.get(repeat, (0, 0))
                hits[repeat] = (r + int((model.predict(tt) == d.y[test]).sum()), t + len(test))
            accs.append(100 * np.mean([r / t for r, t in hits.values()]))
        print(f"{export} {name}: mean {np.mean(accs):.1f} {[round(a, 1) for a in accs]}", flush=True)

if __name__ == '__main__':
    run(sys.argv[1], int(sys.argv[2]), sys.argv[3].split(','))
