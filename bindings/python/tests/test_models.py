"""Mpim, Scale and ModelFile: the core's model and hystcomp-io's model file."""

import copy
import json

import numpy as np
import pytest

import hystcomp
from conftest import TABLE1_FILE

TABLE1_R = [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9]
TABLE1_B = [0.2313, 0.3059, 0.0155, 0.0752, 0.0683, 0.0252, 0.0035, 0.0094, 0.0264, 0.0032]


def one_sided_play(x, r):
    """Eqs. (1)-(2) written out: the reference the compiled model is checked against."""
    w, out = 0.0, []
    for v in x:
        w = max(v - r, min(v, w))
        out.append(w)
    return np.array(out)


def test_table1_is_the_paper_table_and_matches_eq4_written_out():
    m = hystcomp.Mpim.table1()
    assert len(m) == 10
    np.testing.assert_array_equal(m.thresholds, TABLE1_R)
    np.testing.assert_array_equal(m.weights, TABLE1_B)
    assert (m.a1, m.a2) == (-0.1569, 0.4603)
    x = 0.5 + 0.45 * np.sin(np.linspace(0, 12, 700)) * np.linspace(1, 0.2, 700)
    expected = -0.1569 * x**3 + 0.4603 * x + sum(b * one_sided_play(x, r) for r, b in zip(TABLE1_R, TABLE1_B))
    np.testing.assert_allclose(m.process(x), expected, rtol=0, atol=1e-14)


def test_step_and_process_agree_and_reset_forgets():
    a, b = hystcomp.Mpim.table1(), hystcomp.Mpim.table1()
    x = np.abs(np.sin(np.arange(300) * 0.05))
    stepped = np.array([a.step(v) for v in x])
    np.testing.assert_array_equal(stepped, b.process(x))
    assert a.memory.max() > 0
    a.reset()
    np.testing.assert_array_equal(a.memory, np.zeros(10))
    np.testing.assert_array_equal(a.process(x), stepped)


def test_process_accepts_lists_integers_and_strided_views():
    m = hystcomp.Mpim.table1()
    as_list = m.process([0, 1, 0.5])
    m.reset()
    as_ints = m.process(np.array([0, 1, 0], dtype=np.int64))
    m.reset()
    strided = m.process(np.array([0.0, 9.0, 1.0, 9.0, 0.5])[::2])
    assert as_list.dtype == np.float64 and as_list.shape == (3,)
    np.testing.assert_array_equal(as_list, strided)
    assert as_ints[1] == as_list[1]


def test_copies_are_independent():
    m = hystcomp.Mpim.table1()
    m.step(0.7)
    c = m.copy()
    c2 = copy.copy(m)
    c.step(0.1)
    np.testing.assert_array_equal(m.memory, c2.memory)
    assert not np.array_equal(m.memory, c.memory)


def test_set_memory_is_validated():
    m = hystcomp.Mpim.table1()
    m.set_memory(np.full(10, 0.2))
    np.testing.assert_array_equal(m.memory, np.full(10, 0.2))
    with pytest.raises(hystcomp.InvalidValueError, match="entries"):
        m.set_memory([0.1, 0.2])


def test_nan_input_is_refused_and_memory_untouched():
    m = hystcomp.Mpim.table1()
    m.step(0.6)
    before = m.memory
    with pytest.raises(hystcomp.InvalidValueError, match="x = NaN is not finite"):
        m.step(float("nan"))
    with pytest.raises(hystcomp.InvalidValueError, match=r"x\[2\] = inf is not finite"):
        m.process([0.1, 0.2, np.inf])
    np.testing.assert_array_equal(m.memory, before)


@pytest.mark.parametrize(
    "thresholds, weights, a1, a2, message",
    [
        ([0.0, 0.1], [0.2], 0.0, 1.0, "weights has 1 entries but 2 are needed"),
        ([0.0, np.nan], [0.2, 0.1], 0.0, 1.0, r"thresholds\[1\] is NaN"),
        ([0.0, 0.1], [0.2, 0.1], np.inf, 1.0, "a1 is NaN or infinite"),
        ([-0.1, 0.1], [0.2, 0.1], 0.0, 1.0, "negative"),
        ([0.2, 0.1], [0.2, 0.1], 0.0, 1.0, "sort the operators"),
        (
            np.linspace(0.0, 1.0, 10_001),
            np.full(10_001, 1e-4),
            0.0,
            1.0,
            "thresholds has 10001 entries: a model holds at most 10000",
        ),
    ],
)
def test_invalid_parameters_are_refused_with_the_reason(thresholds, weights, a1, a2, message):
    with pytest.raises(hystcomp.InvalidValueError, match=message):
        hystcomp.Mpim(thresholds, weights, a1, a2)


def test_invertibility_check_gives_the_slope_or_the_reason():
    slope = hystcomp.Mpim.table1().check_invertible()
    assert 0 < slope < 1
    folding = hystcomp.Mpim(TABLE1_R, TABLE1_B, -2.0, 0.4603)
    with pytest.raises(hystcomp.NotInvertibleError, match="not invertible on the input range"):
        folding.check_invertible(0.0, 1.0)
    assert folding.check_invertible(0.0, 0.2) > 0
    with pytest.raises(hystcomp.InvalidValueError, match="input range"):
        folding.check_invertible(1.0, 0.0)


def test_pi_part_inverse_undoes_the_pi_part():
    pi = hystcomp.Mpim(TABLE1_R, TABLE1_B, 0.0, 0.4603)
    inverse = pi.pi_part_inverse()
    assert inverse.a1 == 0.0 and inverse.a2 == pytest.approx(1 / 0.4603)
    v = 0.5 + 0.45 * np.sin(np.linspace(0, 20, 2000)) * np.exp(-np.linspace(0, 2, 2000))
    np.testing.assert_allclose(inverse.process(pi.process(v)), v, atol=1e-13)


def test_scale_maps_both_ways_and_refuses_zero_scale():
    s = hystcomp.Scale("voltage", "V", offset=1.0, scale=10.0)
    assert s.to_physical(0.5) == 6.0 and s.normalise(6.0) == 0.5
    assert (s.quantity, s.unit, s.offset, s.scale) == ("voltage", "V", 1.0, 10.0)
    assert s == hystcomp.Scale("voltage", "V", 1.0, 10.0)
    with pytest.raises(hystcomp.InvalidValueError, match="scale > 0"):
        hystcomp.Scale("voltage", "V", 0.0, 0.0)


def test_model_file_fields_and_model(table1):
    assert table1.direction == "plant"
    assert table1.format_version == 1
    assert (table1.input.unit, table1.input.scale) == ("V", 10.0)
    assert (table1.output.unit, table1.output.scale) == ("um", 75.0)
    assert table1.input_range == (0.0, 1.0)
    np.testing.assert_array_equal(table1.weights, TABLE1_B)
    assert "Table 1" in table1.description
    assert table1.identification is None
    m = table1.model()
    assert (m.a1, m.a2) == (table1.a1, table1.a2)


def test_predict_is_the_model_in_physical_units(table1):
    volts = np.linspace(0, 10, 50)
    expected = 75.0 * hystcomp.Mpim.table1().process(volts / 10.0)
    np.testing.assert_allclose(table1.predict(volts), expected, rtol=1e-15, atol=1e-12)


def test_model_file_round_trips_through_json_and_disk(table1, tmp_path):
    # The example file is format_version 1; what is written is version 2 (which only adds
    # optional parts), and from then on it round-trips as it is.
    assert table1.format_version == 1
    again = hystcomp.ModelFile.from_json(table1.to_json())
    assert again.format_version == 2
    assert again.to_json() == table1.to_json()
    assert hystcomp.ModelFile.from_json(again.to_json()) == again
    path = tmp_path / "copy.json"
    table1.description = "a copy"
    table1.save(path)
    loaded = hystcomp.ModelFile.load(str(path))
    assert loaded.description == "a copy"
    assert loaded.to_json() == table1.to_json()
    np.testing.assert_array_equal(loaded.weights, table1.weights)
    assert (loaded.a1, loaded.a2) == (table1.a1, table1.a2)
    assert loaded == hystcomp.ModelFile.load(str(path))
    assert json.loads(path.read_text())["direction"] == "plant"


def test_model_file_is_built_and_validated():
    f = hystcomp.ModelFile(
        "inverse",
        TABLE1_R,
        TABLE1_B,
        0.1,
        1.0,
        input=hystcomp.Scale("displacement", "um", 0.0, 75.0),
        output=hystcomp.Scale("voltage", "V", 0.0, 10.0),
        description="test",
    )
    assert f.direction == "inverse" and f.output.unit == "V"
    plain = hystcomp.ModelFile("plant", [0.0], [0.5], 0.0, 1.0)
    assert plain.input.unit == "1"
    with pytest.raises(hystcomp.InvalidValueError, match='direction "sideways" is unknown'):
        hystcomp.ModelFile("sideways", [0.0], [0.5], 0.0, 1.0)
    with pytest.raises(hystcomp.ModelFileError, match="input_range"):
        hystcomp.ModelFile("plant", [0.0], [0.5], 0.0, 1.0, input_range=(1.0, 0.0))
    with pytest.raises(hystcomp.InvalidValueError, match="refused"):
        hystcomp.ModelFile("plant", [0.0], [np.nan], 0.0, 1.0)


def test_missing_unreadable_and_invalid_files_raise_with_the_path(tmp_path):
    with pytest.raises(FileNotFoundError) as missing:
        hystcomp.ModelFile.load(tmp_path / "none.json")
    assert missing.value.filename.endswith("none.json")
    assert "No such file" in str(missing.value)
    with pytest.raises(OSError):
        hystcomp.ModelFile.load(tmp_path)
    garbage = tmp_path / "garbage.json"
    garbage.write_text("{ not json")
    with pytest.raises(hystcomp.ModelFileError, match="not a valid hystcomp model file"):
        hystcomp.ModelFile.load(garbage)
    future = json.loads(TABLE1_FILE.read_text())
    future["format_version"] = 3
    newer = tmp_path / "newer.json"
    newer.write_text(json.dumps(future))
    with pytest.raises(hystcomp.ModelFileError, match="format_version 3"):
        hystcomp.ModelFile.load(newer)
    with pytest.raises(OSError):
        hystcomp.ModelFile.load(TABLE1_FILE).save(tmp_path / "no" / "such" / "dir" / "m.json")


def test_a_directory_as_model_file_is_refused_naming_it(tmp_path):
    with pytest.raises(IsADirectoryError) as error:
        hystcomp.ModelFile.load(tmp_path)
    assert "is a directory" in str(error.value)
    assert str(tmp_path) in str(error.value)
    with pytest.raises(IsADirectoryError, match="is a directory"):
        hystcomp.Compensator(tmp_path, "ihc")
    # Saving into a missing folder names the target once and the folder that is missing.
    target = tmp_path / "no" / "m.json"
    with pytest.raises(FileNotFoundError) as missing:
        hystcomp.ModelFile.load(TABLE1_FILE).save(target)
    text = str(missing.value)
    assert text.count(str(target)) == 1 and "does not exist" in text, text


@pytest.mark.parametrize("shape", [(3, 4), (1, 5), (2, 1, 3)])
def test_arrays_of_more_dimensions_are_refused_with_their_shape(shape):
    m = hystcomp.Mpim.table1()
    with pytest.raises(TypeError) as error:
        m.process(np.zeros(shape))
    text = str(error.value)
    assert "expected a 1-D array of floats" in text, text
    assert str(shape) in text, text
    assert "dimensionality mismatch" not in text
    # Nested lists too, and through a compensator.
    with pytest.raises(TypeError, match=r"1-D array of floats.*\(2, 2\)"):
        hystcomp.Compensator(TABLE1_FILE, "ihc").process([[1.0, 2.0], [3.0, 4.0]])
    with pytest.raises(TypeError, match=r"0-D array.*wrap a single number in a list"):
        m.process(3.0)
    # Memory untouched by the refusals.
    np.testing.assert_array_equal(m.memory, np.zeros(10))


def test_complex_values_are_refused_not_truncated():
    m = hystcomp.Mpim.table1()
    for z in (np.array([0.1 + 0.2j, 0.3]), [0.5j, 0.1], np.array([0.1, 0.2], dtype=np.complex64)):
        with pytest.raises(TypeError, match="complex values"):
            m.process(z)
    with pytest.raises(TypeError, match=r"complex values.*a\.real"):
        hystcomp.Compensator(TABLE1_FILE, "ihc").process(np.array([30.0 + 0j]))
    with pytest.raises(TypeError, match="expected a 1-D array of floats, but got an array of"):
        m.process(np.array(["0.1", "0.2"]))
    # Complex-typed zeros are still complex: the dtype decides, not the values.
    with pytest.raises(TypeError, match="complex"):
        m.process(np.zeros(3, dtype=complex))
    np.testing.assert_array_equal(m.memory, np.zeros(10))
