#!/usr/bin/env python3
"""Scores votes of the automatic choice's candidates (issue #44) offline, from their test posteriors.

Not part of CI, and not runnable on its own: the posteriors come from a throwaway hook applied to the
presrs tree (`git apply bench/real/posteriors.patch`, never merged), which makes `presrs eval` append,
when `PRESRS_DUMP_POST=FILE` is set, one line per test sample: `seed index label class,names
posterior,posterior,...`. Run `eval` once per candidate (`--features F --classifier C`, the same protocol
and seed: the same draws), each into `post_F-C.txt` in one folder; this averages the posteriors of every
pair and triple (arithmetic and geometric mean) and prints the accuracy (mean and standard deviation over
the repeats, as `eval`), each candidate alone first. Needs numpy.
"""

import argparse
import glob
import itertools
import os
import signal

import numpy as np


def load(path):
    rows = {}
    for line in open(path):
        seed, index, label, names, posteriors = line.split()
        rows[(int(seed), int(index))] = (label, names.split(","), np.array([float(p) for p in posteriors.split(",")]))
    return rows


def accuracy(runs, members, geometric=False):
    by_seed = {}
    for key in sorted(runs[members[0]]):
        label, names, _ = runs[members[0]][key]
        stacked = np.array([runs[m][key][2] for m in members])
        combined = np.log(np.maximum(stacked, 1e-12)).mean(0) if geometric else stacked.mean(0)
        by_seed.setdefault(key[0], []).append(names[int(np.argmax(combined))] == label)
    per_repeat = [np.mean(v) for v in by_seed.values()]
    return 100 * np.mean(per_repeat), 100 * np.std(per_repeat, ddof=1)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", help="where the post_F-C.txt files are")
    args = parser.parse_args()
    runs = {os.path.basename(p)[5:-4]: load(p) for p in sorted(glob.glob(os.path.join(args.folder, "post_*.txt")))}
    names = list(runs)
    for size in (1, 2, 3):
        for members in itertools.combinations(names, size):
            mean, std = accuracy(runs, list(members))
            geometric = accuracy(runs, list(members), geometric=True)[0]
            print(f"{' + '.join(members):90} {mean:6.2f} +- {std:.2f} %  geometric {geometric:6.2f} %")


if __name__ == "__main__":
    signal.signal(signal.SIGPIPE, signal.SIG_DFL)  # a closed pipe (| head) ends quietly
    main()
