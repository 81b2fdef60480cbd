#!/usr/bin/env python3
"""The table of bench/real/run.sh: reads results/<set>/{auto,paper,compare,peers}.json and prints it.

Writes results/latest.md and results/latest.json next to them. Standard library only.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
from pathlib import Path


def seconds(path: Path) -> float | None:
    try:
        return float(Path(str(path) + ".seconds").read_text())
    except (OSError, ValueError):
        return None


def presrs_row(name: str, document: dict, wall: float | None) -> dict:
    report = document["report"]
    repeats = report["repeats"]
    folds = max(1, len(repeats[0]["per_condition"])) if repeats else 1
    train = [r["train_seconds"] / folds for r in repeats]
    return {
        "method": name,
        "accuracy": document["overall_accuracy"],
        "accuracy_std": document["overall_accuracy_std"],
        "train_seconds_per_model": sum(train) / len(train) if train else None,
        "classify_us_per_image": document["median_classify_ns"] / 1000.0,
        "wall_seconds": wall,
    }


def best_compare_row(document: dict) -> dict | None:
    rows = [r for r in document.get("comparison", []) if r.get("overall_accuracy") is not None]
    if not rows:
        return None
    best = max(rows, key=lambda r: r["overall_accuracy"])
    return {
        "method": f"best of --compare: {best['features']} + {best['classifier']}",
        "accuracy": best["overall_accuracy"],
        "accuracy_std": best["overall_accuracy_std"],
        "train_seconds_per_model": best["train_seconds"]["mean"],
        "classify_us_per_image": (best["median_classify_ns"] or 0) / 1000.0,
        "wall_seconds": None,
    }


def chosen(document: dict) -> str:
    counts: dict[str, int] = {}
    for selection in document.get("selections", []):
        scores = selection.get("scores", [])
        index = selection.get("chosen")
        if isinstance(index, int) and 0 <= index < len(scores):
            score = scores[index]
            key = f"{score['features']} + {score['classifier']}"
            intensity = (score.get("config", {}).get("preprocess") or {}).get("intensity")
            if intensity and intensity != "none":
                key = f"{intensity} {key}"
            counts[key] = counts.get(key, 0) + 1
    return "chose " + ", ".join(f"{k} x{v}" for k, v in sorted(counts.items(), key=lambda kv: -kv[1]))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--results", type=Path, required=True)
    parser.add_argument("--sets", nargs="+", required=True)
    parser.add_argument("--command", default="bench/real/run.sh")
    parser.add_argument("--load", nargs=2, default=["?", "?"])
    parser.add_argument("--presrs-version", default="unknown")
    args = parser.parse_args()

    table = []
    for name in args.sets:
        folder = args.results / name
        rows = []
        auto = json.loads((folder / "auto.json").read_text())
        rows.append(presrs_row("presrs auto", auto, seconds(folder / "auto.json")))
        rows[-1]["note"] = chosen(auto)
        internal = auto.get("internal_estimate")
        if internal:
            rows[-1]["internal_estimate"] = internal
        paper = json.loads((folder / "paper.json").read_text())
        rows.append(presrs_row("presrs paper (fft1d + Parzen)", paper, seconds(folder / "paper.json")))
        if (folder / "compare.json").exists():
            best = best_compare_row(json.loads((folder / "compare.json").read_text()))
            if best:
                best["wall_seconds"] = seconds(folder / "compare.json")
                rows.append(best)
        peers = json.loads((folder / "peers.json").read_text())
        peer_wall = seconds(folder / "peers.json")
        for peer in peers["peers"]:
            rows.append(
                {
                    "method": f"scikit-learn {peer['method']}",
                    "accuracy": peer["accuracy"],
                    "accuracy_std": peer["accuracy_std"],
                    "train_seconds_per_model": peer["train_seconds_per_model"],
                    "classify_us_per_image": peer["classify_us_per_image"],
                    "wall_seconds": None,
                }
            )
        if rows and peer_wall is not None:
            rows[-1]["note"] = f"all four peers: {peer_wall:.1f} s"
        samples = len(json.loads((folder / "draws" / "draws.json").read_text())["labels"])
        table.append({"set": name, "samples": samples, "rows": rows})

    def fmt(value, pattern):
        return "-" if value is None else pattern.format(value)

    lines = [
        "| set | method | accuracy (mean ± std over 3 repeats) | train s / model | classify µs / image | wall s | note |",
        "| --- | --- | --- | --- | --- | --- | --- |",
    ]
    for entry in table:
        for row in entry["rows"]:
            method = row["method"].replace("|", "\\|")  # |FFT| inside a Markdown cell
            lines.append(
                f"| {entry['set']} ({entry['samples']}) | {method} | "
                f"{100 * row['accuracy']:.1f} ± {100 * row['accuracy_std']:.1f} % | "
                f"{fmt(row['train_seconds_per_model'], '{:.2f}')} | "
                f"{fmt(row['classify_us_per_image'], '{:.1f}')} | {fmt(row['wall_seconds'], '{:.0f}')} | "
                f"{row.get('note', '')} |"
            )
    header = (
        f"- Date: {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC; presrs {args.presrs_version}; "
        f"command `{args.command.strip()}`\n"
        f"- Machine: {platform.machine()}, {os.cpu_count()} CPUs; load average (1, 5, 15 min) "
        f"{args.load[0]} before, {args.load[1]} after\n"
    )
    text = header + "\n" + "\n".join(lines) + "\n"
    (args.results / "latest.md").write_text(text)
    (args.results / "latest.json").write_text(json.dumps(table, indent=1) + "\n")
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
