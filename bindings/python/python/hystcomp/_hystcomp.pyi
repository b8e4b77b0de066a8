"""Type stubs of the extension module ``hystcomp._hystcomp`` (re-exported by ``hystcomp``).

Array arguments accept any one-dimensional array-like of real numbers (numpy arrays of any real
dtype, lists, tuples); anything else (a 2-D array, complex values, strings) raises ``TypeError``
saying what was given. Array results are new ``float64`` numpy arrays.
"""

import os
import pathlib
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

ArrayLike = Union[npt.ArrayLike, Sequence[float]]
FloatArray = npt.NDArray[np.float64]
PathLike = Union[str, "os.PathLike[str]"]

__version__: str
DEFAULT_MHE_BINS: int

class Mpim:
    """The modified Prandtl-Ishlinskii model of eq. (4), normalised units, with memory."""

    def __init__(self, thresholds: ArrayLike, weights: ArrayLike, a1: float, a2: float) -> None:
        """``y = a1 x^3 + a2 x + sum b_i F_{r_i}[x]``: thresholds ``r_i`` (non-negative,
        increasing) and weights ``b_i``, one per play operator; memory starts at zero (eq. (1)).
        Raises InvalidValueError for NaN, unsorted or negative thresholds, or unequal lengths."""
    @staticmethod
    def table1() -> Mpim:
        """Table 1 of the paper: the plant model for IHC and WIHC."""
    @staticmethod
    def table2() -> Mpim:
        """Table 2 of the paper: the inverse model for DIHC."""
    @property
    def thresholds(self) -> FloatArray: ...
    @property
    def weights(self) -> FloatArray: ...
    @property
    def a1(self) -> float: ...
    @property
    def a2(self) -> float: ...
    @property
    def memory(self) -> FloatArray:
        """The operators' memory ``F_{r_i}[x](t_i)``, one per operator (a copy)."""
    def set_memory(self, memory: ArrayLike) -> None:
        """Sets the memory explicitly (one finite value per operator)."""
    def __len__(self) -> int:
        """The number of play operators ``n``."""
    def step(self, x: float) -> float:
        """One sample; raises InvalidValueError for NaN or infinite ``x``."""
    def process(self, x: ArrayLike) -> FloatArray:
        """A whole signal from the current memory."""
    def reset(self) -> None:
        """Back to zero memory (eq. (1))."""
    def check_invertible(self, lo: float = 0.0, hi: float = 1.0) -> float:
        """The smallest branch slope over ``[lo, hi]``; raises NotInvertibleError."""
    def pi_part_inverse(self) -> Mpim:
        """The eq. (7) inverse of the PI part (``a1 = 0``)."""
    def copy(self) -> Mpim:
        """An independent copy, memory included."""
    def __copy__(self) -> Mpim:
        """``copy.copy(model)``: an independent copy, memory included (also a deep copy)."""

class Scale:
    """``physical = offset + scale * normalised``."""

    def __init__(self, quantity: str, unit: str, offset: float = 0.0, scale: float = 1.0) -> None: ...
    @property
    def quantity(self) -> str: ...
    @property
    def unit(self) -> str: ...
    @property
    def offset(self) -> float: ...
    @property
    def scale(self) -> float: ...
    def normalise(self, physical: float) -> float:
        """``(physical - offset) / scale``."""
    def to_physical(self, normalised: float) -> float:
        """``offset + scale * normalised``."""

class ModelFile:
    """An identified model with its physical scales and direction (JSON, format version 1)."""

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
        """Reads and validates a model file. Raises FileNotFoundError, IsADirectoryError or
        OSError (naming the path), or ModelFileError for bad contents."""
    @staticmethod
    def from_json(text: str) -> ModelFile:
        """Parses and validates a model file's JSON text."""
    def to_json(self) -> str:
        """The JSON text of the file (format version 1)."""
    def save(self, path: PathLike) -> None:
        """Writes the file atomically (a reader sees the old file or the new one)."""
    def model(self) -> Mpim:
        """The normalised MPIM, from zero memory."""
    def predict(self, inputs: ArrayLike) -> FloatArray:
        """Model outputs (physical units) for physical inputs, from zero memory."""
    @property
    def direction(self) -> str: ...
    @property
    def description(self) -> Optional[str]: ...
    @description.setter
    def description(self, value: Optional[str]) -> None: ...
    @property
    def input(self) -> Scale: ...
    @property
    def output(self) -> Scale: ...
    @property
    def input_range(self) -> Tuple[float, float]: ...
    @property
    def thresholds(self) -> FloatArray: ...
    @property
    def weights(self) -> FloatArray: ...
    @property
    def a1(self) -> float: ...
    @property
    def a2(self) -> float: ...
    @property
    def format_version(self) -> int: ...
    @property
    def identification(self) -> Optional[Dict[str, Any]]: ...

class Compensator:
    """Desired position in, drive voltage out (the model file's physical units)."""

    def __init__(
        self,
        model: Union[ModelFile, PathLike],
        method: str = "ihc",
        limits: Optional[Sequence[float]] = None,
    ) -> None:
        """``method``: ``"ihc"``, ``"ihc-delayed"``, ``"wihc"``, ``"wihc-delayed"`` (plant
        models) or ``"dihc"`` (inverse models); ``limits``: ``(min, max)`` drive limits, by
        default the range the model was identified on. Every output stays within them, never
        NaN. Raises WrongDirectionError, NotInvertibleError, InvalidValueError, ModelFileError
        or an OSError for the file."""
    @staticmethod
    def from_mpim(model: Mpim, method: str = "ihc", limits: Sequence[float] = (0.0, 1.0)) -> Compensator:
        """A compensator in normalised units."""
    def step(self, y_d: float) -> float:
        """One sample: the drive for the desired position ``y_d``; InvalidValueError for NaN
        or infinite ``y_d`` (state unchanged)."""
    def process(self, y_d: ArrayLike) -> FloatArray:
        """A whole desired trajectory from the current state: the drive signal."""
    def reset(self) -> None:
        """Back to the initial state (memory zero, eq. (1)); diagnostics cleared."""
    @property
    def limits(self) -> Tuple[float, float]:
        """``(min, max)`` drive limits, in ``control_unit``."""
    @property
    def method(self) -> str:
        """``"ihc"``, ``"ihc-delayed"``, ``"wihc"``, ``"wihc-delayed"`` or ``"dihc"``."""
    @property
    def desired_unit(self) -> str:
        """Unit of the desired position (the input), e.g. ``"um"``."""
    @property
    def control_unit(self) -> str:
        """Unit of the drive (the output), e.g. ``"V"``."""
    @property
    def diagnostics(self) -> Dict[str, int]:
        """``{"saturated": ..., "loop_saturated": ..., "non_finite": ...}`` since the last
        reset: desired positions out of reach (the drive was clamped), samples a delayed loop
        drove to a limit although the position was reachable, and non-finite inputs."""
    @property
    def delayed_loop_gain(self) -> Optional[float]:
        """``wihc``/``wihc-delayed``: the delayed WIHC's worst-case loop gain over the limits,
        ``max |3 a1 x^2 + b_1 + ... + b_k| / a2``; at or above 1 the delayed loop can ring after a
        jump (prefer ``"wihc"``). ``None`` for the other methods. Table 1: 1.66."""

class Identification:
    """An identified model and its fit report."""

    @property
    def model(self) -> ModelFile: ...
    @property
    def report(self) -> Dict[str, Any]: ...
    @property
    def parameters(self) -> Dict[str, Any]: ...

def identify(
    voltage: ArrayLike,
    displacement: ArrayLike,
    n: int = 10,
    method: str = "ls",
    direction: str = "plant",
    *,
    seed: int = 0,
    thresholds: Optional[ArrayLike] = None,
    warmup: Union[str, int] = "auto",
    holdout: float = 0.0,
    offset: Union[str, float] = "fit",
    margin: float = 0.001,
    particles: int = 40,
    iterations: int = 200,
    polish: bool = False,
    accept_poor_fit: bool = False,
    voltage_unit: str = "V",
    displacement_unit: str = "um",
) -> Identification:
    """Identifies an MPIM (eq. (4)) from (voltage, displacement) samples."""

class Stage:
    """A simulated piezo nanopositioning stage."""

    def __init__(self, config_toml: Optional[str] = None, seed: int = 0) -> None:
        """The built-in stage, or one described by a TOML text; ``seed`` fixes its noise."""
    @staticmethod
    def from_file(path: PathLike, seed: int = 0) -> Stage:
        """A stage from a TOML file."""
    def step(self, command_v: float) -> float:
        """One sample: the measured position (um) for a DAC command (V)."""
    def run(self, command_v: ArrayLike) -> StageResponse:
        """A whole command signal from the current state."""
    def reset(self) -> None:
        """Back to rest, time zero, the same noise sequence."""
    @property
    def sample_rate_hz(self) -> float: ...
    @property
    def period_s(self) -> float: ...
    @property
    def samples(self) -> int: ...
    @property
    def time_s(self) -> float: ...
    @property
    def seed(self) -> int: ...
    @property
    def clamps(self) -> Dict[str, int]: ...
    @property
    def full_scale_command_v(self) -> float: ...
    @property
    def config_toml(self) -> str: ...
    def quasi_static_stroke_um(self) -> float: ...

class StageResponse:
    """python-control style: ``time``, ``inputs`` (V), ``outputs`` (um), one per sample."""

    @property
    def time(self) -> FloatArray: ...
    @property
    def inputs(self) -> FloatArray: ...
    @property
    def outputs(self) -> FloatArray: ...
    @property
    def command_v(self) -> FloatArray: ...
    @property
    def amplifier_v(self) -> FloatArray: ...
    @property
    def true_position_um(self) -> FloatArray: ...
    @property
    def measured_position_um(self) -> FloatArray: ...
    @property
    def clamps(self) -> Dict[str, int]: ...
    def __len__(self) -> int: ...

class TrackingIndices:
    """e_mhe (eq. (12)), e_m (D1), e_rms (D2), percent of the desired range."""

    @property
    def e_mhe(self) -> float: ...
    @property
    def e_m(self) -> float: ...
    @property
    def e_rms(self) -> float: ...
    @property
    def mhe_bins(self) -> int: ...
    def as_dict(self) -> Dict[str, float]: ...

def e_m(desired: ArrayLike, measured: ArrayLike) -> float:
    """Maximum tracking error (D1), percent of the desired range."""
def e_rms(desired: ArrayLike, measured: ArrayLike) -> float:
    """Root-mean-square tracking error (D2), percent of the desired range."""
def e_mhe(desired: ArrayLike, measured: ArrayLike, bins: int = 100) -> float:
    """Maximum hysteresis error, eq. (12), over ``bins`` bins, percent of the desired range.

    Needs at least 10 samples per bin on average (``bins <= max(1, len(desired) // 10)``);
    raises otherwise, naming the largest ``bins`` the record supports."""
def tracking_indices(desired: ArrayLike, measured: ArrayLike, bins: int = 100) -> TrackingIndices:
    """e_mhe, e_m and e_rms together; ``bins`` as for :func:`e_mhe`."""

class StudyResult:
    """The paper's Table 3 measured on the simulated stage."""

    @property
    def table(self) -> Dict[str, Any]: ...
    @property
    def published(self) -> Dict[str, Dict[str, float]]: ...
    def indices(self, pipeline: str, method: Optional[str] = None) -> TrackingIndices: ...
    @property
    def summary(self) -> Dict[str, Any]: ...
    @property
    def acceptance(self) -> List[Dict[str, Any]]: ...
    @property
    def passed(self) -> bool: ...
    @property
    def models(self) -> Dict[str, Dict[str, ModelFile]]: ...
    @property
    def time(self) -> FloatArray: ...
    @property
    def desired_um(self) -> FloatArray: ...
    @property
    def evaluation_start(self) -> int: ...
    @property
    def runs(self) -> Dict[str, Dict[str, FloatArray]]: ...
    @property
    def labels(self) -> List[str]: ...
    @property
    def report(self) -> Optional[pathlib.Path]: ...
    @property
    def elapsed_s(self) -> float: ...

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
    """The comparative study of section 4 on the simulated stage."""

def paper_trajectory(duration_s: float = 10.0, sample_rate_hz: float = 10000.0) -> Tuple[FloatArray, FloatArray]:
    """The paper's desired trajectory: ``(time_s, y_d_um)``."""
