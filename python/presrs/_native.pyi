"""Type stubs of presrs's native module (the Rust extension behind `import presrs`)."""

from collections.abc import Callable, Sequence
from os import PathLike
from pathlib import Path
from typing import Any, Literal, Optional, Union

import numpy as np
import numpy.typing as npt

__version__: str
CLASSIFIERS: tuple[str, ...]
"""The classifier names ``classifier=`` takes besides ``"auto"`` (``"pwe"``, ``"lda"``, ...)."""
FEATURE_FAMILIES: tuple[str, ...]
"""The feature families ``features=`` takes besides ``"auto"``, alone or joined with ``+``."""

_Path = Union[str, PathLike[str]]
_Images = npt.ArrayLike
_Labels = Union[Sequence[Any], npt.ArrayLike]

class Recording:
    """A recording: frames of one pressure array, with what the file says about the sensor."""

    def __init__(self, frames: _Images, *, frame_period_s: Optional[float] = None) -> None: ...
    @property
    def frames(self) -> npt.NDArray[np.float64]:
        """float64 (n_frames, rows, cols), in the file's unit (a new array each time)."""
    @property
    def mask(self) -> npt.NDArray[np.bool_]:
        """(rows, cols), True where a sensel is absent (outside the sensor's outline)."""
    @property
    def frame_period_s(self) -> Optional[float]: ...
    @property
    def units(self) -> str: ...
    @property
    def units_stated(self) -> bool: ...
    @property
    def sensor(self) -> dict[str, Any]: ...
    @property
    def shape(self) -> tuple[int, int]: ...
    @property
    def path(self) -> Optional[Path]: ...
    @property
    def warnings(self) -> list[str]: ...
    def total_load(self) -> npt.NDArray[np.float64]: ...
    def __len__(self) -> int: ...

class Stance:
    """One stance phase; frames are 0-based."""

    start: int
    length: int
    end: int
    sample_frame: int
    peak_load: float
    peak_frame: int
    partial: bool

class Trial:
    """One simulated trial."""

    name: str
    terrain: str
    gait: str
    load_kg: float
    recording: Recording

class Model:
    """A trained terrain classifier (the CLI's model files)."""

    @staticmethod
    def train(
        images: _Images,
        labels: _Labels,
        *,
        features: str = "auto",
        classifier: str = "auto",
        groups: Optional[_Labels] = None,
        conditions: Optional[_Labels] = None,
        seed: int = 1,
        dims: Optional[int] = None,
        per_class: Optional[int] = None,
        validation: float = 0.35,
        crop: str = "auto",
        full_search: bool = False,
        validate_by: str = "auto",
        budget: Optional[float] = 60.0,
        choose: str = "auto",
        sample: Literal["frame", "stance", "series"] = "frame",
        stance_length: Optional[int] = None,
        series_axis: Optional[Literal["cols", "rows"]] = None,
        novelty: bool = True,
    ) -> Model:
        """Trains on images ``(n, rows, cols)`` (``sample="frame"``), on stances' movies (a sequence of
        ``(frames, rows, cols)`` arrays of any length, ``sample="stance"``: each summarised over time as
        ``presrs train --sample stance`` does, laid into ``stance_length`` frames, by default the
        longest's) or on series ``(n, channels, time)`` (``sample="series"``; ``series_axis="rows"``
        when time runs down the rows). A value that is not a finite number is an error naming its
        image, row and column; a missing label (``None``, NaN, empty or blank text) one naming its
        index. ``features``: ``"auto"`` or names of ``FEATURE_FAMILIES`` joined with ``+``;
        ``classifier``: ``"auto"`` or a name of ``CLASSIFIERS``."""
    @staticmethod
    def load(path: _Path) -> Model: ...
    def save(self, path: _Path) -> None:
        """Writes the model file atomically, after checking that its folder exists and accepts it."""
    def to_json(self) -> str: ...
    @staticmethod
    def from_json(data: Union[str, bytes]) -> Model: ...
    def predict(self, x: Any, *, novelty: bool = True) -> Any:
        """A `str` for one sample; an array of labels for a batch. A sample is what the model was
        trained on (`sample`): an image (rows, cols), batch (n, rows, cols); a stance's movie
        (frames, rows, cols), batch a list of movies; a series (channels, time), batch
        (n, channels, time). With a model that scores novelty, a sample far from every class is
        ``"unknown"``; ``novelty=False`` names one of the classes for every sample."""
    def novelty(self, x: Any) -> Any:
        """The novelty score: a `float` for one sample, an array for a batch (in [0, 1]: 1 - the
        nearest class's posterior x the credibility of the distance to the nearest training sample, in
        the model's discriminant space; older models: that distance); above `novelty_threshold`, `predict` says
        ``"unknown"``. An error for a model without a novelty score."""
    def confidence(self, x: Any) -> Any:
        """The confidence a decision reports: a `float` for one sample, an array for a batch (the
        posterior of the class `predict_index` names, capped by the sample's credibility when the model
        scores novelty). `predict_proba` gives the classifier's own posteriors."""
    @property
    def novelty_threshold(self) -> Optional[float]:
        """The score above which a sample is ``"unknown"``; `None` without a novelty score."""
    def predict_index(self, x: Any) -> Any:
        """The index in `classes_` of the label: an `int` for one sample, an integer array for a
        batch (`predict` without making the labels)."""
    def predict_proba(self, x: Any) -> npt.NDArray[np.float64]:
        """(n_classes,) for one sample; (n, n_classes) for a batch."""
    @property
    def sample(self) -> Literal["frame", "stance", "series"]:
        """What a sample is for this model."""
    @property
    def classes_(self) -> npt.NDArray[np.str_]: ...
    @property
    def cropped_shape(self) -> tuple[int, int]: ...
    @property
    def has_online_profile(self) -> bool: ...
    def describe(self) -> str: ...

class Evaluation:
    """What an evaluation measured."""

    @property
    def accuracy(self) -> float: ...
    @property
    def accuracy_std(self) -> float: ...
    @property
    def per_condition(self) -> dict[str, tuple[float, float]]: ...
    @property
    def repeats(self) -> list[float]: ...
    @property
    def classes(self) -> list[str]: ...
    @property
    def confusion(self) -> npt.NDArray[np.uint64]: ...
    @property
    def calibration(self) -> dict[str, Optional[float]]: ...
    @property
    def classify_us(self) -> float: ...
    @property
    def warnings(self) -> list[str]: ...
    def to_dict(self) -> dict[str, Any]: ...

class OnlineClassifier:
    """Frames in one at a time, `presrs stream`'s events out (as dicts)."""

    def __init__(
        self,
        model: Model,
        *,
        gait_table: Optional[dict[str, str]] = None,
        decide_at: Optional[int] = None,
        novelty: bool = True,
    ) -> None: ...
    def push(self, frame: _Images, *, timestamp_us: Optional[int] = None) -> list[dict[str, Any]]: ...
    def finish(self) -> list[dict[str, Any]]: ...
    @property
    def warming_up(self) -> bool: ...
    @property
    def stats(self) -> dict[str, int]: ...

def read(
    path: _Path, *, lenient: bool = False, axes: Optional[str] = None, topic: Optional[str] = None
) -> Recording: ...
def segment(
    recording: Union[Recording, _Images],
    *,
    sample: Union[Literal["mid", "peak"], int, None] = None,
    **params: Any,
) -> list[Stance]: ...
def segment_params() -> dict[str, Any]: ...
def features(
    images: _Images, family: str = "fft1d", crop: str = "auto"
) -> npt.NDArray[np.float64]: ...
def evaluate(
    data: Union[_Path, _Images],
    labels: Optional[_Labels] = None,
    *,
    groups: Optional[_Labels] = None,
    conditions: Optional[_Labels] = None,
    leave_one_out: Optional[str] = None,
    train_condition: Optional[str] = None,
    per_class: Optional[int] = None,
    validation: float = 0.35,
    repeats: int = 10,
    seed: int = 1,
    features: str = "auto",
    classifier: str = "auto",
    dims: Optional[int] = None,
    crop: str = "auto",
    full_search: bool = False,
    validate_by: str = "auto",
    budget: Optional[float] = 60.0,
    choose: str = "auto",
    sample: Literal["frame", "stance", "series", "auto"] = "frame",
    stance_length: Optional[int] = None,
    series_axis: Optional[Literal["cols", "rows"]] = None,
    stance_frame: Union[Literal["mid", "peak", "all"], int, None] = None,
    include_partial: bool = False,
    one_sample_per_file: bool = False,
    segment_params: Optional[dict[str, Any]] = None,
    lenient: bool = False,
    axes: Optional[str] = None,
    topic: Optional[str] = None,
    frame_period_s: Optional[float] = None,
    keep_dead_sensels: bool = False,
    progress: Union[bool, Callable[[str, int, Optional[int]], Any], None] = None,
) -> Evaluation:
    """``presrs eval`` on a manifest's path or on samples in memory. ``sample`` and the arguments
    after it are its sample options in Python's words (``segment_params``: the stance detector's
    settings, a dict of ``segment_params()``'s names); those after ``series_axis`` read a manifest's
    files."""
def simulate(
    *,
    terrains: Optional[Sequence[str]] = None,
    gaits: Optional[Sequence[str]] = None,
    hops: Optional[int] = None,
    seed: int = 1,
    load_kg: Optional[float] = None,
    config: Optional[_Path] = None,
) -> list[Trial]: ...
