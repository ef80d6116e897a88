"""Gait events from the trial file (C3D EVENT group) through the real ``gait`` command: Qualisys.c3d's own
events by default and ``--events file`` without any refused. (The exported C3D's EVENT group: the stair
session's test in tests/cli/test_export_real.py.)

Measured: Qualisys.c3d holds 7 gait events (LHS, RTO, RHS, LTO, LHS, RTO, RHS at 3.59–5.03 s from its frame 1;
its first frame 705 at 200 Hz is at 3.52 s): 0.07, 0.165, 0.53, 0.64, 1.015, 1.13, 1.51 s on the trial's axis.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import ezc3d
import numpy as np
import pandas as pd
import pytest

from tests.conftest import SHARED_C3D

from .conftest import copy_sample, gait_many


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    root = tmp_path_factory.mktemp("file_events")
    jobs = {"file_missing": (("filter", copy_sample("normal", root / "normal"), "--events", "file", "--no-plots"),
                             root)}
    if SHARED_C3D.is_dir():
        qualisys = root / "qualisys"
        qualisys.mkdir()
        shutil.copy(SHARED_C3D / "Qualisys.c3d", qualisys / "trial.c3d")
        shutil.copy(Path(__file__).resolve().parents[2] / "docs" / "examples" / "qualisys" / "subject.yaml",
                    qualisys / "subject.yaml")
        jobs["qualisys"] = (("filter", qualisys, "--no-plots"), root)
    return root, gait_many(jobs, workers=2)


def _lab_events(path: Path):
    """(time s from the trial's first frame, file frame, side, kind) of the file's EVENT group, from ezc3d."""
    c = ezc3d.c3d(str(path))
    rate = float(c["parameters"]["POINT"]["RATE"]["value"][0])
    times = np.asarray(c["parameters"]["EVENT"]["TIMES"]["value"])
    out = []
    for label, minutes, seconds in zip(c["parameters"]["EVENT"]["LABELS"]["value"], times[0], times[1]):
        t_file = 60 * minutes + seconds  # from the recording's frame 1
        side, kind = label[0].lower(), {"HS": "heel_strike", "TO": "toe_off"}[label[1:]]
        out.append((t_file - c["header"]["points"]["first_frame"] / rate, int(round(t_file * rate)) + 1, side, kind))
    return sorted(out)


@pytest.mark.shared
def test_qualisys_takes_the_labs_events_by_default(runs, shared_c3d_dir):
    root, results = runs
    assert results["qualisys"].returncode == 0, results["qualisys"].describe()
    events = pd.read_csv(root / "qualisys" / "gait_out" / "filter" / "events.csv")
    lab = _lab_events(root / "qualisys" / "trial.c3d")
    assert len(events) == len(lab) == 7
    assert set(events.source) == {"file"}
    np.testing.assert_allclose(events.time_s, [t for t, *_ in lab], atol=1e-6)
    assert events.frame.tolist() == [f for _, f, *_ in lab]
    assert list(zip(events.side, events.event)) == [(s, k) for *_, s, k in lab]


def test_events_file_without_any_is_refused_naming_the_file_and_event(runs):
    root, results = runs
    r = results["file_missing"]
    assert r.returncode == 2, r.describe()
    error = [line for line in r.stderr_lines if "error" in line]
    assert len(error) == 1 and "trial.c3d" in error[0] and "EVENT" in error[0], r.stderr
    assert "Traceback" not in r.stderr
    assert not (root / "normal" / "gait_out" / "filter").exists()

