"""A session folder as Nexus leaves it: C3D files and the lab's ``.vsk``, no subject.yaml (issue 52, item 1).

``gait run``, ``gait batch`` and ``gait report`` take it as it is and name the ``.vsk`` they used; a folder gait
cannot run is exit 2 with why, never "0 ok" and exit 0.
"""

from __future__ import annotations

import shutil

import pytest

from .conftest import gait, gait_many

VSK_LINE = "subject from Test.vsk (no subject.yaml; male assumed"


def _nexus_folder(pig, folder):
    """../shared/data/pig's files under their own names: a Nexus session folder."""
    folder.mkdir(parents=True)
    for name in ("Static_trial.c3d", "Movement_trial.c3d", "Test.vsk"):
        shutil.copy(pig / name, folder / name)
    return folder


@pytest.mark.shared
def test_run_batch_and_report_take_a_nexus_folder_as_it_is(shared_pig_dir, tmp_path):
    session = _nexus_folder(shared_pig_dir, tmp_path / "session")
    lab = tmp_path / "lab"
    _nexus_folder(shared_pig_dir, lab / "day1" / "subject01")
    done = gait_many({"run": (("run", session, "--no-plots"), tmp_path),
                      "batch": (("batch", lab, "--no-plots"), tmp_path)}, workers=2)
    run, batch = done["run"], done["batch"]
    assert run.returncode == 0 and batch.returncode == 0, run.describe() + batch.describe()
    assert f"session: {VSK_LINE}" in run.stderr
    assert "1 ok, 0 failed" in run.stdout
    assert (session / "gait_out" / "Movement_trial" / "idyn" / "summary.json").is_file()
    assert (session / "gait_out" / "session" / "summary.json").is_file()
    assert f"batch: day1/subject01: {VSK_LINE}" in batch.stderr
    assert "1 ok, 0 failed" in batch.stdout
    assert (lab / "day1" / "subject01" / "gait_out" / "Movement_trial" / "idyn" / "summary.json").is_file()
    report = gait("report", session, cwd=tmp_path)
    assert report.returncode == 0, report.describe()
    assert (session / "gait_out" / "report.html").is_file()


def test_a_folder_of_c3d_files_without_a_subject_is_exit_2(tmp_path):
    """C3D files and neither subject.yaml nor a .vsk: `gait run` says what is missing; `gait batch` of a lab
    folder without any trial says so too."""
    folder = tmp_path / "session"
    folder.mkdir()
    (folder / "Walk 01.c3d").write_bytes(b"not read")
    (tmp_path / "empty").mkdir()
    done = gait_many({"run": (("run", folder), tmp_path), "batch": (("batch", tmp_path / "empty"), tmp_path),
                      "batch_c3d": (("batch", folder), tmp_path)}, workers=2)
    run = done["run"]
    assert run.returncode == 2 and "subject.yaml or a Vicon .vsk" in run.stderr, run.describe()
    for key in ("batch", "batch_c3d"):
        r = done[key]
        assert r.returncode == 2, r.describe()
        assert "no trial or session folder in it (expected folders holding a subject.yaml, or C3D files beside " \
               "the lab's Vicon .vsk)" in r.stderr
        assert "0 ok" not in r.stdout and "Traceback" not in r.stderr
