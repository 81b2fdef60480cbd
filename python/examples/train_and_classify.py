"""Train a terrain classifier on the simulator, then classify a recording stance by stance.

    python python/examples/train_and_classify.py                 # a simulated test walk
    python python/examples/train_and_classify.py walk.asf        # your own 44x44 movie (any format)
    python python/examples/train_and_classify.py walk.asf model.json   # and keep the model

The model file is the command line's: `presrs classify --model model.json walk.asf` gives the same
labels.
"""

import sys

import numpy as np

import presrs


def training_images(seeds=(1, 2, 3)):
    """Mid-stance images of the hopper on the four built-in terrains, gait G2, with their terrains and
    the trial (recording) each came from: the novelty threshold is learned by holding out whole
    recordings, so that a new recording of a known terrain is not called unknown."""
    images, labels, groups = [], [], []
    for seed in seeds:
        for trial in presrs.simulate(gaits=["G2"], hops=10, seed=seed):
            frames, stances = presrs.stance_images(trial.recording)
            images.append(frames)
            labels += [trial.terrain] * len(stances)
            groups += [f"{trial.terrain}, seed {seed}"] * len(stances)
    return np.concatenate(images), labels, groups


def main():
    images, labels, groups = training_images()
    model = presrs.Model.train(
        images, labels, groups=groups, features="fft1d", classifier="pwe", seed=1
    )
    print(f"trained on {len(images)} images:")
    print(model.describe())
    if len(sys.argv) > 2:
        model.save(sys.argv[2])
        print(f"model written to {sys.argv[2]}")

    if len(sys.argv) > 1:
        recording, truth = presrs.read(sys.argv[1]), None
    else:
        trial = presrs.simulate(terrains=["clay"], gaits=["G2"], hops=5, seed=7)[0]
        recording, truth = trial.recording, trial.terrain
    print(f"\n{recording}" + (f" (truly {truth})" if truth else ""))

    frames, stances = presrs.stance_images(recording)
    if not stances:
        print("no complete stance phase found: nothing to classify")
        return
    # "unknown" for a stance unlike every trained terrain; the confidence is the one decisions report.
    labels = model.predict(frames)
    confidences = model.confidence(frames)
    for stance, label, confidence in zip(stances, labels, confidences):
        print(
            f"stance at frame {stance.start:4d} ({stance.length} frames): {label} "
            f"({100 * confidence:.1f} %)"
        )
    values, counts = np.unique(labels, return_counts=True)
    print(f"most stances: {values[counts.argmax()]}")


if __name__ == "__main__":
    main()
