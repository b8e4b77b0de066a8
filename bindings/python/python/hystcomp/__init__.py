"""hystcomp: feedforward hysteresis compensation of piezoelectric nanopositioners.

After G.-Y. Gu and L.-M. Zhu, "Comparative experiments regarding approaches to feedforward
hysteresis compensation for piezoceramic actuators", Smart Mater. Struct. 23 (2014) 095029,
doi:10.1088/0964-1726/23/9/095029. Equation numbers refer to that paper.

Systems are objects with a one-sample ``step`` and a whole-signal ``process`` (numpy arrays in
and out):

- ``Mpim``: the modified Prandtl-Ishlinskii model, eq. (4), in normalised units;
- ``ModelFile``: an identified model with its physical scales (JSON), ``Scale``;
- ``Compensator`` and its shorthands ``Ihc``, ``Wihc``, ``Dihc``: desired position in, drive
  voltage out, never outside the limits;
- ``CompensatorBank``: many channels (a multi-axis stage, a deformable mirror) stepped
  together, ``step`` over shape ``(channels,)``, ``process`` over ``(samples, channels)``;
- ``identify(voltage, displacement, ...)``: a model from measured data (least squares or
  particle swarm);
- ``Stage``: a simulated piezo stage, ``stage.run(volts)`` returning a ``StageResponse``
  (``.time``, ``.inputs``, ``.outputs``, the internal signals; unpacks as ``t, y = ...``),
  plotted by ``plot_response``;
- ``e_m``, ``e_rms``, ``e_mhe``, ``tracking_indices``: the indices of section 4.3;
- ``reproduce()``: the paper's comparative study (Table 3) on the simulated stage;
- ``Learner``: iterative learning feedforward for a repeated motion, ``drive =
  learner.update(measured)`` between trials.

Reports are dataclasses with the fields of the command line's JSON: ``FitReport``
(``Identification.report``), ``Diagnostics``, ``Clamps``, ``StudySummary``, ``LearningUpdate``, ``LearningLaw``.

Errors are ``HystcompError`` subclasses (also ``ValueError``) or ``OSError`` for files.
"""

from __future__ import annotations

from typing import Optional, Sequence

from ._errors import (
    HystcompError,
    IdentificationError,
    InvalidValueError,
    LearningDivergedWarning,
    LearningStoppedError,
    ModelFileError,
    NotInvertibleError,
    StageConfigError,
    UnstableDelayError,
    WrongDirectionError,
)
from ._plot import plot_response
from ._reports import (
    AcceptanceCheck,
    Clamps,
    Diagnostics,
    ErrorStats,
    FitReport,
    Indices,
    LearningLaw,
    LearningUpdate,
    PipelineSummary,
    RunSummary,
    SampleCounts,
    SeriesFile,
    SignalRange,
    StudySummary,
)
from ._hystcomp import (
    DEFAULT_MHE_BINS,
    Compensator,
    CompensatorBank,
    Identification,
    Learner,
    ModelFile,
    Mpim,
    Prediction,
    Scale,
    Stage,
    StageResponse,
    StudyResult,
    TrackingIndices,
    __version__,
    e_m,
    e_mhe,
    e_rms,
    identify,
    paper_trajectory,
    predict,
    reproduce,
    tracking_indices,
)

__all__ = [
    "AcceptanceCheck",
    "Clamps",
    "Diagnostics",
    "ErrorStats",
    "FitReport",
    "Indices",
    "LearningLaw",
    "LearningUpdate",
    "PipelineSummary",
    "RunSummary",
    "SampleCounts",
    "SeriesFile",
    "SignalRange",
    "StudySummary",
    "plot_response",
    "DEFAULT_MHE_BINS",
    "Compensator",
    "CompensatorBank",
    "Dihc",
    "HystcompError",
    "Identification",
    "IdentificationError",
    "Ihc",
    "InvalidValueError",
    "Learner",
    "LearningDivergedWarning",
    "LearningStoppedError",
    "ModelFile",
    "ModelFileError",
    "Mpim",
    "NotInvertibleError",
    "Prediction",
    "Scale",
    "Stage",
    "StageConfigError",
    "StageResponse",
    "StudyResult",
    "TrackingIndices",
    "UnstableDelayError",
    "Wihc",
    "WrongDirectionError",
    "__version__",
    "e_m",
    "e_mhe",
    "e_rms",
    "identify",
    "paper_trajectory",
    "predict",
    "reproduce",
    "tracking_indices",
]


def _family_method(family: str, delayed: bool, guarded: bool) -> str:
    if guarded:
        return family + "-guarded"
    return family + "-delayed" if delayed else family


class Ihc(Compensator):
    """Inverse hysteresis compensation (section 3.1, eqs. (5)-(8)) from a plant model:
    ``Compensator(model, "ihc", "ihc-delayed" or "ihc-guarded", limits)``.

    With ``delayed=True`` the cubic term uses the previous output ``v(t - Ts)``, as real-time
    implementations do (refused with ``UnstableDelayError`` when that loop can oscillate on the
    model, unless ``allow_unstable_delay=True``); with ``guarded=True`` the delayed loop is
    under-relaxed so that it never oscillates; by default the implicit equation is solved
    exactly each sample.
    """

    def __new__(
        cls,
        model,
        limits: Optional[Sequence[float]] = None,
        *,
        delayed: bool = False,
        guarded: bool = False,
        allow_unstable_delay: bool = False,
    ):
        method = _family_method("ihc", delayed, guarded)
        return super().__new__(cls, model, method, limits, allow_unstable_delay=allow_unstable_delay)


class Wihc(Compensator):
    """Compensation without inverse (section 3.2, eq. (9)) from a plant model:
    ``Compensator(model, "wihc", "wihc-delayed" or "wihc-guarded", limits)``.

    With ``delayed=True`` the loop is broken with ``H[v](t - Ts)`` (refused with
    ``UnstableDelayError`` when that loop can oscillate on the model, unless
    ``allow_unstable_delay=True``); with ``guarded=True`` the delayed loop is under-relaxed so
    that it never oscillates; by default the implicit equation is solved exactly each sample.
    """

    def __new__(
        cls,
        model,
        limits: Optional[Sequence[float]] = None,
        *,
        delayed: bool = False,
        guarded: bool = False,
        allow_unstable_delay: bool = False,
    ):
        method = _family_method("wihc", delayed, guarded)
        return super().__new__(cls, model, method, limits, allow_unstable_delay=allow_unstable_delay)


class Dihc(Compensator):
    """Direct inverse hysteresis compensation (section 3.3, eq. (10)) from an inverse model:
    ``Compensator(model, "dihc", limits)``."""

    def __new__(cls, model, limits: Optional[Sequence[float]] = None):
        return super().__new__(cls, model, "dihc", limits)
