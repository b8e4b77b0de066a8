"""The README's Python example and examples/python run as written."""

import os
import re
import subprocess
import sys

import pytest

from conftest import DBO_DATA, ROOT

SNIPPETS = ROOT / "README.md"
EXAMPLE = ROOT / "examples" / "python" / "identify_and_compensate.py"


def readme_python_blocks():
    """The README's Python blocks: the self-contained example and the learning loop."""
    blocks = re.findall(r"```python\n(.*?)```", SNIPPETS.read_text(), flags=re.S)
    examples = [b for b in blocks if b.startswith("import numpy as np")]
    loops = [b for b in blocks if "hystcomp.Learner(" in b]
    assert len(examples) == 1 and len(loops) == 1 and len(blocks) == 2, (
        "README.md has one self-contained Python example and one learning loop"
    )
    return examples[0], loops[0]


def test_readme_python_example_runs_as_written(monkeypatch, capsys):
    example, _ = readme_python_blocks()
    monkeypatch.chdir(ROOT)  # the example's paths are relative to the repository's root
    exec(compile(example, str(SNIPPETS), "exec"), {"__name__": "__readme__"})
    assert capsys.readouterr().out.startswith("TrackingIndices(e_mhe=")


def test_readme_learning_loop_runs_with_the_simulated_stage(monkeypatch, tmp_path, capsys):
    # The loop is written for a user's stage: `plant.json` from `hystcomp identify`, the
    # desired trajectory and `play_and_record` are theirs. Here: Table 1's model, one period
    # of a 1 Hz sine at the stage's 10 kHz, and the simulated stage.
    import shutil

    import numpy as np

    import hystcomp

    _, loop = readme_python_blocks()
    shutil.copy(ROOT / "models" / "table1-plant.json", tmp_path / "plant.json")
    monkeypatch.chdir(tmp_path)
    stage = hystcomp.Stage(seed=1)

    def play_and_record(drive):
        _, measured = stage.run(drive)
        return measured

    t = np.arange(0.0, 1.0, 1e-4)
    namespace = {
        "hystcomp": hystcomp,
        "desired_um": 35.0 + 20.0 * np.sin(2 * np.pi * t),
        "play_and_record": play_and_record,
    }
    exec(compile(loop, str(SNIPPETS), "exec"), namespace)
    printed = [line.split() for line in capsys.readouterr().out.splitlines()]
    assert len(printed) == 10
    e_rms = [float(line[0]) for line in printed]
    assert all(line[1] == "False" for line in printed), "the guard stopped the loop"
    # Learning removes most of what Table 1's model leaves on this stage.
    assert e_rms[-1] < 0.5 * e_rms[0], e_rms
    drive = namespace["drive"]
    assert np.all(np.isfinite(drive)) and np.all((drive >= 0.0) & (drive <= 10.0))


@pytest.mark.skipif(
    not (DBO_DATA / "Model_Vi_Do.dat").is_file(),
    reason=f"the DBO micromanipulator data are not at {DBO_DATA}; the example needs them",
)
def test_identify_and_compensate_example_runs():
    result = subprocess.run(
        [sys.executable, str(EXAMPLE)], capture_output=True, text=True, cwd=ROOT, env=dict(os.environ), timeout=300
    )
    assert result.returncode == 0, result.stdout + result.stderr
    out = result.stdout
    assert "Model_Vi_Do.dat: 8027 samples" in out
    assert "plant    model: fit RMS" in out and "hold-out RMS" in out
    rows = {line.split()[0]: line.split() for line in out.splitlines() if line.startswith(("IHC ", "WIHC ", "DIHC ", "linear "))}
    assert set(rows) == {"IHC", "WIHC", "DIHC", "linear"}
    # IHC inverts the model it is checked against: no tracking error; the linear gain leaves
    # the hysteresis (> 10 % of the range).
    assert float(rows["IHC"][-1]) < 1e-3
    assert float(rows["linear"][-3]) > 10.0


def test_example_says_where_the_data_should_be(tmp_path):
    result = subprocess.run([sys.executable, str(EXAMPLE), str(tmp_path)], capture_output=True, text=True, timeout=60)
    assert result.returncode == 2
    assert "Model_Vi_Do.dat" in result.stderr
