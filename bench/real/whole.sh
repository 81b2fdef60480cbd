#!/usr/bin/env bash
# Whole-stance and series samples (issue #33) on the shared real sets, next to aeon's MiniRocket +
# scikit-learn's RidgeClassifierCV, with the same groups and draws.
#
#   bench/real/whole.sh                       # jiku-walk (stances) and icub20 (series)
#   bench/real/whole.sh jiku-walk             # one set
#   PRESRS=/path/to/presrs PROJECTION=/path/to/ridge_projection bench/real/whole.sh   # no builds
#   ROCKET_PYTHON=/path/to/python bench/real/whole.sh   # an interpreter with aeon (default below)
#   AUTO_FLAGS="--budget 0" bench/real/whole.sh jiku-walk   # more options for the auto rows
#
# Protocol: leave one group out, all training data (no --per-class; 35 % of it validates), 3 repeats,
# seed 1. jiku-walk: `--sample stance --one-sample-per-file` (each movie one stance, summarised);
# icub20: `--sample series` (60 taxels x 75 steps). For each set: presrs auto (its draws exported),
# presrs rocket + ridge, presrs's peer pairings (rocket_unscaled and multirocket_unscaled with
# ridge_raw), then bench/real/rocket_peer.py (aeon's MiniRocket and MultiRocket; bench only) on the
# exported draws, and
# crates/presrs/examples/ridge_projection.rs (rocket + ridge with and without the PCA step, presrs's
# own code).
# Outputs under bench/real/results/whole/ (ignored by git); prints one markdown table.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
target=${CARGO_TARGET_DIR:-$root/target}
data=${DATA:-$root/../shared/data/real}
python=${ROCKET_PYTHON:-/work/wt/rocket-venv/bin/python}
results=$here/results/whole
common=(--leave-one-out group --repeats 3 --seed 1 --json)

sets=()
for arg in "$@"; do
    case $arg in
        jiku-walk|icub20) sets+=("$arg") ;;
        -h|--help) sed -n '2,17p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; exit 0 ;;
        *) echo "whole.sh: unknown argument $arg (try --help)" >&2; exit 2 ;;
    esac
done
[ ${#sets[@]} -gt 0 ] || sets=(jiku-walk icub20)
"$python" -c "import aeon, sklearn" || {
    echo "whole.sh: $python has no aeon (see bench/rocket/README.md; ROCKET_PYTHON=...)" >&2
    exit 2
}

if [ -n "${PRESRS:-}" ]; then
    presrs=$PRESRS
else
    (cd "$root" && CARGO_TARGET_DIR=$target cargo build --release --locked -p presrs-cli)
    presrs=$target/release/presrs
fi
if [ -n "${PROJECTION:-}" ]; then
    projection=$PROJECTION
else
    (cd "$root" && CARGO_TARGET_DIR=$target cargo build --release --locked -p presrs --example ridge_projection)
    projection=$target/release/examples/ridge_projection
fi

sample_of() {
    case $1 in
        jiku-walk) echo "--sample stance --one-sample-per-file" ;;
        icub20) echo "--sample series" ;;
    esac
}

mkdir -p "$results"
for set in "${sets[@]}"; do
    out=$results/$set
    rm -rf "$out"
    mkdir -p "$out"
    # shellcheck disable=SC2207
    sample=($(sample_of "$set"))
    manifest=$data/$set/manifest.csv
    echo "== $set: presrs auto" >&2
    # shellcheck disable=SC2086
    "$presrs" eval --manifest "$manifest" "${common[@]}" "${sample[@]}" ${AUTO_FLAGS:-} \
        --export-draws "$out/draws" > "$out/auto.json"
    echo "== $set: presrs rocket + ridge" >&2
    "$presrs" eval --manifest "$manifest" "${common[@]}" "${sample[@]}" --features rocket \
        --classifier ridge > "$out/rocket_ridge.json"
    echo "== $set: presrs's peer pairings (channels and features as they are)" >&2
    "$presrs" eval --manifest "$manifest" "${common[@]}" "${sample[@]}" --features rocket_unscaled \
        --classifier ridge_raw > "$out/rocket_unscaled_ridge_raw.json"
    "$presrs" eval --manifest "$manifest" "${common[@]}" "${sample[@]}" --features multirocket_unscaled \
        --classifier ridge_raw > "$out/multirocket_unscaled_ridge_raw.json"
    echo "== $set: rocket + ridge with and without the PCA step" >&2
    "$projection" "$out/draws" > "$out/projection.txt"
    echo "== $set: aeon MiniRocket + RidgeClassifierCV" >&2
    "$python" "$here/rocket_peer.py" --export "$out/draws" --pca --channel-scaled --multirocket \
        --out "$out/peer.json"
done

python3 - "$results" "${sets[@]}" <<'EOF'
import json, sys
from pathlib import Path
results, sets = Path(sys.argv[1]), sys.argv[2:]
print("| set | method | accuracy (mean ± std over 3 repeats) |")
print("| --- | --- | --- |")
for name in sets:
    out = results / name
    for label, file in [
        ("presrs auto", "auto.json"),
        ("presrs rocket + ridge", "rocket_ridge.json"),
        ("presrs rocket_unscaled + ridge_raw", "rocket_unscaled_ridge_raw.json"),
        ("presrs multirocket_unscaled + ridge_raw", "multirocket_unscaled_ridge_raw.json"),
    ]:
        d = json.loads((out / file).read_text())
        print(f"| {name} | {label} | {100 * d['overall_accuracy']:.1f} ± {100 * d['overall_accuracy_std']:.1f} % |")
    for line in (out / "projection.txt").read_text().splitlines():
        method, _, rest = line.partition(": ")
        print(f"| {name} | presrs {method} (ridge_projection) | {rest.split(' (')[0]} |")
    for row in json.loads((out / "peer.json").read_text())["peers"]:
        print(f"| {name} | {row['method']} | {100 * row['accuracy']:.1f} ± {100 * row['accuracy_std']:.1f} % |")
EOF
