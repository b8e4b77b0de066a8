"""CompensatorBank: every channel equals its own Compensator bit for bit (step and process),
arrays of shape (channels,) and (samples, channels), per-channel limits and diagnostics, bad
input refused naming the sample and channel, refused channels named."""

import numpy as np
import pytest

import hystcomp
from conftest import MODELS, TABLE1_FILE, TABLE2_FILE

SET_FILE = MODELS / "table1-xyz-set.json"
T = np.arange(0.0, 1.0, 1e-3)
DESIRED = np.stack(
    [
        35.0 + 30.0 * np.sin(2 * np.pi * T),
        30.0 + 25.0 * np.cos(2.6 * np.pi * T),
        45.0 + 40.0 * np.sin(1.4 * np.pi * T + 1.0),
    ],
    axis=1,
)


def singles(method, limits=None):
    """The channels' own compensators, from the set's models."""
    bank = hystcomp.CompensatorBank(SET_FILE, method, limits, allow_unstable_delay=True)
    import json

    data = json.loads(SET_FILE.read_text())
    out = []
    for k, channel in enumerate(data["channels"]):
        model = hystcomp.ModelFile.from_json(json.dumps(channel["model"]))
        lim = None if limits is None else (limits[k] if isinstance(limits[0], (list, tuple)) else limits)
        out.append(hystcomp.Compensator(model, method, lim, allow_unstable_delay=True))
    return bank, out


@pytest.mark.parametrize(
    "method, limits",
    [
        ("ihc", None),
        ("wihc", (0.5, 9.5)),
        ("ihc-guarded", [(0.0, 10.0), (1.0, 9.0), (0.2, 8.0)]),
        ("wihc-delayed", None),
    ],
)
def test_every_channel_equals_its_own_compensator(method, limits):
    bank, own = singles(method, limits)
    assert (bank.channels, len(bank), bank.names, bank.method) == (3, 3, ["x", "y", "z"], method)
    whole = bank.process(DESIRED)
    assert whole.shape == DESIRED.shape and whole.dtype == np.float64
    for c, single in enumerate(own):
        np.testing.assert_array_equal(whole[:, c], single.process(DESIRED[:, c]))
        assert bank.diagnostics[c] == single.diagnostics
        assert bank.limits[c] == single.limits
    bank.reset()
    for c in range(3):
        own[c].reset()
    for k in range(200):
        v = bank.step(DESIRED[k])
        assert v.shape == (3,)
        assert [v[c] for c in range(3)] == [own[c].step(DESIRED[k, c]) for c in range(3)]
    assert bank.desired_units == ["um"] * 3 and bank.control_units == ["V"] * 3


def test_a_list_of_models_makes_a_bank():
    bank = hystcomp.CompensatorBank([TABLE1_FILE, hystcomp.ModelFile.load(TABLE1_FILE)], "ihc")
    assert bank.names == ["table1-plant", "channel_1"]
    v = bank.process(np.column_stack([DESIRED[:, 0], DESIRED[:, 0]]))
    np.testing.assert_array_equal(v[:, 0], v[:, 1])
    np.testing.assert_array_equal(v[:, 0], hystcomp.Compensator(TABLE1_FILE).process(DESIRED[:, 0]))
    dihc = hystcomp.CompensatorBank([TABLE2_FILE] * 2, "dihc")
    assert dihc.channels == 2 and dihc.names == ["channel_0", "channel_1"]


def test_bad_input_is_refused_with_the_reason():
    bank = hystcomp.CompensatorBank(SET_FILE)
    twin = hystcomp.CompensatorBank(SET_FILE)
    before = bank.step([10.0, 10.0, 10.0])
    np.testing.assert_array_equal(twin.step([10.0, 10.0, 10.0]), before)
    bad = DESIRED.copy()
    bad[7, 2] = np.nan
    with pytest.raises(hystcomp.InvalidValueError, match="sample 7, channel 2"):
        bank.process(bad)
    # As Compensator: infinities and magnitudes beyond 1e15 are refused too, naming the place.
    for value, fragment in [(np.inf, "is inf"), (-2e15, "beyond the 1e15")]:
        bad = DESIRED.copy()
        bad[3, 1] = value
        with pytest.raises(hystcomp.InvalidValueError, match="sample 3, channel 1"):
            bank.process(bad)
        with pytest.raises(hystcomp.InvalidValueError, match=fragment):
            bank.step([10.0, value, 10.0])
        with pytest.raises(hystcomp.InvalidValueError, match="not finite|is beyond"):
            hystcomp.Compensator(TABLE1_FILE).step(value)
    with pytest.raises(hystcomp.InvalidValueError, match="3 channels"):
        bank.step([1.0, 2.0])
    with pytest.raises(hystcomp.InvalidValueError, match="columns"):
        bank.process(DESIRED[:, :2])
    with pytest.raises(TypeError, match="shape"):
        bank.process(DESIRED[:, 0])
    with pytest.raises(TypeError, match="real numbers"):
        bank.step(np.array([1j, 2j, 3j]))
    # The state is unchanged by the refusals: the next step is its twin's, which saw none.
    np.testing.assert_array_equal(bank.step([12.0, 11.0, 9.0]), twin.step([12.0, 11.0, 9.0]))
    bank.reset()
    assert np.array_equal(bank.step([10.0, 10.0, 10.0]), before)
    with pytest.raises(hystcomp.WrongDirectionError, match=r"^channel 0 \(x\): "):
        hystcomp.CompensatorBank(SET_FILE, "dihc")
    with pytest.raises(hystcomp.UnstableDelayError, match=r"^channel 0 \(x\): "):
        hystcomp.CompensatorBank(SET_FILE, "wihc-delayed")
    with pytest.raises(hystcomp.InvalidValueError, match=r"^channel 1 \(y\): "):
        hystcomp.CompensatorBank(SET_FILE, "ihc", [(0.0, 10.0), (5.0, 1.0), (0.0, 10.0)])
    with pytest.raises(hystcomp.InvalidValueError, match="drive limits"):
        hystcomp.CompensatorBank(SET_FILE, "ihc", [(0.0, 10.0), (0.0, 10.0)])
    with pytest.raises(OSError):
        hystcomp.CompensatorBank(MODELS / "no-such-set.json")
    # A list's missing file and a bad limits pair are named by their place in the list.
    with pytest.raises(FileNotFoundError, match=r"channel 1 \(missing\)"):
        hystcomp.CompensatorBank([TABLE1_FILE, MODELS / "missing.json"], "ihc")
    with pytest.raises(hystcomp.InvalidValueError, match=r"limits\[1\] must be two numbers"):
        hystcomp.CompensatorBank(SET_FILE, "ihc", [(0.0, 10.0), (0.0, 10.0, 5.0), (0.0, 10.0)])


def test_a_refused_channel_model_names_the_set_file(tmp_path):
    import json

    data = json.loads(SET_FILE.read_text())
    data["channels"][1]["model"]["thresholds"][3] = 0.05  # unsorted thresholds
    bad = tmp_path / "bad-set.json"
    bad.write_text(json.dumps(data))
    with pytest.raises(hystcomp.HystcompError) as refused:
        hystcomp.CompensatorBank(bad, "ihc")
    assert str(refused.value).startswith(f"{bad}: channel 1 (y): "), str(refused.value)
