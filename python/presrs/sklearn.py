"""A scikit-learn estimator over :class:`presrs.Model`, for ``cross_val_score``, ``GridSearchCV`` and
pipelines.

``X`` is images ``(n, rows, cols)``, or a 2-D matrix ``(n, rows * cols)`` of flattened images with
``image_shape=(rows, cols)`` (scikit-learn's tools pass 2-D data; ``image_shape=(1, -1)`` takes each
row as a one-row image, whatever its length). A 2-D ``X`` without ``image_shape`` is refused rather than
guessed. Once fitted, ``predict`` also takes one image ``(rows, cols)`` of the training images' shape
(and gives one label, in an array of one).

With ``sample="stance"``, ``X`` is a sequence of movies ``(frames, rows, cols)`` (one per stance, of
any length); with ``sample="series"``, series ``(n, channels, time)``.

Labels may be any values: ``classes_`` keeps them (strings stay strings, ints ints), and the model
(``model_``, and the file ``model_.save`` writes) names its classes ``str(label)``.
"""

from __future__ import annotations

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data

from ._native import Model, _check_labels
from .errors import DataError

__all__ = ["TerrainClassifier"]


def _check_missing_labels(y):
    """An error naming the first missing label of ``y`` (``None``, NaN, empty or blank text), as
    :meth:`presrs.Model.train` refuses them; other checks of ``y`` are scikit-learn's."""
    if y is None:
        return
    labels = np.asarray(y, dtype=object)
    if labels.ndim == 2 and labels.shape[1] == 1:
        labels = labels[:, 0]
    if labels.ndim == 1:
        _check_labels(labels, "y")


class TerrainClassifier(ClassifierMixin, BaseEstimator):
    """presrs's pipeline (crop, features, PCA, classifier; ridge takes every feature, without the PCA) as a
    scikit-learn classifier.

    Parameters are those of :meth:`presrs.Model.train`: ``features`` and ``classifier`` take the
    command line's names (``"auto"`` chooses by validation), ``dims`` the principal components kept
    (not used by ridge, which has no PCA step),
    ``validation`` the share (or count) of each class that validates the hyper-parameters, ``seed`` the
    random draw (1 by default, as the command line's). ``image_shape`` says how to unflatten a 2-D ``X`` (one of its sizes may be ``-1``);
    ``validate_by`` how the automatic choice validates (``auto``, ``group``, ``condition``, ``split``;
    give ``groups`` to ``fit``); ``budget`` the seconds it may spend (``None``: no limit, the choice
    independent of the machine); ``choose`` how it picks (``best``; ``one-se``: the earliest
    candidate within one standard error of the best; ``auto``, the default: ``one-se`` on stances and
    series, ``best`` on frames). ``sample`` (``frame``, ``stance``, ``series``),
    ``stance_length`` and ``series_axis``: what a sample is, as in :meth:`presrs.Model.train`.
    """

    def __init__(
        self,
        features="auto",
        classifier="auto",
        dims=None,
        validation=0.35,
        crop="auto",
        full_search=False,
        seed=1,
        image_shape=None,
        validate_by="auto",
        budget=60.0,
        choose="auto",
        sample="frame",
        stance_length=None,
        series_axis=None,
    ):
        self.features = features
        self.classifier = classifier
        self.dims = dims
        self.validation = validation
        self.crop = crop
        self.full_search = full_search
        self.seed = seed
        self.image_shape = image_shape
        self.validate_by = validate_by
        self.budget = budget
        self.choose = choose
        self.sample = sample
        self.stance_length = stance_length
        self.series_axis = series_axis

    def _unflatten(self, X):
        """A 2-D ``X`` of flattened images as images ``(n, rows, cols)``, by ``image_shape``."""
        if self.image_shape is None:
            raise DataError(
                f"X is 2-D {X.shape}: give image_shape=(rows, cols) to read each row as an image "
                f"of rows x cols (image_shape=(1, -1) takes each row as a one-row image), or pass "
                f"images as a 3-D array (n, rows, cols)"
            )
        try:
            rows, cols = (int(v) for v in self.image_shape)
        except (TypeError, ValueError):
            raise DataError(
                f"image_shape={self.image_shape!r}: give two sizes (rows, cols), one of them "
                f"perhaps -1"
            ) from None
        n_values = X.shape[1]
        if rows == -1 and cols > 0 and n_values % cols == 0:
            rows = n_values // cols
        elif cols == -1 and rows > 0 and n_values % rows == 0:
            cols = n_values // rows
        if rows <= 0 or cols <= 0 or rows * cols != n_values:
            raise DataError(
                f"image_shape={tuple(self.image_shape)} does not fit X's {n_values} features per "
                f"sample (rows x cols must be {n_values})"
            )
        return X.reshape(X.shape[0], rows, cols)

    def _images(self, X):
        """``X`` as images ``(n, rows, cols)`` float64."""
        if X.ndim == 3:
            return X
        return self._unflatten(X)

    def fit(self, X, y, groups=None, conditions=None):
        """Trains on images ``X`` with labels ``y`` (and, optionally, one group and one condition per
        image). A missing label (``None``, NaN, empty or blank text) is an error naming its index."""
        _check_missing_labels(y)
        if self.sample == "stance":
            movies = X
            y = np.asarray(y)
        else:
            X, y = validate_data(
                self,
                X,
                y,
                allow_nd=True,
                dtype=np.float64,
                ensure_min_samples=2,
                # presrs names the image and the sensel that is not a number.
                ensure_all_finite=False,
            )
            movies = self._images(X)
        check_classification_targets(y)
        self.classes_ = np.unique(y)
        if len(self.classes_) < 2:
            raise ValueError(
                f"TerrainClassifier needs at least 2 classes, got {len(self.classes_)}"
            )
        names = [str(c) for c in self.classes_]
        if len(set(names)) != len(names):
            raise DataError(
                "y: two classes have the same text (e.g. 1 and '1'); the model names classes by "
                "their text"
            )
        self.model_ = Model.train(
            movies,
            [str(label) for label in y],
            features=self.features,
            classifier=self.classifier,
            dims=self.dims,
            validation=self.validation,
            crop=self.crop,
            full_search=self.full_search,
            seed=self.seed,
            validate_by=self.validate_by,
            budget=self.budget,
            choose=self.choose,
            groups=groups,
            conditions=conditions,
            sample=self.sample,
            stance_length=self.stance_length,
            series_axis=self.series_axis,
        )
        # The model's classes are the labels' texts, sorted as text: column j of its posteriors is
        # classes_[_columns[j]].
        position = {name: i for i, name in enumerate(names)}
        self._columns = np.array([position[c] for c in self.model_.classes_])
        self._labels = self.classes_[self._columns]
        self._image_shape = None if self.sample == "stance" else movies.shape[1:]
        return self

    def _samples(self, X):
        """``X`` as the model takes a batch, after the checks scikit-learn asks for. A C-contiguous
        float64 array of the training images' shape (or one such image) skips scikit-learn's
        validation, which copies and costs more than classifying one image."""
        if getattr(self, "model_", None) is None:
            check_is_fitted(self)
        if self.sample == "stance":
            if getattr(X, "ndim", None) == 3:
                return [X]
            return X
        shape = self._image_shape
        if type(X) is np.ndarray and X.dtype == np.float64 and X.flags.c_contiguous:
            if X.shape == shape:
                return X[None]
            if X.ndim == 3 and X.shape[1:] == shape:
                return X
        if X is None:
            raise DataError("X: expected images (n, rows, cols), got None")
        self._check_image_shape(X)
        if getattr(X, "ndim", None) == 2 and tuple(X.shape) == tuple(shape):
            X = np.asarray(X, dtype=np.float64)[None]
        X = validate_data(
            self, X, allow_nd=True, dtype=np.float64, reset=False, ensure_all_finite=False
        )
        return self._images(X)

    def _check_image_shape(self, X):
        """An error unless ``X``'s images have the training images' rows and columns (scikit-learn's
        own check would count a 3-D ``X``'s rows as its features)."""
        shape = self._image_shape
        try:
            given = np.asarray(X).shape
        except ValueError:  # ragged: numpy's conversion names it below
            return
        (rows, cols) = shape
        if len(given) == 3 and tuple(given[1:]) != tuple(shape):
            raise DataError(
                f"X: images of {given[1]} x {given[2]} (rows x cols), but the model was trained on "
                f"images of {rows} x {cols}"
            )
        if len(given) == 2 and self.image_shape is None and tuple(given) != tuple(shape):
            raise DataError(
                f"X: one image of {given[0]} x {given[1]} (rows x cols), but the model was trained "
                f"on images of {rows} x {cols} (give a batch (n, {rows}, {cols}), or image_shape= "
                f"to read each row of a 2-D X as an image)"
            )

    def predict_proba(self, X):
        """The posterior of every class, ``(n, n_classes)`` in ``classes_`` order."""
        samples = self._samples(X)
        posteriors = self.model_.predict_proba(samples)
        out = np.empty_like(posteriors)
        out[:, self._columns] = posteriors
        return out

    def predict(self, X):
        """The label of every image, as given in ``y``."""
        samples = self._samples(X)
        return self._labels[self.model_.predict_index(samples)]

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.input_tags.three_d_array = True
        return tags
