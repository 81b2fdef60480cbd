"""The package and the command line on the same model files and the same images: labels identical,
posteriors within 1e-9, in both directions; and the same evaluation and stream events."""

import json

import numpy as np
import pytest

import presrs
from conftest import json_lines


def _cli_results(cli, model_path, files):
    doc = json.loads(cli("classify", "--model", model_path, "--json", *files))
    return doc["results"]


def test_a_model_trained_in_python_classifies_alike_in_the_cli(
    cli, paper_model, sim_images, tmp_path
):
    model_path = tmp_path / "python-model.json"
    paper_model.save(model_path)
    images = sim_images[0][::3]
    files = []
    for i, image in enumerate(images):
        files.append(tmp_path / f"image{i:03d}.npy")
        np.save(files[-1], image)
    results = _cli_results(cli, model_path, files)
    assert len(results) == len(images)
    labels = paper_model.predict(images)
    posteriors = paper_model.predict_proba(images)
    classes = list(paper_model.classes_)
    for result, label, row in zip(results, labels, posteriors):
        assert result["label"] == label
        theirs = np.array([result["posteriors"][c] for c in classes])
        np.testing.assert_allclose(theirs, row, rtol=0, atol=1e-9)


def test_a_model_trained_by_the_cli_classifies_alike_in_python(cli, sim_dir, tmp_path):
    model_path = tmp_path / "cli-model.json"
    cli(
        "train", "--manifest", sim_dir / "manifest.csv", "--out", model_path,
        "--features", "fft1d", "--classifier", "pwe", "--seed", 2,
    )
    model = presrs.Model.load(model_path)
    files = sorted((sim_dir / "recordings").glob("*.asf"))[:6]
    results = _cli_results(cli, model_path, files)
    assert results
    recordings = {str(f): presrs.read(f) for f in files}
    classes = list(model.classes_)
    for result in results:
        frames = recordings[result["file"]].frames
        image = frames[result["frame"]]
        assert model.predict(image) == result["label"]
        theirs = np.array([result["posteriors"][c] for c in classes])
        np.testing.assert_allclose(model.predict_proba(image), theirs, rtol=0, atol=1e-9)
    # Python -> file -> Python keeps the file's content.
    again = tmp_path / "again.json"
    model.save(again)
    assert json.loads(again.read_text())["model"] == json.loads(model_path.read_text())["model"]


def test_evaluate_on_a_manifest_agrees_with_presrs_eval(cli, sim_dir):
    options = dict(per_class=3, repeats=2, seed=4, features="fft1d", classifier="pwe")
    ours = presrs.evaluate(sim_dir / "manifest.csv", **options)
    doc = json.loads(
        cli(
            "eval", "--manifest", sim_dir / "manifest.csv", "--per-class", 3,
            "--repeats", 2, "--seed", 4, "--features", "fft1d", "--classifier", "pwe",
            "--json",
        )
    )
    assert ours.accuracy == pytest.approx(doc["overall_accuracy"], abs=1e-12)
    assert ours.accuracy_std == pytest.approx(doc["overall_accuracy_std"], abs=1e-12)
    assert ours.confusion.sum() == sum(map(sum, doc["confusion"]["counts"]))


def test_the_online_classifier_gives_the_streams_events(cli, sim_dir, tmp_path):
    model_path = tmp_path / "online-model.json"
    cli(
        "train", "--manifest", sim_dir / "manifest.csv", "--out", model_path,
        "--features", "fft1d", "--classifier", "pwe", "--online-profile",
    )
    movie = sorted((sim_dir / "recordings").glob("*.asf"))[0]
    streamed = json_lines(cli("stream", "--model", model_path, stdin=movie.read_bytes()))
    online = presrs.OnlineClassifier(presrs.Model.load(model_path))
    assert not online.warming_up
    events = []
    recording = presrs.read(movie)
    # The stream times TekScan frames from the file's period; the Python face takes them as given.
    for index, frame in enumerate(recording.frames):
        events += online.push(frame, timestamp_us=round(index * recording.frame_period_s * 1e6))
    events += online.finish()
    drop = {"latency_us"}
    strip = lambda e: {k: v for k, v in e.items() if k not in drop}
    streamed = [strip(e) for e in streamed if e["event"] != "end"]
    ours = [strip(e) for e in events]
    assert [e["event"] for e in ours] == [e["event"] for e in streamed]
    for mine, theirs in zip(ours, streamed):
        assert mine.keys() == theirs.keys()
        for key in mine:
            if key == "posteriors":
                for c in mine[key]:
                    assert mine[key][c] == pytest.approx(theirs[key][c], abs=1e-9)
            elif key != "confidence":
                assert mine[key] == theirs[key], key
    assert online.stats["decisions"] == sum(e["event"] == "classification" for e in ours) > 0


def test_online_push_refuses_a_batch_and_names_the_frame(paper_model):
    online = presrs.OnlineClassifier(paper_model)
    with pytest.raises(presrs.DataError, match="one frame"):
        online.push(np.zeros((2, 44, 44)))
    online.push(np.zeros((44, 44)))
    with pytest.raises(presrs.DataError, match="frame 1"):
        online.push(np.zeros((10, 10)))


def test_evaluate_races_the_sample_kinds_as_presrs_eval_does(cli, sim_dir):
    """`sample="auto"`: the sample kinds raced inside every fold, the same document as the CLI's."""
    manifest = sim_dir / "manifest.csv"
    ours = presrs.evaluate(
        manifest, sample="auto", per_class=4, repeats=1, seed=4, classifier="lda", budget=0
    )
    doc = json.loads(
        cli(
            "eval", "--manifest", manifest, "--sample", "auto", "--per-class", 4,
            "--repeats", 1, "--seed", 4, "--classifier", "lda", "--budget", 0, "--json",
        )
    )
    mine = ours.to_dict()
    assert mine["sample_races"] == doc["sample_races"]
    assert [e["sample"] for e in mine["sample_races"][0]["entries"]] == ["frame", "stance"]
    assert ours.accuracy == pytest.approx(doc["overall_accuracy"], abs=1e-12)


def test_sample_auto_errors_name_python_arguments(sim_dir):
    # a fixed method has no validation score to race on
    with pytest.raises(presrs.DataError) as caught:
        presrs.evaluate(
            sim_dir / "manifest.csv", sample="auto", features="fft1d", classifier="pwe",
            per_class=4,
        )
    assert "sample=" in str(caught.value) and "--" not in str(caught.value)
    # arrays in memory are one reading
    with pytest.raises(presrs.DataError, match="manifest's path"):
        presrs.evaluate(np.zeros((4, 3, 3)), ["a", "b", "a", "b"], sample="auto")
