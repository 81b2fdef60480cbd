#!/usr/bin/env python3
"""A synthetic set of multichannel series shaped like a legged robot's IMU windows (issue #44's scale bench).

    python3 bench/scale/make_series.py OUT_DIR [--samples 11256] [--channels 6] [--length 100]
                                               [--classes 4] [--recordings 48] [--parts 4] [--seed 1]

Writes OUT_DIR/manifest.csv (`path,label,condition,group,recording`) and one `.npy` per sample
(`channels x length`, float64) under OUT_DIR/series/. Each class is a floor: the gait is the same
periodic motion on every floor (a stride of 40-60 steps, harmonics on every channel), and the floor shows
in the details: how hard each foot lands (an impact of the class's own decay and ring frequency on the
vertical channels), a band of vibration in the gyroscope channels, and a slip drift on one axis. Each
recording has its own speed, gains, offsets and phase, and each window its own noise, so that the classes
overlap and a model must generalise to recordings it has not seen: the `group` column holds which of
`--parts` parts a recording belongs to (every part holds recordings of every class), so that
`--leave-one-out group` is a leave-recordings-out evaluation in `--parts` folds.

Deterministic in `--seed`. Needs numpy only.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np


def floor_traits(classes: int, rng: np.random.Generator) -> list[dict]:
    """Each floor's signature, close enough to its neighbours that the classes overlap."""
    traits = []
    for c in range(classes):
        t = c / max(classes - 1, 1)
        traits.append(
            {
                "impact": 1.0 + 0.35 * t + 0.05 * rng.standard_normal(),
                "decay": 0.25 + 0.2 * ((c * 7) % classes) / classes,
                "ring": 0.55 + 0.25 * ((c * 3) % classes) / classes,
                "vibration": 0.10 + 0.08 * ((c * 5 + 1) % classes) / classes,
                "band": 0.9 + 0.6 * ((c * 2 + 1) % classes) / classes,
                "slip": 0.02 * (c % 2) - 0.01,
            }
        )
    return traits


def window(trait: dict, recording: dict, length: int, channels: int, rng: np.random.Generator) -> np.ndarray:
    """One window of one recording: `channels x length`."""
    steps = np.arange(length, dtype=np.float64)
    stride = recording["stride"]
    phase = rng.uniform(0, 2 * np.pi)
    gait = 2 * np.pi * steps / stride + phase
    out = np.empty((channels, length))
    for ch in range(channels):
        harmonics = (
            np.sin(gait + recording["offsets"][ch])
            + 0.4 * np.sin(2 * gait + 1.3 * ch)
            + 0.15 * np.sin(3 * gait + 0.7 * ch)
        )
        out[ch] = recording["gains"][ch] * harmonics + recording["bias"][ch]
    # Foot impacts: twice a stride, on the vertical acceleration (channel 2) and, weaker, on the others.
    landings = np.arange((phase / (2 * np.pi)) * stride % (stride / 2), length, stride / 2)
    for landing in landings:
        after = steps - landing
        hit = after >= 0
        pulse = np.zeros(length)
        pulse[hit] = (
            trait["impact"]
            * recording["hardness"]
            * np.exp(-trait["decay"] * after[hit])
            * np.cos(trait["ring"] * after[hit])
        )
        for ch in range(channels):
            weight = 1.0 if ch == 2 % channels else 0.3 / (1 + ch)
            out[ch] += weight * pulse
    # Vibration in a band, on the gyroscope channels (the last half).
    for ch in range(channels // 2, channels):
        noise = rng.standard_normal(length + 8)
        kernel = np.cos(trait["band"] * np.arange(9)) * np.hanning(9)
        out[ch] += trait["vibration"] * np.convolve(noise, kernel, mode="valid")[:length]
    out[0] += trait["slip"] * steps * recording["slip_gain"]
    out += recording["noise"] * rng.standard_normal((channels, length))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out", type=Path)
    parser.add_argument("--samples", type=int, default=11256)
    parser.add_argument("--channels", type=int, default=6)
    parser.add_argument("--length", type=int, default=100)
    parser.add_argument("--classes", type=int, default=4)
    parser.add_argument("--recordings", type=int, default=48)
    parser.add_argument("--parts", type=int, default=4)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    if args.recordings < args.classes * args.parts:
        parser.error("--recordings must be at least --classes x --parts (every part holds every class)")

    rng = np.random.default_rng(args.seed)
    traits = floor_traits(args.classes, rng)
    recordings = []
    for r in range(args.recordings):
        recordings.append(
            {
                "label": r % args.classes,
                "part": (r // args.classes) % args.parts,
                "stride": rng.uniform(40, 60),
                "gains": rng.uniform(0.7, 1.3, args.channels),
                "offsets": rng.uniform(-0.6, 0.6, args.channels),
                "bias": rng.normal(0, 0.3, args.channels),
                "hardness": rng.uniform(0.75, 1.25),
                "slip_gain": rng.uniform(0.0, 2.0),
                "noise": rng.uniform(0.15, 0.35),
            }
        )
    out = args.out
    (out / "series").mkdir(parents=True, exist_ok=True)
    lines = ["path,label,condition,group,recording"]
    for i in range(args.samples):
        r = i % args.recordings
        recording = recordings[r]
        values = window(traits[recording["label"]], recording, args.length, args.channels, rng)
        name = f"series/{i:06d}.npy"
        np.save(out / name, values)
        lines.append(f"{name},floor{recording['label']},walk,part{recording['part']},rec{r:03d}")
    (out / "manifest.csv").write_text("\n".join(lines) + "\n")
    print(f"{out}: {args.samples} series of {args.channels} x {args.length}, {args.classes} classes, "
          f"{args.recordings} recordings in {args.parts} parts")


if __name__ == "__main__":
    main()
