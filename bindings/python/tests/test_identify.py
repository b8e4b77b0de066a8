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


def test_for_delayed_bounds_both_delayed_loops_and_says_what_it_cost():
    volts, um = table1_record()
    free = hystcomp.identify(volts, um, holdout=0.0)
    # Table 1's delayed WIHC rings (gain 1.66): the free fit keeps it.
    assert free.report.delayed_loop_gains["wihc"] > 1.0
    assert free.report.delayed_constraint is None
    bounded = hystcomp.identify(volts, um, holdout=0.0, for_delayed=True, delayed_loop_bound=0.8)
    gains = bounded.report.delayed_loop_gains
    assert max(gains["ihc"], gains["wihc"]) <= 0.8 + 1e-9
    cost = bounded.report.delayed_constraint
    assert cost["bound"] == 0.8
    assert cost["unconstrained_fit_rms_percent"] == pytest.approx(free.report.fit.rms_percent, abs=1e-9)
    assert cost["unconstrained_gains"]["wihc"] == pytest.approx(free.report.delayed_loop_gains["wihc"])
    assert bounded.report.fit.rms_percent >= free.report.fit.rms_percent - 1e-12
    # The plain delayed WIHC is refused on the free model and builds on the bounded one.
    with pytest.raises(hystcomp.UnstableDelayError):
        hystcomp.Compensator(free.model, "wihc-delayed", limits=(0.0, 10.0))
    hystcomp.Compensator(bounded.model, "wihc-delayed", limits=(0.0, 10.0))
    # Inverse models have no delayed loop: the option changes nothing there.
    inverse = hystcomp.identify(volts, um, direction="inverse", for_delayed=True)
    assert inverse.report.delayed_constraint is None
    with pytest.raises(hystcomp.InvalidValueError, match="delayed"):
        hystcomp.identify(volts, um, for_delayed=True, delayed_loop_bound=1.5)


def test_n_auto_chooses_by_held_out_error_and_says_why():
    volts, um = table1_record()
    fit = hystcomp.identify(volts, um, n="auto", holdout=0.25)
    selection = fit.order_selection
    tried = {c["operators"]: c["holdout_rms_percent"] for c in selection["candidates"]}
    assert set(tried) <= {5, 10, 15, 20, 30, 40, 50} and len(tried) >= 3
    assert selection["holdout"] == 0.25
    best = min(tried.values())
    # The smallest n within 1 % of the best held-out error, and the model has it.
    assert selection["operators"] == min(n for n, e in tried.items() if e <= best * 1.01)
    assert len(fit.model.thresholds) == selection["operators"]
    assert hystcomp.identify(volts, um, n=10).order_selection is None
    with pytest.raises(hystcomp.InvalidValueError, match="auto"):
        hystcomp.identify(volts, um, n="many")


def test_predict_gives_the_models_prediction_and_error_per_sample(table1, table2):
    volts, um = table1_record()
    um = um + 0.01 * np.sin(np.arange(len(um)))
    p = hystcomp.predict(table1, volts, um)
    assert isinstance(p, hystcomp.Prediction) and len(p) == len(volts)
    assert p.direction == "plant" and "reset" in p.initial_state
    np.testing.assert_array_equal(p.predicted, table1.predict(volts))
    np.testing.assert_allclose(p.error, p.predicted - um, rtol=0, atol=0)
    rms = np.sqrt(np.mean(p.error**2))
    assert p.stats.range == pytest.approx(um.max() - um.min())
    assert p.stats.rms_percent == pytest.approx(100 * rms / (um.max() - um.min()), rel=1e-12)
    assert p.outside_input_range == 0
    # An inverse model predicts the voltage from the displacement.
    q = hystcomp.predict(table2, volts, um)
    assert q.direction == "inverse"
    np.testing.assert_array_equal(q.predicted, table2.predict(um))
    np.testing.assert_array_equal(q.error, q.predicted - volts)
    # Inputs beyond the identified range are counted; bad records refused with the reason.
    assert hystcomp.predict(table1, volts * 1.5, um).outside_input_range > 0
    with pytest.raises(hystcomp.InvalidValueError, match="length|samples"):
        hystcomp.predict(table1, volts[:10], um)
    bad = um.copy()
    bad[3] = np.nan
    with pytest.raises(hystcomp.InvalidValueError, match="displacement"):
        hystcomp.predict(table1, volts, bad)
