"""`presrs ros2` against an independent DDS implementation (Eclipse Cyclone DDS, Python): frames
published as ROS 2 messages, decisions read back and compared with `presrs stream` on the same frames."""

import json
import os
import signal
import time

import pytest

import ros2_types as t
from conftest import Case, run_cli, wait_until
from dds_peer import Peer, image, publish_from_process

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


def stamp_of(payload):
    """The header stamp of a frame's CDR bytes."""
    return t.Image.deserialize(payload).header.stamp


def assert_same_decisions(peer, reference, payloads):
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
        # The decision is stamped with its sample frame's header stamp (the stream's timestamp_us is
        # the triggering frame's, the same frame for a one-frame decision; none at the stream's end).
        assert mine.header.stamp == stamp_of(payloads[ref["sample_frame"]])
        if ref["frame"] == ref["sample_frame"] and ref["timestamp_us"] is not None:
            stamp_us = (mine.header.stamp.sec * 10**9 + mine.header.stamp.nanosec) // 1000
            assert stamp_us == ref["timestamp_us"]
        assert mine.gait == (ref["gait"] or "")
        assert mine.gap_frames == ref.get("gap_frames", 0)
        # What a whole-stance decision waited for, and that frame's stamp; nothing for one-frame ones.
        assert mine.decided_at == t.DECIDED_AT[ref.get("decided_at", "none")]
        assert mine.decided_at_frame == ref.get("decided_at_frame", 0)
        assert mine.cut == ref.get("cut", False)
        if "decided_at_frame" in ref:
            assert mine.decided_at_stamp == stamp_of(payloads[ref["decided_at_frame"]])
        else:
            assert (mine.decided_at_stamp.sec, mine.decided_at_stamp.nanosec) == (0, 0)
    liftoffs = [e for e in reference if e["event"] == "liftoff"]
    stances = [s for s in peer.got[peer.stances] if s.event == LIFTOFF]
    assert [(s.stance, s.touchdown_frame, s.end_frame) for s in stances] == [
        (e["stance"], e["touchdown_frame"], e["end_frame"]) for e in liftoffs]


def run_parity(case, domain, node_factory, *node_args, reliable=True, period=0.0):
    peer = Peer(domain, reliable=reliable)
    node = node_factory(case.model, domain, *node_args)
    assert node.joined and node.joined["event"] == "joined", node.joined
    assert peer.wait_matched(30), "the node's topics were not discovered within 30 s"
    # Cyclone has matched the node's reader; the node's side of the match (RustDDS learning of this
    # writer) can take a moment more, and a frame written before it is never delivered to the node
    # (a volatile reader), which would count it apart and decide on 204 frames of 205.
    time.sleep(1.0)
    publish_all(peer, case.payloads, period)
    n = sum(e["event"] == "classification" for e in case.reference)
    assert peer.wait_for(lambda p: len(p.got[p.decisions]) >= n, 30)
    # The last decision comes before the recording's last frames are taken: stopping the node now would
    # cut its input short of the stream's (a truncated last stance). Its diagnostics say when all are in.
    sent = str(len(case.payloads))
    assert peer.wait_for(lambda p: any(diagnostics_values(d)["frames_received"] == sent
                                       for d in p.got[p.diagnostics]), 30), [
        diagnostics_values(d) for d in peer.got[peer.diagnostics][-2:]]
    code, stderr = node.stop(signal.SIGINT)
    assert code == 0, stderr
    assert "stopped by SIGINT" in stderr
    assert peer.wait_for(lambda p: any(e["event"] == "end" for e in p.json_events()), 10)
    return peer, node, stderr


def test_the_real_recording_gives_the_streams_decisions(fras, domain, node_factory):
    peer, node, stderr = run_parity(fras, domain, node_factory, "--input-qos", "reliable")
    assert_same_decisions(peer, fras.reference, fras.payloads)
    # The JSON events on the String topic and on stdout are the stream's, latency aside.
    assert without_latency(peer.json_events()) == without_latency(fras.reference)
    assert without_latency(node.stdout[1:]) == without_latency(fras.reference)
    assert "205 messages received, 205 frames processed" in stderr
    n = sum(e["event"] == "classification" for e in fras.reference)
    assert f"{n} decisions made" in stderr
    # One node of its name and a publisher it can receive: nothing to warn of.
    assert "another node named" not in stderr and "cannot receive" not in stderr, stderr


def test_a_simulated_run_at_100_hz_on_sensor_data_qos(sim, domain, node_factory):
    peer, node, _ = run_parity(sim, domain, node_factory, reliable=False, period=0.01)
    assert_same_decisions(peer, sim.reference, sim.payloads)
    # The gait command of each decision, on its own topic.
    gaits = [m.data for m in peer.got[peer.gait]]
    assert gaits == [e["gait"] for e in sim.reference if e["event"] == "classification"]
    assert gaits and set(gaits) == {"G2"}
    end = [e for e in peer.json_events() if e["event"] == "end"][0]
    assert end["frames"] == len(sim.payloads) and end["rejected_frames"] == 0


@pytest.mark.parametrize("bag, decide_at, waited_for", [
    ("one", None, "liftoff"),  # at the stance's lift-off, in the swing after it
    ("two", None, "length"),  # the stance grew longer than the model's samples
    ("one", 12, "offset"),  # --decide-at 12
])
def test_a_whole_stance_decision_says_what_it_waited_for(walk, bag, decide_at, waited_for, domain,
                                                         node_factory):
    model, bags = walk
    extra = ["--decide-at", str(decide_at)] if decide_at else []
    case = Case(model, bags[bag], *extra)
    decisions = [e for e in case.reference if e["event"] == "classification"]
    assert [e["decided_at"] for e in decisions] == [waited_for]
    # The node first, then the peer. With the peer first, 8 runs of these three tests in 90 failed under
    # load (load average 6-7; none in 30 at 2-3): 7 got no TerrainDecision (the 3 looked into got nothing
    # at all on the peer's first two readers, decisions and stance events, while its later ones, JSON
    # events and diagnostics, got everything), one lost its first JSON event. RustDDS seems to take a
    # reader announced before its participant without an address (the participant's default locators are
    # looked up when the reader is discovered, not again) and never to send to it. Started after the
    # node, the peer's participant reaches the node before its readers do: none failed in 40 runs at the
    # same load.
    node = node_factory(case.model, domain, "--input-qos", "reliable", *extra)
    peer = Peer(domain, reliable=True)
    assert peer.wait_matched(30), "the node's topics were not discovered within 30 s"
    time.sleep(1.0)  # the node's side of the match, as in run_parity
    publish_all(peer, case.payloads)

    def all_taken(p):
        return any(int(diagnostics_values(d)["frames_received"]) == len(case.payloads)
                   for d in p.got[p.diagnostics])

    assert peer.wait_for(all_taken, 20)
    code, stderr = node.stop(signal.SIGINT)
    assert code == 0, stderr
    assert peer.wait_for(lambda p: any(e["event"] == "end" for e in p.json_events()), 10)
    assert_same_decisions(peer, case.reference, case.payloads)
    assert [d.kind for d in peer.got[peer.decisions]] == ["stance"]
    assert without_latency(peer.json_events()) == without_latency(case.reference)


def test_frames_sent_before_the_node_matched_are_counted_apart_from_drops(fras, domain, node_factory):
    # A publisher that wrote 10 frames before the node existed: its first frame taken is its 11th.
    peer = Peer(domain, reliable=True)
    publish_all(peer, fras.payloads[:10])
    node = node_factory(fras.model, domain, "--input-qos", "reliable")
    assert peer.wait_matched(30), "the node's topics were not discovered within 30 s"
    publish_all(peer, fras.payloads)
    assert peer.wait_for(lambda p: any(diagnostics_values(d)["frames_received"] == "205"
                                       for d in p.got[p.diagnostics]), 20)
    code, stderr = node.stop(signal.SIGINT)
    assert code == 0, stderr

    def ended(p):
        return [d for d in p.got[p.diagnostics] if diagnostics_values(d)["state"] == "ended"]

    assert peer.wait_for(ended, 10)
    v = diagnostics_values(ended(peer)[-1])
    assert (v["frames_received"], v["frames_dropped"], v["frames_before_first_taken"]) == (
        "205", "0", "10")
    assert "10 frames sent before the first one taken from their publisher" in stderr


def diagnostics_values(message):
    return {kv.key: kv.value for kv in message.status[0].values}


def test_faults_are_reported_and_the_node_goes_on(fras, domain, node_factory):
    # The frames come from publisher processes (a driver that stops and restarts); the readers stay.
    peer = Peer(domain, reliable=True, input_topic="unused/pressure")
    node = node_factory(fras.model, domain, "--input-depth", "5")
    assert peer.wait_for(lambda p: p.got[p.diagnostics], 30), "no diagnostics within 30 s"
    frames = fras.payloads
    wrong_size = image(10, 10, [0] * 100, encoding="mono16").serialize()
    rgb = image(60, 21, [0] * 1260, encoding="rgb8").serialize()
    assert publish_from_process(domain, frames[:60] + [wrong_size, rgb], 0.002) == 0
    # A frame of another size, then one of an unsupported encoding: one error event each.
    assert peer.wait_for(lambda p: sum(e["event"] == "error" for e in p.json_events()) >= 2, 10)
    errors = [e for e in peer.json_events() if e["event"] == "error"]
    assert len(errors) == 2 and not any(e["fatal"] for e in errors)
    assert "rejected" in errors[0]["message"] and "10x10" in errors[0]["message"]
    assert "rgb8" in errors[1]["message"] and "not supported" in errors[1]["message"]
    assert peer.wait_for(lambda p: any(d.status[0].level == 2 for d in p.got[p.diagnostics]), 5), [
        (d.status[0].level, d.status[0].message) for d in peer.got[peer.diagnostics]]
    bad = [d.status[0] for d in peer.got[peer.diagnostics] if d.status[0].level == 2]
    assert any("rgb8" in s.message or "10x10" in s.message for s in bad)

    # The publisher has stopped; another starts: the node goes on with it.
    time.sleep(1.0)
    assert publish_from_process(domain, frames[60:], 0.002) == 0
    n = sum(e["event"] == "classification" for e in fras.reference)
    assert peer.wait_for(lambda p: len(p.got[p.decisions]) >= n, 30)

    code, stderr = node.stop(signal.SIGTERM)
    assert code == 0, stderr
    assert "stopped by SIGTERM" in stderr
    assert "publish failures" in stderr


def test_a_burst_faster_than_the_node_is_counted_as_dropped(fras, domain, node_factory):
    # 20,000 frames written flat out, each serialized once (a publisher alone writes hundreds of
    # thousands a second, several times the node's pace), on best effort with a history of 5: most
    # cannot be taken. Each one is either taken or counted as dropped, never lost silently; one frame
    # after a pause shows the gap at the burst's end.
    peer = Peer(domain, reliable=False)
    node = node_factory(fras.model, domain, "--input-depth", "5")
    assert peer.wait_matched(30), "the node's topics were not discovered within 30 s"
    frames = peer.serialized(fras.payloads)
    # A first frame the node takes: the gaps are counted between frames it has seen (those before the
    # first one taken are counted apart: the node may have joined late).
    peer.publish_serialized(frames[0])
    assert peer.wait_for(lambda p: any(diagnostics_values(d)["frames_received"] == "1"
                                       for d in p.got[p.diagnostics]), 10)
    burst = 20_000
    for i in range(burst):
        peer.publish_serialized(frames[i % len(frames)])
    time.sleep(1.0)
    peer.publish_serialized(frames[0])
    sent = 1 + burst + 1

    def accounted(d):
        v = diagnostics_values(d)
        return int(v["frames_received"]) + int(v["frames_dropped"]) == sent

    assert peer.wait_for(lambda p: any(accounted(d) for d in p.got[p.diagnostics]), 30), [
        diagnostics_values(d) for d in peer.got[peer.diagnostics][-3:]]
    code, stderr = node.stop(signal.SIGTERM)
    assert code == 0, stderr
    assert "stopped by SIGTERM" in stderr
    v = diagnostics_values(next(d for d in peer.got[peer.diagnostics] if accounted(d)))
    assert int(v["frames_dropped"]) > 0, v
    assert any(d.status[0].level == 1 for d in peer.got[peer.diagnostics])  # WARN
    assert f"{v['frames_dropped']} frames dropped before the node took them" in stderr
    assert f"{v['frames_received']} messages received" in stderr


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
