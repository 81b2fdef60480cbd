#!/usr/bin/env python3
"""Which stance-summary channels carry the signal: the channel-group ablation of docs/methods.md.

Reads what `presrs eval --sample stance --export-draws DIR` wrote (`images.npy`: every stance's summary,
channels x frames padded to one length; `draws.json`: labels, groups and conditions) and writes, for the
whole summary and for each channel group dropped (and kept alone), a data set of series files, one
`.npy` per stance with the remaining channels, and its manifest (the same labels, conditions and
groups). `ablation.sh` then runs `presrs eval --sample series` on each with the same protocol, so every
row is presrs's own automatic choice on the same stances, less some channels.

The groups follow `presrs_core::stance::summary` (12 channels by default): `load` (row 0), `area` (1),
`cop` (the centre of pressure's row and column, 2-3) and `regions` (the 4 x 2 blocks' loads, 4-11).

    python3 bench/real/ablation.py --export DIR --out OUT   # writes OUT/<variant>/manifest.csv
"""

from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path

import numpy as np

GROUPS = {
    "load": [0],
    "area": [1],
    "cop": [2, 3],
    "regions": list(range(4, 12)),
}


def variants(channels: int) -> dict[str, list[int]]:
    if channels != 12:
        raise SystemExit(f"expected the default 12-channel summary, got {channels} channels")
    every = list(range(channels))
    out = {"all": every}
    for name, rows in GROUPS.items():
        out[f"without-{name}"] = [c for c in every if c not in rows]
    for name, rows in GROUPS.items():
        out[f"only-{name}"] = rows
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--export", type=Path, required=True)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    document = json.loads((args.export / "draws.json").read_text())
    images = np.load(args.export / document["images"])
    labels = document["labels"]
    groups = [g or "all" for g in document["groups"]]
    conditions = [c or "all" for c in document["conditions"]]
    for name, rows in variants(images.shape[1]).items():
        folder = args.out / name
        folder.mkdir(parents=True, exist_ok=True)
        with open(folder / "manifest.csv", "w", newline="") as out:
            writer = csv.writer(out)
            writer.writerow(["path", "label", "condition", "group"])
            for i, image in enumerate(images):
                path = f"s{i:04d}.npy"
                np.save(folder / path, np.ascontiguousarray(image[rows], dtype=np.float64))
                writer.writerow([path, labels[i], conditions[i], groups[i]])
        print(name, len(rows), "channels")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
