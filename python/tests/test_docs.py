"""The README's Python quick start and the example script run as written."""

import os
import re
import subprocess
import sys

from conftest import REPO, SHARED


def _python_blocks(markdown):
    return re.findall(r"```python\n(.*?)```", markdown, flags=re.S)


def _checkout_like(tmp_path):
    """A working folder with ../shared beside it, as in a clone; the README runs from there."""
    work = tmp_path / "checkout"
    work.mkdir()
    (tmp_path / "shared").symlink_to(SHARED)
    return work


def test_the_readmes_python_quick_start(tmp_path):
    blocks = _python_blocks((REPO / "README.md").read_text())
    assert blocks, "the README has no Python example"
    work = _checkout_like(tmp_path)
    for block in blocks:
        done = subprocess.run(
            [sys.executable, "-c", block], cwd=work, capture_output=True, text=True, check=False
        )
        assert done.returncode == 0, done.stderr
    assert (work / "model.json").exists() and (work / "walk.npy").exists()


def test_the_packages_readme_example(tmp_path):
    blocks = _python_blocks((REPO / "python" / "README.md").read_text())
    assert blocks
    for block in blocks:
        done = subprocess.run(
            [sys.executable, "-c", block], cwd=tmp_path, capture_output=True, text=True, check=False
        )
        assert done.returncode == 0, done.stderr


def test_the_example_script_trains_and_classifies(tmp_path):
    script = REPO / "python" / "examples" / "train_and_classify.py"
    model = tmp_path / "model.json"
    movie = tmp_path / "walk.npy"
    import numpy as np

    import presrs

    trial = presrs.simulate(terrains=["grass"], gaits=["G2"], hops=4, seed=11)[0]
    np.save(movie, trial.recording.frames)
    done = subprocess.run(
        [sys.executable, str(script), str(movie), str(model)],
        capture_output=True, text=True, check=False, env=dict(os.environ),
    )
    assert done.returncode == 0, done.stderr
    assert "most stances: grass" in done.stdout
    assert model.exists()
