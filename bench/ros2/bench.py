"""Frame published -> decision received over loopback, for `presrs ros2`, with Eclipse Cyclone DDS as the
robot's side: the real recording (FrasP01L) replayed many times.

    PRESRS_CLI=target/release/presrs python bench/ros2/bench.py [--peer c|python] [--wire] [--raw FILE]
        [--realtime PRIORITY] [--replays-100hz 20] [--replays-flat 50] [--throughput-frames 20000]
        [--publishers 1,2] [--only latency|throughput]

Needs numpy, mcap and cyclonedds (the CI venv has them after .ci/run), and for the default C peer
Cyclone's C library, headers and idlc and a C compiler (Debian: cyclonedds-dev cyclonedds-tools gcc).
Prints medians, p99 and rates as JSON.

Three processes, as on a robot: the publisher, the node, and the subscriber. The latency runs' peer is
C by default (harness/peer.c: what a driver and a controller over rmw_cyclonedds_cpp do), or Python
(`--peer python`: the publisher in this process, the subscriber in a process of its own; Cyclone's
Python binding adds about 0.3 ms to a decision). Latency of a decision: its receipt by the subscriber
minus the publication of the frame it was decided on (the decision's `frame`), both on CLOCK_MONOTONIC,
which every process on the machine shares. Publishers pace themselves by sleeping, never by spinning
(a spinning publisher takes one of the machine's two cores). The throughput runs' publishers are Python
processes writing frames serialized once (hundreds of thousands a second). `machine_wakeup` is the
machine's own floor under every thread hand-off (harness/wakeup.c).
"""

import argparse
import json
import multiprocessing
import os
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests" / "ros2"))

import conftest  # noqa: E402  (the test fixtures' model and bag, and Cyclone's loopback configuration)
import ros2_types as t  # noqa: E402
from cyclonedds.core import InstanceState, ReadCondition, SampleState, ViewState, WaitSet  # noqa: E402
from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.pub import DataWriter  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402
from cyclonedds.util import duration  # noqa: E402
from dds_peer import BEST_EFFORT, RELIABLE, serialize_once, write_serialized  # noqa: E402

import numpy as np  # noqa: E402


HARNESS = Path(__file__).resolve().parent / "harness"


def harness_folder():
    return Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target")) / "bench-ros2-peer"


def up_to_date(binary, sources):
    return binary.exists() and all(binary.stat().st_mtime >= s.stat().st_mtime for s in sources)


def c_peer_binary():
    """The C peer (harness/peer.c on Cyclone DDS's C library), built on first use into the cargo target
    folder: `idlc` for the message types, then `cc ... -lddsc`."""
    target = harness_folder()
    binary = target / "peer"
    if up_to_date(binary, [HARNESS / "peer.c", HARNESS / "ros2_types.idl"]):
        return binary
    missing = [tool for tool in ("idlc", "cc") if shutil.which(tool) is None]
    if missing or not Path("/usr/include/dds/dds.h").exists():
        sys.exit("the C peer needs Cyclone DDS's C library, its headers and idlc, and a C compiler "
                 "(Debian: apt-get install cyclonedds-dev cyclonedds-tools gcc), or --peer python")
    target.mkdir(parents=True, exist_ok=True)
    subprocess.run(["idlc", "-o", str(target), str(HARNESS / "ros2_types.idl")], check=True,
                   capture_output=True)
    subprocess.run(["cc", "-O2", "-Wall", "-Wextra", "-I", str(target), "-o", str(binary),
                    str(HARNESS / "peer.c"), str(target / "ros2_types.c"), "-lddsc"], check=True)
    return binary


def machine_wakeup():
    """This machine's floor under every thread hand-off: harness/wakeup.c, 2,000 wake-ups of a sleeping
    thread at 100 Hz (at the priority this process runs at)."""
    binary = harness_folder() / "wakeup"
    if not up_to_date(binary, [HARNESS / "wakeup.c"]):
        binary.parent.mkdir(parents=True, exist_ok=True)
        subprocess.run(["cc", "-O2", "-Wall", "-pthread", "-o", str(binary), str(HARNESS / "wakeup.c")],
                       check=True)
    out = subprocess.run([str(binary), "2000", "10000"], check=True, capture_output=True, text=True)
    return json.loads(out.stdout)


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
        return serialize_once(self.writer, t.Image, payloads)

    def wait_matched(self, timeout=30):
        end = time.monotonic() + timeout
        while not self.writer.get_matched_subscriptions():
            if time.monotonic() > end:
                return False
            time.sleep(0.02)
        return True

    def write(self, ser):
        write_serialized(self.writer, ser)


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


class PythonPeer:
    """The robot's side in Python (Cyclone's Python binding): a publisher in this process, the
    subscriber in a process of its own."""

    name = "python"

    def __init__(self, case, domain, reliable):
        self.case, self.domain, self.reliable = case, domain, reliable

    def start_subscriber(self):
        self.proc, self.stop_event, self.out = start_subscriber(self.domain)

    def publish(self, replays, period):
        pub = FramePublisher(self.domain, self.reliable)
        frames = pub.serialized(self.case.payloads)
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
        return sent

    def stop_subscriber(self):
        self.stop_event.set()
        received = self.out.get(timeout=30)
        self.proc.join(5)
        return received


class CPeer:
    """The robot's side in C (harness/peer.c): publisher and subscriber, a process each."""

    name = "c"

    def __init__(self, case, domain, reliable):
        self.case, self.domain, self.reliable = case, domain, reliable
        self.binary = c_peer_binary()
        self.dir = Path(tempfile.mkdtemp(prefix="presrs-ros2-peer-"))

    def start_subscriber(self):
        self.got = self.dir / "got.txt"
        self.proc = subprocess.Popen([str(self.binary), "sub", str(self.domain), str(self.got)],
                                     stdout=subprocess.PIPE)
        if self.proc.stdout.readline().strip() != b"ready":
            raise RuntimeError("the C subscriber did not find the node")

    def write_frames(self):
        """The bag's images in the C peer's frames file (the head of harness/peer.c)."""
        path = self.dir / "frames.bin"

        def text(b):
            return struct.pack("<I", len(b)) + b

        with open(path, "wb") as f:
            f.write(struct.pack("<I", len(self.case.payloads)))
            for data in self.case.payloads:
                m = t.Image.deserialize(data)
                f.write(struct.pack("<IIIB", m.height, m.width, m.step, m.is_bigendian))
                f.write(text(m.encoding.encode()) + text(m.header.frame_id.encode()) + text(bytes(m.data)))
                f.write(struct.pack("<iI", m.header.stamp.sec, m.header.stamp.nanosec))
        return path

    def publish(self, replays, period):
        sent_path = self.dir / "sent.txt"
        subprocess.run([str(self.binary), "pub", str(self.domain), str(self.write_frames()),
                        str(int(period * 1e9)), str(replays), str(int(self.reliable)), str(sent_path)],
                       check=True, timeout=600)
        return [int(x) for x in sent_path.read_text().split()]

    def stop_subscriber(self):
        self.proc.send_signal(signal.SIGTERM)
        self.proc.wait(10)
        received = []
        for line in self.got.read_text().splitlines():
            frame, now, latency = line.split()
            received.append((int(frame), int(now), float(latency)))
        shutil.rmtree(self.dir, ignore_errors=True)
        return received


PEERS = {"python": PythonPeer, "c": CPeer}


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


def latency_run(case, domain, replays, period, wire=False, peer="c", raw=None):
    reliable = period == 0
    node = conftest.Node(case.model, domain, *(["--input-qos", "reliable"] if reliable else []))
    robot = PEERS[peer](case, domain, reliable)
    robot.start_subscriber()
    if wire:
        ctx = multiprocessing.get_context("spawn")
        wire_ready, wire_stop, wire_out = ctx.Event(), ctx.Event(), ctx.Queue()
        wire_proc = ctx.Process(target=sniffer, args=(wire_ready, wire_stop, wire_out), daemon=True)
        wire_proc.start()
        assert wire_ready.wait(20)
    sent = robot.publish(replays, period)
    # One pass's decisions times the replays. The recording begins in contact (a partial stance that
    # one pass does not decide); after another replay that stance is whole, so the node decides
    # `replays - 1` more.
    expected = replays * sum(e["event"] == "classification" for e in case.reference)
    time.sleep(1.0)
    received = robot.stop_subscriber()
    legs, stamps = None, None
    if wire:
        wire_stop.set()
        stamps = wire_out.get(timeout=30)
        legs = wire_legs(sent, received, stamps)
        wire_proc.join(5)
    code, stderr = node.stop(signal.SIGINT)
    if raw:
        # Every stamp of the run (CLOCK_MONOTONIC, ns), to look at single decisions, and the node's stderr.
        Path(raw).write_text(json.dumps({"sent": sent, "received": received, "wire": stamps,
                                         "node_stderr": stderr}))
    lat = [(now - sent[frame]) / 1000 for frame, now, _ in received if frame < len(sent)]
    inside = [node_us for _, _, node_us in received]
    result = {"peer": peer, "decisions": len(received), "one_pass_decisions_x_replays": expected, **percentiles(lat),
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
    ap.add_argument("--peer", choices=sorted(PEERS), default="c",
                    help="the robot's side of the latency runs: C on Cyclone's C library, as a ROS 2 "
                         "driver and controller over rmw_cyclonedds_cpp (default), or Cyclone's Python "
                         "binding (the bench's cost is then about 0.3 ms of a decision's latency)")
    ap.add_argument("--raw", metavar="FILE",
                    help="write the 100 Hz run's every stamp (publication, receipt, and with --wire the "
                         "datagrams') to FILE as JSON")
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
            results["machine_wakeup"] = machine_wakeup()
            results["latency_100hz_sensor_data"] = latency_run(case, args.domain, args.replays_100hz, 0.01,
                                                                   wire=args.wire, peer=args.peer,
                                                                   raw=args.raw)
            results["latency_flat_out_reliable"] = latency_run(case, args.domain + 1, args.replays_flat, 0.0,
                                                                peer=args.peer)
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
