"""Frame published -> decision received over loopback, for `presrs ros2`, with Cyclone DDS (Python) as the
robot's side: the real recording (FrasP01L) replayed many times.

    python bench/ros2/bench.py [--presrs target/release/presrs] [--replays-100hz 20] [--replays-flat 50]
                               [--throughput-frames 20000]

Needs numpy, mcap and cyclonedds (the CI venv has them after .ci/run). Prints medians, p99 and rates as
JSON. Latency of a decision: its receipt here minus the publication here of the frame it was decided on
(the decision's `frame`), both on this process's monotonic clock.
"""

import argparse
import json
import signal
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests" / "ros2"))

import conftest  # noqa: E402  (the test fixtures' model and bag, and Cyclone's loopback configuration)
import ros2_types as t  # noqa: E402
from cyclonedds.core import WaitSet, ReadCondition, SampleState, ViewState, InstanceState  # noqa: E402
from cyclonedds.util import duration  # noqa: E402
from dds_peer import Peer  # noqa: E402

import numpy as np  # noqa: E402


def percentiles(values_us):
    a = np.asarray(values_us)
    return {"n": len(a), "p50_us": round(float(np.percentile(a, 50)), 1),
            "p99_us": round(float(np.percentile(a, 99)), 1), "max_us": round(float(a.max()), 1)}


def receive(peer, received, stop):
    """Decisions as they arrive, stamped on receipt."""
    ws = WaitSet(peer.dp)
    cond = ReadCondition(peer.decisions, SampleState.Any | ViewState.Any | InstanceState.Any)
    ws.attach(cond)
    while not stop.is_set():
        ws.wait(duration(milliseconds=50))
        now = time.perf_counter()
        for s in peer.decisions.take(N=1000):
            if getattr(getattr(s, "sample_info", None), "valid_data", True):
                received.append((s.frame, now, s.latency_us))


def latency_run(case, domain, replays, period):
    peer = Peer(domain, reliable=(period == 0))
    extra = ["--input-qos", "reliable"] if period == 0 else []
    node = conftest.Node(case.model, domain, *extra)
    assert peer.wait_matched(30)
    time.sleep(0.5)
    images = [t.Image.deserialize(d) for d in case.payloads]
    received, stop = [], threading.Event()
    thread = threading.Thread(target=receive, args=(peer, received, stop), daemon=True)
    thread.start()
    sent = []
    start = time.perf_counter()
    for r in range(replays):
        for i, image in enumerate(images):
            if period:
                target = start + (r * len(images) + i) * period
                while time.perf_counter() < target:
                    pass
            sent.append(time.perf_counter())
            peer.publish(image)
    expected = replays * sum(e["event"] == "classification" for e in case.reference)
    end = time.monotonic() + 30
    while len(received) < expected and time.monotonic() < end:
        time.sleep(0.05)
    stop.set()
    thread.join(2)
    code, stderr = node.stop(signal.SIGINT)
    lat = [(now - sent[frame]) * 1e6 for frame, now, _ in received if frame < len(sent)]
    inside = [node_us for _, _, node_us in received]
    return {"decisions": len(received), "expected": expected, **percentiles(lat),
            "inside_node_p50_us": round(float(np.median(inside)), 1) if inside else None,
            "node_summary": stderr.strip().splitlines()[-1]}


def throughput_run(case, domain, frames):
    peer = Peer(domain, reliable=True)
    node = conftest.Node(case.model, domain, "--input-qos", "reliable", "--input-depth", "1000")
    assert peer.wait_matched(30)
    time.sleep(0.5)
    images = [t.Image.deserialize(d) for d in case.payloads]
    start = time.perf_counter()
    for i in range(frames):
        peer.publish(images[i % len(images)])
    acked = peer.writer.wait_for_acks(duration(seconds=60))
    elapsed = time.perf_counter() - start
    code, stderr = node.stop(signal.SIGINT)
    end = [e for e in node.stdout if e.get("event") == "end"]
    taken = end[0]["frames"] if end else None
    return {"frames_sent": frames, "frames_classified": taken, "all_acked": bool(acked),
            "seconds": round(elapsed, 3), "frames_per_s": round(frames / elapsed),
            "node_summary": stderr.strip().splitlines()[-1]}


def publisher_only(case, domain, frames):
    """How fast this Python publisher writes with nobody listening: the ceiling of the runs above."""
    peer = Peer(domain, reliable=True, input_topic="nobody/listens")
    images = [t.Image.deserialize(d) for d in case.payloads]
    start = time.perf_counter()
    for i in range(frames):
        peer.publish(images[i % len(images)])
    return {"frames": frames, "frames_per_s": round(frames / (time.perf_counter() - start))}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--replays-100hz", type=int, default=20)
    ap.add_argument("--replays-flat", type=int, default=50)
    ap.add_argument("--throughput-frames", type=int, default=20000)
    ap.add_argument("--domain", type=int, default=150)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as d:
        case = conftest.make_fras_case(Path(d))
        results = {
            "presrs": conftest.CLI,
            "latency_100hz_sensor_data": latency_run(case, args.domain, args.replays_100hz, 0.01),
            "latency_flat_out_reliable": latency_run(case, args.domain + 1, args.replays_flat, 0.0),
            "throughput_reliable": throughput_run(case, args.domain + 2, args.throughput_frames),
            "publisher_alone": publisher_only(case, args.domain + 3, args.throughput_frames),
        }
    print(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
