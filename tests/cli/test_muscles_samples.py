"""``gait run --pipeline muscles_eid`` and ``gait muscles --method so|mso`` on every bundled sample trial.

Every run writes the stage's files and summary keys; on the normal trial all three methods converge
(exit 0), on the disturbed ones a method may end unconverged (exit 3, ``converged: false``) where a
locked joint's moment is carried by the orthosis or boot (sample_trials/README.md).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from .conftest import MUSCLE_FILES, MUSCLE_SUMMARY_KEYS, SAMPLES, Result, build_once, copy_sample, gait_many

METHODS = ("so", "mso", "eid")


def _build(root: Path) -> dict:
    for name in SAMPLES:
        copy_sample(name, root / name)
    first = gait_many({name: (("run", root / name, "--pipeline", "muscles_eid"), root) for name in SAMPLES})
    second = gait_many({f"{name}/{method}": (("muscles", root / name, "--method", method), root)
                        for name in SAMPLES for method in ("so", "mso")})
    return {**{f"{name}/eid": r.to_json() for name, r in first.items()},
            **{key: r.to_json() for key, r in second.items()}}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    root, record = build_once(tmp_path_factory, "cli_muscles_samples", _build)
    return record, root


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("name", SAMPLES)
def test_every_method_runs_on_every_sample_trial(runs, name, method):
    record, root = runs
    run = Result.from_json(record[f"{name}/{method}"])
    folder = root / name / "gait_out" / "muscles" / method
    assert run.returncode in (0, 3), run.describe()
    assert "Traceback" not in run.stderr
    for file in MUSCLE_FILES:
        assert (folder / file).is_file(), f"{folder / file} missing"
    info = json.loads((folder / "summary.json").read_text())
    assert set(MUSCLE_SUMMARY_KEYS) <= set(info) and info["method"] == method
    assert info["converged"] is (run.returncode == 0)
    if info["converged"]:
        assert info["max_moment_error_Nm"] < 0.5
    if method == "eid":  # gait run ran filter and idyn first, per the pipeline file
        assert (root / name / "gait_out" / "idyn" / "idyn.h5").is_file()
    if name == "normal":
        assert run.returncode == 0, run.describe()
