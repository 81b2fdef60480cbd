"""A scikit-learn estimator over :class:`presrs.Model`, for ``cross_val_score``, ``GridSearchCV`` and
pipelines.

``X`` is images ``(n, rows, cols)``, or a 2-D matrix ``(n, rows * cols)`` of flattened images with
``image_shape=(rows, cols)`` (scikit-learn's tools pass 2-D data). Without ``image_shape`` each row of
a 2-D ``X`` is taken as a one-row image. Labels may be any values; ``classes_`` keeps them.
"""

from __future__ import annotations

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data

from ._native import Model

__all__ = ["TerrainClassifier"]


class TerrainClassifier(ClassifierMixin, BaseEstimator):
    """presrs's pipeline (crop, features, PCA, classifier) as a scikit-learn classifier.

    Parameters are those of :meth:`presrs.Model.train`: ``features`` and ``classifier`` take the
    command line's names (``"auto"`` chooses by validation), ``dims`` the principal components kept,
    ``validation`` the share (or count) of each class that validates the hyper-parameters, ``seed`` the
    random draw. ``image_shape`` says how to unflatten a 2-D ``X``; ``validate_by`` how the automatic
    choice validates (``auto``, ``group``, ``condition``, ``split``; give ``groups`` to ``fit``);
    ``budget`` the seconds it may spend (``None``: no limit, the choice independent of the machine);
    ``choose`` how it picks (``best``, or ``one-se``: the earliest candidate within one standard error).
    """

    def __init__(
        self,
        features="auto",
        classifier="auto",
        dims=None,
        validation=0.35,
        crop="auto",
        full_search=False,
        seed=0,
        image_shape=None,
        validate_by="auto",
        budget=60.0,
        choose="best",
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

    def _images(self, X):
        """``X`` as images ``(n, rows, cols)`` float64."""
        if X.ndim == 3:
            return X
        shape = self.image_shape if self.image_shape is not None else (1, X.shape[1])
        rows, cols = shape
        if rows * cols != X.shape[1]:
            raise ValueError(
                f"image_shape={tuple(shape)} holds {rows * cols} values but X has "
                f"{X.shape[1]} features per sample"
            )
        return X.reshape(X.shape[0], rows, cols)

    def fit(self, X, y, groups=None, conditions=None):
        """Trains on images ``X`` with labels ``y`` (and, optionally, one group and one condition per
        image)."""
        X, y = validate_data(
            self, X, y, allow_nd=True, dtype=np.float64, ensure_min_samples=2
        )
        check_classification_targets(y)
        self.classes_, encoded = np.unique(y, return_inverse=True)
        if len(self.classes_) < 2:
            raise ValueError(
                f"TerrainClassifier needs at least 2 classes, got {len(self.classes_)}"
            )
        # Class indices as fixed-width text: the model's class order is then classes_'s order.
        width = len(str(len(self.classes_)))
        labels = [f"{i:0{width}d}" for i in encoded]
        self.model_ = Model.train(
            self._images(X),
            labels,
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
        )
        self._columns = np.array([int(c) for c in self.model_.classes_])
        return self

    def predict_proba(self, X):
        """The posterior of every class, ``(n, n_classes)`` in ``classes_`` order."""
        check_is_fitted(self)
        X = validate_data(self, X, allow_nd=True, dtype=np.float64, reset=False)
        posteriors = self.model_.predict_proba(self._images(X))
        out = np.zeros((posteriors.shape[0], len(self.classes_)))
        out[:, self._columns] = posteriors
        return out

    def predict(self, X):
        """The label of every image, as given in ``y``."""
        posteriors = self.predict_proba(X)
        return self.classes_[np.argmax(posteriors, axis=1)]

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.input_tags.three_d_array = True
        return tags
