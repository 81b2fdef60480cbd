"""Issue #45, "Python refuses what the CLI refuses": missing labels are refused with their index, every
sample kind `presrs eval` takes is `presrs.evaluate`'s too, shape errors say what the model takes, the
names the docstrings list are the names the library accepts, and the default seed is the command
line's."""

import ast
import inspect
import json
import re
import warnings
from pathlib import Path

import numpy as np
import pytest

import presrs
from conftest import REPO

FLAG = re.compile(r"--[A-Za-z]")
FAST = dict(features="fft1d", classifier="pwe")


def _refused(call, *args, **kwargs):
    """The message of the `presrs.DataError` (a `ValueError`) that `call` raises, checked for flags."""
    with pytest.raises(ValueError) as caught:
        call(*args, **kwargs)
    assert isinstance(caught.value, presrs.DataError), caught.value
    message = str(caught.value)
    assert not FLAG.search(message), f"a Python message names a command-line flag: {message}"
    return message


# Missing labels: None, NaN (Python's, numpy's), empty and blank text.

MISSING = [
    pytest.param(None, "None", id="None"),
    pytest.param(float("nan"), "NaN", id="nan"),
    pytest.param(np.float32("nan"), "NaN", id="numpy-nan"),
    pytest.param("", "''", id="empty"),
    pytest.param("  ", "'  '", id="blank"),
]


def _with_missing(labels, value, at):
    out = np.array(labels, dtype=object)
    out[at] = value
    return list(out)


@pytest.mark.parametrize("value, shown", MISSING)
def test_model_train_refuses_missing_labels_with_their_index(sim_images, value, shown):
    images, labels, _ = sim_images
    n = len(labels)
    message = _refused(
        presrs.Model.train, images, _with_missing(labels, value, [5, 9, 12]), **FAST
    )
    assert message.startswith(f"labels[5] is {shown}: every sample needs a label"), message
    assert f"3 of {n} labels missing" in message and "at indices 5, 9, 12" in message, message


def test_the_issues_example_none_for_a_third_class_is_refused():
    rng = np.random.default_rng(1)
    images = rng.random((60, 8, 8))
    message = _refused(presrs.Model.train, images, ["a"] * 20 + ["b"] * 20 + [None] * 20, **FAST)
    assert message.startswith("labels[40] is None"), message
    assert "20 of 60 labels missing" in message, message


def test_nan_in_a_float_array_of_labels_is_missing_not_a_class_nan(sim_images):
    images, labels, _ = sim_images
    codes = np.unique(labels, return_inverse=True)[1].astype(float)
    codes[3] = np.nan
    message = _refused(presrs.Model.train, images, codes, **FAST)
    assert message.startswith("labels[3] is NaN"), message


@pytest.mark.parametrize("value, shown", MISSING)
def test_evaluate_refuses_missing_labels(sim_images, value, shown):
    images, labels, _ = sim_images
    message = _refused(
        presrs.evaluate, images, _with_missing(labels, value, [2]), repeats=1, **FAST
    )
    assert message.startswith(f"labels[2] is {shown}"), message


@pytest.mark.parametrize("value, shown", MISSING)
def test_the_estimator_refuses_missing_labels(sim_images, value, shown):
    pytest.importorskip("sklearn")
    from presrs.sklearn import TerrainClassifier

    images, labels, _ = sim_images
    y = np.array(_with_missing(labels, value, [7, 8]), dtype=object)
    message = _refused(TerrainClassifier(**FAST).fit, images, y)
    assert message.startswith(f"y[7] is {shown}: every sample needs a label"), message
    assert "2 of" in message, message


def test_a_stance_model_refuses_missing_labels():
    movies = [np.ones((12, 8, 8)) * (1 + i % 2) for i in range(6)]
    message = _refused(
        presrs.Model.train, movies, ["a", "b", "a", None, "a", "b"], sample="stance",
        features="rocket", classifier="ridge",
    )
    assert message.startswith("labels[3] is None"), message


def test_missing_groups_and_conditions_are_none_not_a_group_named_none(sim_images):
    images, labels, gaits = sim_images
    groups = np.array(gaits, dtype=object)
    groups[::7] = None
    conditions = np.array(gaits, dtype=object)
    conditions[::5] = np.nan
    result = presrs.evaluate(
        images, labels, conditions=conditions, groups=groups, train_condition="G1",
        per_class=3, repeats=1, **FAST,
    )
    assert not {"None", "nan"} & set(result.per_condition), result.per_condition


# Every sample kind of `presrs eval`.


def _cli_eval(cli, manifest, *options):
    return json.loads(cli("eval", "--manifest", manifest, "--json", *map(str, options)))


def test_evaluate_takes_whole_stances_as_presrs_eval_does(cli, sim_dir):
    manifest = sim_dir / "manifest.csv"
    ours = presrs.evaluate(
        manifest, sample="stance", stance_length=30, per_class=4, repeats=2, seed=4,
        features="rocket", classifier="ridge",
    )
    doc = _cli_eval(
        cli, manifest, "--sample", "stance", "--stance-length", 30, "--per-class", 4,
        "--repeats", 2, "--seed", 4, "--features", "rocket", "--classifier", "ridge",
    )
    mine = ours.to_dict()
    assert ours.accuracy == pytest.approx(doc["overall_accuracy"], abs=1e-12)
    assert mine["confusion"] == doc["confusion"]
    assert mine["per_class"] == doc["per_class"]


def test_named_features_with_sample_auto_point_to_a_sample_kind_that_works(cli, sim_dir):
    manifest = sim_dir / "manifest.csv"
    options = dict(features="rocket", classifier="ridge", per_class=4, repeats=1, seed=2)
    message = _refused(presrs.evaluate, manifest, sample="auto", **options)
    assert "name the sample kind" in message, message
    ours = presrs.evaluate(manifest, sample="stance", **options)
    doc = _cli_eval(
        cli, manifest, "--sample", "stance", "--features", "rocket", "--classifier", "ridge",
        "--per-class", 4, "--repeats", 1, "--seed", 2,
    )
    assert ours.accuracy == pytest.approx(doc["overall_accuracy"], abs=1e-12)


def test_evaluate_takes_series_as_presrs_eval_does(cli, tmp_path):
    rng = np.random.default_rng(8)
    rows = ["path,label"]
    for i in range(24):
        label = "soft" if i % 2 else "hard"
        series = rng.normal(size=(30, 6))  # time down the rows
        if label == "hard":
            series[10:20] += 1.5
        np.save(tmp_path / f"s{i:02d}.npy", series)
        rows.append(f"s{i:02d}.npy,{label}")
    manifest = tmp_path / "manifest.csv"
    manifest.write_text("\n".join(rows) + "\n")
    ours = presrs.evaluate(
        manifest, sample="series", series_axis="rows", per_class=6, repeats=2,
        features="rocket", classifier="ridge",
    )
    doc = _cli_eval(
        cli, manifest, "--sample", "series", "--series-axis", "rows", "--per-class", 6,
        "--repeats", 2, "--features", "rocket", "--classifier", "ridge",
    )
    assert ours.accuracy == pytest.approx(doc["overall_accuracy"], abs=1e-12)
    assert ours.to_dict()["confusion"] == doc["confusion"]


def test_evaluate_takes_the_manifests_sample_options(cli, sim_dir):
    manifest = sim_dir / "manifest.csv"
    options = dict(per_class=3, repeats=1, seed=5, **FAST)
    ours = presrs.evaluate(
        manifest, stance_frame="peak", segment_params={"min_stance_frames": 4},
        keep_dead_sensels=True, **options,
    )
    doc = _cli_eval(
        cli, manifest, "--stance-frame", "peak", "--stance-min-frames", 4,
        "--keep-dead-sensels", "--per-class", 3, "--repeats", 1, "--seed", 5,
        "--features", "fft1d", "--classifier", "pwe",
    )
    assert ours.accuracy == pytest.approx(doc["overall_accuracy"], abs=1e-12)
    assert ours.to_dict()["confusion"] == doc["confusion"]
    message = _refused(presrs.evaluate, manifest, stance_frame="middle", **options)
    assert message.startswith('stance_frame="middle"'), message
    message = _refused(presrs.evaluate, manifest, segment_params={"min_frames": 4}, **options)
    assert 'segment_params: unknown parameter "min_frames"' in message, message


def test_evaluate_in_memory_takes_stances_and_refuses_file_options():
    rng = np.random.default_rng(4)
    movies, labels = [], []
    for i in range(16):
        label = "a" if i % 2 else "b"
        movie = rng.random((10 + i % 5, 6, 6)) + (1.0 if label == "a" else 0.0)
        movies.append(movie)
        labels.append(label)
    result = presrs.evaluate(
        movies, labels, sample="stance", per_class=4, repeats=1, features="rocket",
        classifier="ridge",
    )
    assert 0 <= result.accuracy <= 1
    message = _refused(
        presrs.evaluate, movies, labels, sample="stance", one_sample_per_file=True, repeats=1,
    )
    assert message.startswith("one_sample_per_file= applies to reading a manifest's files"), message


def test_stance_length_and_series_axis_belong_to_their_kinds(sim_images):
    images, labels, _ = sim_images
    message = _refused(presrs.evaluate, images, labels, stance_length=20, repeats=1)
    assert message.startswith('stance_length= applies to sample="stance"'), message
    message = _refused(presrs.evaluate, images, labels, sample="series", series_axis="time")
    assert message.startswith("series_axis:"), message
    message = _refused(presrs.evaluate, images, labels, sample="stance", stance_length=0)
    assert message.startswith("stance_length:"), message


# Shape errors say what the model takes.


def test_the_estimator_names_rows_and_cols_not_features():
    pytest.importorskip("sklearn")
    from presrs.sklearn import TerrainClassifier

    rng = np.random.default_rng(3)
    X = rng.random((40, 28, 50))
    y = np.array(["a", "b"] * 20)
    est = TerrainClassifier(**FAST).fit(X, y)
    message = _refused(est.predict, np.zeros((5, 20, 20)))
    assert message == (
        "X: images of 20 x 20 (rows x cols), but the model was trained on images of 28 x 50"
    ), message
    assert "features" not in message
    message = _refused(est.predict_proba, np.zeros((20, 20)))
    assert message.startswith("X: one image of 20 x 20 (rows x cols), but the model was trained"), (
        message
    )


def test_a_stance_model_given_one_frame_says_it_takes_whole_stances():
    rng = np.random.default_rng(6)
    movies = [rng.random((12 + i % 3, 8, 33)) + i % 2 for i in range(12)]
    model = presrs.Model.train(
        movies, ["a", "b"] * 6, sample="stance", features="rocket", classifier="ridge"
    )
    movie = movies[0]
    message = _refused(model.predict, movie[10])
    assert message == (
        "x: the model classifies whole stances: it takes a stance's movie (frames, rows, cols), or "
        "a list of movies; got one image of 8 x 33 (rows x cols)"
    ), message
    message = _refused(model.predict_proba, [movie, movie[3]])
    assert message.startswith("x[1]: the model classifies whole stances"), message
    assert message.endswith("got one image of 8 x 33 (rows x cols)"), message
    message = _refused(model.predict, movie[10, 0])
    assert message.endswith("got an array of shape (33,)"), message
    assert model.predict(movie) == model.predict([movie])[0]


# The names the docs list are the library's.


def _documented_texts():
    """Every docstring of the package's public API, its stubs and its README."""
    from presrs import sklearn

    texts = [presrs.__doc__, sklearn.__doc__, sklearn.TerrainClassifier.__doc__]
    for name in presrs.__all__:
        obj = getattr(presrs, name)
        texts.append(getattr(obj, "__doc__", None))
        if inspect.isclass(obj):
            texts += [getattr(member, "__doc__", None) for member in vars(obj).values()]
    texts.append(Path(presrs.__file__).with_name("_native.pyi").read_text())
    texts.append((REPO / "python" / "README.md").read_text())
    return [t for t in texts if t]


def _quoted_names(text):
    """Names written in backticks or quotes: `fft1d`, ``"pwe"``, 'lda'."""
    return re.findall(r"[`\"']+([A-Za-z][A-Za-z0-9_+\-]*)[`\"']+", text)


def test_every_feature_and_classifier_name_the_docs_give_is_accepted():
    families = set(presrs.FEATURE_FAMILIES)
    classifiers = set(presrs.CLASSIFIERS)
    # A name that starts as a family does (fft..., glcm..., rocket...) is a feature list.
    stems = sorted({re.match(r"[a-z]+", f).group() for f in families}, key=len, reverse=True)
    feature_like = re.compile(rf"^({'|'.join(stems)})[a-z0-9_+\-]*$")
    wrong = []
    for text in _documented_texts():
        # Names in one parenthesised list (not a call's arguments) with a known name are all names:
        # a wrong one stands out.
        for group in re.findall(r"\(([^()=]*)\)", text):
            names = _quoted_names(group)
            if not any(n in families | classifiers for n in names):
                continue
            for name in names:
                parts = set(name.split("+")) - {""}
                if name != "auto" and not (parts <= families or name in classifiers):
                    wrong.append(name)
        for name in _quoted_names(text):
            if feature_like.match(name) and not set(name.split("+")) <= families:
                wrong.append(name)
    assert not wrong, f"documented names the library refuses: {sorted(set(wrong))}"


def test_each_listed_name_trains_a_model(sim_images):
    images, labels, _ = sim_images
    for family in ("fft2d_polar", "fft1d+glcm", "fft2d_polar+contact"):
        model = presrs.Model.train(images[:40], labels[:40], features=family, classifier="lda")
        assert len(model.predict(images[:4])) == 4
    # contact learns its scale from training images: only a model computes it, said in Python's words
    learned = _refused(presrs.features, images[:2], family="contact")
    assert "train a model" in learned, learned
    message = _refused(presrs.features, images[:2], family="auto")
    assert all(f in message for f in presrs.FEATURE_FAMILIES), message


# The default seed is the command line's.


def _cli_default_seed(cli, command):
    text = cli(command, "--help")
    found = re.search(r"--seed <SEED>[^\[]*\[default: (\d+)\]", text)
    assert found, text
    return int(found.group(1))


def _stub_defaults(name):
    """The `seed` default of every stubbed function or method named `name`."""
    tree = ast.parse(Path(presrs.__file__).with_name("_native.pyi").read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef) and node.name == name:
            args = node.args
            for arg, default in zip(args.kwonlyargs, args.kw_defaults):
                if arg.arg == "seed":
                    return ast.literal_eval(default)
    raise AssertionError(f"no seed in the stub of {name}")


def test_the_default_seed_is_the_command_lines(cli):
    pytest.importorskip("sklearn")
    from presrs.sklearn import TerrainClassifier

    expected = {
        "train": inspect.signature(presrs.Model.train).parameters["seed"].default,
        "eval": inspect.signature(presrs.evaluate).parameters["seed"].default,
        "simulate": inspect.signature(presrs.simulate).parameters["seed"].default,
    }
    for command, python_default in expected.items():
        assert python_default == _cli_default_seed(cli, command), command
    assert TerrainClassifier().seed == _cli_default_seed(cli, "train")
    for name in ("train", "evaluate", "simulate"):
        assert _stub_defaults(name) == _cli_default_seed(cli, "train"), name


def test_train_without_a_seed_is_train_with_seed_1(sim_images):
    images, labels, _ = sim_images
    options = dict(features="fft1d", classifier="lda", validation=0.35)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        default = presrs.Model.train(images, labels, **options)
        one = presrs.Model.train(images, labels, seed=1, **options)
    assert json.loads(default.to_json())["model"] == json.loads(one.to_json())["model"]
