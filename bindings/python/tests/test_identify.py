"""identify(): exact recovery on synthetic data, both solvers and directions, real data, and
bad input refused with the reason."""

import numpy as np
import pytest

import hystcomp
from conftest import DBO_DATA, table1_record

TABLE1_B = [0.2313, 0.3059, 0.0155, 0.0752, 0.0683, 0.0252, 0.0035, 0.0094, 0.0264, 0.0032]


def test_least_squares_recovers_table1_exactly():
    volts, um = table1_record()
    fit = hystcomp.identify(volts, um)
    assert isinstance(fit, hystcomp.Identification)
    model = fit.model
    assert model.direction == "plant"
    assert (model.input.unit, model.output.unit) == ("V", "um")
    # The output is normalised by the record's range (not the 75 um Table 1 is scaled by), so
    # compare the parameters in micrometres: the same model.
    assert model.output.scale == pytest.approx(um.max() - um.min())
    assert model.a1 * model.output.scale / 75.0 == pytest.approx(-0.1569, rel=1e-9)
    # F_0[x] = x: a2 and b_1 act alike and only their sum is determined.
    k = model.output.scale / 75.0
    assert (model.a2 + model.weights[0]) * k == pytest.approx(0.4603 + TABLE1_B[0], rel=1e-9)
    np.testing.assert_allclose(model.weights[1:] * k, TABLE1_B[1:], rtol=1e-9)
    report = fit.report
    assert report.solver == "ls"
    assert report.fit.rms_percent < 1e-6
    assert report.samples.total == len(volts)
    assert fit.parameters["weights"] == pytest.approx(list(model.weights))
    assert model.identification["solver"] == "ls"
    np.testing.assert_allclose(model.predict(volts), um, atol=1e-6)
    assert "solver=\"ls\"" in repr(fit)


def test_inverse_models_and_options():
    volts, um = table1_record()
    inverse = hystcomp.identify(volts, um, n=5, direction="inverse", holdout=0.25, warmup=100)
    assert inverse.model.direction == "inverse"
    assert len(inverse.model.thresholds) == 5
    assert inverse.report.samples.warmup == 100
    assert inverse.report.holdout.samples > 0
    given = hystcomp.identify(volts, um, thresholds=[0.0, 0.25, 0.5], offset="none", voltage_unit="kV")
    np.testing.assert_array_equal(given.model.thresholds, [0.0, 0.25, 0.5])
    assert given.model.input.unit == "kV"
    assert given.report.offset_mode == "none"


def test_particle_swarm_is_reproducible_per_seed():
    volts, um = table1_record(2000)
    # 25 iterations do not reach a usable fit: refused by default, accepted on request.
    with pytest.raises(hystcomp.IdentificationError, match="accept-poor-fit"):
        hystcomp.identify(volts, um, method="pso", seed=7, particles=12, iterations=25)
    fast = dict(method="pso", particles=12, iterations=25, accept_poor_fit=True)
    a = hystcomp.identify(volts, um, seed=7, **fast)
    b = hystcomp.identify(volts, um, seed=7, **fast)
    c = hystcomp.identify(volts, um, seed=8, **fast)
    assert a.report.fit.rms_percent > 10.0
    assert a.report.solver == "pso"
    # Same seed, same model (the report differs only by its wall-clock time).
    assert a.parameters == b.parameters
    assert a.parameters != c.parameters
    polished = hystcomp.identify(volts, um, seed=7, polish=True, **fast)
    assert polished.report.fit.rms <= a.report.fit.rms


@pytest.mark.parametrize(
    "kwargs, exception, message",
    [
        (dict(method="newton"), hystcomp.InvalidValueError, 'method "newton" is unknown'),
        (dict(direction="up"), hystcomp.InvalidValueError, 'direction "up" is unknown'),
        (dict(n=0), hystcomp.InvalidValueError, "at least 1"),
        (dict(holdout=1.0), hystcomp.InvalidValueError, "holdout"),
        (dict(warmup="soon"), hystcomp.InvalidValueError, 'warmup "soon"'),
        (dict(offset="zero"), hystcomp.InvalidValueError, 'offset "zero"'),
        (dict(thresholds=[0.5, 0.2]), hystcomp.InvalidValueError, "increase strictly"),
        (dict(method="pso", particles=1), hystcomp.InvalidValueError, "particles"),
        (dict(margin=-1.0), hystcomp.InvalidValueError, "margin"),
    ],
)
def test_bad_options_are_refused_with_the_reason(kwargs, exception, message):
    volts, um = table1_record(1000)
    with pytest.raises(exception, match=message):
        hystcomp.identify(volts, um, **kwargs)


def test_bad_samples_are_refused_with_the_reason():
    volts, um = table1_record(1000)
    with pytest.raises(hystcomp.InvalidValueError, match="length"):
        hystcomp.identify(volts, um[:-1])
    bad = um.copy()
    bad[10] = np.nan
    with pytest.raises(hystcomp.InvalidValueError, match="NaN"):
        hystcomp.identify(volts, bad)
    with pytest.raises(hystcomp.InvalidValueError, match="constant"):
        hystcomp.identify(np.ones(1000), um)
    with pytest.raises(hystcomp.InvalidValueError, match="samples"):
        hystcomp.identify(volts[:10], um[:10])


@pytest.mark.skipif(not (DBO_DATA / "Model_Vi_Do.dat").is_file(), reason="the DBO micromanipulator data are not present")
def test_real_micromanipulator_data_give_a_good_invertible_model():
    record = np.loadtxt(DBO_DATA / "Model_Vi_Do.dat")
    fit = hystcomp.identify(record[:, 0], record[:, 4], warmup=200, holdout=0.2)
    assert fit.report.fit.rms_percent < 1.5
    assert fit.report.holdout.rms_percent < 1.5
    assert fit.model.model().check_invertible() > 0
    volts = hystcomp.Ihc(fit.model).process(np.linspace(-115, -80, 400))
    assert 0.0 <= volts.min() and volts.max() <= 3.6
