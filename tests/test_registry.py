"""The stage registry: a new stage is one module plus one registry entry (docs/architecture.md's example, run from
the page), and `gait run` runs it."""

from __future__ import annotations

import json
import re
import shutil
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np
import pytest

from gaitcli.cli import main
from gaitcli.core.container import Trial
from gaitcli.core.events import SIDES
from gaitcli.core.registry import Stage, register, requirements, stage, stage_names, unregister
from gaitcli.core.validate import parameter
from gaitcli.errors import InputError
from gaitcli.resources import sample_trial
from gaitcli.run.config import PipelineConfig, load_pipeline

# --- the example stage of docs/architecture.md, executed from the page itself --------------------------------
ARCHITECTURE = Path(__file__).resolve().parents[1] / "docs" / "architecture.md"


def example_blocks() -> list[str]:
    """The Python blocks of the page's "Adding a stage": the module, then its registry entry."""
    section = ARCHITECTURE.read_text().split("### Adding a stage", 1)[1].split("\n## ", 1)[0]
    return re.findall(r"```python\n(.*?)```", section, flags=re.S)


def example_namespace() -> dict:
    """What the page's module imports, and its code run: CadenceConfig, Cadence, cadence."""
    namespace = {"dataclass": dataclass, "np": np, "parameter": parameter, "SIDES": SIDES, "Trial": Trial,
                 "Stage": Stage, "register": register}
    exec(example_blocks()[0], namespace)  # noqa: S102 (the documentation's own example)
    return namespace


@pytest.fixture
def registered():
    namespace = example_namespace()
    exec(example_blocks()[1], namespace)  # noqa: S102 (the registry entry, as gaitcli/run/stages.py would hold it)
    yield namespace
    unregister("cadence")
# ---------------------------------------------------------------------------------------------------------------


def test_builtin_stages_in_dependency_order():
    assert stage_names()[:5] == ("filter", "idyn", "emg", "muscles", "predict")
    assert requirements("emg") == ("filter", "emg")
    assert requirements("muscles") == ("filter", "idyn", "muscles")
    assert requirements("filter") == ("filter",)
    assert requirements("predict") == ("predict",)  # idyn is optional: asked for only with a trial
    assert stage("predict").optional == ("idyn",) and not stage("predict").trial


def test_a_stage_that_depends_on_an_unknown_stage_is_refused():
    config = example_namespace()["CadenceConfig"]
    with pytest.raises(InputError, match="expected one of filter, idyn, emg, muscles"):
        register(Stage(name="x", config=config, depends=("filtre",), h5_name="x.h5", run=lambda c, g: None))
    with pytest.raises(InputError, match="stage y: optional: got 'idin'"):
        register(Stage(name="y", config=config, optional=("idin",), h5_name="y.h5", run=lambda c, g: None))
    assert "x" not in stage_names() and "y" not in stage_names()


def test_a_new_stage_gets_a_pipeline_section_and_runs_through_gait_run(registered, tmp_path, capsys):
    trial = tmp_path / "normal"
    shutil.copytree(sample_trial("normal"), trial, ignore=shutil.ignore_patterns("gait_out"))
    pipeline = tmp_path / "cadence.yaml"
    pipeline.write_text("stages: [filter, cadence]\ncadence:\n  side: l\n")
    config = registered["CadenceConfig"]
    assert load_pipeline(pipeline).cadence == config(side="l")
    assert PipelineConfig().cadence == config()

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


@dataclass(frozen=True)
class ProbeConfig:
    label: str = parameter("a", help="Anything.")


@dataclass(frozen=True)
class Probe:
    frames: int
    source: str


def _probe(ctx, cfg):
    trial = ctx.optional("filter")
    return Probe(frames=-1 if trial is None else trial.markers.n_frames,
                 source="" if trial is None else ctx.input_paths["filter"].name)


@pytest.fixture
def probe():
    register(Stage(name="probe", config=ProbeConfig, optional=("filter",), trial=False, result=Probe,
                   h5_name="probe.h5", run=_probe))
    yield
    unregister("probe")


def test_an_optional_stage_is_asked_for_only_with_a_trial(probe, tmp_path, monkeypatch):
    from gaitcli.run.config import pipeline_from_dict
    from gaitcli.run.pipeline import run_stages

    cfg = pipeline_from_dict({"stages": ["filter", "probe"]})
    monkeypatch.chdir(tmp_path)
    (alone,) = run_stages(None, ["probe"], cfg, plots=False)  # no trial: nothing to ask for, no sample trial
    assert alone.summary["frames"] == -1 and alone.folder == tmp_path / "gait_out" / "probe"
    assert not (tmp_path / "gait_out" / "filter").exists()

    trial = tmp_path / "normal"
    shutil.copytree(sample_trial("normal"), trial, ignore=shutil.ignore_patterns("gait_out"))
    both = run_stages(trial, ["filter", "probe"], cfg, plots=False)  # filter computed here: written first
    assert [o.stage for o in both] == ["filter", "probe"] and all(o.status == "written" for o in both)
    assert both[1].summary["frames"] > 100 and both[1].summary["source"] == "filter.h5"
    with h5py.File(trial / "gait_out" / "probe" / "probe.h5", "r") as h5:
        assert "filter.h5" in h5.attrs["input_sha256"]  # the output it read is its input
    before = (trial / "gait_out" / "filter" / "filter.h5").stat().st_mtime_ns
    (again,) = run_stages(trial, ["probe"], cfg, plots=False)  # read back, not filtered again
    assert again.summary["frames"] == both[1].summary["frames"]
    assert (trial / "gait_out" / "filter" / "filter.h5").stat().st_mtime_ns == before
    changed = pipeline_from_dict({"filter": {"cutoff_hz": 5.0}})
    from gaitcli.run.pipeline import TrialRun

    run, other = TrialRun(trial, None, cfg), TrialRun(trial, None, changed)
    assert run.fresh("probe") is not None and other.fresh("probe") is None  # its optional stage's configuration


def test_each_muscle_variant_has_its_own_folder():
    from gaitcli.core.registry import stage
    from gaitcli.muscles.stage import METHODS, MusclesConfig

    folders = {stage("muscles").output_folder(MusclesConfig(method=m, side=s, phase=p, objective=o))
               for m in METHODS for s in ("r", "l") for p in ("cycle", "swing")
               for o in ("metabolic", "crowninshield_brand")}
    assert len(folders) == len(METHODS) * 8
    assert stage("muscles").output_folder(MusclesConfig()) == "muscles/eid"
    assert stage("muscles").output_folder(MusclesConfig(method="so", side="l", phase="swing",
                                                        objective="crowninshield_brand")) == "muscles/so_l_swing_cb"


def test_each_stage_says_its_result_in_one_line():
    from gaitcli.run.stages import describe_idyn, describe_muscles, describe_prediction

    assert describe_idyn({"strides": 6, "speed_m_s": 1.3094, "stance_right_pct": 60.6, "stance_left_pct": 61.5}) == \
        "6 strides, 1.31 m/s, stance 61/62 %"
    assert describe_idyn({"strides": 0, "speed_m_s": None}) == "0 strides, ? m/s, stance ?/? %"
    assert describe_muscles({"method": "eid", "side": "r", "converged": True, "metabolic_cost_J": 215.3,
                             "min_excitation": -1e-8, "max_excitation": 1.0}) == "eid right: converged, 215 J"
    assert describe_muscles({"method": "so", "side": "l", "phase": "swing", "converged": True,
                             "metabolic_cost_J": None, "min_excitation": -0.4, "max_excitation": 0.37,
                             "validation_rms_deg": 0.1}) == \
        "so left swing: converged, excitations -0.40…0.37 outside [0, 1], forward validation 0.10° RMS"
    checks = {"stance_pct": {"ok": True}, "ankle_moment_peak_pct": {"ok": False}}
    assert describe_prediction({"converged": True, "iterations": 232, "cost_of_transport_J_per_m": 350.4,
                                "objective": 11.38015, "gait_checks": checks}) == \
        "converged in 232 it., Et 350 J/m, J 11.38, 1 gait check failed (ankle_moment_peak_pct)"
