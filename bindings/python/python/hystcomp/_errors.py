"""The exceptions hystcomp raises. Every one carries the library's message, which says what is
wrong and what to change. Files that cannot be read or written raise the built-in ``OSError``
subclasses (``FileNotFoundError``, ``PermissionError``, ...) instead."""

__all__ = [
    "HystcompError",
    "InvalidValueError",
    "NotInvertibleError",
    "UnstableDelayError",
    "WrongDirectionError",
    "ModelFileError",
    "IdentificationError",
    "StageConfigError",
    "LearningStoppedError",
    "LearningDivergedWarning",
]


class HystcompError(Exception):
    """Base class of every hystcomp error (besides ``OSError`` for files)."""


class InvalidValueError(HystcompError, ValueError):
    """An argument is unusable: NaN or infinite values, arrays of different lengths, negative or
    unsorted thresholds, limits that are not finite and increasing, an unknown name."""


class NotInvertibleError(InvalidValueError):
    """The model cannot be inverted (or used by the method) over the range asked for: a branch
    slope is not positive, the PI part has no eq. (7) inverse, or ``a2 <= 0`` for WIHC."""


class UnstableDelayError(NotInvertibleError):
    """A plain one-sample-delayed method (``"ihc-delayed"``, ``"wihc-delayed"``) was asked for
    on a model whose delayed loop gain over the limits is 1 or more, so the loop can ring
    between the limits. Use the exact method, the guarded one (``"ihc-guarded"``,
    ``"wihc-guarded"``), or pass ``allow_unstable_delay=True``."""


class WrongDirectionError(InvalidValueError):
    """The model maps the other direction from the one the method needs (IHC and WIHC need a
    plant model, DIHC an inverse model)."""


class ModelFileError(HystcompError, ValueError):
    """A model file's text is not a valid hystcomp model file (not JSON, another format version,
    a missing or mistyped field, invalid scales)."""


class IdentificationError(HystcompError, ValueError):
    """No model could be identified from the data (ill-conditioned regressors, infeasible
    constraints, a solver failure)."""


class StageConfigError(HystcompError, ValueError):
    """A stage file (TOML) does not parse or holds a physically impossible value."""


class LearningStoppedError(HystcompError, RuntimeError):
    """The divergence guard stopped the learning earlier (``Learner.stopped``): the learner
    refuses further updates; its ``drive`` is the last good one. Start a new ``Learner`` with a
    lower gain or bandwidth."""


class LearningDivergedWarning(UserWarning):
    """A trial's RMS error exceeded the divergence factor times the best trial's: the learning
    stopped, and ``Learner.update`` returned the last good drive instead of a new one."""


for _cls in (
    HystcompError,
    InvalidValueError,
    NotInvertibleError,
    UnstableDelayError,
    WrongDirectionError,
    ModelFileError,
    IdentificationError,
    StageConfigError,
    LearningStoppedError,
    LearningDivergedWarning,
):
    _cls.__module__ = "hystcomp"
del _cls
