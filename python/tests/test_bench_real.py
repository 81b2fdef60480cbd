"""bench/real/peers.py (the scikit-learn peers of the real-data benchmark) in its smoke mode: on a tiny
synthetic export of two separable classes in two groups, every peer trains and tests on the given draws
and learns the classes."""

import subprocess
import sys
from pathlib import Path

PEERS = Path(__file__).resolve().parents[2] / "bench" / "real" / "peers.py"


def test_the_benchmark_peers_learn_a_separable_set():
    done = subprocess.run(
        [sys.executable, str(PEERS), "--smoke"], capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stdout + done.stderr
    lines = [line for line in done.stdout.splitlines() if line.endswith("%")]
    assert len(lines) == 4, done.stdout
    assert all(line.endswith("100.0 %") for line in lines), done.stdout
