"""Hostile input, round two (issue 35, items 4–6): reports and inputs stay inside their trees, non-finite options
are refused, impossible marker values are gaps, a run replaces only what gait wrote, and an export whose name
is too long is refused before any stage runs.

Every case is built under its own folder and run once, all in one :func:`gait_many` call.
"""

from __future__ import annotations

import csv
import shutil
from pathlib import Path

import ezc3d
import numpy as np
import pandas as pd
import pytest

from gaitcli.resources import sample_trial
from gaitcli.run.batch import BatchRow, read_summary, write_summary

from .conftest import Result, build_once, gait, gait_many, snapshot

SAMPLE = sample_trial("normal")
SECRET = "top secret: root:x:0:0\n"
#: folder names a spreadsheet would run as formulas, and one that starts with the escape itself
FORMULA_NAMES = ("=HYPERLINK(\"http://x\")", "+1", "-2", "@SUM(A1)", "'quoted")
#: non-finite values of float options: (args, the option the message names)
NON_FINITE = {"speed_nan": (("predict", "--speed", "nan"), "--speed"),
              "foot_mass_nan": (("predict", "--foot-mass", "nan"), "--foot-mass"),
              "strength_scale_nan": (("predict", "--strength-scale", "nan"), "--strength-scale"),
              "time_limit_nan": (("predict", "--time-limit", "nan"), "--time-limit"),
              "noise_inf": (("synth", "--noise-mm", "inf", "out"), "--noise-mm"),
              "cutoff_minus_inf": (("filter", "--cutoff", "-inf", "trial"), "--cutoff")}


def _trial(folder: Path) -> Path:
    folder.mkdir(parents=True)
    shutil.copy(SAMPLE / "trial.c3d", folder / "trial.c3d")
    shutil.copy(SAMPLE / "subject.yaml", folder / "subject.yaml")
    return folder


def _build(root: Path) -> dict:
    jobs = {}
    secret = root / "secret"
    secret.write_text(SECRET)

    # one ASISr sample at 3·10³⁸ mm; stale outputs of gait's own in the -o folder, which the run replaces
    far = _trial(root / "far" / "trial")
    c = ezc3d.c3d(str(far / "trial.c3d"))
    points = c["data"]["points"]
    points[2, 0, 100] = 3e38
    c["data"]["points"] = points
    c.write(str(far / "trial.c3d"))
    (root / "far" / "out" / "filter" / "plots").mkdir(parents=True)
    (root / "far" / "out" / "filter" / "old.csv").write_text("time_s\n0\n")
    (root / "far" / "out" / "filter" / "plots" / "old.png").write_bytes(b"png")
    jobs["far_marker"] = (("filter", "--no-plots", "trial", "-o", "out"), root / "far")

    # a file of the user's in the stage folder -o would replace, which has no manifest: kept whole beside it
    _trial(root / "users_file" / "trial")
    (root / "users_file" / "out" / "filter").mkdir(parents=True)
    (root / "users_file" / "out" / "filter" / "notes.txt").write_text("my notes\n")
    jobs["users_file"] = (("filter", "--no-plots", "trial", "-o", "out"), root / "users_file")

    # a file of the user's with one of gait's suffixes, in a stage folder whose manifest does not list it
    _trial(root / "users_csv" / "trial")
    (root / "users_csv" / "out" / "filter").mkdir(parents=True)
    (root / "users_csv" / "out" / "filter" / ".gait_files").write_text('["summary.json"]\n')
    (root / "users_csv" / "out" / "filter" / "summary.json").write_text("{}\n")
    (root / "users_csv" / "out" / "filter" / "my.csv").write_text("time_s\n0\n")
    jobs["users_csv"] = (("filter", "--no-plots", "trial", "-o", "out"), root / "users_csv")

    # a trial folder whose name fits, but not as export/<name>.c3d with its temporary name: refused before idyn
    shutil.copytree(SAMPLE, root / "long_export" / ("t" * 240), ignore=shutil.ignore_patterns("gait_out", "truth"))
    jobs["long_export"] = (("idyn", "--no-plots", "--export", "c3d", "t" * 240), root / "long_export")

    for name in ("trial.c3d", "static.c3d"):  # found by their usual names, linking out of the folder
        trial = _trial(root / f"link_{name}" / "trial")
        (trial / name).unlink(missing_ok=True)
        shutil.copy(SAMPLE / name, root / f"link_{name}" / name)
        (trial / name).symlink_to(root / f"link_{name}" / name)
        jobs[f"link_{name}"] = (("filter", "trial"), root / f"link_{name}")

    for key, (args, _) in NON_FINITE.items():
        _trial(root / key / "trial")
        jobs[key] = (args, root / key)

    # a batch summary naming a trial outside the lab, whose gait_out a report would be written into
    lab = root / "climb" / "lab"
    lab.mkdir(parents=True)
    (root / "climb" / "victim" / "gait_out").mkdir(parents=True)
    write_summary(lab / "batch_summary.csv", [BatchRow("../victim", "filter", "ok")])
    jobs["report_climbs"] = (("report", "lab"), root / "climb")

    # a study whose figure links to a file outside it
    study = root / "study_link" / "study"
    study.mkdir(parents=True)
    (study / "study.csv").write_text("case,speed_m_s,weights,condition,objective,cost_of_transport_J_per_m,"
                                     "deviation,converged\nc1,1.1,normal,normal,1.0,200,0.5,True\n")
    (study / "study.png").symlink_to(secret)
    jobs["study_figure_link"] = (("report", "study"), root / "study_link")

    # folder names that are spreadsheet formulas, written by the batch writer and read by the report
    lab = root / "formulas" / "lab"
    lab.mkdir(parents=True)
    write_summary(lab / "batch_summary.csv", [BatchRow(n, "filter", "failed", 2, f"-{n} bad") for n in FORMULA_NAMES])
    jobs["formula_names"] = (("report", "lab"), root / "formulas")

    before = {key: snapshot(cwd) for key, (_, cwd) in jobs.items()}
    results = gait_many(jobs)
    after = {key: snapshot(cwd) for key, (_, cwd) in jobs.items()}
    return {"results": {k: r.to_json() for k, r in results.items()}, "before": before, "after": after}


@pytest.fixture(scope="module")
def outcomes(tmp_path_factory):
    root, record = build_once(tmp_path_factory, "hostile_trees", _build)
    record["results"] = {k: Result.from_json(v) for k, v in record["results"].items()}
    return root, record


REFUSED = {"users_csv": ("my.csv", "not an output of gait"),
           "long_export": ("t.c3d", "too long"),
           "link_trial.c3d": ("trial.c3d", "outside the trial folder"),
           "link_static.c3d": ("static.c3d", "outside the trial folder"),
           "report_climbs": ("batch_summary.csv: trial", "'../victim', outside the lab folder"),
           "study_figure_link": ("study.png", "outside the study folder"),
           **{key: (option, "expected a finite number") for key, (_, option) in NON_FINITE.items()}}


@pytest.mark.parametrize("name", list(REFUSED))
def test_refused_with_exit_2_one_line_and_nothing_written(outcomes, name):
    _, record = outcomes
    result = record["results"][name]
    assert result.returncode == 2, result.describe()
    assert len(result.stderr_lines) == 1 and result.stderr_lines[0].startswith("gait: error: "), result.describe()
    for text in REFUSED[name]:
        assert text in result.stderr_lines[0], result.describe()
    assert SECRET.strip() not in result.stderr
    assert record["after"][name] == record["before"][name], result.describe()


def test_an_impossible_marker_sample_is_a_gap_and_only_gaits_own_files_are_replaced(outcomes):
    root, record = outcomes
    result = record["results"]["far_marker"]
    assert result.returncode == 0, result.describe()
    assert ("gait: warning: trial.c3d: 1 marker samples beyond 10000 m of the lab origin read as gaps (ASISr; first "
            "at frame 101)") in result.stderr_lines, result.stderr
    markers = pd.read_csv(root / "far" / "out" / "filter" / "markers_filtered.csv")
    metres = markers.filter(regex="_m$").to_numpy()
    assert np.abs(metres).max() < 10.0  # the whole body stays on the 6 m walk
    z = markers["ASISr_z_m"].to_numpy()
    assert abs(z[100] - (z[99] + z[101]) / 2) < 1e-3  # the gap filled from its neighbours, to 1 mm
    left = {p.relative_to(root / "far" / "out").as_posix() for p in (root / "far" / "out").rglob("*")}
    assert "filter/old.csv" not in left and "filter/plots/old.png" not in left
    assert "filter/.gait_files" in left and "filter/markers_filtered.csv" in left  # the next run's list


def test_a_stage_folder_without_a_manifest_is_kept_whole_with_the_users_file(outcomes):
    root, record = outcomes
    result = record["results"]["users_file"]
    assert result.returncode == 0, result.describe()
    (kept,) = (root / "users_file" / "out").glob("filter.kept-*")
    assert (kept / "notes.txt").read_text() == "my notes\n"
    assert (root / "users_file" / "out" / "filter" / ".gait_files").is_file()


def test_formula_folder_names_are_escaped_in_batch_summary_and_read_back(outcomes, tmp_path):
    root, record = outcomes
    lab = root / "formulas" / "lab"
    with open(lab / "batch_summary.csv", newline="") as f:
        cells = [(r["trial"], r["reason"]) for r in csv.DictReader(f)]
    assert sorted(cells) == sorted(("'" + n, "'-" + n + " bad") for n in FORMULA_NAMES)
    assert sorted(read_summary(lab / "batch_summary.csv")) == sorted(FORMULA_NAMES)
    result = record["results"]["formula_names"]
    assert result.returncode == 0, result.describe()
    page = (lab / "report.html").read_text()
    assert "<td>=HYPERLINK(&quot;http://x&quot;)</td>" in page and "<td>&#x27;quoted</td>" in page
    assert "<td>-+1 bad</td>" in page


def test_a_folder_whose_manifest_was_deleted_is_kept_whole(tmp_path):
    """Issue 53, item 4: `gait filter` into an output folder whose .gait_files was deleted, holding the user's
    my_analysis.csv: before, exit 0 and the file deleted (gait's suffixes were taken as gait's). Now the folder
    is kept whole beside the new outputs, and the console says where."""
    _trial(tmp_path / "trial")
    first = gait("filter", "--no-plots", "trial", cwd=tmp_path)
    assert first.returncode == 0, first.describe()
    out = tmp_path / "trial" / "gait_out" / "filter"
    (out / ".gait_files").unlink()
    (out / "my_analysis.csv").write_text("mine\n")
    before = {p.relative_to(out).as_posix(): p.read_bytes() for p in out.rglob("*") if p.is_file()}
    again = gait("filter", "--no-plots", "trial", cwd=tmp_path)
    assert again.returncode == 0, again.describe()
    (kept,) = out.parent.glob("filter.kept-*")
    assert {p.relative_to(kept).as_posix(): p.read_bytes() for p in kept.rglob("*") if p.is_file()} == before
    assert f"kept whole as {kept.name}" in again.stderr
    assert (out / ".gait_files").is_file() and not (out / "my_analysis.csv").exists()


def test_a_plate_scale_off_is_warned_by_the_mass_check(tmp_path):
    """ANALOG:GEN_SCALE doubled in the bytes of the sample's C3D (issue 53, item 1): every plate reads twice its
    force and nothing in the file says so; the idyn stage's check of subject.yaml's mass against the plates'
    stride estimate warns, with both values."""
    import struct

    from gaitcli.io.c3d.header import check_parameters

    folder = _trial(tmp_path / "trial")
    path = folder / "trial.c3d"
    data = bytearray(path.read_bytes())
    record = check_parameters(path, (data[0] - 1) * 512, data[(data[0] - 1) * 512 + 2], len(data))[
        ("ANALOG", "GEN_SCALE")]
    value = struct.unpack("<f", data[record.data_offset:record.data_offset + 4])[0]
    data[record.data_offset:record.data_offset + 4] = struct.pack("<f", 2 * value)
    path.write_bytes(bytes(data))
    done = gait("idyn", "--no-plots", "trial", cwd=tmp_path)
    assert done.returncode == 0, done.describe()
    assert "body mass 75.0 kg (subject.yaml) differs from the force plates' stride estimate 150" in done.stderr
