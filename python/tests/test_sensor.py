"""A whole-stance model records the sensor it was trained on and refuses another (issue #43): training
on movies of two grids, `Model.predict` and `OnlineClassifier.push` of another grid raise, with the
kind of message a one-frame model gives for a wrong image size."""

import csv

import numpy as np
import pytest

import presrs
from conftest import SHARED

JIKU = SHARED / "data" / "real" / "jiku-walk"


@pytest.fixture(scope="module")
def stance_model():
    """A whole-stance model trained on a quarter of jiku-walk's 63 x 33 movies."""
    if not (JIKU / "manifest.csv").exists():
        pytest.skip("the shared jiku-walk set is not beside the checkout")
    with open(JIKU / "manifest.csv", newline="") as f:
        rows = list(csv.DictReader(f))[::4]
    movies = [presrs.read(JIKU / row["path"]).frames for row in rows]
    labels = [row["label"] for row in rows]
    model = presrs.Model.train(
        movies, labels, sample="stance", features="rocket", classifier="ridge", seed=3
    )
    return model, movies, labels


def test_training_refuses_movies_of_two_sensors(stance_model):
    _, movies, labels = stance_model
    other = np.random.default_rng(1).random((60, 40, 30))
    with pytest.raises(
        presrs.DataError,
        match=r"images\[3\]: a movie of 40x30 frames where images\[0\] has 63x33: a stance model "
        r"is trained on one sensor",
    ):
        presrs.Model.train(
            movies[:3] + [other] + movies[3:], labels[:3] + [labels[0]] + labels[3:],
            sample="stance", features="rocket", classifier="ridge",
        )


def test_predict_refuses_a_movie_of_another_sensor(stance_model):
    model, movies, _ = stance_model
    assert model.predict(movies[0]) in model.classes_
    with pytest.raises(
        presrs.DataError,
        match="expected 63x33 frames, the sensor this whole-stance model was trained on, got 40x30",
    ):
        model.predict(np.random.default_rng(2).random((60, 40, 30)))


def test_the_online_classifier_refuses_frames_of_another_sensor(stance_model):
    model, _, _ = stance_model
    online = presrs.OnlineClassifier(model)
    with pytest.raises(presrs.DataError, match="the sensor this whole-stance model was trained on"):
        online.push(np.zeros((40, 30)))
    assert online.stats["rejected_frames"] == 1
