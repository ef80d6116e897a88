"""The project's own regression check, as a lab's CI would run it (README, "Regression checks in CI"): ``gait
batch`` over copies of the bundled sample trials against the stored outputs in ``tests/baseline/`` (made by
``python tests/baseline/regenerate.py``); and a baseline that differs is exit 1 naming the file and column. The
trials run in the command's own process (``--workers 1``): their outputs are the same wherever they run, and a
local Dask cluster's start (3.4 s of processor time for two workers) is test_batch_cli.py's to check."""

from __future__ import annotations

import shutil
from pathlib import Path

import pandas as pd
import pytest

from gaitcli.resources import sample_trials_dir

from .conftest import SAMPLES, Result, build_once, gait

BASELINE = Path(__file__).resolve().parents[1] / "baseline"


def _build(root: Path) -> dict:
    lab = root / "lab"
    for name in SAMPLES:
        shutil.copytree(sample_trials_dir() / name, lab / name, ignore=shutil.ignore_patterns("gait_out"))
    check = gait("batch", lab, "--baseline", BASELINE, "--no-plots", "--workers", "1", cwd=root, timeout_s=600)
    changed = root / "changed"
    shutil.copytree(BASELINE, changed, ignore=shutil.ignore_patterns("regenerate.py"))
    table = changed / "normal" / "gait_out" / "idyn" / "joint_moments.csv"
    moments = pd.read_csv(table)
    moments["knee_r_extensor_moment_per_kg"] += 0.05  # beyond the 0.01 N·m/kg tolerance
    moments.to_csv(table, index=False, na_rep="NaN")
    (changed / "ski_boot" / "gait_out" / "filter" / "events.csv").unlink()
    differs = gait("batch", lab, "--baseline", changed, "--no-plots", "--workers", "2", cwd=root, timeout_s=600)
    return {"check": check.to_json(), "differs": differs.to_json()}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    _, record = build_once(tmp_path_factory, "cli_regression_baseline", _build)
    return Result.from_json(record["check"]), Result.from_json(record["differs"])


def test_the_sample_trials_reproduce_the_stored_baseline(runs):
    check, _ = runs
    assert check.returncode == 0, check.describe()
    assert f"{len(SAMPLES)} ok, 0 failed, 0 skipped" in check.stdout
    stored = list(BASELINE.rglob("*.csv")) + list(BASELINE.rglob("summary.json"))
    assert len(stored) == 60  # 5 trials × (filter: 3 CSVs + summary; idyn: 7 CSVs + summary)
    assert f"{len(stored)} files compared, 0 differ" in check.stdout, check.describe()


def test_a_baseline_that_differs_is_exit_1_naming_file_and_column(runs):
    _, differs = runs
    assert differs.returncode == 1, differs.describe()
    assert f"0 ok, 0 failed, {len(SAMPLES)} skipped" in differs.stdout  # nothing ran again
    assert "2 differ" in differs.stdout
    assert "knee_r_extensor_moment_per_kg" in differs.stderr and "joint_moments.csv" in differs.stderr
    assert "ski_boot" in differs.stderr and "events.csv" in differs.stderr
