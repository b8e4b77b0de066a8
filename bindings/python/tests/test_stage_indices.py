"""Stage and StageResponse (python-control style), and the tracking indices."""

import numpy as np
import pytest

import hystcomp
from conftest import table1_record


def test_stage_runs_a_command_signal_into_a_response():
    stage = hystcomp.Stage(seed=3)
    assert stage.sample_rate_hz == 10_000.0 and stage.period_s == pytest.approx(1e-4)
    volts = 5.0 + 4.0 * np.sin(2 * np.pi * np.arange(5000) / 5000)
    response = stage.run(volts)
    assert len(response) == 5000
    np.testing.assert_array_equal(response.inputs, volts)
    np.testing.assert_array_equal(response.command_v, volts)
    np.testing.assert_array_equal(response.outputs, response.measured_position_um)
    np.testing.assert_allclose(np.diff(response.time), 1e-4)
    assert response.time[0] == 0.0
    assert 10.0 < response.true_position_um.max() < 75.0
    assert response.amplifier_v.max() == pytest.approx(135.0, rel=0.02)
    assert response.clamps == hystcomp.Clamps(dac_clamped=0, amplifier_clamped=0, non_finite=0, adc_clamped=0)
    # python-control style: unpacks as t, y; plotting is a separate call.
    t, y = response
    np.testing.assert_array_equal(t, response.time)
    np.testing.assert_array_equal(y, response.outputs)
    assert stage.samples == 5000 and stage.time_s == pytest.approx(0.5)


def test_stage_is_deterministic_per_seed_and_resets():
    volts = np.linspace(0, 8, 3000)
    a = hystcomp.Stage(seed=1).run(volts).outputs
    b = hystcomp.Stage(seed=1)
    first = b.run(volts).outputs
    c = hystcomp.Stage(seed=2).run(volts).outputs
    np.testing.assert_array_equal(a, first)
    assert not np.array_equal(a, c)
    b.reset()
    np.testing.assert_array_equal(np.array([b.step(v) for v in volts]), first)


def test_stage_files_and_their_errors(tmp_path):
    default = hystcomp.Stage()
    again = hystcomp.Stage(default.config_toml, seed=0)
    np.testing.assert_array_equal(default.run([1.0, 2.0]).outputs, again.run([1.0, 2.0]).outputs)
    slow = hystcomp.Stage("[mechanics]\nresonance_hz = 600.0\n")
    assert "resonance_hz = 600.0" in slow.config_toml
    path = tmp_path / "stage.toml"
    path.write_text("sample_rate_hz = 5000.0\n")
    assert hystcomp.Stage.from_file(path).sample_rate_hz == 5000.0
    with pytest.raises(hystcomp.StageConfigError, match="mechanics.damping_ratio"):
        hystcomp.Stage("[mechanics]\ndamping_ratio = -1.0\n")
    with pytest.raises(hystcomp.StageConfigError):
        hystcomp.Stage("this is not toml")
    with pytest.raises(FileNotFoundError):
        hystcomp.Stage.from_file(tmp_path / "none.toml")


def test_stage_refuses_non_finite_commands_and_counts_clamps():
    stage = hystcomp.Stage()
    with pytest.raises(hystcomp.InvalidValueError, match="command_v = NaN"):
        stage.step(float("nan"))
    with pytest.raises(hystcomp.InvalidValueError, match=r"command_v\[1\]"):
        stage.run([1.0, np.inf])
    assert stage.samples == 0
    response = stage.run([20.0, -20.0, 5.0])
    assert response.clamps.dac_clamped == 2
    assert stage.full_scale_command_v == 10.0


def test_a_sensor_span_below_the_stroke_saturates_and_is_counted():
    # 0.1 V/um into an ADC of 0 .. 2 V: readings stop at 20 um.
    stage = hystcomp.Stage("[adc]\nmin_v = 0.0\nmax_v = 2.0\n")
    response = stage.run(np.linspace(0.0, 8.0, 4000))
    assert response.true_position_um.max() > 40.0
    assert response.measured_position_um.max() <= 20.0 + 1e-9
    over = int(np.sum(response.true_position_um > 20.5))
    assert over > 0 and response.clamps.adc_clamped >= over


def test_quasi_static_stroke_is_about_the_nominal_75_um():
    assert 70.0 < hystcomp.Stage().quasi_static_stroke_um() < 80.0


def test_indices_of_known_records():
    # 1001 samples: at least 10 per bin with the default 100 e_mhe bins.
    desired = np.linspace(0.0, 10.0, 1001)
    offset = desired + 0.5
    assert hystcomp.e_m(desired, offset) == pytest.approx(5.0)
    assert hystcomp.e_rms(desired, offset) == pytest.approx(5.0)
    assert hystcomp.e_mhe(desired, offset) < 1.01
    # A loop: up along y_d, down 1 above it: a vertical width of 1 in 10, plus the slope of
    # the map within one bin (0.1 with 100 bins, 1 with 10).
    up_down = np.concatenate([desired, desired[::-1]])
    loop = np.concatenate([desired, desired[::-1] + 1.0])
    assert hystcomp.e_mhe(up_down, loop) == pytest.approx(11.0, abs=0.01)
    assert hystcomp.e_mhe(up_down, loop, bins=10) == pytest.approx(20.0, abs=0.01)
    i = hystcomp.tracking_indices(up_down, loop, bins=10)
    assert (i.e_mhe, i.e_m, i.e_rms, i.mhe_bins) == (
        hystcomp.e_mhe(up_down, loop, bins=10),
        hystcomp.e_m(up_down, loop),
        hystcomp.e_rms(up_down, loop),
        10,
    )
    assert i.as_dict() == {"e_mhe": i.e_mhe, "e_m": i.e_m, "e_rms": i.e_rms}
    assert hystcomp.tracking_indices(desired, offset).mhe_bins == hystcomp.DEFAULT_MHE_BINS


@pytest.mark.parametrize(
    "desired, measured, message",
    [
        ([1.0, 2.0], [1.0], "2 samples but the measured record has 1"),
        ([1.0, 1.0], [1.0, 2.0], "constant"),
        ([1.0], [1.0], "at least 2"),
        ([1.0, np.nan], [1.0, 2.0], "NaN or infinite value at sample 1"),
    ],
)
def test_indices_refuse_bad_records_with_the_reason(desired, measured, message):
    with pytest.raises(hystcomp.InvalidValueError, match=message):
        hystcomp.tracking_indices(desired, measured)
    with pytest.raises(hystcomp.InvalidValueError):
        hystcomp.e_m(desired, measured)


def test_paper_trajectory_is_the_section_4_3_multisine():
    t, y_d = hystcomp.paper_trajectory(duration_s=10.0, sample_rate_hz=1000.0)
    assert len(t) == len(y_d) == 10_000
    expected = (
        37.35
        + 10.5 * np.sin(np.pi * t + 2.6)
        + 10.5 * np.sin(1.6 * np.pi * t + 3)
        + 15.75 * np.sin(2 * np.pi * t + 1.5)
    )
    np.testing.assert_allclose(y_d, expected, atol=1e-9)
    with pytest.raises(hystcomp.InvalidValueError):
        hystcomp.paper_trajectory(duration_s=-1.0)


def test_e_mhe_refuses_more_bins_than_the_record_supports():
    desired = np.linspace(0.0, 1.0, 100)
    # A single-valued map: e_mhe is the slope within one bin, at most a tenth of the range.
    assert 0.0 < hystcomp.e_mhe(desired, desired, 10) <= 10.0
    with pytest.raises(hystcomp.InvalidValueError, match="use at most 10 bins"):
        hystcomp.e_mhe(desired, desired, 11)
    with pytest.raises(hystcomp.InvalidValueError, match="use at most 10 bins"):
        hystcomp.tracking_indices(desired, desired)


class _Axes:
    """Records what plot_response asks of matplotlib's Axes (matplotlib is not a dependency)."""

    def __init__(self):
        self.calls = []

    def __getattr__(self, name):
        return lambda *args, **kwargs: self.calls.append((name, args, kwargs))


def test_plot_response_draws_outputs_against_time_on_given_axes():
    stage = hystcomp.Stage(seed=1)
    desired = np.linspace(10.0, 20.0, 200)
    response = stage.run(np.linspace(1.0, 3.0, 200))
    ax = _Axes()
    assert hystcomp.plot_response(response, ax, desired=desired, title="run") is ax
    plots = [c for c in ax.calls if c[0] == "plot"]
    assert len(plots) == 2
    np.testing.assert_array_equal(plots[0][1][1], desired)
    np.testing.assert_array_equal(plots[1][1][0], response.time)
    np.testing.assert_array_equal(plots[1][1][1], response.outputs)
    names = [c[0] for c in ax.calls]
    assert {"set_xlabel", "set_ylabel", "set_title", "legend"} <= set(names)


def test_reports_are_dataclasses_with_the_cli_json_fields():
    import dataclasses

    volts, um = table1_record()
    fit = hystcomp.identify(volts, um, warmup=50, holdout=0.2)
    report = fit.report
    assert dataclasses.is_dataclass(report) and isinstance(report, hystcomp.FitReport)
    assert isinstance(report.fit, hystcomp.ErrorStats) and isinstance(report.samples, hystcomp.SampleCounts)
    assert report.samples.total == report.samples.warmup + report.samples.fit + report.samples.holdout
    # The same fields as the JSON the model file keeps (and `hystcomp identify --json` prints).
    as_json = fit.model.identification
    assert report.to_dict().keys() == as_json.keys()
    assert report.to_dict()["fit"] == as_json["fit"]
    assert report.extra == {}
    # Fields added later on the Rust side are kept, not lost.
    more = dict(as_json, new_field=1)
    assert hystcomp.FitReport.from_json(more).extra == {"new_field": 1}
    assert dataclasses.is_dataclass(hystcomp.Stage().clamps)
