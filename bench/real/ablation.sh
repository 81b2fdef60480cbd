#!/usr/bin/env bash
# Which stance-summary channels carry the signal (docs/methods.md, "The summary of a stance"): presrs's
# automatic choice on a set's stances with each channel group dropped, and with each alone.
#
#   bench/real/ablation.sh                    # jiku-walk, leave one subject out, 3 repeats, seed 1
#   NAME=sim MANIFEST=DIR/manifest.csv STANCE="--sample stance" BY=condition bench/real/ablation.sh
#                                             # the simulator's stances (`presrs simulate --out DIR`),
#                                             # leave one gait out
#   PRESRS=/path/to/presrs bench/real/ablation.sh
#   AUTO_FLAGS="--budget 0" bench/real/ablation.sh
#   PYTHON=/path/to/python bench/real/ablation.sh   # an interpreter with numpy (default python3)
#
# Exports the stances as presrs evaluates them (`eval --sample stance --export-draws`), writes one data
# set of series per variant (ablation.py: every stance's summary less some rows, same labels and groups)
# and runs `presrs eval --sample series` on each with the same protocol (series of the same values are the
# same samples: the rows of a stance summary are its channels). Outputs under bench/real/results/ablation/
# (ignored by git); prints one markdown table.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
target=${CARGO_TARGET_DIR:-$root/target}
data=${DATA:-$root/../shared/data/real}
python=${PYTHON:-python3}
name=${NAME:-jiku-walk}
manifest=${MANIFEST:-$data/jiku-walk/manifest.csv}
stance=${STANCE:---sample stance --one-sample-per-file}
results=$here/results/ablation/$name
common=(--leave-one-out "${BY:-group}" --repeats 3 --seed 1 --json)

if [ -n "${PRESRS:-}" ]; then
    presrs=$PRESRS
else
    (cd "$root" && CARGO_TARGET_DIR=$target cargo build --release --locked -p presrs-cli)
    presrs=$target/release/presrs
fi

rm -rf "$results"
mkdir -p "$results"
# shellcheck disable=SC2086
"$presrs" eval --manifest "$manifest" "${common[@]}" $stance --features rocket --classifier ridge \
    --export-draws "$results/draws" > /dev/null
"$python" "$here/ablation.py" --export "$results/draws" --out "$results/sets" >&2
for set in "$results"/sets/*/; do
    name=$(basename "$set")
    echo "== $name" >&2
    # shellcheck disable=SC2086
    "$presrs" eval --manifest "$set/manifest.csv" "${common[@]}" --sample series ${AUTO_FLAGS:-} \
        > "$results/$name.json"
done

python3 - "$results" <<'PY'
import json, sys
from pathlib import Path
results = Path(sys.argv[1])
print("| channels | accuracy (mean ± std over 3 repeats) | chosen |")
print("| --- | --- | --- |")
for file in sorted(results.glob("*.json"), key=lambda f: (f.stem != "all", f.stem)):
    d = json.loads(file.read_text())
    chosen = {}
    for sel in d.get("selections", []):
        score = sel["scores"][sel["chosen"]]
        name = f"{score['features']} + {score['classifier']}"
        chosen[name] = chosen.get(name, 0) + 1
    text = ", ".join(f"{k} x{v}" for k, v in sorted(chosen.items(), key=lambda kv: -kv[1]))
    print(f"| {file.stem} | {100 * d['overall_accuracy']:.1f} ± {100 * d['overall_accuracy_std']:.1f} % | {text} |")
PY
