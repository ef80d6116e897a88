"""EMG through the real ``gait`` command on ``gait synth --emg``'s normal trial, whose channels are band-limited
noise modulated by the truth's activations (EID on the true motion, truth/activations.csv): ``gait run`` adds
the emg stage where subject.yaml maps EMG channels; the envelopes over each muscle's strides recover the truth;
``gait muscles --method eid`` sets its activations against the envelopes — high correlations, small lags —
and the same comparison with the channels swapped between muscles is poor. Bad EMG input stops with exit 2 and
one line naming the file and the field.
"""

from __future__ import annotations

import dataclasses
import json
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from gaitcli.emg.comparison import compare_with_emg
from gaitcli.emg.stage import EmgResult
from gaitcli.io.h5 import read_result
from gaitcli.muscles.stage import MuscleResult
from gaitcli.signal.cycles import CYCLE_PCT

from .conftest import MINIMAL_SUBJECT, Result, build_once, copy_sample, gait, gait_many, snapshot


def _build(root, synthetic: Path, synthesised: Result):
    """On a copy of the session's ``gait synth --emg`` trial (conftest): run, EID, the report."""
    trial = shutil.copytree(synthetic, root / "synth")
    steps = {"synth": synthesised.to_json()}
    # figures only where the page draws them (the report), to keep the suite short
    for args in (("run", trial, "--no-plots"), ("muscles", trial, "--method", "eid", "--no-plots"),
                 ("report", trial)):
        steps[args[0]] = gait(*args, cwd=root).to_json()
    return steps


@pytest.fixture(scope="module")
def synth(tmp_path_factory, synth_emg):
    root, steps = build_once(tmp_path_factory, "cli_emg", lambda root: _build(root, *synth_emg))
    for name, step in steps.items():
        assert step["returncode"] == 0, (name, step["stderr"])
    return root / "synth", steps


def test_gait_run_processes_the_mapped_emg_and_the_envelopes_recover_the_truth(synth):
    trial, steps = synth
    assert "16 EMG channels" in steps["synth"]["stderr"]
    out = trial / "gait_out" / "emg"
    assert "emg: 16 channels" in steps["run"]["stderr"]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["strides_right"] >= 2 and summary["strides_left"] >= 2 and summary["clipped"] == []
    truth = pd.read_csv(trial / "truth" / "activations.csv")
    cycle = pd.read_csv(out / "cycle.csv")
    events = pd.read_csv(trial / "gait_out" / "filter" / "events.csv")
    for side in "rl":
        strikes = np.sort(events.time_s[(events.side == side) & (events.event == "heel_strike")].to_numpy())
        grid = np.linspace(strikes[0], strikes[1], CYCLE_PCT.size)  # the walk repeats: one stride is the truth
        for muscle in ("soleus", "gastrocnemius", "tibialis_anterior", "vasti", "glutei"):
            name = f"{muscle}_{side}"
            true_cycle = np.interp(grid, truth.time_s, truth[name])
            r = np.corrcoef(cycle[f"{name}_mean"], true_cycle)[0, 1]
            assert r >= 0.95, (name, r)


def test_eid_activations_agree_with_the_envelopes_and_swapped_channels_do_not(synth):
    trial, steps = synth
    folder = trial / "gait_out" / "muscles" / "eid"
    summary = json.loads((folder / "summary.json").read_text())
    table = pd.read_csv(folder / "emg_agreement.csv")
    assert set(table.muscle) == set(summary["emg"]) and len(table) == 8
    assert table.correlation.median() >= 0.85 and table.correlation.min() >= 0.6, table
    assert np.abs(table.lag_s).max() <= 0.02, table
    assert table.on_off_agreement_pct.median() >= 85, table
    # the same activations against the envelopes with each right channel given to the next muscle
    result = read_result(folder / "muscles.h5", MuscleResult)
    emg = read_result(trial / "gait_out" / "emg" / "emg.h5", EmgResult)
    right = [k for k, m in enumerate(emg.muscles) if m.endswith("_r")]
    muscles = list(emg.muscles)
    for k, j in zip(right, right[1:] + right[:1]):
        muscles[k] = emg.muscles[j]
    swapped = compare_with_emg(result.time_s, result.activations, result.muscle_names, "r",
                               dataclasses.replace(emg, muscles=tuple(muscles)))
    assert np.median(swapped.correlation) <= 0.5, swapped.correlation
    assert np.mean(swapped.correlation) <= table.correlation.mean() - 0.4


def test_the_report_has_an_emg_section_and_the_agreement_table(synth):
    trial, steps = synth
    page = (trial / "gait_out" / "report.html").read_text()
    emg = page[page.index("<h2>EMG</h2>"):page.index("<h2>Muscles: EID")]
    assert "16 channels, 3 right and 3 left strides" in emg and emg.count("<img") == 2
    assert emg.count("<tr>") == 17 and "<td>tibialis anterior (right)</td><td>R TA</td>" in emg
    agreement = page[page.index("Activations against the trial's EMG"):]
    assert agreement.count("<tr>") == 9 and "activations (colour) over the EMG envelopes" in agreement


def test_bad_emg_input_stops_with_one_line_and_writes_nothing(synth, tmp_path):
    jobs = {}
    # an MVC trial without the EMG channels (the static has no analog channels at all)
    mvc = copy_sample("normal", tmp_path / "mvc")
    (mvc / "subject.yaml").write_text((mvc / "subject.yaml").read_text() + "emg: {RTIBA: tibialis_anterior_r}\n"
                                      "emg_mvc: static.c3d\n")
    jobs["mvc"] = (("emg", mvc), tmp_path)
    # an MVC trial outside the trial folder
    outside = copy_sample("normal", tmp_path / "outside")
    (outside / "subject.yaml").write_text((outside / "subject.yaml").read_text() + "emg_mvc: ../mvc/static.c3d\n")
    jobs["outside"] = (("emg", outside), tmp_path)
    # a trial without EMG channels
    plain = copy_sample("normal", tmp_path / "plain")
    jobs["plain"] = (("emg", plain), tmp_path)
    # a channel named in the map that the trial (with EMG) lacks
    missing = tmp_path / "missing"
    missing.mkdir()
    shutil.copy(synth[0] / "trial.c3d", missing / "trial.c3d")
    (missing / "subject.yaml").write_text(MINIMAL_SUBJECT + "emg: {R TIBA: tibialis_anterior_r}\n")
    jobs["missing"] = (("emg", missing), tmp_path)
    before = {name: snapshot(args[1]) for name, (args, _) in jobs.items()}
    results = gait_many(jobs)
    expected = {"mvc": "emg_mvc", "outside": "outside the trial folder", "plain": "no analog channels",
                "missing": "channel R TIBA is not in the trial"}
    for name, result in results.items():
        assert result.returncode == 2, result.describe()
        assert len(result.stderr_lines) == 1 and expected[name] in result.stderr, result.describe()
        assert "Traceback" not in result.stderr
        assert snapshot(jobs[name][0][1]) == before[name]  # inputs untouched, no output written
