#!/usr/bin/env python3
"""The tables of bench/scale/run.sh from its results directory: medians over the repeats of each row.

    python bench/scale/table.py eval RESULTS
    python bench/scale/table.py curve RESULTS
"""

from __future__ import annotations

import json
import re
import statistics
import sys
from pathlib import Path


def wall_seconds(text: str) -> float:
    """`/usr/bin/time`'s `h:mm:ss` or `m:ss.ss` in seconds."""
    parts = [float(p) for p in text.split(":")]
    seconds = 0.0
    for part in parts:
        seconds = seconds * 60 + part
    return seconds


def runs(results: Path) -> dict[str, list[dict]]:
    """Each row's runs (name without the repeat's suffix): status, wall seconds, peak MB, output."""
    rows: dict[str, list[dict]] = {}
    for line in (results / "runs.tsv").read_text().splitlines():
        name, *fields = line.split("\t")
        values = dict(field.split("=", 1) for field in fields)
        row = re.sub(r"-\d+$", "", name)
        rows.setdefault(row, []).append(
            {
                "status": int(values["status"]),
                "seconds": wall_seconds(values["wall"]) if values["wall"] else float("nan"),
                "peak_mb": int(values["peak_kb"] or 0) / 1024,
                "out": (results / f"{name}.out").read_text(errors="replace"),
            }
        )
    return rows


def accuracy(out: str) -> str:
    """The accuracy a run printed: presrs's `overall ... %` line or the peer's JSON."""
    for line in out.splitlines():
        if line.startswith("{") and '"accuracy"' in line:
            return f"{100 * json.loads(line)['accuracy']:.1f} %"
        match = re.search(r"overall\D*([\d.]+) %", line)
        if match:
            return f"{match.group(1)} %"
    return "?"


def median(row: list[dict], key: str) -> float:
    return statistics.median(run[key] for run in row)


def table(rows: dict[str, list[dict]], prefix: str) -> None:
    print("| run | status | accuracy | wall s (median) | peak MB (median) | presrs's own lines |")
    print("| --- | --- | --- | --- | --- | --- |")
    for name, row in rows.items():
        if not name.startswith(prefix):
            continue
        last = row[-1]["out"]
        notes = "; ".join(
            line.strip() for line in last.splitlines() if line.startswith(("time", "peak memory", "chosen"))
        )
        status = ",".join(str(run["status"]) for run in row)
        print(
            f"| {name} | {status} | {accuracy(last)} | {median(row, 'seconds'):.0f} | "
            f"{median(row, 'peak_mb'):.0f} | {notes} |"
        )


def main() -> None:
    if len(sys.argv) != 3 or sys.argv[1] not in ("eval", "curve"):
        raise SystemExit(__doc__)
    rows = runs(Path(sys.argv[2]))
    table(rows, sys.argv[1] + "-" if sys.argv[1] == "eval" else "train-")


if __name__ == "__main__":
    main()
