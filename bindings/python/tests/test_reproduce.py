"""reproduce(): the comparative study of section 4 (Table 3) on the simulated stage."""

import numpy as np
import pytest

import hystcomp

# A small swarm keeps the test fast; the exact (least-squares) pipeline does not depend on it.
FAST = dict(pso_iterations=10, pso_particles=8)


@pytest.fixture(scope="module")
def study():
    return hystcomp.reproduce(**FAST)


def test_table3_has_every_index_of_every_run(study):
    table = study.table
    assert set(table) == {"uncompensated", "paper", "exact"}
    for pipeline in ("paper", "exact"):
        assert set(table[pipeline]) == {"ihc", "wihc", "dihc"}
        for indices in table[pipeline].values():
            assert set(indices) == {"e_mhe", "e_m", "e_rms"}
            assert all(np.isfinite(v) and v >= 0 for v in indices.values())
    # The stage is calibrated to the paper's 13 % and the exact inverses cut it to <= 3 %.
    assert 11.5 <= table["uncompensated"]["e_mhe"] <= 14.5
    for method in ("ihc", "wihc", "dihc"):
        assert table["exact"][method]["e_mhe"] <= 3.0
    assert study.indices("exact", "ihc").e_rms == table["exact"]["ihc"]["e_rms"]
    assert study.indices("uncompensated").e_mhe == table["uncompensated"]["e_mhe"]


def test_published_numbers_are_the_papers(study):
    published = study.published
    assert published["uncompensated"]["e_mhe"] == 13.0
    assert published["ihc"] == {"e_mhe": 3.0, "e_m": 2.66, "e_rms": 0.75}
    assert published["dihc"]["e_m"] == 2.06


def test_summary_models_and_signals(study):
    assert study.passed == all(check["passed"] for check in study.acceptance)
    assert study.summary.mhe_bins == hystcomp.DEFAULT_MHE_BINS
    models = study.models
    assert models["exact"]["plant"].direction == "plant"
    assert models["paper"]["inverse"].direction == "inverse"
    n = len(study.time)
    assert len(study.desired_um) == n and 0 < study.evaluation_start < n
    assert study.labels[0] == "uncompensated"
    runs = study.runs
    assert set(runs) == set(study.labels)
    assert len(runs["exact / ihc"]["measured_um"]) == n
    recomputed = hystcomp.tracking_indices(
        study.desired_um[study.evaluation_start:], runs["exact / ihc"]["measured_um"][study.evaluation_start:]
    )
    assert recomputed.e_rms == pytest.approx(study.table["exact"]["ihc"]["e_rms"])
    assert "Table 3" in str(study) and "StudyResult(" in repr(study)
    assert study.report is None and study.elapsed_s > 0


def test_the_report_is_written_on_request(tmp_path):
    result = hystcomp.reproduce(out_dir=tmp_path / "report", **FAST)
    report = result.report
    assert str(report).endswith("index.html")
    assert (tmp_path / "report" / "index.html").is_file()


def test_bad_options_are_refused_with_the_reason(study):
    with pytest.raises(hystcomp.InvalidValueError, match="at least 2 periods"):
        hystcomp.reproduce(periods=1, **FAST)
    with pytest.raises(hystcomp.StageConfigError):
        hystcomp.reproduce(stage_toml="[mechanics]\ndamping_ratio = -1.0\n", **FAST)
    with pytest.raises(hystcomp.InvalidValueError, match="particles"):
        hystcomp.reproduce(pso_iterations=10, pso_particles=1)
    with pytest.raises(hystcomp.InvalidValueError):
        study.indices("exact", "pid")
    with pytest.raises(hystcomp.InvalidValueError, match="pipeline"):
        study.indices("fast", "ihc")
