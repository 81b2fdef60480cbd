"""ROS 2 bags (MCAP) between presrs and the official Python libraries (`mcap`, `mcap-ros2-support`):

- bags written here by mcap-ros2-support from simulated TekScan movies train and classify in the
  `presrs` CLI exactly as the movies do, and read in `presrs.read` (with `topic=`) as the same frames;
- bags written by presrs (`presrs convert`, `presrs stream --record`) read back in the Python MCAP
  reader with the same frames and decisions.
"""

import json

import numpy as np
import pytest

import presrs
from conftest import json_lines

mcap_reader = pytest.importorskip("mcap.reader")
ros2_writer = pytest.importorskip("mcap_ros2.writer")
ros2_decoder = pytest.importorskip("mcap_ros2.decoder")

IMAGE_DEF = """std_msgs/Header header
uint32 height
uint32 width
string encoding
uint8 is_bigendian
uint32 step
uint8[] data
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
"""


def write_bag(path, frames, period_s, topic="/tekscan"):
    """A bag of mono16 images (rows padded by 2 bytes) with a second, unrelated topic."""
    with open(path, "wb") as f:
        w = ros2_writer.Writer(f)
        image = w.register_msgdef("sensor_msgs/msg/Image", IMAGE_DEF)
        text = w.register_msgdef("std_msgs/msg/String", "string data\n")
        for i, frame in enumerate(frames):
            ns = 1_000_000_000 + round(i * period_s * 1e9)
            rows, cols = frame.shape
            raw = frame.astype("<u2")
            data = b"".join(raw[r].tobytes() + b"\0\0" for r in range(rows))
            msg = {
                "header": {"stamp": {"sec": ns // 10**9, "nanosec": ns % 10**9}, "frame_id": "foot"},
                "height": rows, "width": cols, "encoding": "mono16", "is_bigendian": 0,
                "step": cols * 2 + 2, "data": data,
            }
            w.write_message(topic, image, msg, log_time=ns, publish_time=ns, sequence=i)
            w.write_message("/status", text, {"data": "ok"}, log_time=ns, publish_time=ns)
        w.finish()


def read_bag(path):
    """Every message of a bag in file order: {topic: [(schema name, decoded ROS message or JSON)]}."""
    out = {}
    with open(path, "rb") as f:
        reader = mcap_reader.make_reader(f, decoder_factories=[ros2_decoder.DecoderFactory()])
        json_topics = set()
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            if channel.message_encoding == "json":
                json_topics.add(channel.topic)
                out.setdefault(channel.topic, []).append((schema.name, json.loads(message.data)))
        cdr = [t.topic for t in reader.get_summary().channels.values() if t.topic not in json_topics]
        for schema, channel, _, decoded in reader.iter_decoded_messages(
            topics=cdr, log_time_order=False
        ):
            out.setdefault(channel.topic, []).append((schema.name, decoded))
    return out


def image_array(msg):
    assert msg.encoding in ("mono16", "32FC1")
    dtype = "<u2" if msg.encoding == "mono16" else "<f4"
    raw = np.frombuffer(bytes(msg.data), dtype=np.uint8).reshape(msg.height, msg.step)
    return raw[:, : msg.width * np.dtype(dtype).itemsize].copy().view(dtype).astype(np.float64)


@pytest.fixture(scope="module")
def bags(sim_dir, tmp_path_factory):
    """Every simulated movie rewritten as a bag by mcap-ros2-support, and a manifest of them."""
    out = tmp_path_factory.mktemp("bags")
    lines = (sim_dir / "manifest.csv").read_text().splitlines()
    rows = [lines[0]]
    for line in lines[1:]:
        path, rest = line.split(",", 1)
        recording = presrs.read(sim_dir / path)
        bag = out / (path.split("/")[-1][:-4] + ".mcap")
        write_bag(bag, recording.frames.astype(np.int64), recording.frame_period_s)
        rows.append(f"{bag},{rest}")
    (out / "manifest.csv").write_text("\n".join(rows) + "\n")
    return out


def test_a_bag_from_the_python_library_reads_as_its_movie(sim_dir, bags):
    movie = sorted((sim_dir / "recordings").glob("*.asf"))[0]
    recording = presrs.read(movie)
    bag = presrs.read(bags / (movie.stem + ".mcap"), topic="/tekscan")
    np.testing.assert_array_equal(bag.frames, recording.frames)
    assert bag.frame_period_s == pytest.approx(recording.frame_period_s, rel=1e-9)
    # Without topic= the only topic holding frames is read; a wrong one is a clear error.
    np.testing.assert_array_equal(presrs.read(bags / (movie.stem + ".mcap")).frames, recording.frames)
    with pytest.raises(presrs.DataError, match="topic /status holds std_msgs/msg/String"):
        presrs.read(bags / (movie.stem + ".mcap"), topic="/status")


def test_bags_from_the_python_library_train_and_classify_like_the_movies(cli, sim_dir, bags, tmp_path):
    options = ["--features", "fft1d", "--classifier", "lda", "--dims", 10, "--seed", 4]
    cli("train", "--manifest", sim_dir / "manifest.csv", "--out", tmp_path / "asf.json", *options)
    cli("train", "--manifest", bags / "manifest.csv", "--out", tmp_path / "bag.json", *options)
    movies = sorted((sim_dir / "recordings").glob("*.asf"))
    asf = json.loads(cli("classify", "--model", tmp_path / "asf.json", "--json", *movies))["results"]
    bag_files = [bags / (m.stem + ".mcap") for m in movies]
    bag = json.loads(cli("classify", "--model", tmp_path / "bag.json", "--json", *bag_files))["results"]
    assert len(asf) == len(bag) > 4
    for a, b in zip(asf, bag):
        assert (a["frame"], a["label"]) == (b["frame"], b["label"])
        assert a["posteriors"] == pytest.approx(b["posteriors"], abs=1e-12)


def test_presrs_bags_open_in_the_python_reader(cli, sim_dir, tmp_path):
    movie = sorted((sim_dir / "recordings").glob("*.asf"))[1]
    recording = presrs.read(movie)
    converted = tmp_path / "converted.mcap"
    cli("convert", movie, converted)
    messages = read_bag(converted)
    assert list(messages) == ["/presrs/frames"]
    frames = np.stack([image_array(m) for _, m in messages["/presrs/frames"]])
    np.testing.assert_array_equal(frames, recording.frames)
    stamps = [m.header.stamp.sec * 10**9 + m.header.stamp.nanosec for _, m in messages["/presrs/frames"]]
    assert np.diff(stamps) == pytest.approx(recording.frame_period_s * 1e9, abs=1)

    # A stream session recorded: the frames as read, and every decision line as written.
    cli("train", "--manifest", sim_dir / "manifest.csv", "--out", tmp_path / "m.json", "--seed", 1)
    session = tmp_path / "session.mcap"
    out = cli("stream", "--model", tmp_path / "m.json", "--record", session, stdin=movie.read_bytes())
    lines = json_lines(out)
    assert any(line["event"] == "classification" for line in lines)
    messages = read_bag(session)
    assert {s for s, _ in messages["/presrs/frames"]} == {"sensor_msgs/msg/Image"}
    frames = np.stack([image_array(m) for _, m in messages["/presrs/frames"]])
    np.testing.assert_array_equal(frames, recording.frames)
    assert [d for _, d in messages["/presrs/decisions"]] == lines


def test_classify_bags_hold_frames_and_decisions(cli, sim_dir, tmp_path):
    cli("train", "--manifest", sim_dir / "manifest.csv", "--out", tmp_path / "m.json", "--seed", 1)
    movies = sorted((sim_dir / "recordings").glob("*.asf"))[:2]
    bag = tmp_path / "classified.mcap"
    doc = json.loads(cli("classify", "--model", tmp_path / "m.json", "--json", "--mcap", bag, *movies))
    messages = read_bag(bag)
    frames = np.stack([image_array(m) for _, m in messages["/presrs/frames"]])
    np.testing.assert_array_equal(frames, np.concatenate([presrs.read(m).frames for m in movies]))
    decisions = [d for _, d in messages["/presrs/decisions"]]
    classified = [d for d in decisions if d["event"] == "classification"]
    assert [(d["file"], d["frame"], d["label"]) for d in classified] == [
        (r["file"], r["frame"], r["label"]) for r in doc["results"]
    ]
    for d, r in zip(classified, doc["results"]):
        assert d["posteriors"] == pytest.approx(r["posteriors"], abs=0)
    touchdowns = [d for d in decisions if d["event"] == "touchdown"]
    liftoffs = [d for d in decisions if d["event"] == "liftoff"]
    assert len(touchdowns) == len(liftoffs) >= len(classified)
    # Each decision is logged at its frame's time.
    stamps = [m.header.stamp.sec * 10**9 + m.header.stamp.nanosec for _, m in messages["/presrs/frames"]]
    assert stamps == sorted(stamps)


def test_float_frames_round_trip_exactly_through_32fc1(cli, tmp_path):
    # Values exact in f32 (multiples of 1/128) are written as 32FC1 and come back exactly.
    rng = np.random.default_rng(24)
    frames = rng.integers(-4000, 4000, size=(5, 4, 3)) / 128.0
    np.save(tmp_path / "floats.npy", frames)
    bag = tmp_path / "floats.mcap"
    cli("convert", tmp_path / "floats.npy", bag, "--frame-period", 0.02)
    messages = read_bag(bag)["/presrs/frames"]
    assert {m.encoding for _, m in messages} == {"32FC1"}
    np.testing.assert_array_equal(np.stack([image_array(m) for _, m in messages]), frames)
    np.testing.assert_array_equal(presrs.read(bag).frames, frames)
