"""`Evaluation.to_dict()` is the document `presrs eval --json` prints: the same keys and the same values
for the same data, options and seed (timings aside, which no two runs share)."""

import json

import pytest

import presrs

# Measured times: they differ between any two runs, so only their presence and type are compared.
TIMINGS = {
    "median_classify_ns",
    "train_seconds",
    "features_seconds",
    "scoring_seconds",
    "final_fit_seconds",
}
# The command's own process: its peak memory, which a Python process (whose peak is the whole
# session's) does not report; and its warnings in the command line's words (Python's are
# `Evaluation.warnings()`, in its own).
CLI_ONLY = {"memory", "warnings"}


def _compare(ours, theirs, path="document"):
    """Asserts `ours` equals `theirs` key by key (floats to 1e-9), naming the first difference."""
    if isinstance(theirs, dict):
        assert isinstance(ours, dict), path
        assert sorted(ours) == sorted(theirs), f"{path}: keys differ"
        for key, value in theirs.items():
            if key in TIMINGS:
                assert type(ours[key]) is type(value), f"{path}.{key}"
                continue
            _compare(ours[key], value, f"{path}.{key}")
    elif isinstance(theirs, list):
        assert isinstance(ours, list) and len(ours) == len(theirs), path
        for i, (a, b) in enumerate(zip(ours, theirs)):
            _compare(a, b, f"{path}[{i}]")
    elif isinstance(theirs, float):
        assert ours == pytest.approx(theirs, rel=1e-9, abs=1e-12), path
    else:
        assert ours == theirs, path


@pytest.mark.parametrize(
    "method",
    [
        {"features": "fft1d", "classifier": "pwe"},
        # The automatic choice adds `selections` and `internal_estimate`; with no time budget its
        # choice does not depend on the machine's speed.
        {"features": "auto", "classifier": "lda"},
    ],
    ids=["fixed", "auto"],
)
def test_to_dict_is_the_eval_json_document(cli, sim_dir, method):
    manifest = sim_dir / "manifest.csv"
    ours = presrs.evaluate(
        manifest, per_class=3, repeats=2, seed=4, budget=None, **method
    ).to_dict()
    theirs = json.loads(
        cli(
            "eval", "--manifest", manifest, "--per-class", 3, "--repeats", 2, "--seed", 4,
            "--budget", 0, "--features", method["features"], "--classifier", method["classifier"],
            "--json",
        )
    )
    assert "overall_accuracy" in theirs and "report" in theirs
    assert ("selections" in theirs) == (method["features"] == "auto")
    assert theirs["memory"]["peak_bytes"] > 0
    _compare(ours, {key: value for key, value in theirs.items() if key not in CLI_ONLY})
