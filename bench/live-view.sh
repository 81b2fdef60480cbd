#!/usr/bin/env bash
# The online stream's speed with and without a live-view viewer connected (issue #24): `presrs stream`
# classifies a long TekScan stream on stdin as fast as it can be read, (a) alone, (b) with `--http` and a
# viewer (`curl -N .../events`) connected throughout. Prints, per run, frames/s and the decision latency
# (p50/p99 of the `latency_us` of the classification lines), then the medians of each setting.
# Usage: [COPIES=8] bench/live-view.sh [ROUNDS]   (release build: cargo build --release -p presrs-cli)
set -euo pipefail
cd "$(dirname "$0")/.."
rounds="${1:-5}"
presrs="${PRESRS:-${CARGO_TARGET_DIR:-target}/release/presrs}"
work="$(mktemp -d)"
trap 'kill $(jobs -p) 2>/dev/null || true; rm -rf "$work"' EXIT
"$presrs" simulate --out "$work/sim" --seed 3 --gaits G2 --hops-per-gait 24 >/dev/null 2>&1
"$presrs" train --manifest "$work/sim/manifest.csv" --out "$work/model.json" --per-class 10 --dims 10 >/dev/null 2>&1
# One long stream: every recording, COPIES (8) times over (same size: one stream).
for _ in $(seq "${COPIES:-8}"); do cat "$work"/sim/recordings/*.asf; done > "$work/stream.asf"

run() { # $1: alone|viewer -> "frames_per_s p50_us p99_us"
  local out="$work/out.jsonl" port=$((7900 + RANDOM % 90))
  if [ "$1" = viewer ]; then
    mkfifo "$work/in"
    "$presrs" stream --model "$work/model.json" --http "127.0.0.1:$port" <"$work/in" >"$out" 2>/dev/null &
    local pid=$!
    exec 3>"$work/in"
    for _ in $(seq 100); do curl -s "http://127.0.0.1:$port/state" >/dev/null 2>&1 && break; sleep 0.05; done
    curl -sN "http://127.0.0.1:$port/events" >"$work/events.txt" 3>&- &
    local viewer=$!
    sleep 0.5
    local t0; t0=$(date +%s.%N)
    cat "$work/stream.asf" >&3
    exec 3>&-
    wait "$pid"
    local t1; t1=$(date +%s.%N)
    kill "$viewer" 2>/dev/null || true
    rm -f "$work/in"
  else
    local t0; t0=$(date +%s.%N)
    "$presrs" stream --model "$work/model.json" <"$work/stream.asf" >"$out" 2>/dev/null
    local t1; t1=$(date +%s.%N)
  fi
  python3 - "$out" "$t0" "$t1" "$work/events.txt" "$1" <<'PY'
import json, sys
lines = [json.loads(l) for l in open(sys.argv[1])]
end = [l for l in lines if l["event"] == "end"][-1]
lat = sorted(l["latency_us"] for l in lines if l["event"] == "classification")
dt = float(sys.argv[3]) - float(sys.argv[2])
extra = ""
if sys.argv[5] == "viewer":
    frames = open(sys.argv[4]).read().count("event: frame")
    extra = f" viewer_frames={frames} ({frames / dt:.0f}/s)"
print(f"{end['frames'] / dt:.0f} {lat[len(lat) // 2]:.1f} {lat[int(len(lat) * 0.99)]:.1f}{extra}")
PY
}

echo "frames in the stream: $(grep -c '^Frame' "$work/stream.asf")"
: >"$work/alone"; : >"$work/viewer"
for r in $(seq "$rounds"); do
  a=$(run alone); echo "round $r alone:  frames/s p50_us p99_us = $a"; echo "$a" >>"$work/alone"
  v=$(run viewer); echo "round $r viewer: frames/s p50_us p99_us = $v"; echo "$v" >>"$work/viewer"
done
median() { sort -n -k"$2" "$1" | awk -v k="$2" '{v[NR]=$k} END {print v[int((NR+1)/2)]}'; }
for s in alone viewer; do
  echo "median $s: $(median "$work/$s" 1) frames/s, decision latency p50 $(median "$work/$s" 2) us, p99 $(median "$work/$s" 3) us"
done
