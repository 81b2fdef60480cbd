"""Unknown terrain in Python: a model trained on recordings named by `groups` scores novelty and calls a
new recording of a known terrain known; without groups it has no score and says why."""

import warnings

import numpy as np
import pytest

import presrs


def _stances(terrains, seeds, hops=8):
    """Stance images of simulated trials (gait G2), their terrains and their trials as groups."""
    images, labels, groups = [], [], []
    for seed in seeds:
        for trial in presrs.simulate(terrains=terrains, gaits=["G2"], hops=hops, seed=seed):
            frames, stances = presrs.stance_images(trial.recording)
            images.append(frames)
            labels += [trial.terrain] * len(stances)
            groups += [f"{trial.terrain}, seed {seed}"] * len(stances)
    return np.concatenate(images), labels, groups


KNOWN = ["wood", "clay", "grass"]


@pytest.fixture(scope="module")
def scored():
    images, labels, groups = _stances(KNOWN, seeds=(1, 2, 3))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no "no novelty score" warning with groups
        return presrs.Model.train(
            images, labels, groups=groups, features="fft1d", classifier="pwe", seed=1
        )


def test_a_new_recording_of_a_known_terrain_is_known_and_unknown_follows_the_score(scored):
    assert scored.novelty_threshold is not None and scored.novelty_threshold > 0
    known, truth, _ = _stances(KNOWN, seeds=(11,))
    labels = scored.predict(known)
    scores = scored.novelty(known)
    assert np.all(np.isfinite(scores))
    # `unknown` exactly where the score passes the threshold.
    assert list(labels == "unknown") == list(scores > scored.novelty_threshold)
    assert np.mean(labels == "unknown") <= 0.2, labels
    decided = labels != "unknown"
    assert np.mean(labels[decided] == np.array(truth)[decided]) >= 0.8
    # novelty=False names a trained class for every sample.
    assert set(scored.predict(known, novelty=False)) <= set(KNOWN)
    # A terrain never trained on lies farther from the training data than a new recording of a known one.
    novel, _, _ = _stances(["carpet"], seeds=(11,))
    assert np.median(scored.novelty(novel)) > np.median(scores)


def test_the_reported_confidence_is_the_posterior_capped_by_the_credibility(scored):
    known, _, _ = _stances(KNOWN, seeds=(12,), hops=4)
    confidence = scored.confidence(known)
    posteriors = scored.predict_proba(known)
    chosen = posteriors[np.arange(len(known)), scored.predict_index(known)]
    assert confidence.shape == (len(known),)
    assert np.all(confidence <= chosen + 1e-12) and np.all(confidence > 0)
    assert np.any(confidence < chosen)  # the cap binds somewhere
    assert scored.confidence(known[0]) == pytest.approx(confidence[0])


def test_without_groups_there_is_no_score_and_a_warning_says_why():
    images, labels, _ = _stances(KNOWN, seeds=(1,), hops=6)
    with pytest.warns(UserWarning) as caught:
        model = presrs.Model.train(images, labels, features="fft1d", classifier="pwe", seed=1)
    said = " ".join(str(w.message) for w in caught)
    assert "no novelty score" in said and "group" in said, said
    assert "--" not in said  # no command-line flag in a Python warning
    assert model.novelty_threshold is None
    with pytest.raises(presrs.DataError, match="no novelty score"):
        model.novelty(images)
    assert "unknown" not in set(model.predict(images))
    np.testing.assert_allclose(model.confidence(images), model.predict_proba(images).max(axis=1))
