"""Inputs that deserve a warning, not an error: exit 0, the warning on stderr, every output written.

* no force plates and duplicate labels: ``duplicate_labels.c3d`` (48 upper-body markers, no plates);
* plates that never see a load: ``BTS.c3d`` (6 plates, 2, 3 and 6 unloaded; its foot markers
  mapped to the model's CAr/FMr/CAl/FMl by the subject's marker_map);
* a marker that is never seen: the normal sample trial as markers.csv + forces.csv with the
  sternum marker ST all empty.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from gaitcli.io.c3d import read_c3d
from gaitcli.resources import sample_trial

from .conftest import FILTER_FILES, MINIMAL_SUBJECT, Result, build_once, gait_many, snapshot
from .truth import read_table

BTS_SUBJECT = MINIMAL_SUBJECT + """marker_map:
  r heel: CAr
  r met: FMr
  l heel: CAl
  l met: FMl
  r asis: ASISr
  l asis: ASISl
"""
NAN_MARKER = "ST"


def write_csv_trial(source: Path, dest: Path, *, blank: str) -> None:
    """``source``'s trial.c3d as markers.csv + forces.csv (tables.py formats) with marker ``blank`` never seen.

    The sample trial's lab is z-up with the floor at z = 0 (its lab_to_model is the identity),
    as forces.csv requires. COP and free moment follow from each plate's wrench about its
    centre: r = (-M_y/F_z, M_x/F_z), T_z = M_z - (r_x F_y - r_y F_x); empty where F_z ≤ 20 N.
    """
    import warnings

    from gaitcli.errors import GaitWarning

    with warnings.catch_warnings():
        warnings.simplefilter("error", GaitWarning)  # the sample trial itself reads without warnings
        rec = read_c3d(source / "trial.c3d", to_model_axes=False)
    m = rec.markers
    columns = {"time_s": np.arange(m.n_frames) / m.rate_hz}
    for i, label in enumerate(m.labels):
        for k, axis in enumerate("xyz"):
            columns[f"{label}_{axis}_m"] = np.full(m.n_frames, np.nan) if label == blank else m.positions_m[:, i, k]
    pd.DataFrame(columns).to_csv(dest / "markers.csv", index=False, na_rep="", float_format="%.9g")
    forces = {"time_s": np.arange(rec.plates[0].n_samples) / rec.plates[0].rate_hz}
    for k, plate in enumerate(rec.plates, start=1):
        f, mo = plate.force_N, plate.moment_Nm
        loaded = f[:, 2] > 20.0
        with np.errstate(divide="ignore", invalid="ignore"):
            rx, ry = -mo[:, 1] / f[:, 2], mo[:, 0] / f[:, 2]
        free = mo[:, 2] - (rx * f[:, 1] - ry * f[:, 0])
        for a, axis in enumerate("xyz"):
            forces[f"plate{k}_force_{axis}_N"] = f[:, a]
        forces[f"plate{k}_cop_x_m"] = np.where(loaded, plate.centre_m[0] + rx, np.nan)
        forces[f"plate{k}_cop_y_m"] = np.where(loaded, plate.centre_m[1] + ry, np.nan)
        forces[f"plate{k}_free_moment_Nm"] = np.where(loaded, free, np.nan)
    pd.DataFrame(forces).to_csv(dest / "forces.csv", index=False, na_rep="", float_format="%.9g")


def _build(root: Path) -> dict:
    from ..conftest import SHARED_C3D

    jobs = {}
    if SHARED_C3D.is_dir():
        for name, c3d, subject in (("duplicate_labels", "duplicate_labels.c3d", MINIMAL_SUBJECT),
                                   ("bts", "BTS.c3d", BTS_SUBJECT)):
            trial = root / name
            trial.mkdir()
            shutil.copy(SHARED_C3D / c3d, trial / "trial.c3d")
            (trial / "subject.yaml").write_text(subject)
            jobs[name] = (("filter", trial), root)
    csv_trial = root / "nan_marker"
    csv_trial.mkdir()
    shutil.copy(sample_trial("normal") / "subject.yaml", csv_trial)
    write_csv_trial(sample_trial("normal"), csv_trial, blank=NAN_MARKER)
    inputs = snapshot(csv_trial)
    jobs["nan_marker"] = (("filter", csv_trial), root)
    results = gait_many(jobs)
    return {"results": {k: r.to_json() for k, r in results.items()}, "nan_inputs": inputs}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    root, record = build_once(tmp_path_factory, "cli_warnings", _build)
    return {"root": root, "results": {k: Result.from_json(v) for k, v in record["results"].items()},
            "nan_inputs": record["nan_inputs"]}


def _warnings(result) -> list[str]:
    return [line for line in result.stderr_lines if line.startswith("gait: warning: ")]


def _outputs_written(folder: Path) -> None:
    out = folder / "gait_out" / "filter"
    for name in FILTER_FILES:
        assert (out / name).is_file(), name
    assert (out / "plots").is_dir()


def test_no_plates_and_duplicate_labels_warn(runs, shared_c3d_dir):
    result = runs["results"]["duplicate_labels"]
    warned = _warnings(result)
    assert any("duplicate marker labels" in w and "T8_2" in w for w in warned), result.describe()
    assert any("no usable force plates" in w for w in warned), result.describe()
    assert "Traceback" not in result.stderr


def test_no_plates_still_writes_outputs(runs, shared_c3d_dir):
    result = runs["results"]["duplicate_labels"]
    assert result.returncode == 0, result.describe()
    _outputs_written(runs["root"] / "duplicate_labels")
    # the stage's summary.json keeps what it warned, as said on the console (for the report)
    summary = json.loads((runs["root"] / "duplicate_labels" / "gait_out" / "filter" / "summary.json").read_text())
    assert [f"gait: warning: {w}" for w in summary["warnings"]] == _warnings(result)
    said = len(summary["warnings"])
    assert said >= 2 and any(line.startswith("filter: ") and f", {said} warnings; wrote" in line
                             for line in result.stderr_lines), result.describe()
    markers = read_table(runs["root"] / "duplicate_labels" / "gait_out" / "filter" / "markers_filtered.csv")
    assert markers.columns[0] == "time_s" and "T8_2_x_m" in markers.columns


def test_unloaded_plates_warn(runs, shared_c3d_dir):
    result = runs["results"]["bts"]
    assert result.returncode == 0, result.describe()
    warned = _warnings(result)
    for k in (2, 3, 6):
        assert any(f"plate {k} never sees a load" in w for w in warned), result.describe()
    assert not any(f"plate {k} never sees a load" in w for w in warned for k in (1, 4, 5))
    _outputs_written(runs["root"] / "bts")
    grf = read_table(runs["root"] / "bts" / "gait_out" / "filter" / "grf.csv")
    for k in (2, 3, 6):  # an unloaded plate carries no force and no COP, and belongs to nobody
        assert (grf[f"plate{k}_force_z_N"] == 0).all()
        assert grf[f"plate{k}_cop_x_m"].isna().all()
        assert (grf[f"plate{k}_foot"].astype(str) == "").all()


def test_all_nan_marker_warns(runs):
    folder = runs["root"] / "nan_marker"
    result = runs["results"]["nan_marker"]
    assert result.returncode == 0, result.describe()
    warned = _warnings(result)
    assert any("never seen" in w and NAN_MARKER in w for w in warned), result.describe()
    _outputs_written(folder)
    markers = read_table(folder / "gait_out" / "filter" / "markers_filtered.csv")
    for axis in "xyz":
        assert markers[f"{NAN_MARKER}_{axis}_m"].isna().all()
    others = markers.drop(columns=[f"{NAN_MARKER}_{a}_m" for a in "xyz"]).filter(regex="_m$")
    assert others.notna().all().all()
    # the inputs are untouched
    assert {k: v for k, v in snapshot(folder).items() if not k.startswith("gait_out")} == runs["nan_inputs"]


def test_csv_trial_events_and_feet_match_truth(runs):
    # the sample trial read from CSV instead of C3D: plate events and plate owners still match the truth
    folder = runs["root"] / "nan_marker"
    events = read_table(folder / "gait_out" / "filter" / "events.csv")
    truth = pd.read_csv(sample_trial("normal") / "truth" / "events.csv")
    plate = events[events["source"] == "plate"]
    on_plate = truth[truth["on_plate"] == 1]
    assert len(plate) == len(on_plate)
    for _, t in on_plate.iterrows():
        same = plate[(plate["side"] == t["side"]) & (plate["event"] == t["event"])]
        assert (np.abs(same["frame"] - t["frame"]) <= 2).any(), t.to_dict()
    grf = read_table(folder / "gait_out" / "filter" / "grf.csv")
    plates = pd.read_csv(sample_trial("normal") / "truth" / "plates.csv")
    for plate_name, foot in zip(plates["plate"], plates["foot"]):
        assert set(grf[f"{plate_name}_foot"].astype(str)) - {""} == {foot}


def test_each_warning_is_printed_once_and_library_warnings_are_hidden(capsys):
    """A warning said twice (a trial read by two stages) is printed once; numpy's RuntimeWarnings only with
    --debug (in-process: the same main() the command runs)."""
    import warnings as w

    import click

    from gaitcli import cli

    @cli.gait.command("noisy-test", hidden=True)
    def noisy():
        from gaitcli.errors import GaitWarning

        for _ in range(2):
            w.warn("plate 2 never sees a load", GaitWarning, stacklevel=1)
        w.warn("Mean of empty slice", RuntimeWarning, stacklevel=1)
        click.echo("done")

    try:
        with w.catch_warnings():
            w.simplefilter("default")  # a command's process starts with Python's filters, not the suite's "error"
            assert cli.main(["noisy-test"]) == 0
            err = capsys.readouterr().err
            assert err.count("plate 2 never sees a load") == 1 and "Mean of empty slice" not in err
            assert cli.main(["--debug", "noisy-test"]) == 0
            assert "RuntimeWarning: Mean of empty slice" in capsys.readouterr().err
    finally:
        cli.gait.commands.pop("noisy-test")
