"""Fixtures of the ROS 2 node's tests: the presrs binary, models and their bags, the reference events of
`presrs stream` on the same frames, unique DDS domains, and the node as a process with bounded waits."""

import itertools
import json
import os
import queue
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))
import dds_peer  # noqa: E402,F401  (sets Cyclone's loopback configuration before any participant)

ROOT = Path(__file__).resolve().parents[2]
SHARED = ROOT.parent / "shared" / "data"


def _cli_path():
    env = os.environ.get("PRESRS_CLI")
    path = Path(env) if env else ROOT / "target" / "debug" / "presrs"
    if not path.exists():
        pytest.exit(f"the presrs binary {path} is missing: cargo build -p presrs-cli (or set PRESRS_CLI)")
    return str(path)


CLI = _cli_path()


def run_cli(*args, stdin=None, check=True, timeout=300):
    proc = subprocess.run([CLI, *map(str, args)], input=stdin, capture_output=True, timeout=timeout)
    if check and proc.returncode != 0:
        raise AssertionError(f"presrs {' '.join(map(str, args))} failed: {proc.stderr.decode()}")
    return proc


def json_lines(data):
    return [json.loads(line) for line in data.decode().splitlines() if line.strip()]


def bag_images(bag):
    """The CDR payloads of a bag's frames, in order (read with the `mcap` package)."""
    from mcap.reader import make_reader

    with open(bag, "rb") as f:
        return [m.data for _, _, m in make_reader(f).iter_messages(topics=["/presrs/frames"])]


class Case:
    """A model, a bag of frames, and what `presrs stream` (with `stream_args`) makes of the bag."""

    def __init__(self, model, bag, *stream_args):
        self.model = model
        self.bag = bag
        self.reference = json_lines(run_cli("stream", "--format", "mcap", "--model", model, *stream_args,
                                            stdin=Path(bag).read_bytes()).stdout)
        self.payloads = bag_images(bag)


@pytest.fixture(scope="session")
def fras(tmp_path_factory):
    """The real F-Scan insole recording (60 x 21, 205 frames): a model of it and a copy 1.7 times as
    loaded (two classes), its bag, and the stream's events on it."""
    return make_fras_case(tmp_path_factory.mktemp("fras"))


def make_fras_case(d):
    """The `fras` case in folder `d` (also used by bench/ros2)."""
    src = (SHARED / "tekscan" / "FrasP01L.asf").read_text()
    head, sep, body = src.partition("ASCII_DATA @@")
    scaled = []
    for line in body.split("\n"):
        toks = line.strip().split(",")
        if len(toks) > 1 and all(t == "B" or re.fullmatch(r"\d+(\.\d+)?", t) for t in toks):
            line = ",".join(t if t == "B" else "%g" % (float(t) * 1.7) for t in toks)
        scaled.append(line)
    (d / "a.asf").write_text(src)
    (d / "b.asf").write_text(head + sep + "\n".join(scaled))
    (d / "manifest.csv").write_text("path,label\na.asf,normal\nb.asf,heavy\n")
    model = d / "fras.model.json"
    run_cli("train", "--manifest", d / "manifest.csv", "--out", model, "--features", "fft1d",
            "--classifier", "pwe", "--dims", 3, "--validation", 1)
    run_cli("convert", d / "a.asf", d / "a.mcap")
    return Case(model, d / "a.mcap")


@pytest.fixture(scope="session")
def sim(tmp_path_factory):
    """A simulated terrain run (`presrs simulate`, grass, gait G2), a model of the simulated set, its
    bag and the stream's events on it."""
    d = tmp_path_factory.mktemp("sim")
    run_cli("simulate", "--out", d / "set", "--gaits", "G2", "--hops-per-gait", 6, "--seed", 3)
    model = d / "sim.model.json"
    run_cli("train", "--manifest", d / "set" / "manifest.csv", "--out", model, "--features", "fft1d",
            "--classifier", "pwe", "--dims", 10, "--validation", 3,
            "--gait-table", "wood=G1,carpet=G2,clay=G3,grass=G2")
    run_cli("convert", d / "set" / "recordings" / "grass_G2_000.asf", d / "grass.mcap")
    return Case(model, d / "grass.mcap")


@pytest.fixture(scope="session")
def walk(tmp_path_factory):
    """A whole-stance model (MiniRocket and ridge on the stance's summary, with its online profile) of
    every third jiku-walk recording (one stance a file, 63 x 33; its length, the longest stance's, is
    about 80 frames), and bags at 100 Hz of one recording (54 frames, decided at its lift-off) and of
    two one after the other (one stance of 128 frames, longer than the model's), each with a swing of
    12 unloaded frames before and after, as in a walk (the profile learned from one-contact trials
    finds the steps of a stream; a stream that starts loaded starts with a partial stance)."""
    import numpy as np

    d = tmp_path_factory.mktemp("walk")
    src = SHARED / "real" / "jiku-walk"
    rows = (src / "manifest.csv").read_text().splitlines()
    # 40 stances of 3 classes keep the training short.
    (d / "manifest.csv").write_text("\n".join([rows[0]] + [f"{src}/{r}" for r in rows[1::3]]) + "\n")
    model = d / "walk.model.json"
    run_cli("train", "--manifest", d / "manifest.csv", "--out", model, "--sample", "stance",
            "--one-sample-per-file", "--features", "rocket", "--classifier", "ridge", "--online-profile",
            "--decide-at", "12,whole")  # a point for the test of --decide-at 12
    bags = {}
    swing = np.zeros((12, 63, 33), dtype=np.uint16)
    for name, movies in (("one", ["s00_t00.npy"]), ("two", ["s00_t00.npy", "s00_t01.npy"])):
        steps = [np.load(src / m) for m in movies]
        np.save(d / f"{name}.npy", np.concatenate([swing, *steps, swing]))
        run_cli("convert", d / f"{name}.npy", d / f"{name}.mcap", "--frame-period", "0.01")
        bags[name] = d / f"{name}.mcap"
    return model, bags


_domains = itertools.count()


@pytest.fixture
def domain():
    """A DDS domain of this test alone: other tests, and other runs on this machine, use others."""
    return 1 + (os.getpid() * 17 + next(_domains)) % 200


class Node:
    """`presrs ros2` as a process: its stdout lines read on a thread, every wait bounded."""

    def __init__(self, model, domain, *extra, input_topic="foot/pressure", join_timeout=60):
        self.args = [CLI, "ros2", "--model", str(model), "--input", input_topic,
                     "--domain-id", str(domain), "--localhost-only", *map(str, extra)]
        self.proc = subprocess.Popen(self.args, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        self.lines = queue.Queue()
        self.stdout = []
        threading.Thread(target=self._read, daemon=True).start()
        self.joined = self.next_line(join_timeout)

    def _read(self):
        for line in self.proc.stdout:
            self.lines.put(line.decode())
        self.lines.put(None)

    def next_line(self, timeout):
        try:
            line = self.lines.get(timeout=timeout)
        except queue.Empty:
            return None
        if line is None:
            return None
        event = json.loads(line)
        self.stdout.append(event)
        return event

    def stop(self, sig=signal.SIGINT, timeout=30):
        """Signals the node and waits for its end: (exit code, stderr)."""
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
        try:
            self.proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait(timeout=10)
            raise AssertionError(f"presrs ros2 did not end within {timeout} s of {sig!r}")
        while self.next_line(1) is not None:
            pass
        return self.proc.returncode, self.proc.stderr.read().decode()

    def kill(self):
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(timeout=10)


@pytest.fixture
def node_factory():
    nodes = []

    def start(*args, **kwargs):
        node = Node(*args, **kwargs)
        nodes.append(node)
        return node

    yield start
    for node in nodes:
        node.kill()


def wait_until(predicate, timeout, step=0.05):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(step)
    return predicate()
