"""gaitcli's Python API (gaitcli/api.py) on the bundled normal sample trial, processed once for the module.

The getting-started script (docs/examples/stride_table.py: filter, idyn, EID, read back, a table per stride)
runs once (:func:`processed`); the per-stride figures are checked against the trial's truth, every table read
back against the CSVs the stages wrote beside it, and every example of the API's docstrings runs on its
output (doctest). The prediction read back is the session's stopped ``gait predict`` (tests/cli/conftest.py).
"""

from __future__ import annotations

import doctest
import importlib.util
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import gaitcli
from gaitcli import api

from .cli.conftest import stopped_prediction  # noqa: F401  (the session's prediction, a fixture)

REPO = Path(__file__).resolve().parents[1]
SCRIPT = REPO / "docs" / "examples" / "stride_table.py"
CSV_RTOL, CSV_ATOL = 1e-5, 1e-9  # the CSVs' 6 significant digits


def _script():
    spec = importlib.util.spec_from_file_location("stride_table", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def processed(tmp_path_factory):
    """(the trial folder, the stride table) of docs/examples/stride_table.py run once."""
    workdir = tmp_path_factory.mktemp("api")
    table = _script().stride_table(workdir)
    return workdir / "normal", table


def _truth_strides(trial: Path) -> pd.DataFrame:
    """The true strides of the synthetic trial: consecutive heel strikes of one foot (truth/events.csv)."""
    events = pd.read_csv(trial / "truth" / "events.csv")
    rows = []
    for side, strikes in events[events["event"] == "heel_strike"].groupby("side"):
        times = strikes["time_s"].to_numpy()
        rows += [{"side": side, "start_s": a, "end_s": b} for a, b in zip(times[:-1], times[1:])]
    return pd.DataFrame(rows).sort_values("start_s", ignore_index=True)


def test_the_stride_table_follows_the_trials_truth(processed):
    trial, table = processed
    truth = _truth_strides(trial)
    angles = pd.read_csv(trial / "truth" / "anatomical_angles.csv")
    assert len(table) == len(truth) == 6
    assert table["side"].tolist() == truth["side"].tolist()
    # detected heel strikes lie within 3 frames (100 Hz) of the true ones; the periods within 2 ms
    np.testing.assert_allclose(table["start_s"], truth["start_s"], atol=0.03)
    np.testing.assert_allclose(table["period_s"], truth["end_s"] - truth["start_s"], atol=0.002)
    for row, true in zip(table.itertuples(), truth.itertuples()):
        inside = angles[(angles["time_s"] >= true.start_s) & (angles["time_s"] <= true.end_s)]
        peak = inside[f"knee_{row.side}_flexion"].max()
        assert row.peak_knee_flexion_deg == pytest.approx(peak, abs=2.0)  # markers: 1 mm noise, 10 mm artefact


def test_the_stride_table_carries_eid_on_the_stride_it_analysed(processed):
    trial, table = processed
    summary = json.loads((trial / "gait_out" / "muscles" / "eid" / "summary.json").read_text())
    analysed = table.dropna(subset=["eid_metabolic_cost_J"])
    assert len(analysed) == 1 and analysed["side"].item() == "r"
    assert analysed["start_s"].item() == pytest.approx(summary["interval_s"][0], abs=1e-9)
    assert analysed["eid_metabolic_cost_J"].item() == pytest.approx(summary["metabolic_cost_J"], rel=1e-12)


def test_the_getting_started_page_shows_what_the_script_prints(processed):
    _, table = processed
    shown = pd.read_csv(REPO / "docs" / "examples" / "stride_table.txt", sep=r"\s+")
    assert shown.columns.tolist() == table.columns.tolist()
    numbers = table.select_dtypes("number").columns
    np.testing.assert_allclose(shown[numbers], table[numbers], atol=0.006)  # printed to 2 decimals


def _equal_to_csv(frame: pd.DataFrame, csv: Path, rename=None) -> None:
    """``frame`` holds every column of ``csv`` (renamed by ``rename(name)``; None: not one of ``frame``'s), equal
    within the CSV's 6 digits."""
    table = pd.read_csv(csv)
    names = {name: rename(name) if rename else name for name in table.columns}
    names = {name: ours for name, ours in names.items() if ours is not None}
    assert set(names.values()) <= set(frame.columns), sorted(set(names.values()) - set(frame.columns))
    for name, ours in names.items():
        if table[name].dtype.kind in "OU":
            assert frame[ours].astype(str).tolist() == table[name].astype(str).tolist(), name
        else:
            np.testing.assert_allclose(frame[ours].to_numpy(float), table[name].to_numpy(float), rtol=CSV_RTOL,
                                       atol=CSV_ATOL, equal_nan=True, err_msg=name)


def test_every_table_read_back_equals_the_csv_beside_it(processed):
    trial, _ = processed
    root = trial / "gait_out"
    outputs = gaitcli.read_outputs(trial)
    _equal_to_csv(outputs.filter.markers, root / "filter" / "markers_filtered.csv")
    _equal_to_csv(outputs.filter.events, root / "filter" / "events.csv")
    grf = pd.read_csv(root / "filter" / "grf.csv")
    feet = [name for name in grf.columns if name.startswith("foot_")]
    # the feet's loads; the plates' own columns are the filter's (filter.h5 keeps the trial the stages read)
    _equal_to_csv(outputs.filter.grf, root / "filter" / "grf.csv", lambda n: n if n in feet or n == "time_s" else None)
    idyn = outputs.idyn
    angles = pd.read_csv(root / "idyn" / "kinematics.csv").columns[1:]
    moments = [name for name in pd.read_csv(root / "idyn" / "joint_moments.csv").columns if name.endswith("_moment")]
    units = {"time_s": "time_s", **{n: f"{n}_deg" for n in angles}, **{m: f"{m}_Nm" for m in moments},
             **{f"{m}_per_kg": f"{m}_Nm_per_kg" for m in moments}}
    _equal_to_csv(idyn.angles, root / "idyn" / "kinematics.csv", units.get)
    _equal_to_csv(idyn.moments, root / "idyn" / "joint_moments.csv",
                  units.get)  # the foot-load flags are idyn.h5's moment_known
    _equal_to_csv(idyn.powers, root / "idyn" / "joint_powers.csv",
                  lambda n: None if "sagittal" in n else n)  # the total powers; the sagittal ones stay in the CSV
    _equal_to_csv(idyn.cycles, root / "idyn" / "gait_cycle.csv", lambda n: units.get(n, n))
    eid = outputs.muscles["eid"]
    for name in ("forces", "activations", "excitations", "metabolics"):
        _equal_to_csv(getattr(eid, name), root / "muscles" / "eid" / f"{name}.csv")


def test_a_prediction_of_gait_predict_reads_back_as_its_csvs(stopped_prediction):  # noqa: F811
    folder, _ = stopped_prediction
    outputs = gaitcli.read_outputs(folder)
    prediction = outputs.predict
    assert outputs.stages == ("predict",) and not outputs.converged and prediction.prosthesis is None
    for name in ("motion", "grf", "moments", "muscles"):
        _equal_to_csv(getattr(prediction, name), folder / "predict" / f"{name}.csv")
    assert prediction.summary == json.loads((folder / "predict" / "summary.json").read_text())


def test_each_stage_reads_back_from_its_folder_or_file_alike(processed):
    trial, _ = processed
    whole = gaitcli.read_outputs(trial / "gait_out")
    assert whole.stages == ("filter", "idyn", "muscles/eid") and whole.folder == trial / "gait_out"
    for key, path in whole.paths.items():
        for ref in (path, path.parent):
            alone = gaitcli.read_outputs(ref)
            assert alone.stages == (key,) and alone.folder == trial / "gait_out"
    one = gaitcli.read_outputs(trial / "gait_out" / "muscles" / "eid")
    pd.testing.assert_frame_equal(one.muscles["eid"].forces, whole.muscles["eid"].forces)


def test_no_outputs_is_an_input_error_naming_the_folder(tmp_path):
    with pytest.raises(gaitcli.InputError, match=str(tmp_path)) as caught:
        gaitcli.read_outputs(tmp_path)
    assert "no outputs of gait" in str(caught.value)
    (tmp_path / "idyn").mkdir()
    (tmp_path / "idyn" / "idyn.h5").write_text("not HDF5")
    outputs = gaitcli.read_outputs(tmp_path)
    with pytest.raises(gaitcli.InputError, match="idyn.h5"):
        outputs.idyn  # noqa: B018  (read on first use)


def test_a_bad_setting_is_named_as_a_pipeline_files_would_be():
    with pytest.raises(gaitcli.InputError, match="muscles.*method"):
        gaitcli.pipeline_config({"muscles": {"method": "simplex"}})
    with pytest.raises(gaitcli.InputError, match="speed_m_s"):
        gaitcli.predict_gait(speed_m_s=-1.0)
    with pytest.raises(gaitcli.InputError, match="musles"):
        gaitcli.pipeline_config(musles={"method": "so"})


def test_importing_gaitcli_loads_nothing_else():
    # the gait command sets its thread counts after `import gaitcli` and before numpy loads (__main__.py); the API
    # loads on first use of a public name (test_the_public_names_are_the_apis)
    code = "import sys, gaitcli; print(sorted(m for m in sys.modules if m.startswith(('gaitcli', 'numpy'))))"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "['gaitcli']"


def test_the_public_names_are_the_apis():
    assert gaitcli.__all__ == api.__all__
    assert all(getattr(gaitcli, name) is getattr(api, name) for name in gaitcli.__all__)
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        gaitcli.nothing  # noqa: B018


EXAMPLES = [test for test in doctest.DocTestFinder().find(api, globs={}) if test.examples]


def test_every_public_function_and_output_class_has_an_example():
    documented = {test.name.removeprefix("gaitcli.api.") for test in EXAMPLES}
    own = {name for name in api.__all__ if getattr(api, name).__module__ == "gaitcli.api"}
    assert own <= documented, sorted(own - documented)


@pytest.mark.parametrize("test", EXAMPLES, ids=lambda test: test.name.removeprefix("gaitcli.api."))
def test_the_docstring_examples_run(test, processed, stopped_prediction, tmp_path, monkeypatch):  # noqa: F811
    trial, _ = processed
    monkeypatch.chdir(tmp_path)
    test.globs = {"gaitcli": gaitcli, "trial_folder": trial, "prediction_folder": stopped_prediction[0],
                  "workdir": tmp_path}
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    report = []
    runner.run(test, out=report.append)
    assert runner.failures == 0, "".join(report)
