"""Type stubs of the extension module ``hystcomp._hystcomp`` (re-exported by ``hystcomp``).

Array arguments accept any one-dimensional array-like of real numbers (numpy arrays of any real
dtype, lists, tuples); anything else (a 2-D array, complex values, strings) raises ``TypeError``
saying what was given. Array results are new ``float64`` numpy arrays.
"""

import os
import pathlib
from typing import Any, Dict, Iterator, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

from ._reports import Clamps, Diagnostics, ErrorStats, FitReport, LearningLaw, LearningUpdate, StudySummary

ArrayLike = Union[npt.ArrayLike, Sequence[float]]
FloatArray = npt.NDArray[np.float64]
PathLike = Union[str, "os.PathLike[str]"]

__version__: str
DEFAULT_MHE_BINS: int

class Mpim:
    """The modified Prandtl-Ishlinskii model of eq. (4), in normalised units:
    ``y(t) = a1 x(t)^3 + a2 x(t) + sum_i b_i F_{r_i}[x](t)`` with one-sided play operators
    ``F_r`` (eqs. (1)-(2)).

    A system object with memory: ``step(x)`` feeds one sample, ``process(x)`` a whole signal
    (numpy array in, numpy array out), ``reset()`` returns to zero memory (eq. (1)).

    Raises ``InvalidValueError`` for thresholds and weights of different lengths, more than
    10 000 operators (a model file's limit, as for the compensators), negative or unsorted
    thresholds, or NaN/infinite parameters."""

    def __init__(self, thresholds: ArrayLike, weights: ArrayLike, a1: float, a2: float) -> None:
        """``y = a1 x^3 + a2 x + sum b_i F_{r_i}[x]``: thresholds ``r_i`` (non-negative,
        increasing) and weights ``b_i``, one per play operator; memory starts at zero (eq. (1)).
        Raises InvalidValueError for NaN, unsorted or negative thresholds, or unequal lengths."""
    @staticmethod
    def table1() -> Mpim:
        """Table 1 of the paper: the plant model identified for IHC and WIHC (normalised voltage
        in, normalised displacement out)."""
    @staticmethod
    def table2() -> Mpim:
        """Table 2 of the paper: the inverse model identified for DIHC (normalised desired
        displacement in, normalised voltage out; eq. (10) with ``a2``)."""
    @property
    def thresholds(self) -> FloatArray:
        """Thresholds ``r_i`` (a copy)."""
    @property
    def weights(self) -> FloatArray:
        """Weights ``b_i`` (a copy)."""
    @property
    def a1(self) -> float:
        """Cubic coefficient ``a1`` of ``g(x) = a1 x^3 + a2 x``."""
    @property
    def a2(self) -> float:
        """Linear coefficient ``a2`` of ``g(x) = a1 x^3 + a2 x``."""
    @property
    def memory(self) -> FloatArray:
        """The operators' memory ``F_{r_i}[x](t_i)`` (a copy)."""
    def set_memory(self, memory: ArrayLike) -> None:
        """Sets the operators' memory (one finite value per operator)."""
    def __len__(self) -> int:
        """The number of play operators ``n``."""
    def step(self, x: float) -> float:
        """Feeds one input sample ``x(t)`` and returns ``y(t)``, eq. (4).

        Raises ``InvalidValueError`` (memory unchanged) when ``x`` is NaN or infinite, or the
        output overflows (e.g. the cubic term at ``x = 1e308``)."""
    def process(self, x: ArrayLike) -> FloatArray:
        """Runs a whole input signal from the current memory; returns the outputs.

        Raises ``InvalidValueError`` (memory unchanged) when a sample is NaN or infinite, or an
        output overflows (naming the sample)."""
    def reset(self) -> None:
        """Back to zero memory (eq. (1))."""
    def check_invertible(self, lo: float = 0.0, hi: float = 1.0) -> float:
        """Checks that the output is strictly increasing in the current input over ``[lo, hi]``
        from any memory reachable from the reset state (i.e. the model can be inverted there).
        Returns the smallest branch slope; raises ``NotInvertibleError`` with the offending
        slope, input and number of moving operators."""
    def pi_part_inverse(self) -> Mpim:
        """The analytic inverse of the PI part ``a2 v + sum b_i F_{r_i}[v]``, eq. (7), as a model
        with ``a1 = 0``. Raises ``NotInvertibleError`` when it does not exist."""
    def copy(self) -> Mpim:
        """An independent copy, memory included."""
    def __copy__(self) -> Mpim:
        """``copy.copy(model)``: an independent copy, memory included (also a deep copy)."""

class Scale:
    """The physical meaning of a normalised signal: ``physical = offset + scale * normalised``."""

    def __init__(self, quantity: str, unit: str, offset: float = 0.0, scale: float = 1.0) -> None: ...
    @property
    def quantity(self) -> str:
        """What the signal is, e.g. ``"voltage"``."""
    @property
    def unit(self) -> str:
        """Its unit, e.g. ``"V"``."""
    @property
    def offset(self) -> float:
        """Physical value at normalised 0."""
    @property
    def scale(self) -> float:
        """Physical span of one normalised unit."""
    def normalise(self, physical: float) -> float:
        """``(physical - offset) / scale``."""
    def to_physical(self, normalised: float) -> float:
        """``offset + scale * normalised``."""

class ModelFile:
    """A model file: one identified MPIM in normalised units, the physical scales of its input
    and output, and the direction it maps (``"plant"``: voltage to displacement, for IHC and
    WIHC; ``"inverse"``: displacement to voltage, for DIHC). JSON on disk, format version 1.

    Build one with ``ModelFile(...)``, read one with ``ModelFile.load(path)``, get one from
    ``identify(...)``. Without ``input``/``output`` the scales are normalised (unit ``"1"``)."""

    def __init__(
        self,
        direction: str,
        thresholds: ArrayLike,
        weights: ArrayLike,
        a1: float,
        a2: float,
        *,
        input: Optional[Scale] = None,
        output: Optional[Scale] = None,
        input_range: Sequence[float] = (0.0, 1.0),
        description: Optional[str] = None,
    ) -> None:
        """A validated model file: ``direction`` is ``"plant"`` (voltage -> displacement, for
        IHC and WIHC) or ``"inverse"`` (displacement -> voltage, for DIHC); normalised
        parameters of eq. (4) and the physical scales of input and output."""
    @staticmethod
    def load(path: PathLike) -> ModelFile:
        """Reads and validates a model file. Raises ``FileNotFoundError`` (or another ``OSError``)
        when it cannot be read and ``ModelFileError`` when it is not a valid model file."""
    @staticmethod
    def from_json(text: str) -> ModelFile:
        """Parses and validates a model file's JSON text."""
    def to_json(self) -> str:
        """The file's JSON text."""
    def save(self, path: PathLike) -> None:
        """Writes the file atomically (a temporary file, then a rename)."""
    def model(self) -> Mpim:
        """The MPIM of this file (normalised units, zero memory): the hysteresis alone, without
        the file's creep or vibration links (``predict`` runs the whole chain)."""
    def predict(self, inputs: ArrayLike) -> FloatArray:
        """The model's output, in physical units, for a whole input signal in physical units
        (e.g. volts in, micrometres out for a plant model), from zero memory. Raises
        ``InvalidValueError`` for a NaN, an infinity or a magnitude beyond 1e15 (as in a
        record read from a file) and for an output that overflows, naming the sample."""
    @property
    def direction(self) -> str:
        """``"plant"`` or ``"inverse"``."""
    @property
    def description(self) -> Optional[str]:
        """A line for people, or ``None``."""
    @description.setter
    def description(self, value: Optional[str]) -> None:
        """A line for people, or ``None``."""
    @property
    def input(self) -> Scale:
        """Physical meaning of the model input."""
    @property
    def output(self) -> Scale:
        """Physical meaning of the model output."""
    @property
    def input_range(self) -> Tuple[float, float]:
        """The normalised input range the model is valid (and invertible) on."""
    @property
    def thresholds(self) -> FloatArray:
        """Thresholds ``r_i`` (normalised, a copy)."""
    @property
    def weights(self) -> FloatArray:
        """Weights ``b_i`` (normalised, a copy)."""
    @property
    def a1(self) -> float:
        """Cubic coefficient ``a1``."""
    @property
    def a2(self) -> float:
        """Linear coefficient ``a2``."""
    @property
    def format_version(self) -> int:
        """The format version (1)."""
    @property
    def identification(self) -> Optional[Dict[str, Any]]:
        """How the model was obtained (a dict, e.g. the identification report), or ``None``."""

class Compensator:
    """A feedforward hysteresis compensator (figure 1 of the paper): desired position in, drive
    voltage out, in the physical units of its model file (e.g. um in, V out).

    - ``model``: a ``ModelFile`` or the path of one;
    - ``method``: ``"ihc"``, ``"ihc-delayed"``, ``"ihc-guarded"``, ``"wihc"``,
      ``"wihc-delayed"``, ``"wihc-guarded"`` (plant models) or ``"dihc"`` (inverse models);
    - ``limits``: ``(min, max)`` drive limits in the model's voltage unit; by default the range
      the model was identified on;
    - ``allow_unstable_delay``: build ``"ihc-delayed"`` or ``"wihc-delayed"`` even when its loop
      gain over the limits is 1 or more (it can then ring between the limits after a jump); by
      default that raises ``UnstableDelayError``. The ``-guarded`` methods never oscillate.

    Every output lies within ``limits`` and is never NaN. ``step`` and ``process`` refuse NaN,
    infinite and beyond-1e15 desired positions with ``InvalidValueError`` (state unchanged). Raises
    ``WrongDirectionError``, ``NotInvertibleError`` (over the limits), ``UnstableDelayError``,
    ``InvalidValueError``, ``ModelFileError`` or ``FileNotFoundError`` when it cannot be built."""

    def __init__(
        self,
        model: Union[ModelFile, PathLike],
        method: str = "ihc",
        limits: Optional[Sequence[float]] = None,
        *,
        allow_unstable_delay: bool = False,
    ) -> None:
        """``method``: ``"ihc"``, ``"ihc-delayed"``, ``"ihc-guarded"``, ``"wihc"``,
        ``"wihc-delayed"``, ``"wihc-guarded"`` (plant models) or ``"dihc"`` (inverse models);
        ``limits``: ``(min, max)`` drive limits, by default the range the model was identified
        on. Every output stays within them, never NaN. A plain delayed method whose loop gain
        is 1 or more raises UnstableDelayError unless ``allow_unstable_delay=True``. Raises
        WrongDirectionError, NotInvertibleError, InvalidValueError, ModelFileError or an
        OSError for the file."""
    @staticmethod
    def from_mpim(
        model: Mpim,
        method: str = "ihc",
        limits: Sequence[float] = (0.0, 1.0),
        *,
        allow_unstable_delay: bool = False,
    ) -> Compensator:
        """A compensator from a model in normalised units (desired position and control both
        normalised, eq. (11)): a plant model for IHC and WIHC, an inverse model (valid for
        desired positions in ``[0, 1]``) for DIHC."""
    def step(self, y_d: float) -> float:
        """One sample: the drive for the desired position ``y_d``."""
    def process(self, y_d: ArrayLike) -> FloatArray:
        """A whole desired trajectory (array-like) from the current state: the drive signal
        (numpy array). Releases the GIL while it runs."""
    def reset(self) -> None:
        """Back to the initial state: operators' memory zero (eq. (1)), diagnostics cleared."""
    @property
    def limits(self) -> Tuple[float, float]:
        """``(min, max)`` drive limits, in ``control_unit``."""
    @property
    def method(self) -> str:
        """The method: ``"ihc"``, ``"ihc-delayed"``, ``"ihc-guarded"``, ``"wihc"``,
        ``"wihc-delayed"``, ``"wihc-guarded"`` or ``"dihc"``."""
    @property
    def desired_unit(self) -> str:
        """Unit of the desired position (the input), e.g. ``"um"``."""
    @property
    def control_unit(self) -> str:
        """Unit of the drive (the output), e.g. ``"V"``."""
    @property
    def diagnostics(self) -> Diagnostics:
        """Counters since the last reset:
        A ``Diagnostics`` dataclass: ``saturated``, ``loop_saturated``, ``non_finite``. ``saturated``: desired
        positions out of reach within the limits (DIHC: outside the inverse model's range), the
        drive was clamped; ``loop_saturated``: a delayed loop (``ihc-delayed``, ``wihc-delayed``)
        drove the output to a limit although the position was reachable (it lagged or rang);
        ``non_finite``: NaN or infinite desired positions (``step`` and ``process`` refuse them,
        so this stays 0 here)."""
    @property
    def delayed_loop_gain(self) -> Optional[float]:
        """For the IHC and WIHC methods: the worst-case gain of the family's one-sample-delayed
        loop over the limits, whatever the method's own mode: ``max |3 a1 x^2| / (a2 + b_1 +
        ... + b_k)`` for IHC (Table 1: 0.68), ``max |3 a1 x^2 + b_1 + ... + b_k| / a2`` for WIHC
        (eq. (9) with ``H[v](t - Ts)``; Table 1: 1.66). At or above 1 the plain delayed loop can
        ring between the limits after a jump in the desired position and is refused unless
        ``allow_unstable_delay=True``; the exact and ``-guarded`` methods never oscillate.
        ``None`` for DIHC."""
    @property
    def guard_relaxation(self) -> Optional[float]:
        """For the IHC and WIHC methods: the under-relaxation of the family's guarded delayed
        loop, in ``(0, 1]`` (1: no under-relaxation). ``None`` for DIHC."""

class CompensatorBank:
    """Many feedforward hysteresis compensators of one method, one channel per model, stepped
    together (the axes of a stage, the actuators of a deformable mirror): desired positions in,
    drive voltages out, each in its own model's physical units. Channel ``c`` gives what a
    ``Compensator`` built from its own model gives, bit for bit.

    - ``models``: the path of a model-set file (``{"format": "hystcomp-model-set", ...}``), of
      a directory of model files (one channel per ``*.json``, in the order of their names) or of
      one model file; or a list of models (each a ``ModelFile`` or the path of one);
    - ``method``: as ``Compensator``, the same for every channel;
    - ``limits``: ``(min, max)`` for every channel, or one pair per channel; by default each
      channel's identified range;
    - ``allow_unstable_delay``: as ``Compensator``.

    ``step(y_d)`` takes an array of shape ``(channels,)``, ``process(y_d)`` one of shape
    ``(samples, channels)``; both return arrays of the same shape, every drive within its
    channel's limits. NaN, infinite and beyond-1e15 desired positions are refused with
    ``InvalidValueError`` naming the sample and channel (state unchanged). A channel that cannot be built raises the
    error ``Compensator`` would, its message beginning ``channel K (NAME): ``."""

    def __init__(
        self,
        models: Union[PathLike, Sequence[Union[ModelFile, PathLike]]],
        method: str = "ihc",
        limits: Optional[Union[Sequence[float], Sequence[Sequence[float]]]] = None,
        *,
        allow_unstable_delay: bool = False,
    ) -> None: ...
    def step(self, y_d: ArrayLike) -> FloatArray:
        """One control tick: the drives (shape ``(channels,)``) for the desired positions
        ``y_d`` (shape ``(channels,)``)."""
    def process(self, y_d: npt.ArrayLike) -> FloatArray:
        """A whole desired trajectory of shape ``(samples, channels)`` from the current state:
        the drives, same shape. Releases the GIL while it runs."""
    def reset(self) -> None:
        """Every channel back to its initial state: operators' memory zero (eq. (1)), diagnostics
        cleared."""
    @property
    def channels(self) -> int:
        """The number of channels."""
    def __len__(self) -> int: ...
    @property
    def names(self) -> List[str]:
        """The channels' names (a model set's names, file stems, or ``channel_K``)."""
    @property
    def method(self) -> str:
        """The method of every channel."""
    @property
    def limits(self) -> List[Tuple[float, float]]:
        """``(min, max)`` drive limits of every channel, each in its ``control_units``."""
    @property
    def desired_units(self) -> List[str]:
        """Every channel's unit of the desired position, e.g. ``"um"``."""
    @property
    def control_units(self) -> List[str]:
        """Every channel's unit of the drive, e.g. ``"V"``."""
    @property
    def diagnostics(self) -> List[Diagnostics]:
        """Every channel's counters since the last reset, a list of ``Diagnostics`` (as
        ``Compensator.diagnostics``)."""

class Identification:
    """An identified model: ``.model`` (a ``ModelFile``, physical scales and normalised
    parameters), ``.report`` (a ``FitReport`` dataclass: fit errors in physical units and % of the output range,
    sample counts, solver details, smallest branch slope...) and ``.parameters`` (a dict of the
    normalised ``a1``, ``a2``, ``weights`` and fitted ``offset``)."""

    @property
    def model(self) -> ModelFile:
        """The model file (its ``identification`` field holds the report too)."""
    @property
    def report(self) -> FitReport:
        """The fit report, a ``FitReport`` dataclass with the fields of ``hystcomp identify
        --json``'s report (``.fit.rms_percent``, ``.samples.warmup``, ``.holdout``, ...;
        ``.to_dict()`` for the dict)."""
    @property
    def parameters(self) -> Dict[str, Any]:
        """The normalised parameters, as a dict."""
    @property
    def order_selection(self) -> Optional[Dict[str, Any]]:
        """With ``n="auto"``: how the number of play operators was chosen, a dict with
        ``operators`` (the choice), ``holdout`` (the fraction of the record held out to choose
        it) and ``candidates`` (each tried: ``operators``, ``fit_rms_percent``,
        ``holdout_rms_percent``); ``None`` when ``n`` was given."""

def identify(
    voltage: ArrayLike,
    displacement: ArrayLike,
    n: Union[int, str] = 10,
    method: str = "ls",
    direction: str = "plant",
    *,
    seed: int = 0,
    thresholds: Optional[ArrayLike] = None,
    warmup: Union[str, int] = "auto",
    holdout: float = 0.2,
    offset: Union[str, float] = "fit",
    margin: float = 0.001,
    particles: int = 50,
    iterations: int = 10000,
    polish: bool = False,
    accept_poor_fit: bool = False,
    voltage_unit: str = "V",
    displacement_unit: str = "um",
    for_delayed: bool = False,
    delayed_loop_bound: float = 0.9,
) -> Identification:
    """Identifies a modified Prandtl-Ishlinskii model (eq. (4)) from a record of drive voltages
    and measured displacements (equal lengths, finite), as ``hystcomp identify`` does.

    - ``n``: play operators at thresholds ``(i - 1)/n`` of the input range (eq. (11)), unless
      ``thresholds`` gives them (fractions of the input range in ``[0, 1)``, increasing); or
      ``"auto"``: the one of 5, 10, 15, 20, 30, 40, 50 whose model predicts the last
      ``holdout`` of the record (25 % when ``holdout`` is 0) best, fitted on the rest, as
      ``hystcomp identify -n auto`` (``.order_selection`` says which and why);
    - ``method``: ``"ls"`` (constrained least squares, the global optimum) or ``"pso"``
      (particle swarm, as the paper; ``seed``, ``particles``, ``iterations``, ``polish``);
    - ``direction``: ``"plant"`` (voltage to displacement, for IHC and WIHC) or ``"inverse"``
      (displacement to voltage, for DIHC);
    - ``warmup``: ``"auto"`` (up to where the operators' memory becomes known: the voltage
      within 1 % of an end of the record's range), ``"estimate"`` (every sample fitted, the
      memory at the first one estimated with the parameters) or a number of leading samples
      excluded from the fit; ``report.warmup.reason`` says which samples were used and why;
    - ``holdout``: the fraction of samples at the end held out of the fit and reported (0.2,
      as ``hystcomp identify``; 0 fits the whole record);
    - ``offset``: ``"fit"`` (a constant fitted for the sensor's arbitrary zero), ``"none"`` or a
      physical output offset;
    - ``margin``: the smallest branch slope the model must keep (normalised);
    - ``accept_poor_fit``: return the model even when its RMS fit error exceeds the 10 % of the
      output range a usable hysteresis model stays under (by default ``IdentificationError``);
    - ``for_delayed``: a plant model meant for the one-sample-delayed compensators
      (``ihc-delayed``, ``wihc-delayed``): both delayed loops' gains, over every number of
      moving operators and every drive in the fitted range, held to at most
      ``delayed_loop_bound`` (in ``(0, 1)``), so that neither loop can oscillate, as ``hystcomp
      identify --for-delayed``; the report's ``delayed_constraint`` says what it cost in fit
      RMS. Inverse models ignore it.

    Releases the GIL while it runs. Raises ``InvalidValueError`` for unusable samples or
    options and ``IdentificationError`` when no model can be identified (the message says what
    to change)."""

class Prediction:
    """A model's prediction of a record (``hystcomp predict``): ``.predicted`` and ``.error``
    (predicted minus measured; numpy arrays, one per sample, in the model's output unit),
    ``.stats`` (an ``ErrorStats``: RMS, max, mean, in the unit and in % of the measured
    output's range ``.stats.range``), ``.outside_input_range`` (samples the model
    extrapolates), ``.initial_state`` and ``.direction``."""

    @property
    def predicted(self) -> FloatArray:
        """The predicted output: the displacement for a plant model, the voltage for an inverse
        one."""
    @property
    def error(self) -> FloatArray:
        """Predicted minus measured, one per sample."""
    @property
    def stats(self) -> ErrorStats:
        """The errors over every sample, an ``ErrorStats`` (``rms_percent`` is in % of the measured
        output's range over the record, ``range``)."""
    @property
    def outside_input_range(self) -> int:
        """Samples whose input lies outside the range the model was identified on."""
    @property
    def initial_state(self) -> str:
        """How the model started (its reset state, eq. (1); a creep link settled with
        ``settled=True``)."""
    @property
    def direction(self) -> str:
        """``"plant"`` or ``"inverse"``."""
    def __len__(self) -> int: ...

def predict(
    model: ModelFile,
    voltage: ArrayLike,
    displacement: ArrayLike,
    *,
    settled: bool = False,
) -> Prediction:
    """Runs ``model`` (a ``ModelFile``) over a record from its reset state (zero operator memory,
    eq. (1)), as ``hystcomp predict`` does: a plant model over ``voltage``, compared with
    ``displacement``; an inverse model the other way round (equal lengths, finite, not empty).
    ``settled``: a creep link taken as having rested long at the first sample. Returns a
    ``Prediction``. Raises ``InvalidValueError`` for unusable samples or a prediction that is
    not finite (naming the sample). Releases the GIL while it runs."""

class Stage:
    """A simulated piezo nanopositioning stage (DAC, amplifier, hysteresis, creep, resonance,
    sensor, ADC), standing in for the set-up of the paper's section 4.1.

    ``Stage(config_toml=None, seed=0)``: the built-in default stage, or a stage file's TOML
    text (unspecified keys keep their defaults); ``seed`` seeds the sensor noise. Deterministic:
    the same seed gives the same response. ``step(command_v)`` writes one DAC command (V) and
    returns the measured position (um) one sample period later; ``run(volts)`` runs a whole
    command signal and returns a ``StageResponse``.

    Raises ``StageConfigError`` for an invalid stage file and ``InvalidValueError`` for NaN or
    infinite commands (the state is then unchanged)."""

    def __init__(self, config_toml: Optional[str] = None, seed: int = 0) -> None:
        """The built-in stage, or one described by a TOML text; ``seed`` fixes its noise."""
    @staticmethod
    def from_file(path: PathLike, seed: int = 0) -> Stage:
        """A stage from a stage file (TOML). Raises ``FileNotFoundError`` when it is missing."""
    def step(self, command_v: float) -> float:
        """One sample: writes ``command_v`` (V) to the DAC, holds it for one period and returns the
        measured position at the end of the period (um)."""
    def run(self, command_v: ArrayLike) -> StageResponse:
        """A whole command signal (V, one value per sample) from the current state. Releases the
        GIL while it runs."""
    def reset(self) -> None:
        """Back to rest: relaxed, at 0 V, time 0, noise generator re-seeded."""
    @property
    def sample_rate_hz(self) -> float:
        """The controller's sample rate, Hz."""
    @property
    def period_s(self) -> float:
        """The sample period, s."""
    @property
    def samples(self) -> int:
        """Samples run since the stage was built or reset."""
    @property
    def time_s(self) -> float:
        """The stage's time, s."""
    @property
    def seed(self) -> int:
        """The noise seed."""
    @property
    def clamps(self) -> Clamps:
        """Samples clamped or ignored since the stage was built or reset: ``dac_clamped`` and
        ``amplifier_clamped`` (commands beyond the DAC's span or the amplifier's rails),
        ``non_finite`` (NaN or infinite commands) and ``adc_clamped`` (readings beyond the ADC's
        span: the measured position saturated)."""
    @property
    def full_scale_command_v(self) -> float:
        """The full-scale command, V: the one that drives the amplifier to its upper rail, or the
        DAC's top when the amplifier's gain cannot reach the rail from it."""
    @property
    def config_toml(self) -> str:
        """The stage's configuration as a complete stage file (TOML text)."""
    def quasi_static_stroke_um(self) -> float:
        """The quasi-static stroke at full command (a slow ramp on a fresh copy of this stage's
        configuration), um. The linear feedforward gain of section 4.3.1 is
        ``full_scale_command_v / quasi_static_stroke_um()``."""

class StageResponse:
    """The response of ``Stage.run`` (python-control style): one entry per command sample.

    ``time[k]`` is when command ``k`` was written; the positions are read one sample period
    later. ``inputs`` is ``command_v`` and ``outputs`` is ``measured_position_um``; the stage's
    internal signals are ``amplifier_v`` and ``true_position_um``. It unpacks as ``t, y =
    stage.run(volts)``, and ``hystcomp.plot_response(response)`` plots it (matplotlib)."""

    @property
    def time(self) -> FloatArray:
        """Time at which each command was written, s."""
    @property
    def inputs(self) -> FloatArray:
        """The commands, V (same as ``command_v``)."""
    @property
    def outputs(self) -> FloatArray:
        """The measured positions, um (same as ``measured_position_um``)."""
    @property
    def command_v(self) -> FloatArray:
        """The commands, V."""
    @property
    def amplifier_v(self) -> FloatArray:
        """The amplifier's output, V."""
    @property
    def true_position_um(self) -> FloatArray:
        """The true position, um."""
    @property
    def measured_position_um(self) -> FloatArray:
        """The measured position (sensor and ADC), um."""
    @property
    def clamps(self) -> Clamps:
        """Samples the stage clamped during this run, by the same keys as ``Stage.clamps``."""
    def __len__(self) -> int: ...
    def __iter__(self) -> Iterator[FloatArray]:
        """Unpacks as ``t, y = stage.run(volts)``: the time and the measured positions."""

class TrackingIndices:
    """The three indices of the paper's Table 3, in percent of the desired range:
    ``e_mhe`` (eq. (12), the largest vertical width of the ``y`` versus ``y_d`` map over
    ``mhe_bins`` bins of ``y_d``), ``e_m`` ((D1), the largest tracking error) and ``e_rms``
    ((D2), the RMS tracking error)."""

    @property
    def e_mhe(self) -> float:
        """Maximum hysteresis error, eq. (12), %."""
    @property
    def e_m(self) -> float:
        """Maximum tracking error, (D1), %."""
    @property
    def e_rms(self) -> float:
        """RMS tracking error, (D2), %."""
    @property
    def mhe_bins(self) -> int:
        """Bins of the ``y_d`` range used for ``e_mhe``."""
    def as_dict(self) -> Dict[str, float]:
        """``{"e_mhe": ..., "e_m": ..., "e_rms": ...}`` (percent)."""

def e_m(desired: ArrayLike, measured: ArrayLike) -> float:
    """(D1): ``max |y - y_d| / (max y_d - min y_d) * 100`` (percent).

    Raises ``InvalidValueError`` for records of different lengths, fewer than 2 samples, NaN
    or infinite samples, or a constant desired trajectory."""
def e_rms(desired: ArrayLike, measured: ArrayLike) -> float:
    """(D2): ``sqrt(mean (y - y_d)^2) / (max y_d - min y_d) * 100`` (percent)."""
def e_mhe(desired: ArrayLike, measured: ArrayLike, bins: int = 100) -> float:
    """Eq. (12): the largest ``max y - min y`` within one of ``bins`` equal bins of the ``y_d``
    range, divided by ``max y_d - min y_d``, times 100 (percent). Needs at least 10 samples per
    bin on average (``bins <= max(1, len(desired) // 10)``): with fewer, bins hold one sample or
    none and e_mhe reads low; otherwise raises with the largest ``bins`` the record supports."""
def tracking_indices(desired: ArrayLike, measured: ArrayLike, bins: int = 100) -> TrackingIndices:
    """All three indices of ``measured`` (``y``) against ``desired`` (``y_d``); ``bins`` as for
    :func:`e_mhe` (at least 10 samples per bin on average)."""

class Learner:
    """Iterative learning feedforward for a repeated motion (raster scans, periodic patterns): the
    learner keeps the reference its exact inverse (IHC or WIHC of the plant ``model``) follows,
    and after each trial moves it by the filtered error,
    ``r_k+1 = sat(r_k + Q[gamma z^m e_k])``, ``e_k = y_d - y_k`` (Leang & Devasia 2006,
    doi:10.1016/j.mechatronics.2005.11.006; Longman 2000, doi:10.1080/002071700405905; ``Q`` a
    zero-phase low-pass). The law is in the crate ``hystcomp-learn``'s documentation and in
    ``law``.

    - ``model``: a plant ``ModelFile`` (voltage -> displacement) or the path of one;
    - ``desired``: one trial of the desired trajectory (``2`` to ``5_000_000`` samples, the
      model's displacement unit), one whole period of a periodic motion when ``periodic``;
    - ``sample_rate_hz``: the records' sample rate;
    - ``drive``: the drive of the first trial, if not the exact inverse's own (any
      compensator's, or an earlier learner's): the reference is recovered from it by the model;
    - ``gain`` (``gamma``, default 0.8, at most 10), ``bandwidth_hz`` (``Q``'s cut-off; default
      a hundredth of the sample rate, a tenth for a model with a vibration link),
      ``filter_order`` (1 to 8, default 4), ``lead_samples`` (``m``, 0 to 1000),
      ``divergence_factor`` (above 1, default 1.5), ``inverse`` (``"ihc"`` or ``"wihc"``),
      ``limits`` (``(min, max)`` drive limits, by default the model's identified range),
      ``mhe_bins`` (bins of e_mhe).

    The loop: send ``learner.drive`` to the stage (periodic: play it until the motion is
    periodic, record the last period), then ``drive = learner.update(measured)`` and repeat.
    Every drive lies within ``limits`` and is never NaN. When a trial's e_rms exceeds
    ``divergence_factor`` times the best trial's, the divergence guard stops the learning:
    ``update`` warns (``LearningDivergedWarning``) and returns the best trial's drive (the last
    good one), ``stopped`` turns true and further updates raise ``LearningStoppedError``.
    Raises ``InvalidValueError`` for a bad option or record (naming it), ``WrongDirectionError``
    for an inverse model, ``NotInvertibleError`` when the model cannot be inverted over the
    limits."""

    def __init__(
        self,
        model: Union[ModelFile, PathLike],
        desired: ArrayLike,
        sample_rate_hz: float,
        drive: Optional[ArrayLike] = None,
        *,
        periodic: bool = True,
        gain: float = 0.8,
        bandwidth_hz: Optional[float] = None,
        filter_order: int = 4,
        lead_samples: int = 0,
        divergence_factor: float = 1.5,
        inverse: str = "ihc",
        limits: Optional[Sequence[float]] = None,
        mhe_bins: int = 100,
    ) -> None:
        """A learner for one trial of ``desired``, starting from the exact inverse's drive for
        it or from ``drive``. Raises InvalidValueError (naming the option or record),
        WrongDirectionError (an inverse model), NotInvertibleError, ModelFileError or an
        OSError for the file."""
    def update(self, measured: ArrayLike) -> FloatArray:
        """The trial's measured response (array-like, aligned sample by sample with ``desired``
        and the drive that was sent) in; the next trial's drive (numpy array) out. Refuses a
        record of another length or with a NaN or infinite sample (``InvalidValueError``, state
        unchanged). When the divergence guard trips on this trial, warns with
        ``LearningDivergedWarning`` and returns the last good drive; after that, raises
        ``LearningStoppedError``. ``last_update`` holds the trial's indices and the prediction
        for the next. Releases the GIL while it computes."""
    @property
    def drive(self) -> FloatArray:
        """The drive of the next trial (numpy array, the model's voltage unit): within the limits,
        never NaN; after the divergence guard stopped the learning, the last good drive."""
    @property
    def reference(self) -> FloatArray:
        """The reference the exact inverse follows in the next trial (numpy array, the model's
        displacement unit)."""
    @property
    def desired(self) -> FloatArray:
        """The desired trajectory of one trial (numpy array)."""
    @property
    def trials(self) -> int:
        """Trials measured so far (the next ``update`` measures trial ``trials``; trial 0 ran the
        first drive)."""
    @property
    def history(self) -> List[TrackingIndices]:
        """The indices of every trial measured so far (``TrackingIndices``, % of the desired
        range)."""
    @property
    def best_trial(self) -> Optional[int]:
        """The best trial measured so far (lowest e_rms), or ``None`` before the first update."""
    @property
    def best_drive(self) -> Optional[FloatArray]:
        """The best trial's drive (numpy array: the last good drive), or ``None``."""
    @property
    def stopped(self) -> bool:
        """Whether the divergence guard stopped the learning."""
    @property
    def last_update(self) -> Optional[LearningUpdate]:
        """The last trial's outcome, a ``LearningUpdate`` dataclass (``trial``, ``indices``,
        ``predicted`` indices of the next trial, ``clamped_samples`` of the next reference,
        ``status``), or ``None`` before the first update."""
    @property
    def law(self) -> LearningLaw:
        """The learning law in force, a ``LearningLaw`` dataclass: ``gain``, ``lead_samples``,
        ``bandwidth_hz``, ``filter_order``, ``periodic``, ``padding_samples``, ``noise_gain``,
        ``stationary_noise_ratio`` (the learned reference's noise variance relative to the
        sensor's, bounded: noise is not amplified trial after trial), ``divergence_factor``,
        ``inverse``, ``limits``, ``model_has_vibration``."""

class StudyResult:
    """The result of ``reproduce()``: the paper's Table 3 measured on the simulated stage.

    - ``table``: ``{"uncompensated": {...}, "paper": {"ihc": {...}, "wihc": {...},
      "dihc": {...}}, "exact": {...}}`` with ``{"e_mhe", "e_m", "e_rms"}`` in percent;
    - ``published``: the paper's Table 3 in the same shape;
    - ``summary``: everything ``hystcomp reproduce --json`` prints (acceptance checks, cross
      runs, fits...); ``passed``: whether every acceptance check holds;
    - ``models``: the identified model files, ``{"paper": {"plant": ..., "inverse": ...},
      "exact": {...}}``;
    - ``time``, ``desired_um`` and ``runs`` (label -> ``{"command_v", "measured_um"}``) for
      plots; the indices are taken from ``evaluation_start`` on (the last full period);
    - ``report``: the path of the HTML report when ``out_dir`` was given, else ``None``.

    ``str(result)`` is the plain-text Table 3 of ``hystcomp reproduce``."""

    @property
    def table(self) -> Dict[str, Any]:
        """Our Table 3, percent."""
    @property
    def published(self) -> Dict[str, Dict[str, float]]:
        """The paper's Table 3 (measured on its hardware), percent."""
    def indices(self, pipeline: str, method: Optional[str] = None) -> TrackingIndices:
        """The indices of one run: ``result.indices("exact", "ihc")``, or
        ``result.indices("uncompensated")``."""
    @property
    def summary(self) -> StudySummary:
        """Everything ``hystcomp reproduce --json`` reports, as a ``StudySummary`` dataclass with
        the same fields (``.to_dict()`` for the dict)."""
    @property
    def acceptance(self) -> List[Dict[str, Any]]:
        """The acceptance checks: a list of ``{"what", "value", "bound", "passed"}``."""
    @property
    def passed(self) -> bool:
        """Whether every acceptance check holds."""
    @property
    def models(self) -> Dict[str, Dict[str, ModelFile]]:
        """The identified model files of each pipeline."""
    @property
    def time(self) -> FloatArray:
        """Time axis of the tracking runs, s."""
    @property
    def desired_um(self) -> FloatArray:
        """The desired trajectory, um."""
    @property
    def evaluation_start(self) -> int:
        """First sample of the evaluation window (the last full period)."""
    @property
    def runs(self) -> Dict[str, Dict[str, FloatArray]]:
        """Every tracking run, by label (e.g. ``"exact / ihc"``): its command (V) and measured
        position (um)."""
    @property
    def labels(self) -> List[str]:
        """The labels of the runs, in order."""
    @property
    def report(self) -> Optional[pathlib.Path]:
        """The HTML report written to ``out_dir``, or ``None``."""
    @property
    def elapsed_s(self) -> float:
        """Wall-clock time of the study, s."""

def reproduce(
    *,
    stage_toml: Optional[str] = None,
    seed: int = 1,
    periods: int = 2,
    operators: int = 10,
    pso_iterations: Optional[int] = None,
    pso_particles: Optional[int] = None,
    out_dir: Optional[PathLike] = None,
) -> StudyResult:
    """Reproduces the paper's comparative study (section 4, Table 3) on the simulated stage, as
    ``hystcomp reproduce`` does: an identification experiment, a plant and an inverse model
    identified by particle swarm (``paper`` pipeline, with delayed IHC and WIHC) and by least
    squares (``exact`` pipeline, with exact IHC and WIHC), DIHC in both, and the uncompensated
    run; the indices on the last of ``periods`` periods of the paper's trajectory.

    - ``stage_toml``: a stage file's TOML text (the default stage without it);
    - ``seed``: the stage noise (identification; tracking runs use ``seed + 1``) and the swarm;
    - ``pso_iterations``, ``pso_particles``: the ``paper`` pipeline's swarm (by default that of
      ``hystcomp reproduce``; fewer is faster);
    - ``out_dir``: also write the HTML report, the figures and the models there.

    Releases the GIL while it runs. Raises
    ``StageConfigError``, ``IdentificationError``, ``InvalidValueError`` (e.g. fewer than 2
    periods) or ``OSError`` (the report could not be written)."""

def paper_trajectory(duration_s: float = 10.0, sample_rate_hz: float = 10000.0) -> Tuple[FloatArray, FloatArray]:
    """The paper's desired trajectory (section 4.3),
    ``y_d(t) = 37.35 + 10.5 sin(pi t + 2.6) + 10.5 sin(1.6 pi t + 3) + 15.75 sin(2 pi t + 1.5)``
    um, sampled at ``sample_rate_hz`` for ``duration_s`` (one 10 s period by default).
    Returns ``(time_s, y_d_um)``."""
