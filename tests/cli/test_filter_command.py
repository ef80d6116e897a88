"""``gait filter`` end to end: files, columns, units, summary.json, HDF5 provenance, overrides, reruns,
and agreement with the synthetic trials' truth (issue 2's "Done when").

Runs (once per session, two at a time): the copied ``normal`` sample trial with defaults and
the bundled trial (no TRIAL argument, so ``./gait_out``) with a pipeline file saying 7 Hz and
``--cutoff 8`` on the command line; then ``normal`` again with ``--json`` into the same output
folder, and the copied ``ski_boot`` trial with defaults.
"""

from __future__ import annotations

import hashlib
import json
import shutil
from datetime import datetime, timedelta, timezone
from pathlib import Path
from types import SimpleNamespace

import ezc3d
import h5py
import numpy as np
import pandas as pd
import pytest
import yaml

from gaitcli import __version__
from gaitcli.resources import sample_trial

from .conftest import FILTER_FILES, Result, build_once, copy_sample, gait, gait_many, snapshot
from .truth import (
    COP_M,
    FREE_MOMENT_NM,
    GRF_FRACTION_OF_PEAK,
    KINEMATIC_HEEL_STRIKE_FRAMES,
    KINEMATIC_TOE_OFF_FRAMES,
    PLATE_EVENT_FRAMES,
    event_errors,
    grf_errors,
    plate_feet,
    read_table,
    read_truth,
)

CSVS = ("markers_filtered.csv", "grf.csv", "events.csv")
SUMMARY_KEYS = ("frames", "marker_rate_hz", "analog_rate_hz", "cutoff_hz", "gaps_filled", "events")
RATE_HZ = 100.0  # the sample trials' marker rate (sample_trials/README.md)


def _build(root: Path) -> dict:
    normal = copy_sample("normal", root / "normal")
    ski_boot = copy_sample("ski_boot", root / "ski_boot")
    bundled = root / "bundled_cwd"
    bundled.mkdir()
    pipeline = root / "cutoff7.yaml"
    pipeline.write_text("filter:\n  cutoff_hz: 7.0\n  force_cutoff_hz: 7.0\n")
    inputs, samples = snapshot(normal), snapshot(sample_trial("normal").parent)
    first = gait_many({
        "normal": (("filter", normal), root),
        "bundled": (("filter", "--pipeline", pipeline, "--cutoff", "8"), bundled),
    })
    out = normal / "gait_out" / "filter"
    if (out / "filter.h5").is_file():  # keep the first run's outputs to compare with the rerun's
        (root / "first_run").mkdir()
        for name in (*CSVS, "filter.h5"):
            shutil.copy(out / name, root / "first_run" / name)
    second = gait_many({"rerun": (("--json", "filter", normal), root), "ski_boot": (("filter", ski_boot), root)})
    results = {**first, **second}
    return {"results": {k: r.to_json() for k, r in results.items()}, "inputs_before": inputs,
            "samples_before": samples}


@pytest.fixture(scope="session")
def runs(tmp_path_factory):
    root, record = build_once(tmp_path_factory, "cli_filter", _build)
    normal, ski_boot, bundled = root / "normal", root / "ski_boot", root / "bundled_cwd"
    results = {k: Result.from_json(v) for k, v in record["results"].items()}
    return SimpleNamespace(root=root, normal=normal, ski_boot=ski_boot, bundled=bundled, results=results,
                           first_run=root / "first_run", inputs_before=record["inputs_before"],
                           samples_before=record["samples_before"],
                           out={"normal": normal / "gait_out" / "filter", "ski_boot": ski_boot / "gait_out" / "filter",
                                "bundled": bundled / "gait_out" / "filter"})


def _datasets(path: Path) -> dict:
    found = {}
    with h5py.File(path, "r") as h5:
        h5.visititems(lambda name, obj: found.setdefault(name, obj[()]) if isinstance(obj, h5py.Dataset) else None)
    return found


def _summary(path: Path) -> dict:
    return json.loads((path / "summary.json").read_text())


def test_runs_succeed_quietly(runs):
    for result in runs.results.values():
        assert result.returncode == 0, result.describe()
        # the clean synthetic trial gives no warnings; the last line says where the outputs went
        assert not [line for line in result.stderr_lines if "warning" in line or "error" in line], result.describe()
        assert "Traceback" not in result.stderr


@pytest.mark.parametrize("which", ["normal", "ski_boot", "bundled"])
def test_writes_every_file_of_the_stage(runs, which):
    out = runs.out[which]
    for name in FILTER_FILES:
        assert (out / name).is_file() and (out / name).stat().st_size > 0, name
    for name in ("markers.png", "grf.png"):
        assert (out / "plots" / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", name
    # the stage folder was swapped in whole: no temporary or old folders next to it
    assert sorted(p.name for p in out.parent.iterdir()) == ["filter"]
    assert [p.name for p in out.rglob(".*")] == [".gait_files"]  # no temporary file; the list of gait's files
    listed = json.loads((out / ".gait_files").read_text())
    files = sorted(p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file())
    assert list(listed) == [f for f in files if f != ".gait_files"]


def test_default_output_folders(runs):
    # TRIAL/gait_out/<stage>/ for a trial folder; ./gait_out/ for the bundled sample; nothing in sample_trials/
    assert runs.out["normal"] == runs.normal / "gait_out" / "filter"
    assert (runs.bundled / "gait_out" / "filter" / "summary.json").is_file()
    assert not (sample_trial("normal") / "gait_out").exists()


def test_inputs_untouched(runs):
    after = {k: v for k, v in snapshot(runs.normal).items() if not k.startswith("gait_out")}
    assert after == runs.inputs_before
    assert snapshot(sample_trial("normal").parent) == runs.samples_before  # nothing written into sample_trials/


@pytest.mark.parametrize("name", CSVS)
def test_tables_start_with_time_s(runs, name):
    table = read_table(runs.out["normal"] / name)
    assert table.columns[0] == "time_s"
    if name != "events.csv":
        # one row per marker frame, at the marker rate from t = 0
        np.testing.assert_allclose(table["time_s"], np.arange(len(table)) / RATE_HZ, atol=1e-9)


def test_table_columns_and_units(runs):
    out = runs.out["normal"]
    c3d = ezc3d.c3d(str(runs.normal / "trial.c3d"))
    labels = [s.strip() for s in c3d["parameters"]["POINT"]["LABELS"]["value"]]
    n_frames = c3d["data"]["points"].shape[2]
    n_plates = len(read_truth(runs.normal)["plates"])

    markers = read_table(out / "markers_filtered.csv")
    assert len(markers) == n_frames
    for label in labels:
        for axis in "xyz":
            assert f"{label}_{axis}_m" in markers.columns
    assert markers.filter(regex="_m$").notna().all().all()  # no gaps in the synthetic trial

    grf = read_table(out / "grf.csv")
    assert len(grf) == n_frames
    per_load = ["force_x_N", "force_y_N", "force_z_N", "cop_x_m", "cop_y_m", "cop_z_m", "free_moment_Nm"]
    for prefix in [f"plate{k}" for k in range(1, n_plates + 1)] + ["foot_r", "foot_l"]:
        for column in per_load:
            assert f"{prefix}_{column}" in grf.columns
    for k in range(1, n_plates + 1):
        assert set(grf[f"plate{k}_foot"].astype(str)) <= {"", "r", "l"}
    # every numeric column names its unit
    text = {"frame"} | {f"plate{k}_foot" for k in range(1, n_plates + 1)}
    for table in (markers, grf):
        for column in table.columns[1:]:
            assert column in text or column.endswith(("_m", "_N", "_Nm")), column

    events = read_table(out / "events.csv")
    assert list(events.columns) == ["time_s", "frame", "side", "event", "source"]
    assert set(events["side"]) <= {"r", "l"} and set(events["event"]) <= {"heel_strike", "toe_off"}
    assert set(events["source"]) <= {"plate", "kinematics"}
    assert (np.diff(events["time_s"]) >= 0).all()
    # 1-based file frame numbers, as in the C3D and the truth
    np.testing.assert_array_equal(events["frame"], np.rint(events["time_s"] * RATE_HZ).astype(int) + 1)


def test_summary_json_keys(runs):
    summary = _summary(runs.out["normal"])
    for key in SUMMARY_KEYS:
        assert key in summary, key
    truth_frames = len(pd.read_csv(runs.normal / "truth" / "kinematics.csv"))
    assert summary["frames"] == truth_frames
    assert summary["marker_rate_hz"] == 100.0 and summary["analog_rate_hz"] == 1000.0
    assert summary["cutoff_hz"] == 6.0
    assert summary["gaps_filled"] == 0 and isinstance(summary["gaps_filled"], int)
    events = read_table(runs.out["normal"] / "events.csv")
    assert len(summary["events"]) == len(events)
    for row, (_, e) in zip(summary["events"], events.iterrows()):
        assert (row["frame"], row["side"], row["event"], row["source"]) == (e["frame"], e["side"], e["event"],
                                                                            e["source"])
        assert row["time_s"] == pytest.approx(e["time_s"], abs=1e-5)


def test_h5_provenance_and_units(runs):
    path = runs.out["normal"] / "filter.h5"
    with h5py.File(path, "r") as h5:
        attrs = dict(h5.attrs)
        for key in ("gaitcli_version", "config_yaml", "input_sha256", "created_utc"):
            assert key in attrs, key
        assert attrs["gaitcli_version"] == __version__
        config = yaml.safe_load(attrs["config_yaml"])
        assert config["filter"]["cutoff_hz"] == 6.0 and config["filter"]["force_cutoff_hz"] == 6.0  # auto's
        hashes = json.loads(attrs["input_sha256"])
        for name in ("trial.c3d", "subject.yaml"):
            assert hashes[name] == hashlib.sha256((runs.normal / name).read_bytes()).hexdigest()
        created = datetime.fromisoformat(attrs["created_utc"])
        assert created.tzinfo is not None
        assert abs(datetime.now(timezone.utc) - created) < timedelta(hours=1)

        missing = []
        h5.visititems(lambda name, obj: missing.append(name)
                      if isinstance(obj, h5py.Dataset) and not str(obj.attrs.get("units", "")) else None)
        assert not missing, f"datasets without units: {missing}"
        assert h5["trial/markers/positions_m"].attrs["units"] == "m"
        assert h5["plates/plate1/force"].attrs["units"] == "N"
        filtered = h5["trial/markers/positions_m"][()]
    # the HDF5 holds what the CSV shows (CSV: 6 significant digits)
    markers = read_table(runs.out["normal"] / "markers_filtered.csv")
    np.testing.assert_allclose(markers.filter(regex="_m$").to_numpy(), filtered.reshape(len(markers), -1),
                               rtol=1e-5, atol=1e-9)


def test_cli_cutoff_overrides_pipeline_file(runs):
    # cutoff7.yaml says 7 Hz; --cutoff 8 on the command line wins
    summary = _summary(runs.out["bundled"])
    assert summary["cutoff_hz"] == 8.0
    with h5py.File(runs.out["bundled"] / "filter.h5", "r") as h5:
        config = yaml.safe_load(h5.attrs["config_yaml"])
    assert config["filter"]["cutoff_hz"] == 8.0
    # and it took effect: the filtered markers differ from the 6 Hz run on the same trial
    six = read_table(runs.out["normal"] / "markers_filtered.csv").filter(regex="_m$").to_numpy()
    eight = read_table(runs.out["bundled"] / "markers_filtered.csv").filter(regex="_m$").to_numpy()
    assert six.shape == eight.shape
    assert np.abs(six - eight).max() > 1e-4


def test_json_prints_the_summary(runs):
    printed = json.loads(runs.results["rerun"].stdout)
    assert printed == _summary(runs.out["normal"])
    for key in SUMMARY_KEYS:
        assert key in printed


def test_rerun_gives_identical_outputs(runs):
    out = runs.out["normal"]
    assert runs.first_run.is_dir(), "the first run wrote no outputs"
    for name in CSVS:
        assert (out / name).read_bytes() == (runs.first_run / name).read_bytes(), name
    before, after = _datasets(runs.first_run / "filter.h5"), _datasets(out / "filter.h5")
    assert after.keys() == before.keys()
    for name, values in after.items():
        np.testing.assert_array_equal(values, before[name], err_msg=name)


# ----------------------------------------------------------------------------------- truth


@pytest.mark.parametrize("which", ["normal", "ski_boot"])
def test_plate_to_foot_assignment_matches_truth(runs, which):
    trial = getattr(runs, which)
    truth = read_truth(trial)
    grf = read_table(runs.out[which] / "grf.csv")
    expected = {p: [f] for p, f in zip(truth["plates"]["plate"], truth["plates"]["foot"])}
    assert plate_feet(grf, len(expected)) == expected
    with h5py.File(runs.out[which] / "filter.h5", "r") as h5:
        for plate, foot in expected.items():
            owner = h5[f"plates/{plate}/foot"].asstr()[()]
            assert set(owner) - {""} == set(foot)
            np.testing.assert_array_equal(owner, grf[f"{plate}_foot"].astype(str).to_numpy())


@pytest.mark.parametrize("which", ["normal", "ski_boot"])
def test_plate_events_match_truth(runs, which):
    trial = getattr(runs, which)
    truth = read_truth(trial)["events"]
    events = read_table(runs.out[which] / "events.csv")
    plate = events[events["source"] == "plate"]
    on_plate = truth[truth["on_plate"] == 1]
    assert len(plate) == len(on_plate) == 4  # two plates: a heel strike and a toe off each
    for _, t in on_plate.iterrows():
        same = plate[(plate["side"] == t["side"]) & (plate["event"] == t["event"])]
        assert (np.abs(same["frame"] - t["frame"]) <= PLATE_EVENT_FRAMES).any(), t.to_dict()
    errors = event_errors(events, truth, RATE_HZ, "plate")
    assert (errors["on_plate"] == 1).all()
    assert (errors["frame_diff"].abs() <= PLATE_EVENT_FRAMES).all()


@pytest.mark.parametrize("which", ["normal", "ski_boot"])
def test_kinematic_events_within_documented_tolerance(runs, which):
    trial = getattr(runs, which)
    truth = read_truth(trial)["events"]
    events = read_table(runs.out[which] / "events.csv")
    errors = event_errors(events, truth, RATE_HZ, "kinematics")
    strikes = errors[errors["event"] == "heel_strike"]["err_frames"]
    offs = errors[errors["event"] == "toe_off"]["err_frames"]
    assert len(strikes) >= 5 and len(offs) >= 5
    # measured: normal heel strike −3.0 … −3.7 frames, toe off +0.9 … +1.1; ski_boot −3.5 … −4.0, −1.3 … +1.2
    lo, hi = KINEMATIC_HEEL_STRIKE_FRAMES
    assert strikes.between(lo, hi).all(), strikes.tolist()
    assert (offs.abs() <= KINEMATIC_TOE_OFF_FRAMES).all(), offs.tolist()
    # every truth event is found, by one source or the other
    for _, t in truth.iterrows():
        same = events[(events["side"] == t["side"]) & (events["event"] == t["event"])]
        assert (np.abs(same["time_s"] - t["time_s"]) * RATE_HZ <= -lo).any(), t.to_dict()


@pytest.mark.parametrize("which", ["normal", "ski_boot"])
def test_per_foot_grf_matches_truth(runs, which):
    trial = getattr(runs, which)
    grf = read_table(runs.out[which] / "grf.csv")
    for e in grf_errors(grf, read_truth(trial), RATE_HZ, cutoff_hz=6.0):
        assert e["frames"] > 50, e  # the plate's whole stance (~0.7 s) is given to its foot
        # measured: Fz ≤ 0.07 % of peak; COP ≤ 0.4 mm; free moment ≤ 0.06 N·m (truth.py derives the bounds)
        assert (e["force_rel"] <= GRF_FRACTION_OF_PEAK).all(), e
        assert (e["cop_m"] <= COP_M).all(), e
        assert e["free_moment_Nm"] <= FREE_MOMENT_NM, e
        # the filter's own effect (the unfiltered truth, 3 % of peak at the loading edge) is far larger
        assert e["unfiltered_rel"] > 3 * e["force_rel"][2], e


def test_a_stage_run_again_for_other_settings_says_why(tmp_path):
    """``gait filter --cutoff 8`` then ``gait idyn`` (which asks for the default, auto: 6 Hz): the filter runs
    again, and a warning names the settings that differ; the next idyn reuses the 6 Hz filter without a word."""
    trial = copy_sample("normal", tmp_path / "t")
    assert gait("filter", trial, "--cutoff", "8", "--no-plots", cwd=tmp_path).returncode == 0
    idyn = gait("idyn", trial, "--no-plots", cwd=tmp_path)
    assert idyn.returncode == 0, idyn.describe()
    assert ("gait: warning: filter: filter.cutoff_hz 8.0 in the existing output, 6.0 asked; "
            "filter.force_cutoff_hz 8.0 in the existing output, 6.0 asked: running filter again") in idyn.stderr_lines
    again = gait("idyn", trial, "--no-plots", cwd=tmp_path)
    assert again.returncode == 0 and "running filter again" not in again.stderr, again.describe()


def test_gait_run_takes_the_common_overrides(tmp_path):
    trial = copy_sample("normal", tmp_path / "t")
    run = gait("run", trial, "--cutoff", "8", "--frames", "anatomical", "--export", "opensim", "--no-plots",
               cwd=tmp_path)
    assert run.returncode == 0, run.describe()
    out = trial / "gait_out"
    assert json.loads((out / "filter" / "summary.json").read_text())["cutoff_hz"] == 8.0
    assert yaml.safe_load(h5py.File(out / "idyn" / "idyn.h5", "r").attrs["config_yaml"])["idyn"]["frames"] == \
        "anatomical"
    assert (out / "export" / "opensim" / "external_loads.xml").is_file()
    bad = gait("run", trial, "--pipeline", "muscles_eid", "--cutoff", "-1", cwd=tmp_path)
    assert bad.returncode == 2 and "--cutoff" in bad.stderr, bad.describe()
