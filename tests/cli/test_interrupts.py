"""Ctrl-C and SIGTERM sent to a real ``gait`` process inside an optimizer's solve: "gait: interrupted", exit
130, the earlier result untouched, nothing half-written (issue 9; the predict case is in test_predict_cli.py, whose
unconverged run is the earlier result there). CasADi stops IPOPT on an interrupt but
returns its iterate as an ordinary failure, which was once written as an unconverged result."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from pathlib import Path

from .conftest import ENV, copy_sample, gait, snapshot


def start_gait(*args, cwd: Path) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "gaitcli.cli", *args], cwd=cwd, env=ENV, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))


def interrupt_after(process: subprocess.Popen, delay_s: float, signum: int) -> str:
    time.sleep(delay_s)
    assert process.poll() is None, "the run ended before the signal"
    process.send_signal(signum)
    _, stderr = process.communicate(timeout=60)  # a run that ignored the signal fails here (TimeoutExpired)
    return stderr


def test_ctrl_c_during_eid_keeps_the_earlier_converged_result(tmp_path):
    """A first uninterrupted run finds when the EID solve runs (its wall time and solve time); the second is
    sent SIGINT a quarter into the solve."""
    trial = copy_sample("normal", tmp_path / "normal")
    assert gait("idyn", trial, "--no-plots", cwd=tmp_path).returncode == 0
    start = time.perf_counter()
    first = gait("muscles", trial, "--no-plots", "--nodes", "90", cwd=tmp_path, fresh=True)
    wall = time.perf_counter() - start
    assert first.returncode == 0, first.describe()
    eid = trial / "gait_out" / "muscles" / "eid"
    solve_s = json.loads((eid / "summary.json").read_text())["solve_time_s"]
    assert solve_s > 2.0, f"EID took {solve_s:.1f} s: too short to aim a signal at"
    before = snapshot(trial / "gait_out")
    process = start_gait("muscles", str(trial), "--no-plots", "--nodes", "90", cwd=tmp_path)
    # a quarter into the solve, not half-way: the second run can be faster than the first by more than half
    # the solve when the other test worker's load changes (seen on a clean clone: it ended before the signal);
    # a signal a little before the solve is an interrupt all the same
    stderr = interrupt_after(process, wall - 0.75 * solve_s, signal.SIGINT)
    assert process.returncode == 130 and stderr.strip().splitlines()[-1] == "gait: interrupted", stderr
    assert "converge" not in stderr and "Traceback" not in stderr, stderr
    assert snapshot(trial / "gait_out") == before  # the converged EID as it was, no .part folder left
