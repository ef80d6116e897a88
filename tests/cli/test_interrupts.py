"""Ctrl-C and SIGTERM sent to a real ``gait`` process inside an optimizer's solve: "gait: interrupted", exit
130, the earlier result untouched, nothing half-written (issue 9; the predict case is in test_predict_cli.py, whose
unconverged run is the earlier result there). CasADi stops IPOPT on an interrupt but
returns its iterate as an ordinary failure, which was once written as an unconverged result."""

from __future__ import annotations

import os
import resource
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from gaitcli.core.recording import Markers
from gaitcli.io.c3d_write import write_c3d

from .conftest import ENV, MINIMAL_SUBJECT, copy_sample, gait, snapshot


def start_gait(*args, cwd: Path) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "gaitcli", *args], cwd=cwd, env=ENV, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))


def children_cpu_s() -> float:
    """CPU seconds of this process's finished children (user + system)."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def cpu_s(pid: int) -> float:
    """CPU seconds (user + system) a running process has used so far, from /proc."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def interrupt_at_cpu(process: subprocess.Popen, cpu_target_s: float, signum: int) -> str:
    """Send ``signum`` once the process has used ``cpu_target_s`` of CPU: a point in its work that another test
    worker's load does not move, as a wall-clock delay would."""
    while process.poll() is None and cpu_s(process.pid) < cpu_target_s:
        time.sleep(0.01)
    if process.poll() is not None:
        process.communicate()  # its pipes closed, not left to the collector in a later test
        pytest.fail("the run ended before the signal")
    process.send_signal(signum)
    _, stderr = process.communicate(timeout=60)
    return stderr


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads a process's CPU time from /proc")
def test_ctrl_c_during_eid_keeps_the_earlier_converged_result(tmp_path):
    """SO alone, then EID (which starts from SO's solution), each in a new process, give the CPU time up to
    EID's solve and of the whole run; a third run is sent SIGINT once it has used that much plus half the
    solve's. EID on its default 50 nodes: 1.3 s of processor time after SO's 0.9 s (measured 2026-12-07; on 90
    nodes 2.7 s), so the signal comes some 0.3 s of IPOPT's iterations (10 ms each) after the build and as much
    before the writing."""
    trial = copy_sample("normal", tmp_path / "normal")
    assert gait("idyn", trial, "--no-plots", cwd=tmp_path).returncode == 0
    used = children_cpu_s()
    assert gait("muscles", trial, "--no-plots", "--method", "so", cwd=tmp_path, fresh=True).returncode == 0
    before_eid = children_cpu_s() - used
    used = children_cpu_s()
    first = gait("muscles", trial, "--no-plots", cwd=tmp_path, fresh=True)
    whole = children_cpu_s() - used
    assert first.returncode == 0, first.describe()
    assert whole - before_eid > 0.5, f"EID took {whole - before_eid:.2f} s of CPU: too short to aim a signal at"
    before = snapshot(trial / "gait_out")
    process = start_gait("muscles", str(trial), "--no-plots", cwd=tmp_path)
    stderr = interrupt_at_cpu(process, before_eid + 0.5 * (whole - before_eid), signal.SIGINT)
    assert process.returncode == 130 and stderr.strip().splitlines()[-1] == "gait: interrupted", stderr
    assert "converge" not in stderr and "Traceback" not in stderr, stderr
    assert snapshot(trial / "gait_out") == before  # the converged EID as it was, no .part folder left


# ------------------------------------------------------------------- worker and reader processes (issue 35)
def children(pid: int) -> set[int]:
    """The pids of ``pid``'s child processes (Linux /proc)."""
    found = set()
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except (OSError, IndexError):
            continue
        if int(fields[1]) == pid:
            found.add(int(stat.parent.name))
    return found


def wait_for_children(process: subprocess.Popen, count: int, timeout_s: float = 120.0) -> set[int]:
    """Wait until ``process`` has ``count`` children (its workers or its C3D reader); their pids."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        assert process.poll() is None, process.communicate()[1]
        found = children(process.pid)
        if len(found) >= count:
            return found
        time.sleep(0.005)
    raise AssertionError(f"no {count} child processes within {timeout_s} s")


def assert_gone(pids: set[int], timeout_s: float = 30.0) -> None:
    """Every one of ``pids`` has ended (a zombie waiting for its dead parent counts as ended)."""
    deadline = time.monotonic() + timeout_s
    alive = pids
    while alive and time.monotonic() < deadline:
        alive = {pid for pid in alive if Path(f"/proc/{pid}").exists()
                 and Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"}
        time.sleep(0.05)
    assert not alive, f"processes left behind: {sorted(alive)}"


@pytest.mark.parametrize("work", ["starts", "study"])
def test_sigterm_with_workers_ends_them_exits_130_and_writes_nothing(tmp_path, work):
    """SIGTERM once the worker processes of ``--starts 2`` or of a two-chain study run: exit 130, the workers
    ended, nothing written after the signal (once an AttributeError in the stop code, and the workers solving
    on for ~100 s and writing case folders)."""
    (tmp_path / "two.yaml").write_text("name: two\nspeeds_m_s: [1.0, 1.2]\nweights: [b]\nconditions: [normal, sach]\n"
                                       "nodes: 6\n")
    options = ("--study", "two.yaml") if work == "study" else ("--nodes", "6", "--starts", "2", "--no-plots")
    process = start_gait("predict", *options, "--workers", "2", "-o", "out", cwd=tmp_path)
    workers = wait_for_children(process, 2)
    before = snapshot(tmp_path / "out") if (tmp_path / "out").exists() else {}
    process.send_signal(signal.SIGTERM)
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == 130 and stderr.strip().splitlines()[-1] == "gait: interrupted", stderr
    assert "Traceback" not in stderr and "internal error" not in stderr, stderr
    assert_gone(workers)
    after = snapshot(tmp_path / "out") if (tmp_path / "out").exists() else {}
    assert after == before


def test_a_killed_gait_leaves_no_c3d_reader_behind(tmp_path):
    """SIGKILL of ``gait`` while its child reads a C3D: the child ends with it (it once blocked for ever sending
    the recording through a pipe whose read end it held itself)."""
    trial = tmp_path / "long"
    trial.mkdir()
    frames = 60_000  # a read of about 2 s
    t = np.arange(frames) / 100.0
    positions = np.stack([np.stack([np.sin(0.1 * t + k), np.cos(0.2 * t), 0.5 + 0 * t], axis=1) for k in range(3)],
                         axis=1)
    write_c3d(trial / "trial.c3d", Markers(("A", "B", "C"), positions, 100.0, first_frame=1), [])
    (trial / "subject.yaml").write_text(MINIMAL_SUBJECT)
    process = start_gait("filter", str(trial), "--no-plots", cwd=tmp_path)
    reader = wait_for_children(process, 1)
    process.kill()
    process.communicate(timeout=60)
    assert_gone(reader)
