"""presrs: terrain identification from high-resolution pressure images.

Read recordings in any format the ``presrs`` command line reads, find their stance phases, compute
features, train and evaluate classifiers on numpy arrays, and classify one image or a batch at native
speed, with the same model files as the command line::

    import presrs
    rec = presrs.read("walk.asf")
    stances = presrs.segment(rec)
    model = presrs.Model.load("model.json")
    model.predict(rec.frames[stances[0].sample_frame])

``presrs.sklearn.TerrainClassifier`` is a scikit-learn estimator over :class:`Model`.
"""

from ._native import (
    CLASSIFIERS,
    FEATURE_FAMILIES,
    Evaluation,
    Model,
    OnlineClassifier,
    Recording,
    Stance,
    Trial,
    __version__,
    evaluate,
    features,
    read,
    segment,
    segment_params,
    simulate,
)
from .errors import DataError, FileError, PresrsError


def stance_images(recording, *, include_partial=False, sample=None, **params):
    """The sample frame of every stance of ``recording`` as one array ``(n, rows, cols)``, with the
    stances they come from: what a data set takes from a movie. Partial stances (cut by the start or
    end of the recording) are left out unless ``include_partial``."""
    import numpy as np

    stances = [
        s
        for s in segment(recording, sample=sample, **params)
        if include_partial or not s.partial
    ]
    frames = recording.frames
    if not stances:
        return np.empty((0,) + frames.shape[1:]), stances
    return frames[[s.sample_frame for s in stances]], stances


__all__ = [
    "CLASSIFIERS",
    "FEATURE_FAMILIES",
    "DataError",
    "Evaluation",
    "FileError",
    "Model",
    "OnlineClassifier",
    "PresrsError",
    "Recording",
    "Stance",
    "Trial",
    "__version__",
    "evaluate",
    "features",
    "read",
    "segment",
    "segment_params",
    "simulate",
    "stance_images",
]
