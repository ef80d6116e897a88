"""``gait batch LAB_DIR``: every trial folder below a lab folder on a Dask cluster, failures isolated, current
outputs skipped; on a local cluster and on a real scheduler and worker started as separate processes on
loopback, one of whose worker processes is killed in the middle of a trial."""

from __future__ import annotations

import csv
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from gaitcli.resources import sample_trials_dir

from .conftest import ENV, SAMPLES, Result, build_once, gait

#: a trial whose trial.c3d has mode 000 (root reads it anyway: tests/test_batch.py simulates that case)
UNREADABLE = os.geteuid() != 0
#: the trials that fail: broken, invalid, huge_mass (and unreadable)
BAD = 3 + UNREADABLE
LINE = re.compile(r"^(\d+) ok, (\d+) failed, (\d+) skipped \(([\d.]+) s\)$", re.M)


def _lab(root: Path, samples=SAMPLES) -> Path:
    """Copies of the sample trials, a trial whose trial.c3d is not a C3D and one whose subject.yaml is invalid."""
    lab = root / "lab"
    for name in samples:
        shutil.copytree(sample_trials_dir() / name, lab / "walks" / name, ignore=shutil.ignore_patterns("gait_out"))
    (lab / "broken").mkdir(parents=True)
    shutil.copy(sample_trials_dir() / "normal" / "subject.yaml", lab / "broken" / "subject.yaml")
    (lab / "broken" / "trial.c3d").write_text("exported as text by mistake\n")
    shutil.copytree(sample_trials_dir() / "normal", lab / "invalid", ignore=shutil.ignore_patterns("gait_out"))
    (lab / "invalid" / "subject.yaml").write_text("mass_kg: 70\nstature_m: 170\nsex: male\n")
    shutil.copytree(sample_trials_dir() / "normal", lab / "huge_mass", ignore=shutil.ignore_patterns("gait_out"))
    (lab / "huge_mass" / "subject.yaml").write_text(f"mass_kg: {'9' * 400}\nstature_m: 1.7\nsex: male\n")
    if UNREADABLE:
        shutil.copytree(sample_trials_dir() / "normal", lab / "unreadable", ignore=shutil.ignore_patterns("gait_out"))
        (lab / "unreadable" / "trial.c3d").chmod(0)
    return lab


def _build(root: Path) -> dict:
    lab = _lab(root)
    first = gait("batch", lab, "--workers", "2", "--no-plots", cwd=root, timeout_s=600)
    rows_first = (lab / "batch_summary.csv").read_text()
    written = _outputs(lab)
    second = gait("batch", lab, "--workers", "2", "--no-plots", cwd=root, timeout_s=600)
    return {"first": first.to_json(), "second": second.to_json(), "rows_first": rows_first,
            "outputs_first": written, "outputs_second": _outputs(lab)}


def _outputs(lab: Path) -> dict[str, int]:
    """Every file below the lab's gait_out folders with its modification time (ns)."""
    return {str(p.relative_to(lab)): p.stat().st_mtime_ns for p in sorted(lab.rglob("gait_out/**/*")) if p.is_file()}


@pytest.fixture(scope="module")
def batch(tmp_path_factory):
    root, record = build_once(tmp_path_factory, "cli_batch", _build)
    return (root / "lab", Result.from_json(record["first"]), Result.from_json(record["second"]), record["rows_first"],
            record)


def _counts(result: Result) -> tuple[int, int, int, float]:
    match = LINE.search(result.stdout)
    assert match, result.describe()
    return int(match[1]), int(match[2]), int(match[3]), float(match[4])


def test_every_good_trial_runs_and_the_bad_ones_fail_with_their_reasons(batch):
    lab, first, _, rows_text, _ = batch
    assert first.returncode == 0, first.describe()
    assert _counts(first)[:3] == (len(SAMPLES), BAD, 0)
    rows = list(csv.DictReader(rows_text.splitlines()))
    assert len(rows) == 2 * (len(SAMPLES) + BAD)  # filter and idyn per trial
    by = {(r["trial"], r["stage"]): r for r in rows}
    assert all(by[(f"walks/{s}", st)]["status"] == "ok" for s in SAMPLES for st in ("filter", "idyn"))
    assert by[("broken", "filter")]["status"] == "failed" and by[("broken", "filter")]["exit_code"] == "2"
    assert "trial.c3d" in by[("broken", "filter")]["reason"] and "not a C3D file" in by[("broken", "filter")]["reason"]
    assert "stature_m" in by[("invalid", "idyn")]["reason"] and "centimetres" in by[("invalid", "idyn")]["reason"]
    assert by[("huge_mass", "filter")]["exit_code"] == "2" and "400-digit" in by[("huge_mass", "filter")]["reason"]
    if UNREADABLE:
        assert by[("unreadable", "filter")]["exit_code"] == "2"
        assert "trial.c3d: cannot be read" in by[("unreadable", "filter")]["reason"]
    assert float(by[("walks/normal", "idyn")]["speed_m_s"]) == pytest.approx(1.30, abs=0.01)
    assert "broken: failed:" in first.stderr and "Traceback" not in first.stderr
    for s in SAMPLES:  # the outputs are the stages' own
        assert (lab / "walks" / s / "gait_out" / "idyn" / "joint_moments.csv").is_file()
    assert not list(lab.rglob("*.part"))


def test_a_second_run_skips_everything_current_without_a_cluster_or_a_write(batch):
    _, _, second, _, record = batch
    assert second.returncode == 0, second.describe()
    ok, failed, skipped, _ = _counts(second)
    assert (ok, failed, skipped) == (0, BAD, len(SAMPLES))
    assert "Dask dashboard" not in second.stderr  # nothing to run: no cluster started
    assert record["outputs_first"] and record["outputs_second"] == record["outputs_first"]  # nothing rewritten


def test_workers_and_scheduler_exclude_each_other_and_a_missing_lab_is_exit_2(tmp_path):
    both = gait("batch", tmp_path, "--workers", "2", "--scheduler", "tcp://127.0.0.1:1", cwd=tmp_path)
    assert both.returncode == 2 and "exclude each other" in both.stderr
    missing = gait("batch", tmp_path / "nowhere", cwd=tmp_path)
    assert missing.returncode == 2 and len(missing.stderr_lines) == 1 and "lab folder not found" in missing.stderr


# ------------------------------------------------------------------ a real scheduler and workers on loopback

def test_a_batch_on_an_existing_scheduler(dask_cluster, tmp_path):
    # one good trial among the bad ones (a second good one was the same task on the same cluster)
    address, _ = dask_cluster
    lab = _lab(tmp_path, samples=("normal",))
    r = gait("batch", lab, "--scheduler", address, "--no-plots", cwd=tmp_path, timeout_s=300)
    assert r.returncode == 0, r.describe()
    assert _counts(r)[:3] == (1, BAD, 0)
    assert (lab / "walks" / "normal" / "gait_out" / "idyn" / "joint_moments.csv").is_file()


def test_a_worker_killed_mid_trial_leaves_no_half_written_output(dask_cluster, tmp_path):
    """The worker process running the trial is killed (SIGKILL) while it computes; the scheduler reruns the trial
    on the other worker, which finishes it, and no stage folder is left half-written."""
    address, client = dask_cluster
    lab = tmp_path / "lab"
    shutil.copytree(sample_trials_dir() / "normal", lab / "normal", ignore=shutil.ignore_patterns("gait_out"))
    batch = subprocess.Popen([sys.executable, "-m", "gaitcli", "batch", str(lab), "--scheduler", address],
                             cwd=tmp_path, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    victim, deadline = None, time.monotonic() + 120
    while victim is None and time.monotonic() < deadline and batch.poll() is None:
        busy = [w for w, tasks in client.processing().items() if tasks]
        if busy:
            time.sleep(0.5)  # into the trial's work
            victim = client.run(os.getpid, workers=busy[:1])[busy[0]]
            os.kill(victim, signal.SIGKILL)
        time.sleep(0.05)
    stdout, stderr = batch.communicate(timeout=300)
    assert victim is not None, (stdout, stderr)
    assert batch.returncode == 0, (stdout, stderr)
    rows = list(csv.DictReader((lab / "batch_summary.csv").read_text().splitlines()))
    assert {r["status"] for r in rows} <= {"ok", "failed"}
    assert all(r["status"] == "ok" or r["reason"] for r in rows)
    assert not list(lab.rglob("*.part")), "a half-written stage folder was left"
    if rows[0]["status"] == "ok":
        for stage in ("filter", "idyn"):
            assert (lab / "normal" / "gait_out" / stage / "summary.json").is_file()

