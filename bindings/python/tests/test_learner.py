"""hystcomp.Learner: iterative learning between trials, against a plain numpy reference of the
law, with its guarantees (limits, divergence guard, refusals) checked on seeded random records."""

import json
import warnings

import numpy as np
import pytest

import hystcomp
from conftest import TABLE1_FILE, TABLE2_FILE

FS = 1000.0
N = 1000


def desired_sine(offset=35.0, amplitude=20.0, n=N):
    k = np.arange(n)
    return offset + amplitude * np.sin(2 * np.pi * k / n)


def wrong_plant(table1, factor):
    """The Table 1 model with its output scaled by ``factor``: a 'stage' the model gets wrong."""
    data = json.loads(table1.to_json())
    data["output"]["scale"] *= factor
    data["output"]["offset"] *= factor
    return hystcomp.ModelFile.from_json(json.dumps(data))


def periodic_response(plant, drive):
    """The plant's periodic state under a drive repeated: the middle of three periods."""
    n = len(drive)
    return plant.predict(np.tile(drive, 3))[n : 2 * n]


def reference_update(reference, error, gain, cutoff_hz, order, lead, fs):
    """``r + Q[gamma z^m e]`` for a periodic record, straight from the definition: the DFT of
    the error weighed by ``gamma Q(f) e^(j 2 pi f m / fs)`` with ``Q(f) = 1 / (1 + (f /
    f_c)^(2n))``."""
    n = len(error)
    h = np.arange(n)
    f = np.minimum(h, n - h) * fs / n
    q = 1.0 / (1.0 + (f / cutoff_hz) ** (2 * order))
    weights = gain * q * np.exp(2j * np.pi * h * lead / n)
    return reference + np.real(np.fft.ifft(np.fft.fft(error) * weights))


def test_learns_a_wrong_plant_down_to_rounding(table1):
    plant = wrong_plant(table1, 0.95)
    learner = hystcomp.Learner(table1, desired_sine(), FS)
    e_rms = []
    drive = learner.drive
    for _ in range(6):
        measured = periodic_response(plant, drive)
        drive = learner.update(measured)
        e_rms.append(learner.last_update.indices.e_rms_percent)
    assert e_rms[0] > 1.0, e_rms
    assert e_rms[5] < e_rms[0] / 100.0, e_rms
    assert [i.e_rms for i in learner.history] == pytest.approx(e_rms)
    assert learner.trials == 6
    assert learner.best_trial == 5
    assert not learner.stopped


@pytest.mark.parametrize("seed", range(8))
def test_update_matches_the_law_on_random_records(table1, seed):
    """Random smooth measured records (seeded): the next reference is r + Q[gamma z^m e] of
    the numpy reference wherever it stays in the reachable range; the drive is finite, within
    the limits and the exact inverse of that reference."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(200, 1200))
    gain = float(rng.uniform(0.2, 1.5))
    cutoff = float(rng.uniform(5.0, 200.0))
    order = int(rng.integers(1, 6))
    lead = int(rng.integers(0, 5))
    desired = desired_sine(offset=float(rng.uniform(30, 40)), amplitude=float(rng.uniform(5, 20)), n=n)
    learner = hystcomp.Learner(
        table1, desired, FS, gain=gain, bandwidth_hz=cutoff, filter_order=order, lead_samples=lead, mhe_bins=10
    )
    r0 = learner.reference
    np.testing.assert_allclose(r0, desired)
    k = np.arange(n)
    measured = desired + rng.normal(0, 0.5) * np.sin(2 * np.pi * 3 * k / n + rng.uniform(0, 6)) + rng.normal(0, 0.05, n)
    drive = learner.update(measured)
    want = reference_update(r0, desired - measured, gain, cutoff, order, lead, FS)
    got = learner.reference
    inside = (want > 0.5) & (want < 70.0)  # well inside the reachable range: not clamped
    assert inside.mean() > 0.9
    np.testing.assert_allclose(got[inside], want[inside], atol=1e-9)
    lo, hi = learner.law.limits
    assert np.all(np.isfinite(drive)) and drive.min() >= lo and drive.max() <= hi
    np.testing.assert_array_equal(drive, learner.drive)
    # The drive is the exact inverse of the reference: the model maps it back (periodic state).
    np.testing.assert_allclose(periodic_response(table1, drive), got, atol=1e-6)
    law = learner.law
    assert (law.gain, law.bandwidth_hz, law.filter_order, law.lead_samples) == (gain, cutoff, order, lead)
    assert law.stationary_noise_ratio is None or law.stationary_noise_ratio > 0


@pytest.mark.parametrize("seed", range(5))
def test_drive_never_leaves_the_limits_whatever_is_measured(table1, seed):
    """Wild measurements (seeded: large offsets, spikes, noise): every drive stays within the
    limits given and is finite, trial after trial, until the guard stops the learning."""
    rng = np.random.default_rng(100 + seed)
    limits = (1.0, 9.0)
    learner = hystcomp.Learner(table1, desired_sine(), FS, limits=limits, gain=float(rng.uniform(0.5, 3.0)), divergence_factor=100.0)
    for _ in range(6):
        measured = rng.normal(rng.uniform(-100, 200), rng.uniform(0, 100), N)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", hystcomp.LearningDivergedWarning)
            drive = learner.update(measured)
        assert np.all(np.isfinite(drive))
        assert drive.min() >= limits[0] and drive.max() <= limits[1]
        if learner.stopped:
            break


def test_divergence_guard_warns_keeps_the_last_good_drive_and_then_refuses(table1):
    plant = wrong_plant(table1, 0.95)
    learner = hystcomp.Learner(table1, desired_sine(), FS, gain=10.0, bandwidth_hz=FS / 2)
    first = learner.drive
    drive = learner.update(periodic_response(plant, first))
    assert learner.last_update.status == {"state": "learning"}
    with pytest.warns(hystcomp.LearningDivergedWarning, match="divergence guard stopped the learning at trial 1"):
        kept = learner.update(periodic_response(plant, drive))
    np.testing.assert_array_equal(kept, first)
    np.testing.assert_array_equal(learner.best_drive, first)
    assert learner.stopped and learner.best_trial == 0
    update = learner.last_update
    assert update.diverged and update.predicted is None and update.status["best_trial"] == 0
    with pytest.raises(hystcomp.LearningStoppedError, match="last good one"):
        learner.update(periodic_response(plant, kept))
    assert isinstance(hystcomp.LearningStoppedError("x"), RuntimeError)


def test_resuming_from_a_drive_recovers_the_reference(table1):
    plant = wrong_plant(table1, 1.05)
    learner = hystcomp.Learner(table1, desired_sine(), FS)
    drive = learner.update(periodic_response(plant, learner.drive))
    resumed = hystcomp.Learner(TABLE1_FILE, desired_sine(), FS, drive=drive)
    np.testing.assert_allclose(resumed.reference, learner.reference, atol=1e-6)
    measured = periodic_response(plant, drive)
    np.testing.assert_allclose(resumed.update(measured), learner.update(measured), atol=1e-6)


def test_finite_trials_are_learned_too(table1):
    plant = wrong_plant(table1, 0.95)
    desired = 35.0 + 20.0 * np.sin(np.pi * np.arange(N) / N) ** 2
    learner = hystcomp.Learner(table1, desired, FS, periodic=False)
    assert learner.law.padding_samples > 0 and not learner.law.periodic
    e = []
    for _ in range(5):
        learner.update(plant.predict(learner.drive))
        e.append(learner.last_update.indices.e_rms_percent)
    assert e[4] < e[0] / 20.0, e


def test_bad_arguments_are_refused_naming_what(table1):
    desired = desired_sine()
    with pytest.raises(hystcomp.InvalidValueError, match="gain"):
        hystcomp.Learner(table1, desired, FS, gain=0.0)
    with pytest.raises(hystcomp.InvalidValueError, match="sample rate"):
        hystcomp.Learner(table1, desired, float("nan"))
    with pytest.raises(hystcomp.InvalidValueError, match="bandwidth"):
        hystcomp.Learner(table1, desired, FS, bandwidth_hz=FS)
    with pytest.raises(hystcomp.InvalidValueError, match="inverse"):
        hystcomp.Learner(table1, desired, FS, inverse="dihc")
    with pytest.raises(hystcomp.InvalidValueError, match=r"desired\[3\]"):
        hystcomp.Learner(table1, np.where(np.arange(N) == 3, np.nan, desired), FS)
    with pytest.raises(hystcomp.InvalidValueError, match="drive"):
        hystcomp.Learner(table1, desired, FS, drive=np.full(N, 50.0))
    with pytest.raises(hystcomp.InvalidValueError, match="samples"):
        hystcomp.Learner(table1, desired, FS, drive=np.full(N - 1, 5.0))
    with pytest.raises(hystcomp.WrongDirectionError, match="plant model"):
        hystcomp.Learner(TABLE2_FILE, desired, FS)
    with pytest.raises(hystcomp.InvalidValueError, match="e_mhe bins"):
        hystcomp.Learner(table1, desired[:500], FS)
    with pytest.raises(TypeError):
        hystcomp.Learner(table1, np.ones((2, 3)), FS)
    learner = hystcomp.Learner(table1, desired, FS)
    before = learner.drive
    with pytest.raises(hystcomp.InvalidValueError, match="measured.*999 samples"):
        learner.update(desired[:-1])
    with pytest.raises(hystcomp.InvalidValueError, match=r"measured\[7\]"):
        learner.update(np.where(np.arange(N) == 7, np.inf, desired))
    # Refused records change nothing.
    assert learner.trials == 0 and learner.last_update is None
    np.testing.assert_array_equal(learner.drive, before)
    assert "Learner(samples=1000, trials=0" in repr(learner)
