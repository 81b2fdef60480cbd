#!/usr/bin/env python3
"""Plain scikit-learn peers evaluated on presrs's own draws (bench/real/run.sh runs it).

Reads what `presrs eval --export-draws DIR` wrote -- `images.npy` (samples x rows x cols, the images as
presrs evaluates them, absent sensels as 0) and `draws.json` (every repeat's folds: training, validation
and test indices into the samples) -- and evaluates four peers on exactly those sets:

* raw + PCA + LDA: the image flattened row-major, PCA to min(51, n_train - classes) dimensions, then
  sklearn's LinearDiscriminantAnalysis (default solver);
* raw + SVC: the image flattened, standardised per feature (StandardScaler), an RBF SVC with
  gamma="scale" and C chosen from {0.1, 1, 10, 100} on the draw's validation images, then refitted on
  training + validation;
* |FFT| + PCA + LDA and |FFT| + SVC: the same on the magnitude of the image's 2-D real FFT
  (np.abs(np.fft.rfft2(image)), flattened).

PCA + LDA has nothing to tune, so it trains on training + validation at once: every peer learns from the
same images presrs's models learn from (presrs trains on the training images and validates its
hyper-parameters on the validation images). Accuracy per repeat is pooled over the repeat's folds, as
presrs's `overall_accuracy`; the table gives its mean and sample standard deviation over the repeats.

Only numpy and scikit-learn are used. `--smoke` builds a tiny synthetic export and checks that the peers
run and that a separable data set is learnt (a test of this script, not a benchmark).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from sklearn.decomposition import PCA
from sklearn.discriminant_analysis import LinearDiscriminantAnalysis
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.svm import SVC

SVC_C_GRID = (0.1, 1.0, 10.0, 100.0)


def raw_features(images: np.ndarray) -> np.ndarray:
    return images.reshape(len(images), -1)


def fft_features(images: np.ndarray) -> np.ndarray:
    return np.abs(np.fft.rfft2(images, axes=(1, 2))).reshape(len(images), -1)


def pca_lda(x_train, y_train, x_val, y_val):
    x = np.concatenate([x_train, x_val])
    y = np.concatenate([y_train, y_val])
    # at most n - classes: the within-class scatter of more dimensions would be singular
    dims = max(1, min(51, len(x) - len(np.unique(y)), x.shape[1]))
    model = make_pipeline(PCA(n_components=dims, random_state=0), LinearDiscriminantAnalysis())
    return model.fit(x, y)


def svc(x_train, y_train, x_val, y_val):
    best_c, best_score = SVC_C_GRID[0], -1.0
    if len(x_val):
        for c in SVC_C_GRID:
            model = make_pipeline(StandardScaler(), SVC(C=c, gamma="scale"))
            score = model.fit(x_train, y_train).score(x_val, y_val)
            if score > best_score:  # the first best: the smaller C on ties
                best_c, best_score = c, score
    x = np.concatenate([x_train, x_val])
    y = np.concatenate([y_train, y_val])
    return make_pipeline(StandardScaler(), SVC(C=best_c, gamma="scale")).fit(x, y)


PEERS = [
    ("raw + PCA + LDA", raw_features, pca_lda),
    ("raw + SVC", raw_features, svc),
    ("|FFT| + PCA + LDA", fft_features, pca_lda),
    ("|FFT| + SVC", fft_features, svc),
]


def evaluate(images: np.ndarray, document: dict) -> list[dict]:
    labels = np.array(document["labels"])
    draws = document["draws"]
    repeats = sorted({d["repeat"] for d in draws})
    rows = []
    for name, features_of, fit in PEERS:
        start = time.perf_counter()
        x_all = features_of(images.astype(np.float64))
        feature_seconds = time.perf_counter() - start
        accuracies, train_seconds, classify_seconds, n_classified = [], [], 0.0, 0
        for repeat in repeats:
            hits = total = 0
            for draw in (d for d in draws if d["repeat"] == repeat):
                tr, va, te = (np.array(draw[k], dtype=int) for k in ("train", "validation", "test"))
                start = time.perf_counter()
                model = fit(x_all[tr], labels[tr], x_all[va], labels[va])
                train_seconds.append(time.perf_counter() - start)
                start = time.perf_counter()
                predicted = model.predict(x_all[te])
                classify_seconds += time.perf_counter() - start
                n_classified += len(te)
                hits += int(np.sum(predicted == labels[te]))
                total += len(te)
            accuracies.append(hits / total)
        rows.append(
            {
                "method": name,
                "accuracy": float(np.mean(accuracies)),
                "accuracy_std": float(np.std(accuracies, ddof=1)) if len(accuracies) > 1 else 0.0,
                "accuracies": accuracies,
                "train_seconds_per_model": float(np.mean(train_seconds)),
                # the features of every image once, shared by training and testing
                "feature_seconds_all_images": feature_seconds,
                "classify_us_per_image": 1e6 * classify_seconds / max(n_classified, 1),
            }
        )
    return rows


def load(export: Path) -> tuple[np.ndarray, dict]:
    document = json.loads((export / "draws.json").read_text())
    if document.get("format") != "presrs-eval-draws":
        raise SystemExit(f"{export / 'draws.json'}: not a presrs draws export")
    images = np.load(export / document["images"])
    if len(images) != len(document["labels"]):
        raise SystemExit(
            f"{export}: {len(images)} images but {len(document['labels'])} labels in draws.json"
        )
    return images, document


def smoke() -> int:
    """Two well separated classes in two groups, leave-one-group-out: every peer must learn them."""
    rng = np.random.default_rng(1)
    images, labels, groups = [], [], []
    for group in ("g0", "g1"):
        for label in ("row", "column"):
            for _ in range(12):
                # a bright row or a bright column near the middle: the raw images and their |FFT| both tell
                image = rng.normal(0.0, 0.1, (12, 8))
                if label == "row":
                    image[rng.integers(3, 6), :] += 5.0
                else:
                    image[:, rng.integers(3, 6)] += 5.0
                images.append(image)
                labels.append(label)
                groups.append(group)
    images = np.array(images)
    draws = []
    for repeat in range(2):
        for held_out in ("g0", "g1"):
            pool = [i for i, g in enumerate(groups) if g != held_out]
            rng.shuffle(pool)
            by_class = {c: [i for i in pool if labels[i] == c] for c in ("row", "column")}
            train = sorted(i for c in by_class.values() for i in c[:7])
            validation = sorted(i for c in by_class.values() for i in c[7:10])
            test = [i for i, g in enumerate(groups) if g == held_out]
            draws.append(
                {"repeat": repeat, "held_out": held_out, "train": train, "validation": validation, "test": test}
            )
    rows = evaluate(images, {"labels": labels, "draws": draws})
    failed = [r["method"] for r in rows if r["accuracy"] < 0.99]
    for row in rows:
        print(f"{row['method']}: {100 * row['accuracy']:.1f} %")
    if failed or len(rows) != len(PEERS):
        print(f"smoke: these peers did not learn two separable classes: {failed}", file=sys.stderr)
        return 1
    return 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--export", type=Path, help="the folder `presrs eval --export-draws` wrote")
    parser.add_argument("--out", type=Path, help="write the rows as JSON here (default: stdout)")
    parser.add_argument("--smoke", action="store_true", help="a tiny synthetic self-test")
    args = parser.parse_args()
    if args.smoke:
        return smoke()
    if args.export is None:
        parser.error("--export DIR is needed (or --smoke)")
    images, document = load(args.export)
    rows = evaluate(images, document)
    text = json.dumps({"manifest": document.get("manifest"), "peers": rows}, indent=1)
    if args.out:
        args.out.write_text(text + "\n")
    else:
        print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
