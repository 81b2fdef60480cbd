#!/usr/bin/env bash
# The Python package's per-call costs beside the Rust figures, in one run, on release builds: the CLI
# (`cargo build --release`) and the package (`pip install ./python`, maturin's release profile) in a
# virtual environment of its own (VENV, default bench/python/.venv).
set -euo pipefail
cd "$(dirname "$0")/../.."
venv=${VENV:-bench/python/.venv}
cargo build --release --locked -p presrs-cli
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv"
fi
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check numpy scikit-learn
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check ./python
"$venv/bin/python" bench/python/bench.py --cli target/release/presrs "$@"
