"""What `presrs ros2` says about an input it cannot receive or that stops, a stance with frames missing,
its name, and frames sent before it took one: against Cyclone DDS, as in test_node.py."""

import signal
import time

import ros2_types as t
from conftest import Case
from dds_peer import Peer, publish_from_process
from test_node import diagnostics_values, publish_all

WARN, ERROR = 1, 2


def statuses(peer):
    return [d.status[0] for d in peer.got[peer.diagnostics]]


def first_problem(peer, words, timeout):
    """The first diagnostics status of level WARN or more whose message has `words`; None on timeout."""
    def found(p):
        return [s for s in statuses(p) if s.level >= WARN and words in s.message]

    peer.wait_for(found, timeout)
    hits = found(peer)
    return hits[0] if hits else None


def test_a_publisher_of_incompatible_qos_is_reported(fras, domain, node_factory):
    # The node asks reliable; the publisher offers best effort: DDS does not match them, so not a
    # frame would come. Discovery shows the publisher: the node says so within 2 s of seeing it.
    node = node_factory(fras.model, domain, "--input-qos", "reliable")
    started = time.monotonic()
    peer = Peer(domain, reliable=False)
    status = first_problem(peer, "best-effort", 15)
    assert status is not None, [(s.level, s.message) for s in statuses(peer)]
    elapsed = time.monotonic() - started
    # Discovery on the loopback takes a fraction of a second; then at most a report period (1 s).
    assert elapsed < 3.0, elapsed
    assert status.level == ERROR and "cannot receive" in status.message, status.message
    assert "--input-qos" in status.message
    code, stderr = node.stop(signal.SIGINT)
    assert code == 0, stderr
    assert "error: a publisher on /foot/pressure that the node cannot receive" in stderr, stderr
    assert stderr.count("offers best-effort") == 1, stderr  # said once, not at every report


def test_a_publisher_of_another_type_is_reported(fras, domain, node_factory):
    node = node_factory(fras.model, domain)
    started = time.monotonic()
    peer = Peer(domain, reliable=False, input_type=t.String)
    status = first_problem(peer, "std_msgs/msg/String", 15)
    assert status is not None, [(s.level, s.message) for s in statuses(peer)]
    assert time.monotonic() - started < 3.0
    assert status.level == ERROR
    assert "publishes std_msgs/msg/String, the node reads sensor_msgs/msg/Image" in status.message
    code, stderr = node.stop(signal.SIGINT)
    assert code == 0, stderr
    assert "publishes std_msgs/msg/String" in stderr, stderr


def test_a_publisher_that_stops_is_a_warning_in_the_first_report_after_1_s(fras, domain, node_factory):
    peer = Peer(domain, reliable=True)
    node = node_factory(fras.model, domain, "--input-qos", "reliable")
    assert peer.wait_matched(30), "the node's topics were not discovered within 30 s"
    publish_all(peer, fras.payloads[:60], 0.01)
    assert peer.wait_for(lambda p: any(diagnostics_values(d)["frames_received"] == "60"
                                       for d in p.got[p.diagnostics]), 20)
    last_frame = time.time()  # the node took the last frame at or before this

    def wall(status_msg):
        stamp = status_msg.header.stamp
        return stamp.sec + stamp.nanosec * 1e-9

    # Every report stamped more than 1 s after the last frame warns; the first comes within 2 s.
    assert peer.wait_for(lambda p: any(wall(d) > last_frame + 1.05 for d in p.got[p.diagnostics]), 5)
    late = [d for d in peer.got[peer.diagnostics] if wall(d) > last_frame + 1.05]
    assert wall(late[0]) < last_frame + 2.2, wall(late[0]) - last_frame
    first = late[0].status[0]
    assert first.level == WARN, (first.level, first.message)
    assert "no frame on /foot/pressure for" in first.message, first.message
    assert float(diagnostics_values(late[0])["seconds_since_last_frame"]) >= 1.0
    # Frames again: the warning is gone.
    publish_all(peer, fras.payloads[60:70], 0.01)
    assert peer.wait_for(lambda p: statuses(p)[-1].level == 0
                         and diagnostics_values(p.got[p.diagnostics][-1])["frames_received"] == "70", 5)
    code, stderr = node.stop(signal.SIGINT)
    assert code == 0, stderr
    assert "warning: no frame on /foot/pressure for" in stderr, stderr


def test_a_restart_in_a_stance_gives_a_decision_with_the_gap_stated(walk, domain, node_factory):
    # One stance at 100 Hz; its publisher dies after frame 24 and a new one starts at frame 35: the
    # ten frames between were never sent. The stance is decided at its end, with the gap stated.
    model, bags = walk
    case = Case(model, bags["one"])
    payloads = case.payloads
    peer = Peer(domain, reliable=True, input_topic="unused/pressure")
    node = node_factory(model, domain, "--input-qos", "reliable")
    assert peer.wait_for(lambda p: p.got[p.diagnostics], 30), "no diagnostics within 30 s"
    assert publish_from_process(domain, payloads[:25], 0.01) == 0
    assert publish_from_process(domain, payloads[35:], 0.01) == 0
    sent = len(payloads) - 10
    assert peer.wait_for(lambda p: any(int(diagnostics_values(d)["frames_received"]) == sent
                                       for d in p.got[p.diagnostics]), 20)
    code, stderr = node.stop(signal.SIGINT)
    assert code == 0, stderr
    assert peer.wait_for(lambda p: any(e["event"] == "end" for e in p.json_events()), 10)
    decisions = peer.got[peer.decisions]
    assert len(decisions) == 1 and decisions[0].kind == "stance"
    assert decisions[0].gap_frames == 10, decisions[0]
    [line] = [e for e in peer.json_events() if e["event"] == "classification"]
    assert line["gap_frames"] == 10
    [liftoff] = [s for s in peer.got[peer.stances] if s.event == 1]
    assert liftoff.gap_frames == 10
    assert diagnostics_values(peer.got[peer.diagnostics][-1])["publishers_seen"] == "2"


def test_two_nodes_of_one_name_are_warned_of_and_the_input_is_named_resolved(fras, domain, node_factory):
    peer = Peer(domain, reliable=True, input_topic="robot/pressure")
    first = node_factory(fras.model, domain, "--namespace", "/robot", input_topic="pressure")
    assert first.joined["input"] == "/robot/pressure", first.joined
    second = node_factory(fras.model, domain, "--namespace", "/robot", input_topic="pressure")
    status = first_problem(peer, "another node named /robot/presrs", 15)
    assert status is not None, [(s.level, s.message) for s in statuses(peer)]
    assert status.level == WARN
    for node in (first, second):
        code, stderr = node.stop(signal.SIGINT)
        assert code == 0, stderr
        assert "warning: another node named /robot/presrs is in the graph" in stderr, stderr


def test_frames_sent_once_matched_reach_a_node_started_first(fras, domain, node_factory):
    # The node is started first; each publisher writes as soon as its writer has matched the node's
    # reader. Reliable: every frame reaches the node (RustDDS asks the publisher for what it sent
    # before the node had discovered it). Best effort: frames sent before the node had discovered
    # the publisher are lost and counted in frames_before_first_taken; every frame is accounted for.
    peer = Peer(domain, reliable=True, input_topic="unused/pressure")
    node = node_factory(fras.model, domain, "--input-qos", "reliable")
    assert peer.wait_for(lambda p: p.got[p.diagnostics], 30), "no diagnostics within 30 s"
    frames = fras.payloads[:100]
    assert publish_from_process(domain, frames, 0.01, settle=0.0) == 0
    assert peer.wait_for(lambda p: any(diagnostics_values(d)["frames_received"] == "100"
                                       for d in p.got[p.diagnostics]), 20), [
        diagnostics_values(d) for d in peer.got[peer.diagnostics][-2:]]
    v = diagnostics_values(peer.got[peer.diagnostics][-1])
    assert (v["frames_before_first_taken"], v["frames_dropped"]) == ("0", "0"), v
    node.stop(signal.SIGINT)

    node = node_factory(fras.model, domain)
    peer.got[peer.diagnostics].clear()
    assert peer.wait_for(lambda p: p.got[p.diagnostics], 30), "no diagnostics within 30 s"
    assert publish_from_process(domain, frames, 0.01, reliable=False, settle=0.0) == 0

    def accounted(d):
        # The best-effort publisher sends one frame more after a pause (dds_peer).
        v = diagnostics_values(d)
        return int(v["frames_received"]) + int(v["frames_before_first_taken"]) == 101

    assert peer.wait_for(lambda p: any(accounted(d) for d in p.got[p.diagnostics]), 20), [
        diagnostics_values(d) for d in peer.got[peer.diagnostics][-2:]]
    v = diagnostics_values(next(d for d in peer.got[peer.diagnostics] if accounted(d)))
    assert v["frames_dropped"] == "0", v
    code, stderr = node.stop(signal.SIGINT)
    assert code == 0, stderr
    print(f"best effort, node first: {v['frames_before_first_taken']} frames before the first taken")
