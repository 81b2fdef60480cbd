"""Evaluation on arrays, and the simulator from Python."""

import numpy as np
import pytest

import presrs


def test_evaluate_on_images(sim_images):
    images, labels, gaits = sim_images
    result = presrs.evaluate(
        images, labels, conditions=gaits, train_condition="G2", per_class=3, repeats=3,
        seed=5, features="fft1d", classifier="pwe",
    )
    assert 0.0 <= result.accuracy <= 1.0 and result.accuracy > 0.7
    assert len(result.repeats) == 3
    assert result.classes == ["carpet", "clay", "grass", "wood"]
    assert result.confusion.shape == (4, 4)
    # Each repeat tests every image it did not train on.
    tested = len(images) - 4 * 3
    assert result.confusion.sum() == 3 * tested
    assert set(result.per_condition) >= {"G1"}
    assert 0.0 <= result.calibration["mean_confidence"] <= 1.0
    assert result.to_dict()["overall_accuracy"] == result.accuracy
    assert result.to_dict()["report"]["overall"]["mean"] == result.accuracy
    again = presrs.evaluate(
        images, labels, conditions=gaits, train_condition="G2", per_class=3, repeats=3,
        seed=5, features="fft1d", classifier="pwe",
    )
    assert again.repeats == result.repeats


def test_leave_one_group_out(sim_images):
    images, labels, gaits = sim_images
    result = presrs.evaluate(
        images, labels, groups=gaits, leave_one_out="group", repeats=1,
        features="fft1d", classifier="lda",
    )
    assert set(result.per_condition) == {"G1", "G2"}


def test_evaluation_errors_say_what_to_do(sim_images):
    images, labels, _ = sim_images
    # No protocol, no groups and no per-class draw: refused before any training, in Python's words.
    with pytest.raises(presrs.DataError, match="no image would be left to test on") as error:
        presrs.evaluate(images, labels, repeats=1, features="fft1d", classifier="pwe")
    assert 'leave_one_out="group"' in str(error.value) and "--" not in str(error.value)
    with pytest.raises(presrs.DataError, match="labels"):
        presrs.evaluate(images)
    with pytest.raises(presrs.DataError, match="choose one protocol"):
        presrs.evaluate(images, labels, leave_one_out="group", train_condition="G1")
    with pytest.raises(presrs.DataError, match="no such column"):
        presrs.evaluate(images, labels, leave_one_out="group", repeats=1)


def test_simulate_is_seeded_and_labelled():
    a = presrs.simulate(terrains=["wood", "clay"], gaits=["G3"], hops=2, seed=9)
    b = presrs.simulate(terrains=["wood", "clay"], gaits=["G3"], hops=2, seed=9)
    assert [t.name for t in a] == ["wood_G3_000", "clay_G3_000"]
    assert [t.terrain for t in a] == ["wood", "clay"] and {t.gait for t in a} == {"G3"}
    for x, y in zip(a, b):
        np.testing.assert_array_equal(x.recording.frames, y.recording.frames)
    assert a[0].recording.frame_period_s == pytest.approx(0.01)
    stances = [s for s in presrs.segment(a[0].recording) if not s.partial]
    assert len(stances) >= 2
    with pytest.raises(presrs.DataError, match="moon"):
        presrs.simulate(terrains=["moon"], hops=1)


def test_evaluate_reports_progress(sim_images, capsys):
    images, labels, gaits = sim_images
    seen = []
    presrs.evaluate(
        images, labels, conditions=gaits, train_condition="G2", per_class=3, repeats=2,
        features="fft1d", classifier="pwe", progress=lambda task, done, total: seen.append((task, done, total)),
    )
    assert seen, "no progress was reported"
    task, done, total = seen[-1]
    assert total is not None and done == total
    presrs.evaluate(
        images, labels, conditions=gaits, train_condition="G2", per_class=3, repeats=1,
        features="fft1d", classifier="pwe", progress=True,
    )
    assert "presrs: " in capsys.readouterr().err
