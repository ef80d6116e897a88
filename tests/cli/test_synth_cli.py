"""`gait synth --gait`: the predicted walk refuses a locked-joint condition before writing anything."""

from __future__ import annotations

from .conftest import gait


def test_a_predicted_walk_with_a_locked_joint_is_exit_2_and_writes_nothing(tmp_path):
    run = gait("synth", tmp_path / "boot", "--gait", "predicted", "--condition", "ski_boot", cwd=tmp_path)
    assert run.returncode == 2, run.describe()
    assert run.stderr_lines == [run.stderr_lines[0]] and "--gait" in run.stderr and "ski_boot" in run.stderr
    assert "Traceback" not in run.stderr and not (tmp_path / "boot").exists()
