#!/usr/bin/env bash
# presrs' MiniRocket transform of one sample (criterion) and aeon's on the same shapes, back to back in
# one run. Needs the aeon venv of README.md (AEON_PYTHON, default /work/wt/rocket-venv/bin/python).
set -euo pipefail
cd "$(dirname "$0")/../.."
python="${AEON_PYTHON:-/work/wt/rocket-venv/bin/python}"
for round in 1 2; do
    echo "== round $round: presrs"
    cargo bench -p presrs-core --bench rocket -- --warm-up-time 1 --measurement-time 5 2>&1 |
        grep -E "^rocket_transform_one|time:"
    echo "== round $round: aeon"
    "$python" bench/rocket/aeon_peer.py --runs 2000
done
