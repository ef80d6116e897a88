"""``gait compare`` as a command on a real output tree: a lab folder with one trial made by ``gait synth`` and
``gait run`` (once per session), copied as the baseline and as today's runs with known changes.

The invocations run once per module: the baseline against an identical copy (exit 0), against a copy whose
``knee_r_extensor_moment`` is shifted by 1 N·m (default tolerance 0.5 N·m: exit 1 naming trial, file, column and
difference; within a tolerance file's 2 N·m: exit 0; with ``--json``), against copies without one file and
without one stage (exit 1, reported), and bad input (a missing tree, an unknown family: exit 2, one line).
"""

from __future__ import annotations

import json
import shutil

import numpy as np
import pandas as pd
import pytest

from .conftest import build_once, gait_many

TRIAL = "walk01"
SHIFT_NM = 1.0  # > the moment family's 0.5 N·m
COLUMN = "knee_r_extensor_moment"


def _build(root):
    runs = gait_many({"synth": (("synth", root / "lab" / TRIAL, "--seed", "1"), root),
                      "run": (("--quiet", "run", root / "lab" / TRIAL, "--no-plots"), root)}, workers=1)
    for result in runs.values():
        assert result.returncode == 0, result.describe()
    return {}


def _shift(csv, column: str, by: float) -> None:
    """Add ``by`` to one column of a table, every other cell left as written."""
    table = pd.read_csv(csv, dtype=str, keep_default_na=False)
    values = np.array(table[column], dtype=float) + by  # 'NaN' cells stay NaN
    assert np.isfinite(values).sum() > 100  # the right knee's moments where its load is known
    table[column] = ["NaN" if np.isnan(v) else f"{v:.6g}" for v in values]
    table.to_csv(csv, index=False)


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    made, _ = build_once(tmp_path_factory, "compare_lab", _build)
    work = tmp_path_factory.mktemp("compare")
    copies = {}
    for name in ("baseline", "same", "shifted", "no_file", "no_stage"):
        copies[name] = work / name
        shutil.copytree(made / "lab", copies[name], ignore=shutil.ignore_patterns("*.c3d"))
    idyn = "gait_out/idyn"
    _shift(copies["shifted"] / TRIAL / idyn / "joint_moments.csv", COLUMN, SHIFT_NM)
    (copies["no_file"] / TRIAL / idyn / "sagittal.csv").unlink()
    shutil.rmtree(copies["no_stage"] / TRIAL / "gait_out" / "filter")
    (work / "loose.yaml").write_text("families:\n  moment: 2.0\n")
    (work / "bad.yaml").write_text("families:\n  moments: 2.0\n")
    base = ("compare", "baseline")
    jobs = {"same": ((*base, "same"), work), "shifted": ((*base, "shifted"), work),
            "loose": ((*base, "shifted", "--tolerances", "loose.yaml"), work),
            "json": (("--json", *base, "shifted"), work), "no_file": ((*base, "no_file"), work),
            "no_stage": ((*base, "no_stage"), work), "missing": ((*base, "no_such_tree"), work),
            "bad": ((*base, "same", "--tolerances", "bad.yaml"), work)}
    return gait_many(jobs, workers=2), work


def test_identical_trees_exit_0(runs):
    result = runs[0]["same"]
    assert result.returncode == 0, result.describe()
    assert result.stderr_lines[-1].startswith("compare: ") and result.stderr_lines[-1].endswith(" 0 differ")
    assert len(result.stderr_lines) == 1  # no table when nothing differs


def test_a_shifted_moment_column_exits_1_naming_trial_file_column_and_difference(runs):
    result = runs[0]["shifted"]
    assert result.returncode == 1, result.describe()
    lines = [line for line in result.stderr_lines if COLUMN in line]
    assert len(lines) == 1, result.describe()  # its per-kg twin was left as it was
    cells = lines[0].split()
    assert cells[:4] == [TRIAL, "idyn", "joint_moments.csv", COLUMN]
    assert float(cells[4]) == pytest.approx(SHIFT_NM, abs=1e-4) and cells[5] == "N·m"
    assert "0.5 N·m" in lines[0] and "time_s=" in lines[0]
    assert result.stderr_lines[-1].endswith(" 1 differ")
    assert result.stdout == ""


def test_within_a_tolerance_file_the_shift_is_accepted(runs):
    result = runs[0]["loose"]
    assert result.returncode == 0, result.describe()


def test_json_lists_the_findings(runs):
    result = runs[0]["json"]
    assert result.returncode == 1, result.describe()
    data = json.loads(result.stdout)
    (finding,) = data["findings"]
    assert (finding["trial"], finding["stage"], finding["file"], finding["column"]) == (
        TRIAL, "idyn", "joint_moments.csv", COLUMN)
    assert finding["difference"] == pytest.approx(SHIFT_NM, abs=1e-4)
    assert (finding["family"], finding["tolerance"], finding["unit"]) == ("moment", 0.5, "N·m")
    assert data["files_differing"] == 1 and data["files_compared"] >= 10


def test_a_missing_file_is_reported_and_exits_1(runs):
    result = runs[0]["no_file"]
    assert result.returncode == 1, result.describe()
    (line,) = [line for line in result.stderr_lines if "sagittal.csv" in line]
    assert line.split()[:3] == [TRIAL, "idyn", "sagittal.csv"] and "only in A" in line
    assert result.stderr_lines[-1].endswith(" 1 differ")


def test_a_missing_stage_is_reported_and_exits_1(runs):
    result = runs[0]["no_stage"]
    assert result.returncode == 1, result.describe()
    (line,) = [line for line in result.stderr_lines if "only in A" in line]
    assert line.split()[:3] == [TRIAL, "filter", "(folder)"] and "folder of 4 file(s)" in line
    assert result.stderr_lines[-1].endswith(" 4 differ")


def test_bad_input_exits_2_with_one_line(runs):
    missing, bad = runs[0]["missing"], runs[0]["bad"]
    assert missing.returncode == 2 and missing.stderr_lines == [
        "gait: error: no_such_tree: not found (expected the output folder B)"], missing.describe()
    assert bad.returncode == 2 and len(bad.stderr_lines) == 1, bad.describe()
    assert bad.stderr_lines[0].startswith("gait: error: bad.yaml: families.moments: unknown key; did you mean")
