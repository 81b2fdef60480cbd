#!/usr/bin/env python3
"""Screen for issue #43: the contact part of the novelty score, its cost on new recordings of known
terrains, and whether leaving known classes out inside the training data can decide it per model.

Not part of CI; numpy twin of `crates/presrs-core/src/novelty/` (as `novelty_numpy.py`, whose helpers it
uses): each model's vectors are the 51 principal components of its features, optionally with the 20
contact measures of `features/contact.rs` appended (standardised over the training images, weighted by
`w` x the square root of the components' mean variance, as the unmerged branch `novelty-contact` did);
the discriminant space, the nearest training vector, the posterior and the threshold (0.95 quantile of
held-out scores, calibration folds by at most 5 merged groups) as presrs computes them.

    python3 bench/real/novelty_contact_weight.py sim    # needs the presrs Python package
    python3 bench/real/novelty_contact_weight.py tais   # needs bench/real/novelty_numpy.py's export

`sim`: trained as `python/examples/train_and_classify.py` trains (gait G2, seeds 1-3), the share of
new-trial images (seeds 20-39, all four terrains) called unknown with and without the contact part, and the
inner leave-class-out AUROC of both. `tais`: tais22 leave 6 classes out, the AUROC with w = 0, w = 1 and
w chosen per model by the inner check (the higher inner AUROC; a tie keeps w = 0). Figures:
bench/real/RESULTS.md, "The contact part decided by leaving classes out inside the training data".
"""
import csv
import sys
from pathlib import Path

import numpy as np
from sklearn.covariance import ledoit_wolf
from sklearn.metrics import roc_auc_score

sys.path.insert(0, str(Path(__file__).resolve().parent))
import novelty_numpy as nn  # noqa: E402

WEIGHTS = [0.0, 1.0]
TAIS22 = nn.DATA


def pca(X, dims=51):
    mu = X.mean(0)
    P = np.linalg.svd(X - mu, full_matrices=False)[2][:dims]
    return lambda Xn: (Xn - mu) @ P.T


def discriminant(V, y):
    classes = sorted(set(y))
    M = np.array([V[y == c].mean(0) for c in classes])
    within, _ = ledoit_wolf(np.concatenate([V[y == c] - M[i] for i, c in enumerate(classes)]))
    values, vectors = np.linalg.eigh(within)
    whiten = vectors / np.sqrt(np.maximum(values, 1e-12))
    D = np.linalg.svd(M @ whiten - (M @ whiten).mean(0), full_matrices=False)[2][:len(classes) - 1]
    T = whiten @ D.T
    return (lambda Vn: Vn @ T), M @ T


def vectors_of(X, C, train, w):
    V = pca(X[train])(X)
    if w == 0:
        return V
    mean, spread = C[train].mean(0), C[train].std(0)
    spread = np.where(spread > 0, spread, 1.0)
    return np.hstack([V, w * np.sqrt(V[train].var(0).mean()) * (C - mean) / spread])


def scores(V, y, g, train, test):
    """The scores of `test` under a model fitted on `train`, and its threshold."""
    idx = np.flatnonzero(train)
    project, means = discriminant(V[train], y[train])
    order = {v: i % 5 for i, v in enumerate(sorted(set(g[train])))}
    fold = np.array([order[v] for v in g[train]])
    held_d, held_p = [], []
    for f in sorted(set(fold)):
        out, inside = idx[fold != f], idx[fold == f]
        inside = inside[np.isin(y[inside], list(set(y[out])))]
        if len(inside) == 0 or len(set(y[out])) < 2:
            continue
        p, m = discriminant(V[out], y[out])
        held_d.append(nn.nearest_distance(p(V[inside]), p(V[out])))
        held_p.append(nn.top_posterior(p(V[inside]), m))
    held = np.concatenate(held_d)
    ordered = np.sort(held)

    def credibility(d):
        return (len(ordered) - np.searchsorted(ordered, d, "left") + 1) / (len(ordered) + 1)

    threshold = np.quantile(1 - np.concatenate(held_p) * credibility(held), 0.95)
    Z = project(V[test])
    distance = nn.nearest_distance(Z, project(V[train]))
    return 1 - nn.top_posterior(Z, means) * credibility(distance), threshold


def auroc(novel, known):
    return roc_auc_score(np.r_[np.ones(len(novel)), np.zeros(len(known))], np.r_[novel, known])


def inner_auroc(X, C, y, g, train, w, most_classes=6):
    """Leave classes out inside `train`: each of up to 6 classes (evenly spaced) against the known
    samples of each held-out group, the model fitted without both."""
    classes = sorted(set(y[train]))
    picked = [classes[int(i)] for i in np.linspace(0, len(classes) - 1, min(most_classes, len(classes)))]
    result = []
    for c in picked:
        novel, known = [], []
        for group in sorted(set(g[train])):
            fit, held = train & (y != c) & (g != group), train & (g == group)
            if len(set(y[fit])) < 2 or not held.any():
                continue
            s, _ = scores(vectors_of(X, C, fit, w), y, g, fit, held)
            novel += list(s[y[held] == c])
            known += list(s[y[held] != c])
        if novel and known:
            result.append(auroc(novel, known))
    return float(np.mean(result))


def chosen_weight(X, C, y, g, train):
    inner = {w: inner_auroc(X, C, y, g, train, w) for w in WEIGHTS}
    best = max(inner.values())
    return next(w for w in WEIGHTS if inner[w] >= best), inner


def tais():
    rows = list(csv.DictReader(open(TAIS22 / "manifest.csv")))
    images = [np.sqrt(np.load(TAIS22 / r["path"]).astype(float)) for r in rows]
    y, g = np.array([r["label"] for r in rows]), np.array([r["group"] for r in rows])
    X = nn.exported_features(sys.argv[2] if len(sys.argv) > 2 else "target/release/presrs", images)
    C = np.array([nn.contact(a) for a in images])
    results, choices = {k: {} for k in WEIGHTS + ["chosen"]}, []
    for held_class in nn.HELD:
        pooled = {k: ([], []) for k in results}
        for test_group in sorted(set(g)):
            train, test = (g != test_group) & (y != held_class), g == test_group
            w_chosen, _ = chosen_weight(X, C, y, g, train)
            choices.append(w_chosen)
            for k in results:
                s, _ = scores(vectors_of(X, C, train, w_chosen if k == "chosen" else k), y, g, train, test)
                pooled[k][0].extend(s[y[test] == held_class])
                pooled[k][1].extend(s[y[test] != held_class])
        for k, (novel, known) in pooled.items():
            results[k][held_class] = auroc(novel, known)
    for k, by_class in results.items():
        print(f"tais22, w = {k}: mean AUROC {np.mean(list(by_class.values())):.3f} "
              + ", ".join(f"{c} {v:.3f}" for c, v in by_class.items()))
    print(f"w chosen per model: {dict(zip(*np.unique(choices, return_counts=True)))}")


def sim():
    import presrs

    def images_of(trials, tag):
        frames, labels, groups = [], [], []
        for trial in trials:
            images, stances = presrs.stance_images(trial.recording)
            frames.append(images)
            labels += [trial.terrain] * len(stances)
            groups += [f"{trial.terrain}, {tag}"] * len(stances)
        return frames, labels, groups

    frames, labels, groups = [], [], []
    for seed in (1, 2, 3):
        f, l, gr = images_of(presrs.simulate(gaits=["G2"], hops=10, seed=seed), f"seed {seed}")
        frames += f; labels += l; groups += gr
    n_train = len(labels)
    for seed in range(20, 40):
        f, l, gr = images_of(presrs.simulate(gaits=["G2"], hops=5, seed=seed), f"seed {seed}")
        frames += f; labels += l; groups += gr
    images = np.concatenate(frames)
    y, g = np.array(labels), np.array(groups)
    X = presrs.features(images, family="fft1d")
    C = np.array([nn.contact(a[:38, 3:].astype(float)) for a in images])  # the paper's crop
    train = np.arange(len(y)) < n_train
    for w in WEIGHTS:
        s, threshold = scores(vectors_of(X, C, train, w), y, g, train, ~train)
        unknown = s > threshold
        by = ", ".join(f"{t} {unknown[y[~train] == t].sum()}/{(y[~train] == t).sum()}" for t in sorted(set(y)))
        print(f"simulator, w = {w}: new trials of known terrains called unknown {100 * unknown.mean():.1f} % ({by})")
    w, inner = chosen_weight(X, C, y, g, train)
    print(f"simulator: inner leave-class-out AUROC {inner}, w chosen {w}")


if __name__ == "__main__":
    {"sim": sim, "tais": tais}[sys.argv[1]]()
