"""The stage registry: a new stage is one module plus one registry entry, and `gait run` runs it."""

from __future__ import annotations

import json
import shutil
from dataclasses import dataclass

import h5py
import numpy as np
import pytest

from gaitcli.cli import main
from gaitcli.run.config import PipelineConfig, load_pipeline
from gaitcli.core.container import Trial
from gaitcli.core.events import SIDES
from gaitcli.core.registry import Stage, register, requirements, stage_names, unregister
from gaitcli.core.validate import parameter
from gaitcli.errors import InputError
from gaitcli.resources import sample_trial


# --- the example stage of docs/architecture.md ----------------------------------------------------------------
@dataclass(frozen=True)
class CadenceConfig:
    side: str = parameter("r", choices=SIDES, help="Which foot's heel strikes.")


@dataclass(frozen=True)
class Cadence:
    steps_per_min: float
    strides: int


def cadence(trial: Trial, cfg: CadenceConfig) -> Cadence:
    """Steps per minute from one foot's heel strikes (two steps per stride)."""
    strikes = trial.events.times(cfg.side, "heel_strike")
    return Cadence(steps_per_min=2 * 60 / float(np.mean(np.diff(strikes))), strides=len(strikes) - 1)


CADENCE = Stage(name="cadence", config=CadenceConfig, depends=("filter",), result=Cadence, h5_name="cadence.h5",
                run=lambda ctx, cfg: cadence(ctx.inputs["filter"], cfg))
# ---------------------------------------------------------------------------------------------------------------


@pytest.fixture
def registered():
    register(CADENCE)
    yield CADENCE
    unregister("cadence")


def test_builtin_stages_in_dependency_order():
    assert stage_names()[:3] == ("filter", "idyn", "muscles")
    assert requirements("muscles") == ("filter", "idyn", "muscles")
    assert requirements("filter") == ("filter",)


def test_a_stage_that_depends_on_an_unknown_stage_is_refused():
    with pytest.raises(InputError, match="expected one of filter, idyn, muscles"):
        register(Stage(name="x", config=CadenceConfig, depends=("filtre",), h5_name="x.h5", run=lambda c, g: None))
    assert "x" not in stage_names()


def test_a_new_stage_gets_a_pipeline_section_and_runs_through_gait_run(registered, tmp_path, capsys):
    trial = tmp_path / "normal"
    shutil.copytree(sample_trial("normal"), trial, ignore=shutil.ignore_patterns("gait_out"))
    pipeline = tmp_path / "cadence.yaml"
    pipeline.write_text("stages: [filter, cadence]\ncadence:\n  side: l\n")
    assert load_pipeline(pipeline).cadence == CadenceConfig(side="l")
    assert PipelineConfig().cadence == CadenceConfig()

    assert main(["--quiet", "--json", "run", str(trial), "--pipeline", str(pipeline), "--no-plots"]) == 0
    printed = json.loads(capsys.readouterr().out)
    assert set(printed) == {"filter", "cadence"}

    # the sample's left heel strikes, independently: truth/events.csv of the synthetic trial
    import pandas as pd

    truth = pd.read_csv(trial / "truth" / "events.csv")
    strikes = np.sort(truth[(truth.side == "l") & (truth.event == "heel_strike")].time_s.to_numpy())
    expected = 120.0 / np.mean(np.diff(strikes))
    out = trial / "gait_out" / "cadence"
    summary = json.loads((out / "summary.json").read_text())
    assert summary["strides"] == len(strikes) - 1
    assert summary["steps_per_min"] == pytest.approx(expected, rel=0.01)  # plate events vs truth: < 10 ms
    with h5py.File(out / "cadence.h5", "r") as h5:
        assert h5["result/steps_per_min"][()] == pytest.approx(summary["steps_per_min"])
        assert "stage_key" in h5.attrs and "cadence" in h5.attrs["config_yaml"]
    assert not (out / "plots").exists()

    # the new stage alone reads the filter stage's fresh output back instead of filtering again
    alone = tmp_path / "alone.yaml"
    alone.write_text("stages: [cadence]\ncadence:\n  side: l\n")
    before = (trial / "gait_out" / "filter" / "filter.h5").stat().st_mtime_ns
    assert main(["--quiet", "run", str(trial), "--pipeline", str(alone), "--no-plots"]) == 0
    assert (trial / "gait_out" / "filter" / "filter.h5").stat().st_mtime_ns == before
    assert json.loads((out / "summary.json").read_text())["steps_per_min"] == summary["steps_per_min"]
    bad = tmp_path / "bad.yaml"
    bad.write_text("stages: [filter, cadence]\ncadence:\n  side: left\n")
    assert main(["--quiet", "run", str(trial), "--pipeline", str(bad)]) == 2
    assert "cadence.side: got 'left' (expected one of r, l" in capsys.readouterr().err
