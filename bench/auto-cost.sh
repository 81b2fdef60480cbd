#!/usr/bin/env bash
# The cost of the automatic choice (issue #23's timing goals), side by side for one or more presrs
# binaries, rounds interleaved so that a noisy machine weighs on every binary alike.
#
#   bench/auto-cost.sh                         # this checkout's release build
#   bench/auto-cost.sh OLD_PRESRS NEW_PRESRS   # several binaries, one column each
#   ROUNDS=5 bench/auto-cost.sh ...
#   WORKLOADS="train600 eval-8groups" bench/auto-cost.sh ...   # some workloads only
#   bench/auto-cost.sh --search [PRESRS ...]   # the default search next to the full one (below)
#   SETS="tais22" bench/auto-cost.sh --search ...
#
# --search (issue #35): on the shared real sets of single pressure maps (tais22, icub20: an object on
# the array), `eval` leaving one group out, 20 per class, 1 repeat, seed 1, with the default search
# (its 60 s budget per model) and with `--full-search --budget 0` (every transform with every family,
# no limit): per binary and search, the wall time, the accuracy and the methods chosen in the five
# models, so that what the default leaves on the table, and what it costs to take it, sit side by side.
#
# Workloads (real data from ../shared/data/real; the issue's own sets are not shared, so the nearest):
#   train600: `train` auto on 600 one-contact plantar frames of 63 x 33 (jiku-walk, every stance frame,
#             200 per class) — the issue's "600 images of 63 x 33 in under 15 s";
#   eval-tais22: `eval` auto, leave one group out (5 groups) x 3 repeats, 20 per class, on tais22
#             (28 x 50);
#   eval-8groups: `eval` auto, leave one group out x 3 repeats on the 120 jiku-walk movies put in 8
#             groups (row number mod 8), every stance frame, 135 per class (405 training images of
#             63 x 33 per fold) — the nearest to the issue's "465 images of 64 x 27, 8 groups x 3
#             repeats, under 60 s" (its set is not shared);
#   eval-8groups-2c: the same with the issue's shape: 2 classes (fast and slow), images cropped to
#             63 x 27, 203 per class (406 training images per fold).
# Prints the median wall time of each workload and binary, and the ratio to the first binary.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/.." && pwd)
data=${DATA:-$root/../shared/data/real}
rounds=${ROUNDS:-3}
search=0
if [ "${1:-}" = --search ]; then
    search=1
    shift
fi
binaries=("$@")
if [ ${#binaries[@]} -eq 0 ]; then
    (cd "$root" && cargo build --release --locked -p presrs-cli >&2)
    binaries=("${CARGO_TARGET_DIR:-$root/target}/release/presrs")
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# The default search next to the full one (--search): one line per set, binary and search.
search_side_by_side() {
    local sets=(${SETS:-tais22 icub20})
    echo "| set | binary | search | time (s) | accuracy | chosen (models) |"
    echo "| --- | --- | --- | --- | --- | --- |"
    for set in "${sets[@]}"; do
        for i in "${!binaries[@]}"; do
            for search in default full; do
                local extra=()
                [ "$search" = full ] && extra=(--full-search --budget 0)
                local start end
                start=$(date +%s.%N)
                "${binaries[$i]}" eval --manifest "$data/$set/manifest.csv" --leave-one-out group \
                    --per-class 20 --repeats 1 --seed 1 "${extra[@]}" > "$tmp/search.out" 2> "$tmp/err"
                end=$(date +%s.%N)
                local accuracy chosen
                accuracy=$(awk '$1 == "overall" { print $2 " %" }' "$tmp/search.out")
                chosen=$(awk '/^automatic choice/ { on = 1; next } on && /^  / { sub(/^  /, ""); printf "%s%s", sep, $0; sep = "; "; next } { on = 0 }' "$tmp/search.out")
                printf '| %s | %s | %s | %.1f | %s | %s |\n' "$set" "$i" "$search" \
                    "$(awk "BEGIN { print $end - $start }")" "$accuracy" "$chosen"
            done
        done
    done
    for i in "${!binaries[@]}"; do echo "binary $i: ${binaries[$i]}"; done
}
if [ "$search" = 1 ]; then
    search_side_by_side
    exit 0
fi

run() {
    local binary=$1 workload=$2
    case $workload in
        train600) "$binary" train --manifest "$data/jiku-walk/manifest.csv" --one-sample-per-file \
            --stance-frame all --per-class 200 --out "$tmp/model.json" ;;
        eval-tais22) "$binary" eval --manifest "$data/tais22/manifest.csv" --leave-one-out group \
            --per-class 20 --repeats 3 --seed 1 ;;
        eval-8groups) "$binary" eval --manifest "$tmp/eight-groups.csv" --one-sample-per-file \
            --stance-frame all --leave-one-out group --per-class 135 --repeats 3 --seed 1 ;;
        eval-8groups-2c) "$binary" eval --manifest "$tmp/eight-groups-2c.csv" --one-sample-per-file \
            --stance-frame all --crop 0:3:63:27 --leave-one-out group --per-class 203 --repeats 3 \
            --seed 1 ;;
    esac
}

# jiku-walk's movies in 8 groups (absolute paths: the manifest lives in $tmp).
awk -F, -v dir="$data/jiku-walk" 'NR == 1 { print; next } { print dir "/" $1 "," $2 "," $3 ",g" (NR - 2) % 8 }' \
    "$data/jiku-walk/manifest.csv" > "$tmp/eight-groups.csv"
awk -F, 'NR == 1 || $2 != "normal"' "$tmp/eight-groups.csv" > "$tmp/eight-groups-2c.csv"

declare -A times
workloads=(${WORKLOADS:-train600 eval-tais22 eval-8groups eval-8groups-2c})
for round in $(seq "$rounds"); do
    for workload in "${workloads[@]}"; do
        for i in "${!binaries[@]}"; do
            start=$(date +%s.%N)
            run "${binaries[$i]}" "$workload" > "$tmp/out.$i.$workload" 2> "$tmp/err"
            end=$(date +%s.%N)
            seconds=$(awk "BEGIN { printf \"%.2f\", $end - $start }")
            times[$workload.$i]="${times[$workload.$i]:-} $seconds"
            echo "round $round $workload binary $i: $seconds s (load $(cut -d' ' -f1 /proc/loadavg))" >&2
        done
    done
done

median() { tr ' ' '\n' | grep . | sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }
echo "| workload | $(for i in "${!binaries[@]}"; do printf 'binary %s (s) | ' "$i"; done)ratio to binary 0 |"
echo "| --- | $(for _ in "${binaries[@]}"; do printf -- '--- | '; done)--- |"
for workload in "${workloads[@]}"; do
    row="| $workload |"
    base=$(echo "${times[$workload.0]}" | median)
    ratios=""
    for i in "${!binaries[@]}"; do
        m=$(echo "${times[$workload.$i]}" | median)
        row="$row $m |"
        ratios="$ratios $(awk "BEGIN { printf \"%.2f\", $m / $base }")"
    done
    echo "$row$ratios |"
done
for i in "${!binaries[@]}"; do echo "binary $i: ${binaries[$i]}"; done
