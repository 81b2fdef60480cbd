"""Whole-stance and series samples from numpy (`Model.train(..., sample="stance")`, issue #33): the
same movies trained in Python and by `presrs train --sample stance` classify alike, and the estimator
takes the same parameters."""

import csv
import json
import warnings

import numpy as np
import pytest

import presrs
from conftest import SHARED

JIKU = SHARED / "data" / "real" / "jiku-walk"
# Every other movie of each class and walker keeps the test short; the rocket + ridge method is fixed
# (no search), so both faces train the same pipeline on the same draw.
METHOD = dict(features="rocket", classifier="ridge", seed=3, validation=0.25)


@pytest.fixture(scope="module")
def jiku_rows(tmp_path_factory):
    """Half of jiku-walk's rows (each movie one stance), and a manifest listing them."""
    if not (JIKU / "manifest.csv").exists():
        pytest.skip("the shared jiku-walk set is not beside the checkout")
    with open(JIKU / "manifest.csv", newline="") as f:
        rows = list(csv.DictReader(f))[::2]
    manifest = tmp_path_factory.mktemp("jiku") / "manifest.csv"
    with open(manifest, "w", newline="") as f:
        out = csv.DictWriter(f, fieldnames=["path", "label", "condition", "group"])
        out.writeheader()
        for row in rows:
            out.writerow({**row, "path": str(JIKU / row["path"])})
    return rows, manifest


def _movies(rows):
    return [presrs.read(JIKU / row["path"]).frames for row in rows]


def test_a_stance_model_trained_in_python_classifies_as_the_cli_trained_one(
    cli, jiku_rows, tmp_path
):
    rows, manifest = jiku_rows
    movies = _movies(rows)
    labels = [row["label"] for row in rows]
    groups = [row["group"] for row in rows]
    ours = presrs.Model.train(movies, labels, groups=groups, sample="stance", **METHOD)
    assert ours.sample == "stance"
    cli_model = tmp_path / "cli.json"
    sample_options = ["--sample", "stance", "--one-sample-per-file", "--keep-dead-sensels"]
    cli(
        "train", "--manifest", manifest, "--out", cli_model, "--features", "rocket",
        "--classifier", "ridge", "--seed", 3, "--validation", 0.25, *sample_options,
    )
    theirs = presrs.Model.load(cli_model)
    assert theirs.sample == "stance"
    assert list(ours.classes_) == list(theirs.classes_)
    np.testing.assert_allclose(
        ours.predict_proba(movies), theirs.predict_proba(movies), rtol=0, atol=1e-9
    )
    # And the command line classifying the files with the Python model gives Python's labels.
    ours_path = tmp_path / "python.json"
    ours.save(ours_path)
    files = [JIKU / row["path"] for row in rows[:8]]
    doc = json.loads(
        cli("classify", "--model", ours_path, "--json", *sample_options, *files)
    )
    assert [r["label"] for r in doc["results"]] == list(ours.predict(movies[:8]))
    # One movie gives one label; a batch (a list of movies) an array.
    assert ours.predict(movies[0]) == ours.predict(movies[:1])[0]


def test_stances_longer_than_the_length_are_cut_with_a_warning(jiku_rows):
    rows, _ = jiku_rows
    movies = _movies(rows[:12])
    labels = [row["label"] for row in rows[:12]]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        model = presrs.Model.train(
            movies, labels, sample="stance", stance_length=40, **METHOD
        )
    assert any("longer than 40 frames" in str(w.message) for w in caught)
    assert model.cropped_shape[1] == 40
    with pytest.warns(UserWarning, match="more than the model's 40"):
        model.predict(movies[0])


def test_stance_samples_refuse_images_and_name_the_movie():
    movies = [np.ones((12, 8, 8))] * 3 + [np.ones((8, 8))]
    with pytest.raises(presrs.DataError, match=r"images\[3\]: .*movie"):
        presrs.Model.train(movies, list("abab"), sample="stance", **METHOD)
    bad = [np.ones((12, 8, 8)) for _ in range(4)]
    bad[2][5, 1, 2] = np.nan
    with pytest.raises(presrs.DataError, match=r"images\[2\]: frame 5, row 1, col 2 .* NaN"):
        presrs.Model.train(bad, list("abab"), sample="stance", **METHOD)
    with pytest.raises(presrs.DataError, match="stance_length="):
        presrs.Model.train(bad, list("abab"), stance_length=10)
    with pytest.raises(presrs.DataError, match="series_axis"):
        presrs.Model.train(bad, list("abab"), sample="series", series_axis="time")


def test_series_samples_read_channels_by_time_and_transpose_on_request():
    rng = np.random.default_rng(5)
    n, channels, time = 24, 6, 30
    labels = np.array(["soft", "hard"] * (n // 2))
    series = rng.normal(size=(n, channels, time))
    series[labels == "hard", :, 10:20] += 2.0
    model = presrs.Model.train(series, labels, sample="series", **METHOD)
    assert model.sample == "series"
    assert np.mean(model.predict(series) == labels) > 0.9
    rows = presrs.Model.train(
        series.transpose(0, 2, 1), labels, sample="series", series_axis="rows", **METHOD
    )
    np.testing.assert_allclose(
        rows.predict_proba(series.transpose(0, 2, 1)), model.predict_proba(series), atol=1e-9
    )
    assert rows.predict(series[0].T) == model.predict(series[0])


def test_the_estimator_takes_the_sample_parameters(jiku_rows):
    from presrs.sklearn import TerrainClassifier

    rows, _ = jiku_rows
    movies = _movies(rows)
    labels = np.array([row["label"] for row in rows])
    est = TerrainClassifier(sample="stance", stance_length=90, **METHOD).fit(movies, labels)
    model = presrs.Model.train(movies, labels, sample="stance", stance_length=90, **METHOD)
    assert list(est.predict(movies)) == list(model.predict(movies))
    assert est.get_params()["sample"] == "stance"
