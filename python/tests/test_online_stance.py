"""`OnlineClassifier` with a whole-stance model (trained with `--sample stance` on the shared `jiku-walk`
movies, one contact each): each movie streamed as a step (a swing of unloaded frames before and after
it, as in a walk: the profile learned from one-contact trials finds the steps of a stream) gives one
decision, at the stance's lift-off and the same as `presrs classify`'s, or `decide_at` frames after
touchdown (a point the model was trained for), or at its first confident point (`"auto"`); `decide_at`
refused with a one-frame model, and at a moment the model was not trained for, in Python's words."""

import json

import numpy as np
import pytest

import presrs

from conftest import SHARED

JIKU = SHARED / "data" / "real" / "jiku-walk"
MOVIES = ["s01_t00.npy", "s01_t03.npy", "s00_t05.npy"]
# Unloaded frames around each movie: a foot's swing.
SWING = 12

pytestmark = pytest.mark.skipif(
    not (JIKU / "manifest.csv").exists(), reason="the shared jiku-walk movies are not here"
)


@pytest.fixture(scope="module")
def stance_model(cli, tmp_path_factory):
    path = tmp_path_factory.mktemp("stance") / "stance.json"
    cli(
        "train", "--manifest", JIKU / "manifest.csv", "--out", path,
        "--sample", "stance", "--one-sample-per-file", "--features", "rocket",
        "--classifier", "lda", "--dims", "20", "--seed", "1", "--online-profile",
        "--decide-at", "5,10,whole",
    )
    return path


@pytest.fixture(scope="module")
def whole_only_model(cli, tmp_path_factory):
    path = tmp_path_factory.mktemp("whole") / "whole.json"
    cli(
        "train", "--manifest", JIKU / "manifest.csv", "--out", path,
        "--sample", "stance", "--one-sample-per-file", "--features", "rocket",
        "--classifier", "lda", "--dims", "20", "--seed", "1", "--online-profile",
    )
    return path


def stream(model, movie, **options):
    """The events of `movie` streamed as one step of a walk, a swing before and after it."""
    online = presrs.OnlineClassifier(model, **options)
    recording = presrs.read(JIKU / movie)
    swing = [np.zeros(recording.shape)] * SWING
    events = []
    for frame in swing + list(recording.frames) + swing:
        events += online.push(frame)
    events += online.finish()
    return recording, events


def decisions(events):
    return [e for e in events if e["event"] == "classification"]


@pytest.mark.parametrize("movie", MOVIES)
def test_the_liftoff_decision_is_the_offline_classification(cli, stance_model, movie):
    model = presrs.Model.load(stance_model)
    recording, events = stream(model, movie)
    (decision,) = decisions(events)
    frames = len(recording.frames)
    assert decision["kind"] == "stance"
    assert decision["decided_at"] == "liftoff"
    # Lift-off is known once the detector's bridged dropout (2 frames) has passed unloaded.
    assert decision["decided_at_frame"] == SWING + frames + 2
    assert decision["cut"] is False
    assert decision["frames_used"] == frames
    assert decision["touchdown_frame"] == SWING
    liftoff = [e for e in events if e["event"] == "liftoff"]
    assert liftoff[-1]["sampled"] is True
    assert events.index(decision) < events.index(liftoff[-1])
    # The frames as read (the stream fills no dead sensels).
    offline = json.loads(
        cli(
            "classify", "--model", stance_model, JIKU / movie, "--one-sample-per-file",
            "--keep-dead-sensels", "--json",
        )
    )
    (result,) = offline["results"]
    assert decision["label"] == result["label"]
    assert decision["confidence"] == pytest.approx(result["confidence"], abs=1e-9)
    for label, p in result["posteriors"].items():
        assert decision["posteriors"][label] == pytest.approx(p, abs=1e-9)


def test_decide_at_decides_as_frame_k_arrives(stance_model):
    model = presrs.Model.load(stance_model)
    _, events = stream(model, MOVIES[0], decide_at=10)
    (decision,) = decisions(events)
    assert decision["decided_at"] == "offset"
    assert decision["decided_at_frame"] == SWING + 10
    assert decision["frame"] == SWING + 10
    assert decision["frames_used"] == 11
    assert (decision["early_rule"], decision["early_reason"]) == ("fixed", "fixed")
    assert decision["early_point"] == 10


def test_auto_decides_at_a_trained_point_or_the_liftoff(stance_model):
    model = presrs.Model.load(stance_model)
    recording, events = stream(model, MOVIES[0], decide_at="auto")
    (decision,) = decisions(events)
    assert decision["early_rule"] == "auto"
    assert decision["early_threshold"] is not None
    if decision["early_reason"] in ("confident", "deadline"):
        assert decision["early_point"] in (5, 10)
        assert decision["frame"] == SWING + decision["early_point"]
        confident = decision["confidence"] >= decision["early_threshold"]
        assert confident == (decision["early_reason"] == "confident")
    else:
        assert decision["early_reason"] == "not_confident"
        assert decision["decided_at"] == "liftoff"


@pytest.mark.parametrize("decide_at", [7, "auto"])
def test_a_moment_the_model_was_not_trained_for_is_refused_in_python_words(
    stance_model, whole_only_model, decide_at
):
    for path in [whole_only_model] + ([stance_model] if decide_at == 7 else []):
        with pytest.raises(ValueError) as info:
            presrs.OnlineClassifier(presrs.Model.load(path), decide_at=decide_at)
        message = str(info.value)
        assert "not trained to decide at" in message
        assert 'sample="stance"' in message
        assert f"decide_at={decide_at!r}".replace("'", '"') in message
        assert "--" not in message


def test_decide_at_with_a_one_frame_model_is_refused_in_python_words(paper_model):
    with pytest.raises(Exception) as info:
        presrs.OnlineClassifier(paper_model, decide_at=5)
    message = str(info.value)
    assert "decide_at=5" in message
    assert "whole-stance" in message
    assert "--decide-at" not in message


def test_frames_missing_inside_a_stance_are_stated(stance_model):
    """Frames lost in the middle of a step (their times jump by 5 periods): the lift-off decision
    says so in `gap_frames`, as `presrs stream` does; without times, nothing is known of a gap."""
    model = presrs.Model.load(stance_model)
    recording = presrs.read(JIKU / MOVIES[0])
    swing = [np.zeros(recording.shape)] * SWING
    frames = swing + list(recording.frames) + swing
    middle = SWING + len(recording.frames) // 2
    period_us = 10_000

    def run(with_times):
        online = presrs.OnlineClassifier(model)
        events = []
        for i, frame in enumerate(frames):
            # Four frames lost before `middle`: its time is five periods after the previous one.
            time = (i + (4 if i >= middle else 0)) * period_us
            events += online.push(frame, timestamp_us=time if with_times else None)
        return events + online.finish()

    events = run(with_times=True)
    (decision,) = decisions(events)
    assert decision["gap_frames"] == 4
    liftoff = [e for e in events if e["event"] == "liftoff"]
    assert liftoff[-1]["gap_frames"] == 4
    (decision,) = decisions(run(with_times=False))
    assert decision.get("gap_frames", 0) == 0
