#!/usr/bin/env bash
# The scale bench of issue #44: presrs next to aeon's MiniRocket + ridge in one run, and the curve of
# `presrs train`'s time and memory against the number of samples. Figures in bench/scale/README.md.
#
#   bench/scale/run.sh eval            # 11,256 series of 6 x 100, leave each of 4 groups out: presrs auto,
#                                      # presrs rocket + ridge, aeon MiniRocket + RidgeClassifierCV
#   bench/scale/run.sh curve           # presrs train (auto) on 1k, 10k, 100k series of 12 x 60
#   bench/scale/run.sh curve 1000 10000   # chosen sizes
#   REPEATS=3 bench/scale/run.sh eval  # each row run 3 times, medians reported
#
# Environment: PRESRS (the binary; default: built here, release), PYTHON (an interpreter with numpy, and
# aeon + scikit-learn for the peer; default /work/wt/scale-target/aeon-venv/bin/python), DATA (where the
# synthetic sets go; default bench/scale/data, ignored by git), RESULTS (default bench/scale/results),
# MEMORY_LIMIT_KB (every run's address space is capped, default 20000000: on a shared machine a run that
# would take more fails alone instead of pushing others out).
# Each run's wall time and peak resident memory come from /usr/bin/time -v; presrs also prints its own
# peak (VmHWM) and its time split (scoring, training the winner) at the end.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
python=${PYTHON:-/work/wt/scale-target/aeon-venv/bin/python}
data=${DATA:-$here/data}
results=${RESULTS:-$here/results}
repeats=${REPEATS:-1}
limit=${MEMORY_LIMIT_KB:-20000000}
mkdir -p "$data" "$results"

if [ -n "${PRESRS:-}" ]; then
    presrs=$PRESRS
else
    target=${CARGO_TARGET_DIR:-$root/target}
    (cd "$root" && CARGO_TARGET_DIR=$target cargo build --release --locked -p presrs-cli)
    presrs=$target/release/presrs
fi

# measure NAME CMD...: runs CMD with its address space capped; keeps its output, wall time and peak RSS.
measure() {
    local name=$1
    shift
    local status=0
    (ulimit -v "$limit"; /usr/bin/time -v "$@") >"$results/$name.out" 2>"$results/$name.err" || status=$?
    local wall peak
    wall=$(grep 'Elapsed (wall clock)' "$results/$name.err" | awk '{print $NF}')
    peak=$(grep 'Maximum resident set size' "$results/$name.err" | awk '{print $NF}')
    echo "$name	status=$status	wall=$wall	peak_kb=$peak" | tee -a "$results/runs.tsv"
}

make_set() { # make_set DIR ARGS...: the synthetic set, once
    local dir=$1
    shift
    [ -f "$dir/manifest.csv" ] || "$python" "$here/make_series.py" "$dir" "$@"
}

run_eval() {
    local set=$data/imu11k
    make_set "$set"
    local common=(eval --manifest "$set/manifest.csv" --sample series --leave-one-out group --repeats 1 --seed 1)
    for k in $(seq 1 "$repeats"); do
        measure "eval-auto-$k" "$presrs" "${common[@]}"
        measure "eval-rocket-ridge-$k" "$presrs" "${common[@]}" --features rocket --classifier ridge
        measure "eval-peer-$k" "$python" "$here/peer.py" "$set/manifest.csv"
    done
    "$python" "$here/table.py" eval "$results"
}

run_curve() {
    local sizes=("$@")
    [ ${#sizes[@]} -gt 0 ] || sizes=(1000 10000 100000)
    for n in "${sizes[@]}"; do
        local set=$data/series12x60-$n
        make_set "$set" --samples "$n" --channels 12 --length 60
        for k in $(seq 1 "$repeats"); do
            measure "train-$n-$k" "$presrs" train --manifest "$set/manifest.csv" --sample series \
                --out "$results/train-$n.model.json" --no-online-profile
        done
    done
    "$python" "$here/table.py" curve "$results"
}

case ${1:-} in
    eval) run_eval ;;
    curve) shift; run_curve "$@" ;;
    -h|--help|"") sed -n '2,19p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//' ;;
    *) echo "run.sh: unknown command $1 (try --help)" >&2; exit 2 ;;
esac
