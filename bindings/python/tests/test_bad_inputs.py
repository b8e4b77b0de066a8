"""Bad inputs through the Python API (issue 13): every size is bounded before anything is
allocated, and every refusal is an ordinary exception with a message naming the option; a
``PanicException`` (a BaseException that ``except Exception`` does not catch) never reaches
Python."""

import numpy as np
import pytest

import hystcomp
from conftest import TABLE1_FILE, table1_record


def refused(call, *fragments):
    """Calls ``call``; asserts it raises an Exception (not a panic) whose message holds every
    fragment, and returns it."""
    try:
        call()
    except BaseException as error:  # noqa: BLE001 - what is caught is what is checked
        assert isinstance(error, Exception), f"{type(error).__name__}: {error}"
        assert type(error).__name__ != "PanicException", str(error)
        message = str(error)
        for fragment in fragments:
            assert fragment in message, f"{fragment!r} not in {message!r}"
        return error
    pytest.fail(f"{call} was accepted")


@pytest.mark.parametrize(
    "kwargs, fragments",
    [
        (dict(stage_toml="sample_rate_hz = 1e300"), ["sample_rate_hz", "1e6"]),
        (dict(stage_toml="sample_rate_hz = 1e7"), ["sample_rate_hz", "1e6"]),
        # Within the stage's bound, beyond what the study simulates in one run.
        (
            dict(stage_toml="sample_rate_hz = 500000.0"),
            ["sample_rate_hz", "5000000"],
        ),
        (dict(pso_particles=10**9), ["particles", "1000"]),
        (dict(pso_iterations=10**9), ["iterations", "100000"]),
        (dict(operators=10**6), ["play operators", "1000"]),
        (dict(periods=10**9), ["periods"]),
        (dict(periods=1), ["periods"]),
    ],
)
def test_reproduce_refuses_sizes_beyond_their_bounds(kwargs, fragments):
    error = refused(lambda: hystcomp.reproduce(**kwargs), *fragments)
    assert isinstance(error, hystcomp.HystcompError)


@pytest.mark.parametrize(
    "kwargs, fragments",
    [
        (dict(n=5000), ["play operators", "1000"]),
        (dict(method="pso", particles=10**8), ["particles", "1000"]),
        (dict(method="pso", iterations=10**9), ["iterations", "100000"]),
        (dict(thresholds=np.linspace(0, 0.99, 2000)), ["thresholds", "1000"]),
    ],
)
def test_identify_refuses_sizes_beyond_their_bounds(kwargs, fragments):
    voltage, displacement = table1_record(2000)
    error = refused(lambda: hystcomp.identify(voltage, displacement, **kwargs), *fragments)
    assert isinstance(error, hystcomp.HystcompError)


def test_stage_and_trajectory_sizes_are_bounded():
    refused(lambda: hystcomp.Stage("sample_rate_hz = 1e300"), "sample_rate_hz")
    refused(lambda: hystcomp.paper_trajectory(duration_s=1e300), "1e8")
    # Integers beyond the native range are refused by the conversion, as an OverflowError.
    refused(lambda: hystcomp.reproduce(pso_particles=10**30))


def test_a_model_file_with_a_bare_nan_says_what_it_is(tmp_path):
    # What json.dump writes for float("nan").
    path = tmp_path / "nan.json"
    path.write_text(TABLE1_FILE.read_text().replace("-0.1569", "NaN", 1))
    refused(lambda: hystcomp.ModelFile.load(path), "nan.json", "bare NaN", "json.dump")
