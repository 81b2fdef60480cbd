#!/usr/bin/env python3
"""aeon's MiniRocket transform of ONE sample, single thread, on the shapes of presrs' criterion bench
`crates/presrs-core/benches/rocket.rs` (11 channels x 128 frames, 60 x 75; 10,000 features; a model
fitted on 8 random samples; 16 distinct random inputs transformed in turn).

Two timings per shape, each the median of many runs after numba's warm-up:
- `transform`: the public `MiniRocket.transform(X)` with X of shape (1, channels, length), as a user
  calls it (input checks and conversion included);
- `kernel`: aeon's numba function alone (`_static_transform_multi` on the float32 array), the floor of
  what aeon can do per sample.

aeon is a bench-only dependency: install it in a venv of its own (see README.md), never in the product
or CI. Usage: python aeon_peer.py [--runs N]
"""

import argparse
import statistics
import time

import numba
import numpy as np
from aeon.transformations.collection.convolution_based import MiniRocket
from aeon.transformations.collection.convolution_based import _minirocket as internals

SHAPES = [(11, 128), (60, 75)]
TRAIN = 8
INPUTS = 16


def median_us(call, inputs, runs):
    """Median wall time of `call(x)` in microseconds, cycling through `inputs`."""
    times = []
    for i in range(runs):
        x = inputs[i % len(inputs)]
        start = time.perf_counter_ns()
        call(x)
        times.append(time.perf_counter_ns() - start)
    return statistics.median(times) / 1000.0


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=2000)
    args = parser.parse_args()
    numba.set_num_threads(1)
    rng = np.random.default_rng(33)
    print(f"aeon MiniRocket, numba {numba.__version__}, numpy {np.__version__}, 1 thread")
    for channels, length in SHAPES:
        train = rng.uniform(-1.0, 1.0, (TRAIN, channels, length))
        inputs = [rng.uniform(-1.0, 1.0, (1, channels, length)) for _ in range(INPUTS)]
        model = MiniRocket(n_kernels=10_000, n_jobs=1, random_state=0).fit(train)
        features = model.transform(inputs[0]).shape[1]
        inputs32 = [x.astype(np.float32) for x in inputs]

        def kernel(x):
            return internals._static_transform_multi(x, model.parameters, MiniRocket._indices)

        for _ in range(20):  # numba warm-up (compiled on first call, then cached)
            model.transform(inputs[0])
            kernel(inputs32[0])
        public = median_us(model.transform, inputs, args.runs)
        bare = median_us(kernel, inputs32, args.runs)
        print(
            f"{channels}x{length}: {features} features; transform median {public:.1f} us, "
            f"kernel median {bare:.1f} us ({args.runs} runs)"
        )


if __name__ == "__main__":
    main()
