#!/usr/bin/env python3
"""The novelty score of `presrs eval --leave-class-out` re-implemented in numpy, to screen score and
feature variants in seconds, without a build per variant (issue #43).

Not part of CI. It exports tais22's `fft2d_polar+glcm` features after sqrt with `presrs features` (the
images square-rooted into a temporary directory, as `--intensity sqrt` prepares them), then for each of the
six held-out classes and each held-out session: the discriminant space of the training classes (PCA to 51
components, Ledoit-Wolf-shrunk pooled within-class covariance whitened, the class means' directions), the
distance to the nearest training vector, the posterior of the nearest class mean, the held-out distances
of the calibration (each session out in turn, its classes that others hold), and the score
`1 - posterior x credibility`, as `crates/presrs-core/src/novelty/` computes it. AUROC per held-out class
over the sessions pooled, as the eval does. The first line reproduces the eval's figures (0.875: 0.877,
0.851, 0.996, 0.856, 0.873, 0.797 against 0.877, 0.852, 0.996, 0.851, 0.873, 0.797); `--contact` adds
the contact-geometry measures (numpy, as `features/contact.rs`; standardised on each model's training
images) as a third unit-norm part, as `fft2d_polar+glcm+contact` does (0.896 here and in presrs: 0.941,
0.944, 0.994, 0.865, 0.898, 0.733 against 0.942, 0.944, 0.993, 0.865, 0.898, 0.730).

    python3 bench/real/novelty_numpy.py --presrs target/release/presrs [--contact]

Needs numpy and scikit-learn. Figures: bench/real/RESULTS.md, "Contact geometry as a feature family".
"""
import argparse
import csv
import subprocess
import tempfile
from pathlib import Path

import numpy as np
from sklearn.covariance import ledoit_wolf
from sklearn.metrics import roc_auc_score

DATA = Path(__file__).resolve().parents[3] / "shared" / "data" / "real" / "tais22"
HELD = ["adhesive", "bottle", "cable_pipe", "highlighter", "rock", "tube"]
AREA_SHARES = [0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 0.9]
PROFILE_RADII = [0.05, 0.1, 0.15, 0.2, 0.3, 0.4, 0.6, 0.8]


def exported_features(presrs, images):
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for k, image in enumerate(images):
            path = Path(tmp) / f"{k}.npy"
            np.save(path, image)
            out = subprocess.run([presrs, "features", "--features", "fft2d_polar+glcm", str(path)],
                                 check=True, capture_output=True, text=True).stdout.strip().splitlines()
            rows.append([float(x) for x in out[-1].split(",")[1:]])
    return np.array(rows)


def contact(a):
    scale = np.sqrt(a.size)
    total, peak = a.sum(), a.max()
    r, c = np.indices(a.shape)
    cr, cc = (a * r).sum() / total, (a * c).sum() / total
    cov = np.array([[(a * (r - cr) ** 2).sum(), (a * (r - cr) * (c - cc)).sum()],
                    [(a * (r - cr) * (c - cc)).sum(), (a * (c - cc) ** 2).sum()]]) / total
    minor, major = np.clip(np.linalg.eigvalsh(cov), 0, None)
    distance = np.hypot(r - cr, c - cc)
    return np.array([(a > s * peak).mean() for s in AREA_SHARES]
                    + [np.sqrt(major) / scale, np.sqrt(minor) / scale, minor / major if major > 0 else 0.0,
                       np.log1p(total / a.size), np.log1p(peak)]
                    + [a[distance < q * scale / 2].sum() / total for q in PROFILE_RADII])


def space(X, y, dims=51):
    mu = X.mean(0)
    P = np.linalg.svd(X - mu, full_matrices=False)[2][:dims]
    Z = (X - mu) @ P.T
    classes = sorted(set(y))
    M = np.array([Z[y == c].mean(0) for c in classes])
    within, _ = ledoit_wolf(np.concatenate([Z[y == c] - M[i] for i, c in enumerate(classes)]))
    values, vectors = np.linalg.eigh(within)
    whiten = vectors / np.sqrt(np.maximum(values, 1e-12))
    D = np.linalg.svd(M @ whiten - (M @ whiten).mean(0), full_matrices=False)[2][:len(classes) - 1]
    T = P.T @ whiten @ D.T
    return (lambda Xn: (Xn - mu) @ T), M @ whiten @ D.T


def nearest_distance(Zq, Zt):
    return np.sqrt(((Zq[:, None, :] - Zt[None]) ** 2).sum(-1)).min(1)


def top_posterior(Zq, means):
    logits = -0.5 * ((Zq[:, None, :] - means[None]) ** 2).sum(-1)
    p = np.exp(logits - logits.max(1, keepdims=True))
    return (p / p.sum(1, keepdims=True)).max(1)


def scores(Xtr, ytr, gtr, Xte):
    project, means = space(Xtr, ytr)
    held = []
    for g in sorted(set(gtr)):
        out, inside = gtr != g, gtr == g
        keep = inside & np.isin(ytr, list(set(ytr[inside]) & set(ytr[out])))
        p_out, _ = space(Xtr[out], ytr[out])
        held.append(nearest_distance(p_out(Xtr[keep]), p_out(Xtr[out])))
    held = np.sort(np.concatenate(held))
    Zte = project(Xte)
    d = nearest_distance(Zte, project(Xtr))
    credibility = (len(held) - np.searchsorted(held, d, "left") + 1) / (len(held) + 1)
    return 1 - top_posterior(Zte, means) * credibility


def unit(X):
    return X / (np.linalg.norm(X, axis=1, keepdims=True) + 1e-12)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--presrs", default="target/release/presrs")
    parser.add_argument("--contact", action="store_true")
    args = parser.parse_args()
    rows = list(csv.DictReader(open(DATA / "manifest.csv")))
    images = [np.sqrt(np.load(DATA / r["path"]).astype(float)) for r in rows]
    y, g = np.array([r["label"] for r in rows]), np.array([r["group"] for r in rows])
    X = exported_features(args.presrs, images)
    C = np.array([contact(a) for a in images])
    aurocs = {}
    for held_class in HELD:
        novel, known = [], []
        for test_group in sorted(set(g)):
            train, test = (g != test_group) & (y != held_class), g == test_group
            features = X
            if args.contact:
                n, eps = train.sum(), np.finfo(float).eps
                mean, variance = C[train].mean(0), C[train].var(0)
                zero = variance <= n * eps * variance + (n * mean * eps) ** 2  # as StandardScaler
                spread = np.where(zero, 1.0, np.sqrt(variance))
                features = np.hstack([X, unit((C - mean) / spread)])
            s = scores(features[train], y[train], g[train], features[test])
            novel += list(s[y[test] == held_class])
            known += list(s[y[test] != held_class])
        labels = np.r_[np.ones(len(novel)), np.zeros(len(known))]
        aurocs[held_class] = roc_auc_score(labels, np.r_[novel, known])
    print(f"mean AUROC {np.mean(list(aurocs.values())):.3f}:",
          ", ".join(f"{k} {v:.3f}" for k, v in aurocs.items()))


if __name__ == "__main__":
    main()
