"""Errors and warnings speak Python: the options they name are this package's arguments
(`per_class=`), never the command line's flags (`--per-class`). Each case below reaches a message that
named a flag before the library carried options as data."""

import re
import warnings
from pathlib import Path

import numpy as np
import pytest

import presrs

MCAP_FIXTURES = (
    Path(__file__).resolve().parents[2] / "crates" / "presrs-io" / "tests" / "fixtures" / "mcap"
)

# `--` then a letter: a command-line flag (an em-dash written `--` or a negative number is not one).
FLAG = re.compile(r"--[A-Za-z]")


def _no_flag(text):
    assert not FLAG.search(text), f"a Python message names a command-line flag: {text}"


def _raised(call, *args, **kwargs):
    """The message of the `presrs.DataError` that `call` raises, checked for flags."""
    with pytest.raises(presrs.DataError) as caught:
        call(*args, **kwargs)
    message = str(caught.value)
    _no_flag(message)
    return message


def _warned(call, *args, **kwargs):
    """What `call` returns and the messages of the warnings it gives, each checked for flags."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = call(*args, **kwargs)
    messages = [str(w.message) for w in caught]
    for message in messages:
        _no_flag(message)
    return result, messages


def test_validation_too_small_names_the_argument(sim_images):
    images, labels, _ = sim_images
    message = _raised(
        presrs.Model.train, images, labels, features="fft1d", classifier="pwe", validation=0
    )
    assert "validation=0 leaves no validation images" in message
    assert "or another classifier=" in message


def test_leave_one_out_on_a_missing_column_names_the_argument(sim_images):
    images, labels, _ = sim_images
    message = _raised(presrs.evaluate, images, labels, leave_one_out="site", repeats=1)
    assert "leave_one_out=\"site\": the manifest has no such column" in message


def test_too_many_dims_warns_with_the_argument(sim_images):
    images, labels, _ = sim_images
    model, messages = _warned(
        presrs.Model.train, images[:12], labels[:12], features="fft1d", classifier="lda",
        dims=500, validation=0,
    )
    assert any(m.startswith("dims=500: kept") for m in messages), messages
    result, messages = _warned(
        presrs.evaluate, images, labels, repeats=1, per_class=3, validation=0,
        features="fft1d", classifier="lda", dims=500,
    )
    assert any(m.startswith("dims=500: models trained on") for m in messages), messages
    assert all(m in messages for m in result.warnings), (result.warnings, messages)
    for message in result.warnings:
        _no_flag(message)


def test_a_capped_per_class_warns_with_the_argument(sim_images):
    images, labels, _ = sim_images
    _, messages = _warned(
        presrs.Model.train, images, labels, features="fft1d", classifier="lda", per_class=1000,
    )
    assert any(m.startswith("per_class=1000: capped") for m in messages), messages
    images, labels, gaits = sim_images
    result, messages = _warned(
        presrs.evaluate, images, labels, conditions=gaits, train_condition="G1", repeats=1,
        per_class=1000, features="fft1d", classifier="lda",
    )
    capped = [m for m in result.warnings if "per_class=1000: capped" in m]
    assert capped and capped[0] in messages, (result.warnings, messages)


def test_a_spent_budget_warns_with_the_argument(sim_images):
    images, labels, gaits = sim_images
    _, messages = _warned(
        presrs.Model.train, images, labels, conditions=gaits, classifier="lda", budget=1e-9,
        seed=1,
    )
    cut = [m for m in messages if "cut short" in m]
    assert cut and "give budget= a larger value" in cut[0] and "budget=0 for no limit" in cut[0]


def test_a_validation_that_hides_a_class_warns_with_the_argument(sim_images):
    # Each terrain one group (its trial), as in one gait of the simulator's data: leaving a group out
    # leaves its terrain out of training, so the choice validates by splits and says so (issue #35).
    images, labels, gaits = sim_images
    g2 = gaits == "G2"
    _, messages = _warned(
        presrs.Model.train, images[g2], labels[g2], groups=labels[g2], classifier="lda",
        features="fft1d", budget=0, seed=1,
    )
    # (a fixed method makes no choice)
    assert not any("instead of" in m for m in messages), messages
    model, messages = _warned(
        presrs.Model.train, images[g2], labels[g2], groups=labels[g2], classifier="auto",
        features="fft1d", budget=0, seed=1,
    )
    fell = [m for m in messages if "instead of leaving one group out" in m]
    assert len(fell) == 1, messages
    assert 'validate_by="split"' in fell[0] and "leaves no training image of class" in fell[0]


def test_a_time_last_npy_warns_with_the_argument(tmp_path):
    np.save(tmp_path / "time-last.npy", np.random.default_rng(3).random((6, 5, 40)))
    rec, messages = _warned(presrs.read, tmp_path / "time-last.npy")
    assert any('give axes="rows,cols,frames"' in m for m in messages), messages
    assert rec.warnings == messages


def test_a_bag_of_several_topics_names_the_argument():
    message = _raised(presrs.read, MCAP_FIXTURES / "two_topics.mcap")
    assert "choose one with topic=" in message


@pytest.mark.parametrize(
    "load, argument",
    [
        # one press from the first frame to the last: one contact, partial at both ends
        (5 + 4 * np.sin(np.linspace(0, np.pi, 40)), "one_sample_per_file"),
        # a press already under way when the recording starts
        (np.r_[np.linspace(10, 0, 15), np.zeros(25)], "include_partial"),
    ],
)
def test_a_manifest_without_samples_names_the_argument_that_takes_them(tmp_path, load, argument):
    rows = ["path,label"]
    for i in range(8):
        scale = 1 + (i % 2)
        np.save(tmp_path / f"press{i}.npy", np.ones((len(load), 8, 8)) * load[:, None, None] * scale)
        rows.append(f"press{i}.npy,{'ab'[i % 2]}")
    (tmp_path / "manifest.csv").write_text("\n".join(rows) + "\n")
    message = _raised(presrs.evaluate, tmp_path / "manifest.csv", repeats=1)
    assert "8 of 8 files gave no sample" in message
    assert f"try {argument}=" in message
    # Issue #45: the argument named is presrs.evaluate's, and it takes the samples.
    result = presrs.evaluate(
        tmp_path / "manifest.csv", repeats=1, per_class=3, validation=1, features="fft1d",
        classifier="lda", **{argument: True},
    )
    assert result.confusion.sum() > 0


# Issue #35, Python: each message below names the argument and the image, in Python's words.


def test_one_image_per_class_says_so(sim_images):
    images, labels, _ = sim_images
    first = [list(labels).index(c) for c in np.unique(labels)]
    for classifier in ("pwe", "lda", "auto"):
        message = _raised(
            presrs.Model.train, images[first], labels[first], features="fft1d",
            classifier=classifier,
        )
        assert "too few samples per class" in message and "has 1" in message, message


def test_predict_none_says_none(paper_model):
    message = _raised(paper_model.predict, None)
    assert message == "x: expected a numpy array of images, got None"


def test_an_object_array_names_the_missing_value(paper_model, sim_images):
    images = sim_images[0][:3].astype(object)
    images[1, 4, 5] = None
    message = _raised(paper_model.predict, images)
    assert "x: image 1, row 4, col 5 (0-based) is NaN" in message
    assert "dtype object" in message
    message = _raised(paper_model.predict_proba, images[1])
    assert "x: row 4, col 5 (0-based) is NaN" in message


def test_nan_in_training_images_names_the_image(sim_images):
    images, labels, _ = sim_images
    images = images.copy()
    images[7, 3, 2] = np.nan
    message = _raised(presrs.Model.train, images, labels, features="fft1d", classifier="pwe")
    assert message.startswith("images: image 7, row 3, col 2 (0-based) is NaN")
    images[7, 3, 2] = np.inf
    message = _raised(presrs.Model.train, images, labels, features="fft1d", classifier="pwe")
    assert "image 7, row 3, col 2 (0-based) is inf" in message


def test_saving_into_a_missing_folder_says_so_first(paper_model, tmp_path):
    with pytest.raises(presrs.FileError) as caught:
        paper_model.save(tmp_path / "no" / "such" / "model.json")
    assert "does not exist (create it first, or write elsewhere)" in str(caught.value)
    _no_flag(str(caught.value))
