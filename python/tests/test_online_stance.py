"""`OnlineClassifier` with a whole-stance model (trained with `--sample stance` on the shared `jiku-walk`
movies, one contact each): each movie streamed as a step (a swing of unloaded frames before and after
it, as in a walk: the profile learned from one-contact trials finds the steps of a stream) gives one
decision, at the stance's lift-off and the same as `presrs classify`'s, or `decide_at` frames after
touchdown; `decide_at` refused with a one-frame model, in Python's words."""

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


def test_decide_at_with_a_one_frame_model_is_refused_in_python_words(paper_model):
    with pytest.raises(Exception) as info:
        presrs.OnlineClassifier(paper_model, decide_at=5)
    message = str(info.value)
    assert "decide_at=5" in message
    assert "whole-stance" in message
    assert "--decide-at" not in message
