"""Training, classifying and storing models from Python."""

import json
import pickle
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pytest

import presrs


def test_one_image_and_a_batch_give_the_same_answers(paper_model, sim_images):
    images = sim_images[0]
    labels = paper_model.predict(images)
    posteriors = paper_model.predict_proba(images)
    assert labels.shape == (len(images),)
    assert posteriors.shape == (len(images), len(paper_model.classes_))
    np.testing.assert_allclose(posteriors.sum(axis=1), 1.0, atol=1e-12)
    for image, label, row in zip(images[:8], labels, posteriors):
        assert paper_model.predict(image) == label
        np.testing.assert_allclose(paper_model.predict_proba(image), row, rtol=0, atol=1e-12)
    assert list(paper_model.classes_[posteriors.argmax(axis=1)]) == list(labels)


def test_the_model_learns_the_simulated_terrains(paper_model, sim_images):
    images, labels, _ = sim_images
    assert list(paper_model.classes_) == ["carpet", "clay", "grass", "wood"]
    assert np.mean(paper_model.predict(images) == labels) > 0.9


@pytest.mark.parametrize("dtype", [np.float32, np.uint16, np.int64])
def test_any_numeric_dtype_and_either_order(paper_model, sim_images, dtype):
    images = np.round(sim_images[0][:6])
    expected = paper_model.predict_proba(images)
    converted = images.astype(dtype)
    np.testing.assert_allclose(paper_model.predict_proba(converted), expected, atol=1e-9)
    fortran = np.asfortranarray(images[0])
    np.testing.assert_array_equal(paper_model.predict_proba(fortran), expected[0])
    strided = images[:, ::1, ::1][::2]
    np.testing.assert_array_equal(paper_model.predict_proba(strided), expected[::2])
    as_list = images[0].tolist()
    assert paper_model.predict(as_list) == paper_model.predict(images[0])


@pytest.mark.parametrize(
    "bad, message",
    [
        (np.zeros(5), "expected one image"),
        (np.zeros((2, 2, 2, 2)), "expected one image"),
        (np.zeros((10, 10)), "10x10"),
        ("image.png", "string"),
        (np.array([["a", "b"], ["c", "d"]]), "dtype"),
        (np.zeros((44, 44), dtype=complex), "dtype"),
        (np.full((44, 44), np.nan), "NaN"),
        (np.zeros((0, 44, 44)), None),
        (np.zeros((44, 0)), "empty"),
    ],
)
def test_bad_input_is_a_clear_value_error(paper_model, bad, message):
    if message is None:
        # An empty batch is no error: no labels.
        assert paper_model.predict(bad).shape == (0,)
        return
    with pytest.raises(presrs.DataError, match=message) as caught:
        paper_model.predict(bad)
    assert isinstance(caught.value, ValueError)


def test_a_nan_in_a_batch_names_its_image(paper_model, sim_images):
    images = sim_images[0][:5].copy()
    images[3, 10, 10] = np.nan
    with pytest.raises(presrs.DataError, match="image 3"):
        paper_model.predict(images)


def test_training_errors_name_the_cause(sim_images):
    images, labels, _ = sim_images
    with pytest.raises(presrs.DataError, match="labels"):
        presrs.Model.train(images, labels[:-1])
    with pytest.raises(presrs.DataError, match="classifier"):
        presrs.Model.train(images, labels, classifier="oracle")
    with pytest.raises(presrs.DataError, match="validation"):
        presrs.Model.train(images, labels, validation=-1)
    with pytest.raises(presrs.DataError, match="batch"):
        presrs.Model.train(images[0], labels[:1])


def test_labels_may_be_any_values(sim_images):
    images, labels, _ = sim_images
    numbers = np.unique(labels, return_inverse=True)[1]
    model = presrs.Model.train(images, numbers, features="fft1d", classifier="lda", seed=1)
    assert list(model.classes_) == ["0", "1", "2", "3"]


def test_save_and_load_keep_every_posterior(paper_model, sim_images, tmp_path):
    path = tmp_path / "model.json"
    paper_model.save(path)
    loaded = presrs.Model.load(path)
    np.testing.assert_array_equal(
        loaded.predict_proba(sim_images[0]), paper_model.predict_proba(sim_images[0])
    )
    assert presrs.Model.from_json(paper_model.to_json()).describe() == paper_model.describe()
    assert "pwe" in paper_model.describe() and "fft1d" in paper_model.describe()


def test_a_model_file_that_is_not_one(tmp_path):
    path = tmp_path / "model.json"
    path.write_text('{"format": "something else"}')
    with pytest.raises(presrs.DataError, match="not a presrs model file"):
        presrs.Model.load(path)


def _labels_in_worker(model, images):
    return list(model.predict(images))


def test_a_pickled_model_classifies_alike_in_other_processes(paper_model, sim_images):
    images = sim_images[0][:12]
    clone = pickle.loads(pickle.dumps(paper_model))
    np.testing.assert_array_equal(clone.predict_proba(images), paper_model.predict_proba(images))
    with ProcessPoolExecutor(max_workers=2) as pool:
        results = list(pool.map(_labels_in_worker, [paper_model] * 2, [images] * 2))
    expected = list(paper_model.predict(images))
    assert results == [expected, expected]


def test_threads_share_a_model(paper_model, sim_images):
    from concurrent.futures import ThreadPoolExecutor

    images = sim_images[0][:16]
    expected = [paper_model.predict(image) for image in images]
    with ThreadPoolExecutor(max_workers=4) as pool:
        got = list(pool.map(paper_model.predict, images))
    assert got == expected


def test_auto_chooses_and_says_what(sim_images):
    images, labels, gaits = sim_images
    model = presrs.Model.train(images, labels, conditions=gaits, seed=1)
    assert "chosen automatically" in model.describe()


def test_auto_validates_by_the_groups_asked_for(sim_images):
    images, labels, gaits = sim_images
    model = presrs.Model.train(
        images, labels, groups=gaits, validate_by="group", features="fft1d", seed=1
    )
    assert "group" in model.describe()
    with pytest.raises(presrs.DataError, match="validate_by"):
        presrs.Model.train(images, labels, validate_by="sideways")


def test_the_choice_rule_is_named_in_python_words(sim_images):
    images, labels, gaits = sim_images
    for rule in ("auto", "best", "one-se"):
        model = presrs.Model.train(
            images, labels, conditions=gaits, features="fft1d", choose=rule, seed=1
        )
        assert "chosen automatically" in model.describe()
    with pytest.raises(presrs.DataError, match=r"choose=.median.*known: auto, best, one-se") as caught:
        presrs.Model.train(images, labels, choose="median")
    assert "--choose" not in str(caught.value)


def test_a_model_file_read_as_a_recording_is_named(paper_model, tmp_path):
    path = tmp_path / "model.json"
    paper_model.save(path)
    with pytest.raises(presrs.DataError, match="a presrs model file, not a recording") as caught:
        presrs.read(path)
    assert "Model.load(path).describe()" in str(caught.value)


def test_auto_budget_cuts_from_the_end_and_none_is_no_limit(sim_images):
    images, labels, gaits = sim_images
    # fixed classifier: one candidate per feature group; a budget spent at once scores the first only
    with pytest.warns(UserWarning, match="cut short"):
        cut = presrs.Model.train(
            images, labels, conditions=gaits, classifier="lda", budget=1e-9, seed=1
        )
    scores = json.loads(cut.to_json())["model"]["selection"]["scores"]
    assert [s.get("skipped", False) for s in scores][:2] == [False, True]
    full = presrs.Model.train(
        images, labels, conditions=gaits, classifier="lda", budget=None, seed=1
    )
    assert not any(
        s.get("skipped", False) for s in json.loads(full.to_json())["model"]["selection"]["scores"]
    )
    with pytest.raises(presrs.DataError, match="budget"):
        presrs.Model.train(images, labels, budget=-1.0)
