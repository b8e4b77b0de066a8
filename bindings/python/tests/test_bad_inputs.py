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


def test_positions_beyond_a_records_bound_are_refused_naming_the_sample(table1):
    # A model whose output scale is below 1 turned 1e308 um into an infinity and held the
    # previous drive (counted as non-finite, no error); the command line refuses such values
    # when it reads a record, and so does the Python boundary.
    half = hystcomp.ModelFile(
        "plant",
        table1.thresholds,
        table1.weights,
        table1.a1,
        table1.a2,
        input=table1.input,
        output=hystcomp.Scale("displacement", "um", 0.0, 0.5),
    )
    for method in ["ihc", "wihc", "ihc-guarded"]:
        c = hystcomp.Compensator(half, method)
        before = c.process([0.1, 0.2])
        refused(lambda: c.process([0.1, 1e308, 0.2]), "y_d[1]", "1e15")
        refused(lambda: c.step(-2e15), "y_d", "1e15")
        assert c.diagnostics.non_finite == 0
        c.reset()
        np.testing.assert_array_equal(c.process([0.1, 0.2]), before)
    refused(lambda: table1.predict([1.0, 1e16]), "inputs[1]", "1e15")


def test_a_model_output_that_overflows_is_refused_with_the_memory_kept():
    m = hystcomp.Mpim.table1()
    m.process([0.5, 0.2])
    memory = m.memory.copy()
    refused(lambda: m.process([0.3, 1e308]), "x[1]", "overflow")
    refused(lambda: m.step(-1e200), "x", "overflow")
    np.testing.assert_array_equal(m.memory, memory)
    assert np.isfinite(m.process([1e15, -1e15])).all()


def test_a_model_file_too_large_to_read_back_is_not_written(table1, tmp_path):
    path = tmp_path / "described.json"
    path.write_text("old")
    table1.description = "x" * (17 << 20)
    refused(lambda: table1.save(path), "described.json", "16 MiB", "description")
    assert path.read_text() == "old"
