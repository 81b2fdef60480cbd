#!/usr/bin/env bash
# presrs on the shared real data sets, next to plain scikit-learn peers, with the same groups and draws.
#
#   bench/real/run.sh                  # every set; prints the table, writes bench/real/results/latest.{json,md}
#   bench/real/run.sh tais22           # some sets only (tais22, icub20, jiku-walk)
#   COMPARE=0 bench/real/run.sh        # leave out `presrs eval --compare` (the slowest part)
#   DATA=/path/to/real bench/real/run.sh
#   PRESRS=/path/to/presrs bench/real/run.sh   # that binary instead of building one
#   bench/real/run.sh --smoke          # only the peer script's self-test on synthetic data
#
# Protocol on every set: leave one group out (the manifest's `group` column), 20 images per class drawn
# from the training groups (35 % of them validate), 3 repeats, seed 1. presrs writes its draws
# (`eval --export-draws`) and the peers (bench/real/peers.py) train and test on exactly those sets.
# Needs cargo and python3 with venv; makes its own virtual environment under target/ and pip-installs
# numpy and scikit-learn there (pinned in bench/requirements.txt). See bench/real/README.md.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
target=${CARGO_TARGET_DIR:-$root/target}
venv=$target/bench-real-venv
data=${DATA:-$root/../shared/data/real}
results=$here/results
compare=${COMPARE:-1}
common=(--leave-one-out group --per-class 20 --repeats 3 --seed 1)

sets=()
smoke=0
for arg in "$@"; do
    case $arg in
        --smoke) smoke=1 ;;
        -h|--help) sed -n '2,15p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; exit 0 ;;
        tais22|icub20|jiku-walk) sets+=("$arg") ;;
        *) echo "run.sh: unknown argument $arg (try --help)" >&2; exit 2 ;;
    esac
done
[ ${#sets[@]} -gt 0 ] || sets=(tais22 icub20 jiku-walk)

echo "== Python environment ($venv)" >&2
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
fi
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check --only-binary=:all: \
    -r "$root/bench/requirements.txt"
python=$venv/bin/python
if [ "$smoke" = 1 ]; then
    exec "$python" "$here/peers.py" --smoke
fi

if [ -n "${PRESRS:-}" ]; then
    presrs=$PRESRS
else
    echo "== presrs (release build)" >&2
    (cd "$root" && CARGO_TARGET_DIR=$target cargo build --release --locked -p presrs-cli)
    presrs=$target/release/presrs
fi

# Extra options per set: jiku-walk's movies are each one foot contact (one sample per file).
options_of() {
    case $1 in
        jiku-walk) echo "--one-sample-per-file" ;;
        *) echo "" ;;
    esac
}

# Runs a command, its stdout to $1, and appends its wall time in seconds to $1.seconds.
timed() {
    local out=$1
    shift
    local start end
    start=$(date +%s.%N)
    "$@" > "$out"
    end=$(date +%s.%N)
    awk "BEGIN { print $end - $start }" > "$out.seconds"
}

mkdir -p "$results"
load_before=$(cut -d' ' -f1-3 /proc/loadavg)
for set in "${sets[@]}"; do
    manifest=$data/$set/manifest.csv
    [ -f "$manifest" ] || { echo "run.sh: no $manifest (DATA=...?)" >&2; exit 2; }
    out=$results/$set
    rm -rf "$out"
    mkdir -p "$out"
    # shellcheck disable=SC2207
    extra=($(options_of "$set"))
    echo "== $set: presrs auto (and the draws)" >&2
    timed "$out/auto.json" "$presrs" eval --manifest "$manifest" "${common[@]}" "${extra[@]}" \
        --json --export-draws "$out/draws"
    echo "== $set: the paper's method (fft1d + Parzen)" >&2
    timed "$out/paper.json" "$presrs" eval --manifest "$manifest" "${common[@]}" "${extra[@]}" \
        --features fft1d --classifier pwe --json
    if [ "$compare" = 1 ]; then
        echo "== $set: presrs eval --compare" >&2
        timed "$out/compare.json" "$presrs" eval --manifest "$manifest" "${common[@]}" "${extra[@]}" \
            --compare --json
    fi
    echo "== $set: scikit-learn peers" >&2
    timed "$out/peers.json" "$python" "$here/peers.py" --export "$out/draws" --out /dev/stdout
done
load_after=$(cut -d' ' -f1-3 /proc/loadavg)

"$python" "$here/table.py" --results "$results" --sets "${sets[@]}" \
    --command "bench/real/run.sh $*" --load "$load_before" "$load_after" \
    --presrs-version "$(cd "$root" && git rev-parse --short HEAD 2>/dev/null || echo unknown)"
