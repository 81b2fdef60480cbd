#!/usr/bin/env python3
"""The "Calibration of the simulator" table of docs/reproducing.md: how the paper's method degrades as the simulator's
realism knobs get harsher.

For each setting (everything else at the built-in configuration) it writes a simulator configuration,
simulates the default data set with it (`presrs simulate --config C --seed 1`), evaluates the paper's method
with the paper's protocol (`presrs eval --train-condition G2 --per-class 20 --validation 7 --repeats 10
--features fft1d --classifier pwe --seed 1`) and prints one Markdown row: overall accuracy (mean ± std over
the repeats) and the carpet recall (the weakest class), then the summed confusion counts (rows: true
carpet, clay, grass, wood; columns: predicted, same order).

Usage (from the repository root, after `cargo build --release -p presrs-cli`):
    python3 scripts/realism-table.py [ROW ...]     # ROW: 0-based row numbers; default every row
Environment: PRESRS (binary, default target/release/presrs), WORK (scratch folder, default a temporary
one; each data set is about 160 MB and is deleted after its row). Standard library only; about 20 s per
row on a 2-core machine.
"""

import copy
import json
import os
import shutil
import subprocess
import sys
import tempfile

PRESRS = os.environ.get("PRESRS", "target/release/presrs")


def setting(base, **changes):
    """`base` with realism knobs changed; `carpet_loop_position_sd_m` sets the carpet's loop spread."""
    config = copy.deepcopy(base)
    for knob, value in changes.items():
        if knob == "carpet_loop_position_sd_m":
            config["terrains"]["carpet"]["loop_position_sd_m"] = value
        else:
            if knob not in config["realism"]:
                sys.exit(f"no realism knob {knob!r} in `presrs simulate --print-config`")
            config["realism"][knob] = value
    return config


def rows(base):
    placement_x1_5 = dict(lateral_cop_sd_m=0.0045, foreaft_cop_sd_m=0.0033)
    return [
        ("default (calibrated)", setting(base)),
        ("foot placement spread x1.5 (4.5 / 3.3 mm)", setting(base, **placement_x1_5)),
        (
            "foot placement spread x2 (6.0 / 4.4 mm)",
            setting(base, lateral_cop_sd_m=0.006, foreaft_cop_sd_m=0.0044),
        ),
        ("sensor noise 4 counts (default 1)", setting(base, sensor_noise_counts=4.0)),
        ("sensor noise 8 counts", setting(base, sensor_noise_counts=8.0)),
        ("per-sensel gain spread 15 % (default 5 %)", setting(base, gain_spread=0.15)),
        (
            "5 % dead sensels (filled by the default dead-sensel correction)",
            setting(base, dead_sensel_fraction=0.05),
        ),
        (
            "carpet on a near-perfect lattice (0.12 mm spread, the first default)",
            setting(base, carpet_loop_position_sd_m=0.00012),
        ),
        ("terrain variability x2", setting(base, terrain_variability=2.0)),
        (
            "placement x1.5 + noise 3 + 2 % dead sensels",
            setting(base, **placement_x1_5, sensor_noise_counts=3.0, dead_sensel_fraction=0.02),
        ),
    ]


def run(*args):
    return subprocess.run([PRESRS, *args], check=True, capture_output=True, text=True).stdout


def main():
    if not os.access(PRESRS, os.X_OK):
        sys.exit(f"no {PRESRS}: run cargo build --release -p presrs-cli first")
    base = json.loads(run("simulate", "--print-config"))
    only = {int(a) for a in sys.argv[1:]}
    work = os.environ.get("WORK") or tempfile.mkdtemp(prefix="presrs-realism-")
    os.makedirs(work, exist_ok=True)
    print("| setting (everything else default) | overall | carpet recall |")
    print("| --- | --- | --- |")
    for index, (name, config) in enumerate(rows(base)):
        if only and index not in only:
            continue
        config_path = os.path.join(work, f"config{index}.json")
        data = os.path.join(work, f"data{index}")
        with open(config_path, "w") as f:
            json.dump(config, f)
        run("simulate", "--config", config_path, "--out", data, "--seed", "1")
        result = json.loads(
            run(
                "eval", "--manifest", os.path.join(data, "manifest.csv"),
                "--train-condition", "G2", "--per-class", "20", "--validation", "7",
                "--repeats", "10", "--features", "fft1d", "--classifier", "pwe",
                "--seed", "1", "--json",
            )
        )
        shutil.rmtree(data, ignore_errors=True)
        confusion = result["confusion"]
        carpet = confusion["labels"].index("carpet")
        recall = confusion["row_normalised"][carpet][carpet]
        print(
            f"| {name} | {100 * result['overall_accuracy']:.1f} % ± "
            f"{100 * result['overall_accuracy_std']:.1f} | {100 * recall:.1f} % | "
            f"{json.dumps(confusion['counts'])}",
            flush=True,
        )


if __name__ == "__main__":
    try:
        main()
    except BrokenPipeError:
        pass
