#!/usr/bin/env bash
# presrs next to numpy and scikit-learn: the paper's pipeline (1-D |FFT| -> PCA 51 -> Parzen window) on the
# same 38x41 images with the same trained state, timed one image per call and as one batch.
#
#   bench/side_by_side.sh            # build, export the inputs, run the peer, print the table
#   bench/side_by_side.sh --record   # also rewrite bench/RESULTS.md with the measured figures
#   bench/side_by_side.sh --quick    # fewer timed calls, one round (a smoke test, not figures to quote)
#   SEED=2 ROUNDS=5 bench/side_by_side.sh
#
# Needs cargo and python3 (3.11 or newer, with the venv module); downloads pinned wheels from PyPI into
# bench/.venv on the first run. Writes bench/results/ (inputs, latest.json, latest.md). See bench/README.md.
set -euo pipefail

bench_dir=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(dirname "$bench_dir")
venv=$bench_dir/.venv
results=$bench_dir/results
seed=${SEED:-1}
rounds=${ROUNDS:-3}
record=0
iterations=20000
sklearn_iterations=2000
for arg in "$@"; do
    case $arg in
        --record) record=1 ;;
        --quick) iterations=2000; sklearn_iterations=200; rounds=1 ;;
        -h|--help) sed -n '2,11p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; exit 0 ;;
        *) echo "side_by_side.sh: unknown argument $arg (try --help)" >&2; exit 2 ;;
    esac
done

echo "== Python environment ($venv)" >&2
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
fi
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check --only-binary=:all: \
    -r "$bench_dir/requirements.txt"
# presrs's own Python package (built from python/ with maturin): its row in the table. PYTHON_PACKAGE=0
# leaves it out.
if [ "${PYTHON_PACKAGE:-1}" != 0 ]; then
    echo "== the presrs Python package (pip install ./python, release build)" >&2
    "$venv/bin/python" -m pip install --quiet --disable-pip-version-check "$root/python"
fi

echo "== presrs (release build)" >&2
cargo build --release --locked --quiet -p presrs-cli --manifest-path "$root/Cargo.toml"
target_dir=$(cargo metadata --format-version 1 --no-deps --manifest-path "$root/Cargo.toml" |
    "$venv/bin/python" -c 'import json, sys; print(json.load(sys.stdin)["target_directory"])')
presrs=$target_dir/release/presrs

commit=$(git -C "$root" describe --always --dirty 2>/dev/null || echo unknown)

mkdir -p "$results"
load_before=$(cut -d' ' -f1-3 /proc/loadavg 2>/dev/null || true)
echo "== presrs $commit: the trained model, the test images, presrs's results (load average $load_before)" >&2
"$presrs" bench --seed "$seed" --iterations 1000 --batch-runs 1 --export "$results/inputs" >/dev/null

echo "== presrs, numpy and scikit-learn on the same inputs, $rounds round(s)" >&2
status=0
"$venv/bin/python" "$bench_dir/peer.py" --export "$results/inputs" --presrs "$presrs" --seed "$seed" \
    --rounds "$rounds" --iterations "$iterations" --sklearn-iterations "$sklearn_iterations" \
    --load-before "$load_before" --presrs-commit "$commit" \
    --out "$results/latest.json" --markdown "$results/latest.md" || status=$?
echo "(written: $results/latest.json, $results/latest.md)" >&2
if [ "$status" -ne 0 ]; then
    echo "side_by_side.sh: the peer's predictions do not all agree with presrs's (exit $status)" >&2
    exit "$status"
fi
if [ "$record" -eq 1 ]; then
    cp "$results/latest.md" "$bench_dir/RESULTS.md"
    echo "(recorded in $bench_dir/RESULTS.md)" >&2
fi
