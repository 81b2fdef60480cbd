"""Frame published -> decision received over loopback, for `presrs ros2`, with Cyclone DDS (Python) as the
robot's side: the real recording (FrasP01L) replayed many times.

    PRESRS_CLI=target/release/presrs python bench/ros2/bench.py [--replays-100hz 20] [--replays-flat 50]
        [--throughput-frames 20000] [--publishers 1,2] [--only latency|throughput]

Needs numpy, mcap and cyclonedds (the CI venv has them after .ci/run). Prints medians, p99 and rates as
JSON.

Three processes, as on a robot: the publisher (this process), the node, and the subscriber (a process
of its own). Latency of a decision: its receipt by the subscriber minus the publication of the frame it
was decided on (the decision's `frame`), both read from CLOCK_MONOTONIC (`time.monotonic_ns`), which
every process on the machine shares. The publisher writes frames it serialized once, so that Python's
per-frame serialization (about 0.3 ms for a 60x21 image here) is not counted as transport, and paces itself
by sleeping, never by spinning: a spinning publisher takes one of the machine's two cores, and a
subscriber thread in the publisher's process waits for the GIL (5 ms switch interval), which is what
the first version of this bench measured (bench/ros2/README.md).
"""

import argparse
import json
import multiprocessing
import os
import signal
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests" / "ros2"))

import conftest  # noqa: E402  (the test fixtures' model and bag, and Cyclone's loopback configuration)
import ros2_types as t  # noqa: E402
from cyclonedds._clayer import ddspy_write  # noqa: E402
from cyclonedds.core import InstanceState, ReadCondition, SampleState, ViewState, WaitSet  # noqa: E402
from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.pub import DataWriter  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402
from cyclonedds.util import duration  # noqa: E402
from dds_peer import BEST_EFFORT, RELIABLE  # noqa: E402

import numpy as np  # noqa: E402


def percentiles(values_us):
    a = np.asarray(values_us)
    if len(a) == 0:
        return {"n": 0}
    return {"n": len(a), "p50_us": round(float(np.percentile(a, 50)), 1),
            "p99_us": round(float(np.percentile(a, 99)), 1), "max_us": round(float(a.max()), 1)}


class FramePublisher:
    """A Cyclone writer of `sensor_msgs/Image` that writes frames serialized once (as a C++ driver
    would hand over its buffer), in a participant of its own."""

    def __init__(self, domain, reliable, topic="foot/pressure"):
        self.dp = DomainParticipant(domain)
        self.writer = DataWriter(self.dp, Topic(self.dp, "rt/" + topic, t.Image),
                                 qos=RELIABLE if reliable else BEST_EFFORT)

    def serialized(self, payloads):
        """The bag's CDR payloads as this writer writes them (Cyclone's own serialization, padded)."""
        out = []
        for data in payloads:
            ser = t.Image.deserialize(data).serialize(use_version_2=self.writer._use_version_2)
            out.append(ser.ljust((len(ser) + 3) & ~3, b"\0"))
        return out

    def wait_matched(self, timeout=30):
        end = time.monotonic() + timeout
        while not self.writer.get_matched_subscriptions():
            if time.monotonic() > end:
                return False
            time.sleep(0.02)
        return True

    def write(self, ser):
        if ddspy_write(self.writer._ref, ser) < 0:
            raise RuntimeError("Cyclone could not write a frame")


def subscriber(domain, ready, stop, out):
    """The decisions as they arrive, stamped on receipt (a process of its own)."""
    dp = DomainParticipant(domain)
    reader = DataReader(dp, Topic(dp, "rt/presrs/decisions", t.TerrainDecision), qos=RELIABLE)
    ws = WaitSet(dp)
    ws.attach(ReadCondition(reader, SampleState.Any | ViewState.Any | InstanceState.Any))
    end = time.monotonic() + 30
    while not reader.get_matched_publications() and time.monotonic() < end:
        time.sleep(0.02)
    ready.set()
    got = []
    while not stop.is_set():
        ws.wait(duration(milliseconds=50))
        now = time.monotonic_ns()
        for s in reader.take(N=1000):
            if getattr(getattr(s, "sample_info", None), "valid_data", True):
                got.append((s.frame, now, s.latency_us))
    out.put(got)


def start_subscriber(domain):
    ctx = multiprocessing.get_context("spawn")
    ready, stop, out = ctx.Event(), ctx.Event(), ctx.Queue()
    proc = ctx.Process(target=subscriber, args=(domain, ready, stop, out), daemon=True)
    proc.start()
    if not ready.wait(40):
        raise RuntimeError("the subscriber did not find the node")
    return proc, stop, out


def sniffer(ready, stop, out):
    """The loopback's packets, stamped by the kernel as they pass (needs CAP_NET_RAW): the frames that
    reach the node (RTPS datagrams of more than 2,000 bytes: the images) and the typed decisions that
    leave it (the datagrams that name a class and are not a JSON event), on CLOCK_MONOTONIC."""
    import socket
    import struct

    so_timestampns = 35  # <asm-generic/socket.h>, SCM_TIMESTAMPNS the same
    sock = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.ntohs(0x0003))
    sock.bind(("lo", 0))
    sock.setsockopt(socket.SOL_SOCKET, so_timestampns, 1)
    sock.settimeout(0.1)
    offset = time.time_ns() - time.monotonic_ns()
    frames, decisions = [], []
    ready.set()
    while not stop.is_set():
        try:
            data, ancillary, _, addr = sock.recvmsg(65536, 64)
        except socket.timeout:
            continue
        if addr[2] != socket.PACKET_HOST:  # a loopback datagram is seen going out and coming in
            continue
        stamp = next((struct.unpack("qq", d[:16]) for level, kind, d in ancillary
                      if level == socket.SOL_SOCKET and kind == so_timestampns), None)
        payload = data[14 + 20 + 8:]  # Ethernet, IPv4, UDP headers
        if stamp is None or not payload.startswith(b"RTPS"):
            continue
        ns = stamp[0] * 1_000_000_000 + stamp[1] - offset
        if len(payload) > 2000:
            frames.append(ns)
        elif b"heavy\0" in payload and b'"event"' not in payload:
            decisions.append(ns)
    out.put((frames, decisions))


def wire_legs(sent, received, wire):
    """The three legs of each decision from the sniffer's stamps: the frame's way to the node (its
    publication to its datagram on the loopback), the node (that datagram to the decision's), and the
    decision's way to the subscriber (its datagram to its receipt)."""
    frames, decisions = wire
    if len(frames) != len(sent) or len(decisions) != len(received):
        return {"unmatched": {"frames": [len(frames), len(sent)],
                              "decisions": [len(decisions), len(received)]}}
    legs = {"to_node": [], "in_node": [], "to_subscriber": []}
    for (frame, now, _), out_ns in zip(received, decisions):
        legs["to_node"].append((frames[frame] - sent[frame]) / 1000)
        legs["in_node"].append((out_ns - frames[frame]) / 1000)
        legs["to_subscriber"].append((now - out_ns) / 1000)
    return {k: percentiles(v) for k, v in legs.items()}


def latency_run(case, domain, replays, period, wire=False):
    reliable = period == 0
    node = conftest.Node(case.model, domain, *(["--input-qos", "reliable"] if reliable else []))
    proc, stop, out = start_subscriber(domain)
    if wire:
        ctx = multiprocessing.get_context("spawn")
        wire_ready, wire_stop, wire_out = ctx.Event(), ctx.Event(), ctx.Queue()
        wire_proc = ctx.Process(target=sniffer, args=(wire_ready, wire_stop, wire_out), daemon=True)
        wire_proc.start()
        assert wire_ready.wait(20)
    pub = FramePublisher(domain, reliable)
    frames = pub.serialized(case.payloads)
    assert pub.wait_matched(30)
    time.sleep(0.5)
    sent = []
    start = time.monotonic()
    for r in range(replays):
        for i, ser in enumerate(frames):
            if period:
                wait = start + (r * len(frames) + i) * period - time.monotonic()
                if wait > 0:
                    time.sleep(wait)
            sent.append(time.monotonic_ns())
            pub.write(ser)
    # One pass's decisions times the replays. The recording begins in contact (a partial stance that
    # one pass does not decide); after another replay that stance is whole, so the node decides
    # `replays - 1` more.
    expected = replays * sum(e["event"] == "classification" for e in case.reference)
    time.sleep(1.0)
    stop.set()
    received = out.get(timeout=30)
    proc.join(5)
    legs = None
    if wire:
        wire_stop.set()
        legs = wire_legs(sent, received, wire_out.get(timeout=30))
        wire_proc.join(5)
    code, stderr = node.stop(signal.SIGINT)
    lat = [(now - sent[frame]) / 1000 for frame, now, _ in received if frame < len(sent)]
    inside = [node_us for _, _, node_us in received]
    result = {"decisions": len(received), "one_pass_decisions_x_replays": expected, **percentiles(lat),
              "inside_node_p50_us": round(float(np.median(inside)), 1) if inside else None,
              "node_summary": stderr.strip().splitlines()[-1]}
    if legs is not None:
        result["legs"] = legs
    return result


def publish_many(domain, frames, payloads, ready, go, done):
    """One publisher process: `frames` frames flat out, then until all are acknowledged."""
    pub = FramePublisher(domain, reliable=True)
    serialized = pub.serialized(payloads)
    ok = pub.wait_matched(30)
    ready.put(ok)
    go.wait(60)
    for i in range(frames):
        pub.write(serialized[i % len(serialized)])
    acked = pub.writer.wait_for_acks(duration(seconds=120))
    done.put((bool(acked), time.monotonic()))


def throughput_run(case, domain, frames, publishers):
    """`frames` frames from `publishers` processes flat out to the node on the reliable profile, until
    every frame is acknowledged; the node's summary says whether all were classified."""
    node = conftest.Node(case.model, domain, "--input-qos", "reliable", "--input-depth", "1000")
    sub, sub_stop, sub_out = start_subscriber(domain)
    ctx = multiprocessing.get_context("spawn")
    ready, go, done = ctx.Queue(), ctx.Event(), ctx.Queue()
    share = frames // publishers
    procs = [ctx.Process(target=publish_many, args=(domain, share, case.payloads, ready, go, done))
             for _ in range(publishers)]
    for p in procs:
        p.start()
    assert all(ready.get(timeout=60) for _ in procs)
    time.sleep(0.5)
    start = time.monotonic()
    go.set()
    ends = [done.get(timeout=180) for _ in procs]
    elapsed = max(e for _, e in ends) - start
    for p in procs:
        p.join(10)
    time.sleep(1.0)
    sub_stop.set()
    received = sub_out.get(timeout=30)
    sub.join(5)
    code, stderr = node.stop(signal.SIGINT)
    end = [e for e in node.stdout if e.get("event") == "end"]
    sent = share * publishers
    # The acknowledgements say the frames reached the node's DDS reader; the node's own pace is that of
    # its decisions: the last one's frame, taken by then, over the time since the start.
    frame, now, _ = max(received, default=(0, start * 1e9, 0))
    node_s = now / 1e9 - start
    return {"publishers": publishers, "frames_sent": sent,
            "frames_classified": end[0]["frames"] if end else None,
            "all_acked": all(a for a, _ in ends), "seconds": round(elapsed, 3),
            "frames_per_s": round(sent / elapsed),
            "node_frames_per_s": round((frame + 1) / node_s) if node_s > 0 else None,
            "node_summary": stderr.strip().splitlines()[-1]}


def publisher_alone(case, domain, frames):
    """How fast one such publisher writes with nobody listening: the ceiling of one publisher."""
    pub = FramePublisher(domain, reliable=True, topic="nobody/listens")
    serialized = pub.serialized(case.payloads)
    start = time.monotonic()
    for i in range(frames):
        pub.write(serialized[i % len(serialized)])
    return {"frames": frames, "frames_per_s": round(frames / (time.monotonic() - start))}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--replays-100hz", type=int, default=20)
    ap.add_argument("--replays-flat", type=int, default=50)
    ap.add_argument("--throughput-frames", type=int, default=20000)
    ap.add_argument("--publishers", default="1,2", help="publisher processes of the throughput runs")
    ap.add_argument("--only", choices=["latency", "throughput"])
    ap.add_argument("--domain", type=int, default=150)
    ap.add_argument("--wire", action="store_true",
                    help="split the 100 Hz latency into its legs from the loopback's packets (root)")
    ap.add_argument("--realtime", type=int, metavar="PRIORITY",
                    help="run the latency runs' processes (publisher, node, subscriber) at this SCHED_FIFO "
                         "priority, as a robot runs its control loop (root or CAP_SYS_NICE)")
    args = ap.parse_args()
    if args.realtime:
        # Inherited by the node and the subscriber, which this process starts.
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(args.realtime))
    results = {"presrs": conftest.CLI}
    with tempfile.TemporaryDirectory() as d:
        case = conftest.make_fras_case(Path(d))
        if args.only != "throughput":
            results["latency_100hz_sensor_data"] = latency_run(case, args.domain, args.replays_100hz, 0.01,
                                                                   wire=args.wire)
            results["latency_flat_out_reliable"] = latency_run(case, args.domain + 1, args.replays_flat, 0.0)
        if args.realtime:
            os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))
        if args.only != "latency":
            for i, n in enumerate(int(x) for x in args.publishers.split(",")):
                results[f"throughput_reliable_{n}_publishers"] = throughput_run(
                    case, args.domain + 2 + i, args.throughput_frames, n)
            results["publisher_alone"] = publisher_alone(case, args.domain + 9, args.throughput_frames)
    print(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
