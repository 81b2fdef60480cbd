"""The test side of the DDS graph: Cyclone DDS (Python) publishing frames and reading the node's outputs,
on this machine's loopback only."""

import os
import time

# Cyclone reads its configuration when the first domain is created: loopback only, discovery by unicast
# to this machine's participant ports (lo has no multicast).
LOOPBACK_CONFIG = """<CycloneDDS><Domain id="any">
  <General><Interfaces><NetworkInterface name="lo"/></Interfaces><AllowMulticast>false</AllowMulticast></General>
  <Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>60</MaxAutoParticipantIndex>
    <Peers><Peer address="127.0.0.1"/></Peers></Discovery>
</Domain></CycloneDDS>"""
os.environ["CYCLONEDDS_URI"] = LOOPBACK_CONFIG

from cyclonedds.core import Policy, Qos  # noqa: E402
from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.pub import DataWriter  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402
from cyclonedds.util import duration  # noqa: E402

import ros2_types as t  # noqa: E402

# ROS 2's own DDS representation: plain CDR (XCDR1), as rmw_cyclonedds_cpp writes it.
XCDR1 = Policy.DataRepresentation(use_cdrv0_representation=True)
RELIABLE = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepAll, XCDR1)
BEST_EFFORT = Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(5), XCDR1)


def serialize_once(writer, kind, payloads):
    """CDR payloads (a bag's) as `writer` writes them: Cyclone's own serialization, padded to 4 bytes."""
    out = []
    for data in payloads:
        ser = kind.deserialize(data).serialize(use_version_2=writer._use_version_2)
        out.append(ser.ljust((len(ser) + 3) & ~3, b"\0"))
    return out


def write_serialized(writer, ser):
    """Writes bytes serialized once, as a driver hands over its buffer: hundreds of thousands of frames
    a second, far faster than `DataWriter.write` (which serializes in Python each time)."""
    from cyclonedds._clayer import ddspy_write

    if ddspy_write(writer._ref, ser) < 0:
        raise RuntimeError("Cyclone could not write a frame")


class Peer:
    """One Cyclone participant on `domain`, with a frame writer and readers of the node's outputs."""

    def __init__(self, domain, input_topic="foot/pressure", input_type=t.Image, reliable=True,
                 namespace=""):
        self.domain = domain
        self.dp = DomainParticipant(domain)
        self.input_type = input_type
        self.input_topic = input_topic
        self.writer_qos = RELIABLE if reliable else BEST_EFFORT
        self.start_publisher()
        ns = namespace.strip("/")
        prefix = f"rt/{ns}/" if ns else "rt/"

        def reader(name, kind, absolute=False):
            topic = ("rt/" + name) if absolute else (prefix + name)
            return DataReader(self.dp, Topic(self.dp, topic, kind), qos=RELIABLE)

        self.decisions = reader("presrs/decisions", t.TerrainDecision)
        self.stances = reader("presrs/stance_events", t.StanceEvent)
        self.events = reader("presrs/events", t.String)
        self.gait = reader("presrs/gait", t.String)
        self.diagnostics = reader("diagnostics", t.DiagnosticArray, absolute=True)
        self.readers = [self.decisions, self.stances, self.events, self.gait, self.diagnostics]
        self.got = {r: [] for r in self.readers}

    def start_publisher(self):
        """The frames' publisher: a participant of its own, as a camera driver's process would be."""
        self.pub_dp = DomainParticipant(self.domain)
        topic = Topic(self.pub_dp, "rt/" + self.input_topic, self.input_type)
        self.writer = DataWriter(self.pub_dp, topic, qos=self.writer_qos)

    def stop_publisher(self):
        """The publisher's process ends: its participant leaves the graph."""
        import gc

        self.writer = None
        self.pub_dp = None
        gc.collect()

    def wait_matched(self, timeout=30.0):
        """Until the node's reader and every output writer are matched; False on timeout."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if self.writer.get_matched_subscriptions() and all(
                r.get_matched_publications() for r in self.readers
            ):
                return True
            time.sleep(0.05)
        return False

    def publish(self, message):
        self.writer.write(message)

    def serialized(self, payloads):
        """The bag's CDR payloads as this peer's writer writes them, for `publish_serialized`."""
        return serialize_once(self.writer, self.input_type, payloads)

    def publish_serialized(self, ser):
        write_serialized(self.writer, ser)

    def poll(self):
        """Takes what has arrived on every output."""
        for r in self.readers:
            # Without the samples that only say a publisher went away (no data).
            self.got[r].extend(s for s in r.take(N=10_000)
                               if getattr(getattr(s, "sample_info", None), "valid_data", True))

    def wait_for(self, predicate, timeout=20.0):
        """Polls until `predicate(self)` holds; False on timeout."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            self.poll()
            if predicate(self):
                return True
            time.sleep(0.05)
        self.poll()
        return predicate(self)

    def json_events(self):
        import json

        return [json.loads(m.data) for m in self.got[self.events]]

    def close(self):
        # Dropping the participant leaves the graph (its writers' publishers disappear).
        self.dp = None
        self.writer = None
        self.readers = []


def image(rows, cols, values, stamp_ns=0, encoding="mono16", big_endian=False, frame_id="foot"):
    """A sensor_msgs/Image of `values` (row-major ints or floats)."""
    import numpy as np

    dtype = {"mono16": "u2", "16UC1": "u2", "mono8": "u1", "32FC1": "f4"}.get(encoding, "u2")
    array = np.asarray(values).reshape(rows, cols).astype((">" if big_endian else "<") + dtype)
    data = array.tobytes()
    return t.Image(
        header=t.Header(stamp=t.Time(sec=stamp_ns // 1_000_000_000, nanosec=stamp_ns % 1_000_000_000),
                        frame_id=frame_id),
        height=rows, width=cols, encoding=encoding, is_bigendian=int(big_endian),
        step=cols * array.itemsize, data=list(data))


def _publish_in_child(domain, topic, payloads, period, reliable, ready_timeout, matched, go, published,
                      settle=0.5):
    import ros2_types as types

    dp = DomainParticipant(domain)
    writer = DataWriter(dp, Topic(dp, "rt/" + topic, types.Image), qos=RELIABLE if reliable else BEST_EFFORT)
    end = time.monotonic() + ready_timeout
    while not writer.get_matched_subscriptions():
        if time.monotonic() > end:
            raise SystemExit(3)
        time.sleep(0.05)
    time.sleep(settle)
    matched.set()
    if not go.wait(ready_timeout):
        raise SystemExit(4)
    for data in payloads:
        writer.write(types.Image.deserialize(data))
        if period:
            time.sleep(period)
    published.set()
    # Reliable: until the node has taken them all (bounded). Best effort: a while, so that a paused
    # node finds its publisher still there when it resumes. Then the process leaves the graph.
    if reliable:
        writer.wait_for_acks(duration(seconds=5))
    else:
        # One more frame once the node has resumed: the frames lost at the burst's end are a gap
        # before it.
        time.sleep(1.5)
        writer.write(types.Image.deserialize(payloads[-1]))
        time.sleep(2)


def publish_from_process(domain, payloads, period=0.0, reliable=True, topic="foot/pressure", timeout=60,
                         when_matched=None, when_published=None, settle=0.5):
    """Publishes `payloads` (CDR images) from a process of its own, as a camera driver would, and waits
    for it to end (bounded); `when_matched()` runs once it has found the node, before it publishes.
    `settle`: seconds it waits after its writer matched the node's reader before it publishes (0: at
    once, as a driver that waits for a subscriber does). Returns its exit code (0: all published)."""
    import multiprocessing

    ctx = multiprocessing.get_context("spawn")
    matched, go, published = ctx.Event(), ctx.Event(), ctx.Event()
    proc = ctx.Process(target=_publish_in_child,
                       args=(domain, topic, list(payloads), period, reliable, 30, matched, go, published,
                             settle))
    proc.start()
    if matched.wait(40) and when_matched is not None:
        when_matched()
    go.set()
    if published.wait(timeout) and when_published is not None:
        when_published()
    proc.join(timeout)
    if proc.is_alive():
        proc.kill()
        proc.join(5)
        return None
    return proc.exitcode
