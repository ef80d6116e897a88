"""`gait synth --gait`: the predicted walk refuses a locked-joint condition before writing anything."""

from __future__ import annotations

from .conftest import gait


def test_a_predicted_walk_with_a_locked_joint_is_exit_2_and_writes_nothing(tmp_path):
    run = gait("synth", tmp_path / "boot", "--gait", "predicted", "--condition", "ski_boot", cwd=tmp_path)
    assert run.returncode == 2, run.describe()
    assert run.stderr_lines == [run.stderr_lines[0]] and "--gait" in run.stderr and "ski_boot" in run.stderr
    assert "Traceback" not in run.stderr and not (tmp_path / "boot").exists()


def test_a_period_of_no_whole_marker_frames_still_writes_a_readable_trial(tmp_path):
    # 1.068 s is 1068 analog samples: the trial is cut to whole marker frames (10 samples each)
    assert gait("synth", tmp_path / "t", "--period-s", "1.068", "--strides", "1", cwd=tmp_path).returncode == 0
    run = gait("filter", tmp_path / "t", "-o", tmp_path / "out", cwd=tmp_path)
    assert run.returncode == 0, run.describe()
