"""Typed reports: dataclasses with the same fields as the command line's JSON.

``Identification.report`` is a :class:`FitReport` (``hystcomp identify --json``'s report),
``Compensator.diagnostics`` a :class:`Diagnostics`, ``Stage.clamps`` and
``StageResponse.clamps`` a :class:`Clamps`, ``StudyResult.summary`` a :class:`StudySummary`
(``hystcomp reproduce --json``). Fields the Rust side adds later, and that a class here does
not name yet, are kept in ``extra`` rather than lost; ``to_dict()`` gives the JSON's dict back.
"""

from __future__ import annotations

import dataclasses
import typing
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional


class _Report:
    """Shared by the report classes: building from the JSON's dict, and back."""

    @classmethod
    def from_json(cls, data: Dict[str, Any]):
        """The report from the dict of the command line's JSON (unknown keys go to ``extra``)."""
        hints = typing.get_type_hints(cls)
        known = {f.name for f in dataclasses.fields(cls)} - {"extra"}
        values = {name: _convert(hints[name], data[name]) for name in known if name in data}
        # The JSON leaves out empty optional fields (e.g. ``pso`` of a least-squares fit).
        for name in known - values.keys():
            if typing.get_origin(hints[name]) is typing.Union and type(None) in typing.get_args(hints[name]):
                values[name] = None
        extra = {k: v for k, v in data.items() if k not in known}
        return cls(**values, extra=extra)

    def to_dict(self) -> Dict[str, Any]:
        """The report as the command line's JSON dict."""
        out = {}
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if f.name == "extra" or value is None:  # (the JSON leaves empty options out)
                continue
            out[f.name] = _plain(value)
        out.update(self.extra)
        return out


def _convert(hint, value):
    origin = typing.get_origin(hint)
    args = typing.get_args(hint)
    if value is None:
        return None
    if origin is typing.Union:  # Optional[X]
        inner = [a for a in args if a is not type(None)]
        return _convert(inner[0], value) if inner else value
    if origin in (list, List) and args:
        return [_convert(args[0], v) for v in value]
    if isinstance(hint, type) and issubclass(hint, _Report):
        return hint.from_json(value)
    return value


def _plain(value):
    if isinstance(value, _Report):
        return value.to_dict()
    if isinstance(value, list):
        return [_plain(v) for v in value]
    return value


@dataclass(frozen=True)
class ErrorStats(_Report):
    """Errors of a fit or a prediction: in the output's unit and in % of its range."""

    samples: int
    rms: float
    max: float
    mean: float
    range: float
    rms_percent: float
    max_percent: float
    std_percent: float
    extra: Dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class SignalRange(_Report):
    """The range of a fitted signal, with its quantity and unit."""

    quantity: str
    unit: str
    min: float
    max: float
    extra: Dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class SampleCounts(_Report):
    """How the record's samples were used: ``total = warmup + fit + holdout``."""

    total: int
    warmup: int
    fit: int
    holdout: int
    extra: Dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class FitReport(_Report):
    """An identification's report (``hystcomp identify --json``): the direction, the solver,
    sample counts, the fitted ranges, fit and hold-out errors, constraints and the smallest
    branch slope (the invertibility margin)."""

    direction: str
    solver: str
    detail: str
    thresholds: List[float]
    samples: SampleCounts
    input: SignalRange
    output: SignalRange
    offset_mode: Any
    output_offset: float
    fit: ErrorStats
    holdout: Optional[ErrorStats]
    condition_number: float
    constraints: int
    active_constraints: int
    violated_constraints: int
    margin: float
    min_branch_slope: float
    pso: Optional[Dict[str, Any]]
    elapsed_s: float
    #: Plant models: ``{"ihc": ..., "wihc": ...}``, the gains of the delayed IHC and WIHC loops
    #: over the fitted voltage range (below 1 they settle after any jump; at or above 1 they
    #: can ring, and the plain delayed methods are refused unless allowed). ``None`` for
    #: inverse models.
    delayed_loop_gains: Optional[Dict[str, float]] = None
    #: With ``for_delayed=True`` (plant models): ``{"bound": ..., "unconstrained_fit_rms_percent":
    #: ..., "unconstrained_gains": {"ihc": ..., "wihc": ...}}``, the bound both delayed loops'
    #: gains were held to and what it cost: the fit RMS without it and its gains. ``None``
    #: otherwise.
    delayed_constraint: Optional[Dict[str, Any]] = None
    #: Which samples were fitted and why: ``{"mode": ..., "first_fitted": ...,
    #: "memory_known_from": ..., "reason": ...}`` (the warm-up of ``hystcomp identify``'s report).
    warmup: Optional[Dict[str, Any]] = None
    extra: Dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Diagnostics(_Report):
    """A compensator's clamped samples: ``saturated`` (desired positions out of reach within
    the limits; the drive was clamped), ``loop_saturated`` (a delayed loop hit a limit although
    the position was reachable) and ``non_finite`` (NaN or infinite desired positions)."""

    saturated: int = 0
    loop_saturated: int = 0
    non_finite: int = 0
    extra: Dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Clamps(_Report):
    """Samples the stage clamped or ignored: commands beyond the DAC's span
    (``dac_clamped``) or the amplifier's rails (``amplifier_clamped``), NaN or infinite
    commands (``non_finite``), readings beyond the ADC's span (``adc_clamped``)."""

    dac_clamped: int = 0
    amplifier_clamped: int = 0
    non_finite: int = 0
    adc_clamped: int = 0
    extra: Dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Indices(_Report):
    """Tracking indices in % of the desired range: e_mhe (eq. (12)) over ``mhe_bins`` bins,
    e_m (D1), e_rms (D2)."""

    e_mhe_percent: float
    e_m_percent: float
    e_rms_percent: float
    mhe_bins: int
    extra: Dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class RunSummary(_Report):
    """One tracking run of the study: its label (``"exact / ihc"``), indices, samples clamped
    by the compensator and the model's mismatch during the run (% RMS)."""

    label: str
    indices: Indices
    saturated: int
    model_mismatch_rms_percent: Optional[float]
    extra: Dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class PipelineSummary(_Report):
    """One pipeline of the study (``paper`` or ``exact``): its runs (IHC, WIHC, DIHC) and its
    models' fits (% RMS of the output range)."""

    name: str
    description: str
    runs: List[RunSummary]
    plant_fit_rms_percent: float
    inverse_fit_rms_percent: float
    extra: Dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class AcceptanceCheck(_Report):
    """One acceptance check: what, our value (%), the bound in words, whether it passed."""

    what: str
    value: float
    bound: str
    passed: bool
    extra: Dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class SeriesFile(_Report):
    """A CSV file beside the report's ``study.json`` with series the figures show."""

    file: str
    columns: List[str]
    figures: str
    extra: Dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class StudySummary(_Report):
    """The study's numbers (``hystcomp reproduce --json``): Table 3 beside the paper's, the
    cross runs, the acceptance checks (counted and informational), the noise floor, the
    ablation and the run time."""

    mhe_bins: int
    uncompensated: Indices
    published: Dict[str, Any]
    pipelines: List[PipelineSummary]
    cross_runs: List[RunSummary]
    acceptance: List[AcceptanceCheck]
    informational: List[AcceptanceCheck]
    noise_floor: Dict[str, Any]
    ablations: List[Dict[str, Any]]
    elapsed_s: float
    identification_warmup_samples: int = 0
    identification_holdout: float = 0.0
    series: List[SeriesFile] = field(default_factory=list)
    extra: Dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class LearningUpdate(_Report):
    """One learning trial (``Learner.last_update``; ``hystcomp learn --json``'s trial): its
    number (0: the first drive), its ``indices``, the indices ``predicted`` for the next trial
    by the law's linear model (``None`` once the guard stopped the learning), the samples of
    the next reference clamped into the reachable range, and ``status`` (``{"state":
    "learning"}`` or ``{"state": "diverged", "e_rms_percent", "best_trial",
    "best_e_rms_percent", "factor"}``)."""

    trial: int
    indices: Indices
    predicted: Optional[Indices]
    clamped_samples: int
    status: Dict[str, Any]
    extra: Dict[str, Any] = field(default_factory=dict)

    @property
    def diverged(self) -> bool:
        """Whether the divergence guard stopped the learning on this trial."""
        return self.status.get("state") == "diverged"


@dataclass(frozen=True)
class LearningLaw(_Report):
    """The learning law ``r_k+1 = sat(r_k + Q[gamma z^m e_k])`` in force (``Learner.law``):
    ``gain`` (gamma), ``lead_samples`` (m), ``Q``'s ``bandwidth_hz`` and ``filter_order``,
    ``periodic``, ``padding_samples`` of a finite record, ``noise_gain`` (share of white sensor
    noise's variance one update passes on), ``stationary_noise_ratio`` (the learned reference's
    noise variance relative to the sensor's after many trials: bounded, ``None`` if the update
    does not contract), ``divergence_factor``, ``inverse``, drive ``limits`` and
    ``model_has_vibration``."""

    gain: float
    lead_samples: int
    bandwidth_hz: float
    filter_order: int
    periodic: bool
    padding_samples: int
    noise_gain: float
    stationary_noise_ratio: Optional[float]
    divergence_factor: float
    inverse: str
    limits: List[float]
    model_has_vibration: bool
    extra: Dict[str, Any] = field(default_factory=dict)
