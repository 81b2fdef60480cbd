"""`presrs ros2` against an independent DDS implementation (Eclipse Cyclone DDS, Python): frames
published as ROS 2 messages, decisions read back and compared with `presrs stream` on the same frames."""

import json
import signal
import time

import pytest

import ros2_types as t
from conftest import run_cli, wait_until
from dds_peer import Peer, image

# Decisions equal the stream's: the same label, class and frames; the confidence and posteriors to 1e-9.
TOL = 1e-9
# StanceEvent.msg's constants.
TOUCHDOWN, LIFTOFF = 0, 1


def publish_all(peer, payloads, period=0.0):
    for data in payloads:
        peer.publish(t.Image.deserialize(data))
        if period:
            time.sleep(period)


def without_latency(events):
    return [{k: v for k, v in e.items() if k != "latency_us"} for e in events]


def assert_same_decisions(peer, reference):
    decisions = [e for e in reference if e["event"] == "classification"]
    got = peer.got[peer.decisions]
    assert len(got) == len(decisions)
    for mine, ref in zip(got, decisions):
        assert mine.label == ref["label"] and mine.class_index == ref["class"]
        assert abs(mine.confidence - ref["confidence"]) <= TOL
        assert mine.stance == ref["stance"] and mine.kind == ref["kind"]
        assert (mine.touchdown_frame, mine.sample_frame, mine.frame) == (
            ref["touchdown_frame"], ref["sample_frame"], ref["frame"])
        for name, p in zip(mine.class_names, mine.posteriors):
            assert abs(p - ref["posteriors"][name]) <= TOL
        # The decision is stamped with its sample frame's header stamp.
        stamp_us = (mine.header.stamp.sec * 10**9 + mine.header.stamp.nanosec) // 1000
        assert stamp_us == ref["timestamp_us"]
        assert mine.gait == (ref["gait"] or "")
    liftoffs = [e for e in reference if e["event"] == "liftoff"]
    stances = [s for s in peer.got[peer.stances] if s.event == LIFTOFF]
    assert [(s.stance, s.touchdown_frame, s.end_frame) for s in stances] == [
        (e["stance"], e["touchdown_frame"], e["end_frame"]) for e in liftoffs]


def run_parity(case, domain, node_factory, *node_args, reliable=True, period=0.0):
    peer = Peer(domain, reliable=reliable)
    node = node_factory(case.model, domain, *node_args)
    assert node.joined and node.joined["event"] == "joined", node.joined
    assert peer.wait_matched(30), "the node's topics were not discovered within 30 s"
    publish_all(peer, case.payloads, period)
    n = sum(e["event"] == "classification" for e in case.reference)
    assert peer.wait_for(lambda p: len(p.got[p.decisions]) >= n, 30)
    code, stderr = node.stop(signal.SIGINT)
    assert code == 0, stderr
    assert "stopped by SIGINT" in stderr
    assert peer.wait_for(lambda p: any(e["event"] == "end" for e in p.json_events()), 10)
    return peer, node, stderr


def test_the_real_recording_gives_the_streams_decisions(fras, domain, node_factory):
    peer, node, stderr = run_parity(fras, domain, node_factory, "--input-qos", "reliable")
    assert_same_decisions(peer, fras.reference)
    # The JSON events on the String topic and on stdout are the stream's, latency aside.
    assert without_latency(peer.json_events()) == without_latency(fras.reference)
    assert without_latency(node.stdout[1:]) == without_latency(fras.reference)
    assert "205 messages received, 205 frames classified" in stderr


def test_a_simulated_run_at_100_hz_on_sensor_data_qos(sim, domain, node_factory):
    peer, node, _ = run_parity(sim, domain, node_factory, reliable=False, period=0.01)
    assert_same_decisions(peer, sim.reference)
    # The gait command of each decision, on its own topic.
    gaits = [m.data for m in peer.got[peer.gait]]
    assert gaits == [e["gait"] for e in sim.reference if e["event"] == "classification"]
    assert gaits and set(gaits) == {"G2"}
    end = [e for e in peer.json_events() if e["event"] == "end"][0]
    assert end["frames"] == len(sim.payloads) and end["rejected_frames"] == 0


def diagnostics_values(message):
    return {kv.key: kv.value for kv in message.status[0].values}


def test_faults_are_reported_and_the_node_goes_on(fras, domain, node_factory):
    peer = Peer(domain, reliable=True)
    node = node_factory(fras.model, domain, "--input-depth", "5")
    assert peer.wait_matched(30)
    # Best effort: a frame sent before the node's side of the match is set up would be lost unseen.
    time.sleep(0.5)
    frames = fras.payloads
    publish_all(peer, frames[:60], 0.002)
    # A frame of another size, then one of an unsupported encoding: one error event each.
    peer.publish(image(10, 10, [0] * 100, encoding="mono16"))
    peer.publish(image(60, 21, [0] * 1260, encoding="rgb8"))
    assert peer.wait_for(lambda p: sum(e["event"] == "error" for e in p.json_events()) >= 2, 10)
    errors = [e for e in peer.json_events() if e["event"] == "error"]
    assert len(errors) == 2 and not any(e["fatal"] for e in errors)
    assert "rejected" in errors[0]["message"] and "10x10" in errors[0]["message"]
    assert "rgb8" in errors[1]["message"] and "not supported" in errors[1]["message"]
    assert peer.wait_for(lambda p: any(d.status[0].level == 2 for d in p.got[p.diagnostics]), 5)
    bad = [d.status[0] for d in peer.got[peer.diagnostics] if d.status[0].level == 2]
    assert any("rgb8" in s.message or "10x10" in s.message for s in bad)

    # The publisher stops and another starts: the node goes on with it.
    peer_writer_frames = frames[60:]
    peer.writer = None
    time.sleep(1.0)
    from cyclonedds.pub import DataWriter
    from cyclonedds.topic import Topic
    from dds_peer import RELIABLE
    peer.writer = DataWriter(peer.dp, Topic(peer.dp, "rt/foot/pressure", t.Image), qos=RELIABLE)
    assert wait_until(lambda: peer.writer.get_matched_subscriptions(), 30)
    time.sleep(0.5)
    publish_all(peer, peer_writer_frames, 0.002)
    n = sum(e["event"] == "classification" for e in fras.reference)
    assert peer.wait_for(lambda p: len(p.got[p.decisions]) >= n, 30)

    # A burst faster than the node: the node is paused while 4000 frames (10 MB) come, more than its
    # socket buffer and its history (5 frames) hold.
    burst = 4000
    node.proc.send_signal(signal.SIGSTOP)
    try:
        publish_all(peer, (frames * 20)[:burst])
        time.sleep(0.5)
    finally:
        node.proc.send_signal(signal.SIGCONT)
    time.sleep(1.0)
    publish_all(peer, frames[:1])  # a last frame closes the gap of the burst's tail

    def dropped(p):
        return max([int(diagnostics_values(d)["frames_dropped"]) for d in p.got[p.diagnostics]] + [0])

    assert peer.wait_for(lambda p: dropped(p) > 0, 10)
    code, stderr = node.stop(signal.SIGTERM)
    assert code == 0, stderr
    assert "stopped by SIGTERM" in stderr
    peer.wait_for(lambda p: any(diagnostics_values(d)["state"] == "ended" for d in p.got[p.diagnostics]), 10)
    final = [d for d in peer.got[peer.diagnostics] if diagnostics_values(d)["state"] == "ended"]
    assert final, "no final diagnostics"
    v = diagnostics_values(final[-1])
    sent = len(frames) + 2 + burst + 1
    # Every frame sent is accounted for: taken by the node, or counted as dropped.
    assert int(v["frames_received"]) + int(v["frames_dropped"]) == sent, v
    assert int(v["frames_dropped"]) > 0 and int(v["publishers_seen"]) == 2
    assert f"{v['frames_dropped']} frames dropped before the node took them" in stderr


@pytest.mark.parametrize("model_text", [None, "{not json"])
def test_a_missing_or_bad_model_fails_before_joining_the_graph(tmp_path, domain, model_text):
    peer = Peer(domain, reliable=True)
    model = tmp_path / "model.json"
    if model_text is not None:
        model.write_text(model_text)
    proc = run_cli("ros2", "--model", model, "--input", "foot/pressure", "--domain-id", domain,
                   "--localhost-only", check=False, timeout=60)
    assert proc.returncode == 1
    assert "model.json" in proc.stderr.decode()
    assert proc.stdout == b""  # no `joined` line
    time.sleep(0.5)
    assert not peer.writer.get_matched_subscriptions()


@pytest.mark.parametrize("option,value,what", [
    ("--namespace", "robot", "namespace"),
    ("--name", "2feet", "node name"),
    ("--input", "/foot//pressure", "topic name"),
    ("--domain-id", "300", "domain id"),
])
def test_bad_names_and_domains_are_refused(fras, option, value, what):
    args = {"--input": "foot/pressure", "--domain-id": "5"}
    args[option] = value
    flat = [x for kv in args.items() for x in kv]
    proc = run_cli("ros2", "--model", fras.model, *flat, check=False, timeout=60)
    assert proc.returncode in (1, 2)
    assert what in proc.stderr.decode(), proc.stderr.decode()
