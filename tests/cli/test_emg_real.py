"""``gait emg`` on the two real trials with raw EMG in ``../shared/data`` (skipped where it is absent): BTS.c3d (8
channels in mV, labels the presets know) and the Motion Analysis Gait.c3d (16 channels in V with DC offsets,
the rectus femoris channels clipping at ±1 V; French labels mapped in subject.yaml). Per stride: the tibialis
anterior on around heel strike, the triceps surae peaking in late stance; the clipping channels warned about.
"""

from __future__ import annotations

import json
import shutil

import numpy as np
import pandas as pd
import pytest

from .conftest import build_once, gait_many

pytestmark = pytest.mark.shared

BTS = ("mass_kg: 70.0\nstature_m: 1.75\nsex: male\nmarker_map: {r heel: CAr, l heel: CAl, r met: MT2r, "
       "l met: MT2l}\n")
#: Gait.c3d's French labels (../shared/data/emg/README.md), as a lab's map
GAIT = ("mass_kg: 70.0\nstature_m: 1.75\nsex: male\nmarker_set: plug_in_gait\nemg:\n"
        + "".join(f"  {side}{label}: {muscle}_{side.lower()}\n" for side in "RL"
                  for label, muscle in (("REC", "rectus_femoris"), ("VAS", "vasti"), ("GRF", "glutei"),
                                        ("ISC", "hamstrings"), ("BIC", "biceps_femoris"),
                                        ("TIB", "tibialis_anterior"), ("SOL", "soleus"),
                                        ("JUM", "gastrocnemius"))))
TRIALS = {"bts": ("c3d/BTS.c3d", BTS), "gait": ("emg/Gait.c3d", GAIT)}


def _build(root):
    from ..conftest import REPO

    data = REPO.parent / "shared" / "data"
    jobs = {}
    for name, (file, subject) in TRIALS.items():
        if (data / file).is_file():
            (root / name).mkdir()
            shutil.copy(data / file, root / name / "trial.c3d")
            (root / name / "subject.yaml").write_text(subject)
            jobs[name] = (("emg", root / name), root)
    return {k: r.to_json() for k, r in gait_many(jobs).items()}


@pytest.fixture(scope="module")
def runs(tmp_path_factory, shared_c3d_dir):
    root, record = build_once(tmp_path_factory, "emg_real", _build)
    return root, record


@pytest.mark.parametrize("name", list(TRIALS))
def test_real_emg_gives_envelopes_per_stride_and_the_muscles_act_when_they_should(runs, name):
    root, record = runs
    if name not in record:
        pytest.skip(f"../shared/data/{TRIALS[name][0]} is not present")
    result = record[name]
    assert result["returncode"] == 0, result["stderr"]
    out = root / name / "gait_out" / "emg"
    summary = json.loads((out / "summary.json").read_text())
    cycle = pd.read_csv(out / "cycle.csv")
    bursts = pd.read_csv(out / "onoff.csv")
    assert {"envelopes.csv", "cycle.csv", "onoff.csv", "emg.h5", "summary.json"} <= {p.name for p in out.iterdir()}
    assert {p.name for p in (out / "plots").iterdir()} == {"emg_raw.png", "emg_cycle.png"}
    with_strides = [m for m, s in summary["muscles"].items() if s["strides"]]
    tested = [m for m in with_strides if m.startswith(("tibialis_anterior", "soleus", "gastrocnemius"))]
    assert tested, summary["muscles"]
    for muscle in tested:
        mean = cycle[f"{muscle}_mean"].to_numpy()
        assert np.nanmax(mean) == pytest.approx(1.0)  # normalised to the peak of the mean
        own = bursts[bursts.muscle == muscle]
        if muscle.startswith("tibialis_anterior"):  # on at heel strike (the burst from late swing on)
            assert ((own.on_pct <= 5) | (own.off_pct >= 95)).any(), own
            assert cycle[f"{muscle}_on_fraction"].iloc[[0, 1, 2]].max() >= 0.5
        else:  # the triceps surae: its mean envelope peaks in late stance
            assert 25 <= summary["muscles"][muscle]["peak_pct"] <= 55, (muscle, summary["muscles"][muscle])
    if name == "gait":
        assert summary["strides_right"] == summary["strides_left"] == 1
        assert {"LREC", "RREC"} <= set(summary["clipped"])
        assert "LREC clips" in result["stderr"] and "RREC clips" in result["stderr"]
        assert all(0.05 < s["reference_V"] < 1.0 for s in summary["muscles"].values())  # V, amplifier output
    else:
        assert summary["strides_left"] == 3 and summary["clipped"] == []
        assert all(1e-5 < s["reference_V"] < 1e-3 for s in summary["muscles"].values())  # read in mV
