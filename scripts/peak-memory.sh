#!/usr/bin/env bash
# Peak resident memory (maximum RSS, from GNU time's `-v`) of
#   1. `presrs reproduce` (the paper's experiment end to end), and
#   2. `presrs stream --listen` while CLIENTS `presrs replay --rate max` clients send at once, ROUNDS
#      times over (loopback only; the server exits after the last connection, --exit-after).
#
# Usage: scripts/peak-memory.sh            (from the repository root, after `cargo build --release`)
# Environment: PRESRS (binary, default target/release/presrs), CLIENTS (default 8), ROUNDS (default 3),
#   SKIP_REPRODUCE=1 (only the stream), KEEP=1 (keep the work folder), TIMEOUT (seconds per step, 900).
# Needs GNU time at /usr/bin/time (Debian/Ubuntu: apt-get install time).
set -euo pipefail

PRESRS=${PRESRS:-target/release/presrs}
CLIENTS=${CLIENTS:-8}
ROUNDS=${ROUNDS:-3}
TIMEOUT=${TIMEOUT:-900}
TIME=/usr/bin/time

[[ -x $PRESRS ]] || { echo "no $PRESRS: run cargo build --release -p presrs-cli first" >&2; exit 1; }
[[ -x $TIME ]] && $TIME -v true 2>/dev/null || {
    echo "GNU time is needed at $TIME (apt-get install time)" >&2
    exit 1
}

WORK=$(mktemp -d "${TMPDIR:-/tmp}/presrs-peak-memory.XXXXXX")
SERVER=""
cleanup() {
    [[ -n $SERVER ]] && kill "$SERVER" 2>/dev/null || true
    [[ ${KEEP:-0} == 1 ]] && echo "work folder kept: $WORK" || rm -rf "$WORK"
}
trap cleanup EXIT

# "Maximum resident set size (kbytes): N" and the wall clock of a GNU time -v report, as "MiB s".
peak() {
    awk -F': ' '/Maximum resident set size/ {kb = $2}
        /Elapsed \(wall clock\)/ {
            n = split($2, p, ":"); s = 0; for (i = 1; i <= n; i++) s = s * 60 + p[i]
        }
        END {printf "%.1f MiB, %.1f s wall", kb / 1024, s}' "$1"
}

echo "presrs: $PRESRS ($($PRESRS --version 2>/dev/null || echo unknown)); $(nproc) cores; load $(cut -d' ' -f1-3 /proc/loadavg)"

if [[ ${SKIP_REPRODUCE:-0} != 1 ]]; then
    echo "reproduce: running (about a minute) ..."
    timeout "$TIMEOUT" $TIME -v -o "$WORK/reproduce.time" \
        "$PRESRS" reproduce --out "$WORK/reproduce" >"$WORK/reproduce.out" 2>"$WORK/reproduce.err"
    echo "reproduce: peak RSS $(peak "$WORK/reproduce.time")"
fi

# A model and recordings to stream: a small simulated data set, the paper's method.
"$PRESRS" simulate --out "$WORK/sim" --hops-per-gait 20 >/dev/null 2>&1
"$PRESRS" train --manifest "$WORK/sim/manifest.csv" --out "$WORK/model.json" --train-condition G2 \
    --per-class 20 --validation 7 --features fft1d --classifier pwe >/dev/null 2>&1
mapfile -t FILES < <(ls -S "$WORK"/sim/recordings/*.asf | head -n "$CLIENTS")
frames=0
for f in "${FILES[@]}"; do frames=$((frames + $(grep -c '^Frame ' "$f"))); done

connections=$((CLIENTS * ROUNDS))
timeout "$TIMEOUT" $TIME -v -o "$WORK/stream.time" "$PRESRS" stream --model "$WORK/model.json" \
    --listen 127.0.0.1:0 --max-clients "$CLIENTS" --exit-after "$connections" \
    >"$WORK/stream.out" 2>"$WORK/stream.err" &
SERVER=$!
addr=""
for _ in $(seq 100); do
    addr=$(sed -n 's/.*"addr": *"\([0-9.]*:[0-9]*\)".*/\1/p' "$WORK/stream.out" | head -n 1)
    [[ -n $addr ]] && break
    sleep 0.1
done
[[ -n $addr ]] || { echo "stream did not start: $(cat "$WORK/stream.err")" >&2; exit 1; }

echo "stream: $CLIENTS clients x $ROUNDS rounds, each sending one of the $CLIENTS longest recordings" \
    "at full speed ($frames frames per round) to $addr ..."
started=$(date +%s.%N)
for round in $(seq "$ROUNDS"); do
    pids=()
    for f in "${FILES[@]}"; do
        timeout "$TIMEOUT" "$PRESRS" replay "$f" --connect "$addr" --rate max \
            >"$WORK/replay.$round.$(basename "$f").out" 2>&1 &
        pids+=($!)
    done
    for p in "${pids[@]}"; do wait "$p"; done
done
elapsed=$(echo "$(date +%s.%N) - $started" | bc)
wait "$SERVER"
SERVER=""
lines=$(cat "$WORK"/replay.*.out | grep -c '"label"' || true)
echo "stream: peak RSS $(peak "$WORK/stream.time") ($((frames * ROUNDS)) frames in ${elapsed%.*} s" \
    "of replay, $lines classified stances returned)"
