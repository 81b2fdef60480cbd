"""Shared fixtures: the repository, the `presrs` command line (the same build as the package), a small
simulated data set made by the command line, and its stance images."""

import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import presrs

REPO = Path(__file__).resolve().parents[2]
SHARED = REPO.parent / "shared"


def _cli_path():
    """`PRESRS_CLI`, else the workspace's debug build (built here when missing)."""
    given = os.environ.get("PRESRS_CLI")
    if given:
        return Path(given)
    path = REPO / "target" / "debug" / "presrs"
    if not path.exists():
        subprocess.run(
            ["cargo", "build", "--quiet", "-p", "presrs-cli"], cwd=REPO, check=True
        )
    return path


@pytest.fixture(scope="session")
def cli():
    """Runs `presrs ARGS...` and returns its standard output (a failure fails the test)."""
    path = _cli_path()

    def run(*args, stdin=None):
        done = subprocess.run(
            [str(path), *map(str, args)],
            input=stdin,
            capture_output=True,
            check=False,
        )
        assert done.returncode == 0, done.stderr.decode()
        return done.stdout.decode()

    return run


@pytest.fixture(scope="session")
def sim_dir(tmp_path_factory, cli):
    """`presrs simulate`: 4 terrains x gait G2, 6 hops each, seed 3."""
    out = tmp_path_factory.mktemp("sim")
    cli("simulate", "--out", out, "--gaits", "G2", "--hops-per-gait", 6, "--seed", 3)
    return out


@pytest.fixture(scope="session")
def sim_images():
    """Stance images of simulated trials (4 terrains, gaits G1 and G2), labels and gaits."""
    trials = presrs.simulate(gaits=["G1", "G2"], hops=5, seed=2)
    images, labels, gaits = [], [], []
    for trial in trials:
        frames, stances = presrs.stance_images(trial.recording)
        images.append(frames)
        labels += [trial.terrain] * len(stances)
        gaits += [trial.gait] * len(stances)
    return np.concatenate(images), np.array(labels), np.array(gaits)


@pytest.fixture(scope="session")
def paper_model(sim_images):
    images, labels, _ = sim_images
    return presrs.Model.train(images, labels, features="fft1d", classifier="pwe", seed=1)


def json_lines(text):
    return [json.loads(line) for line in text.splitlines() if line.strip()]
