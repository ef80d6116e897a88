"""Ctrl-C and SIGTERM sent to a real ``gait`` process inside an optimizer's solve: "gait: interrupted", exit
130, the earlier result untouched, nothing half-written (issue 9). CasADi stops IPOPT on an interrupt but
returns its iterate as an ordinary failure, which was once written as an unconverged result."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from pathlib import Path

from .conftest import ENV, copy_sample, gait, snapshot


def _start(*args, cwd: Path) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "gaitcli.cli", *args], cwd=cwd, env=ENV, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))


def _interrupt_after(process: subprocess.Popen, delay_s: float, signum: int) -> str:
    time.sleep(delay_s)
    assert process.poll() is None, "the run ended before the signal"
    process.send_signal(signum)
    _, stderr = process.communicate(timeout=60)  # a run that ignored the signal fails here (TimeoutExpired)
    return stderr


def test_ctrl_c_during_eid_keeps_the_earlier_converged_result(tmp_path):
    """A first uninterrupted run finds when the EID solve runs (its wall time and solve time); the second is
    sent SIGINT half-way through the solve."""
    trial = copy_sample("normal", tmp_path / "normal")
    assert gait("idyn", trial, "--no-plots", cwd=tmp_path).returncode == 0
    start = time.perf_counter()
    first = gait("muscles", trial, "--no-plots", "--nodes", "90", cwd=tmp_path)
    wall = time.perf_counter() - start
    assert first.returncode == 0, first.describe()
    eid = trial / "gait_out" / "muscles" / "eid"
    solve_s = json.loads((eid / "summary.json").read_text())["solve_time_s"]
    assert solve_s > 2.0, f"EID took {solve_s:.1f} s: too short to aim a signal at"
    before = snapshot(trial / "gait_out")
    process = _start("muscles", str(trial), "--no-plots", "--nodes", "90", cwd=tmp_path)
    stderr = _interrupt_after(process, wall - solve_s / 2, signal.SIGINT)
    assert process.returncode == 130 and stderr.strip().splitlines()[-1] == "gait: interrupted", stderr
    assert "converge" not in stderr and "Traceback" not in stderr, stderr
    assert snapshot(trial / "gait_out") == before  # the converged EID as it was, no .part folder left


def test_sigterm_during_predict_keeps_the_earlier_result(tmp_path):
    """A first run stopped after one IPOPT iteration finds when IPOPT starts (imports and the NLP's construction,
    8–15 s); the second, which at 6 nodes would iterate for minutes, gets SIGTERM 3 s into its iterations. (In
    CasADi's construction, C++ that does not return to Python, an interrupt waits until it returns.)"""
    start = time.perf_counter()
    first = gait("predict", "--nodes", "6", "--max-iterations", "1", "--no-plots", "-o", "first", cwd=tmp_path)
    to_first_iteration = time.perf_counter() - start
    assert first.returncode == 3, first.describe()
    earlier = tmp_path / "out" / "predict"
    earlier.mkdir(parents=True)
    (earlier / "summary.json").write_text('{"earlier": true}\n')
    process = _start("predict", "--nodes", "6", "-o", "out", cwd=tmp_path)
    stderr = _interrupt_after(process, to_first_iteration + 3.0, signal.SIGTERM)
    assert process.returncode == 130 and "gait: interrupted" in stderr, stderr
    assert (earlier / "summary.json").read_text() == '{"earlier": true}\n'
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["predict"]  # no half-written folder
