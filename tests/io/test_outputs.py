"""Output writers: the stage folder swap, HDF5 units and provenance, CSV tables, summary.json."""

from __future__ import annotations

import errno
import hashlib
import json
import math
import os
import stat
from datetime import datetime, timezone
from pathlib import Path

import h5py
import numpy as np
import pandas as pd
import pytest
import yaml

from gaitcli import __version__
from gaitcli.errors import GaitWarning, InputError
from gaitcli.io.atomic import MANIFEST, check_output_folder, check_replaceable
from gaitcli.io.h5 import Dataset, provenance, write_h5
from gaitcli.io.outputs import stage_folder, write_json, write_table


def _tree(folder: Path) -> dict[str, bytes]:
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _old_outputs(target: Path) -> dict[str, bytes]:
    (target / "plots").mkdir(parents=True)
    (target / "summary.json").write_text('{"frames": 10}\n')
    (target / "only_in_old.csv").write_text("time_s\n0\n")
    (target / "plots" / "grf.png").write_bytes(b"old png")
    (target / MANIFEST).write_text(json.dumps(["summary.json", "only_in_old.csv", "plots/grf.png"]))  # gait's
    return _tree(target)


# ------------------------------------------------------------------------------- stage_folder


def test_stage_folder_replaces_previous_outputs_whole(tmp_path):
    target = tmp_path / "out" / "filter"
    _old_outputs(target)
    with stage_folder(target) as tmp:
        assert tmp.parent == target.parent and tmp != target
        assert (target / "only_in_old.csv").is_file()  # the old outputs stay until the new ones are complete
        write_json(tmp / "summary.json", {"frames": 20})
        (tmp / "plots").mkdir()
    assert json.loads((target / "summary.json").read_text()) == {"frames": 20}
    assert not (target / "only_in_old.csv").exists()  # nothing of the previous run survives
    assert sorted(p.name for p in target.parent.iterdir()) == ["filter"]  # no temp or old folders left


def test_stage_folder_creates_missing_parents(tmp_path):
    target = tmp_path / "a" / "b" / "filter"
    with stage_folder(target) as tmp:
        (tmp / "x.csv").write_text("time_s\n")
    assert (target / "x.csv").is_file()
    assert sorted(p.name for p in target.parent.iterdir()) == ["filter"]


class Boom(RuntimeError):
    pass


def test_stage_folder_failure_keeps_old_outputs(tmp_path):
    target = tmp_path / "out" / "filter"
    old = _old_outputs(target)
    with pytest.raises(Boom):
        with stage_folder(target) as tmp:
            write_json(tmp / "summary.json", {"frames": 20})
            write_table(tmp / "grf.csv", {"time_s": np.arange(3) / 100})
            raise Boom("the plots failed")
    assert _tree(target) == old
    assert sorted(p.name for p in target.parent.iterdir()) == ["filter"]


def test_stage_folder_failure_without_previous_outputs_leaves_nothing(tmp_path):
    target = tmp_path / "out" / "filter"
    with pytest.raises(Boom):
        with stage_folder(target) as tmp:
            (tmp / "half.csv").write_text("time_s\n0.0")
            raise Boom()
    assert not target.exists()
    assert list(target.parent.iterdir()) == []


@pytest.mark.parametrize("code", [errno.ENOSPC, errno.EDQUOT, errno.EROFS])
def test_a_full_disk_is_an_input_error_naming_the_output_and_keeps_old_outputs(tmp_path, code):
    target = tmp_path / "out" / "filter"
    old = _old_outputs(target)
    with pytest.raises(InputError, match=f"filter: cannot be written \\({os.strerror(code)}\\)"):
        with stage_folder(target) as tmp:
            write_json(tmp / "summary.json", {"frames": 20})
            raise OSError(code, os.strerror(code))
    assert _tree(target) == old
    assert sorted(p.name for p in target.parent.iterdir()) == ["filter"]


def test_other_os_errors_while_writing_stay_internal(tmp_path):
    with pytest.raises(FileNotFoundError):
        with stage_folder(tmp_path / "filter"):
            raise FileNotFoundError(errno.ENOENT, "an input vanished")


def test_stage_folder_keyboard_interrupt_also_cleans_up(tmp_path):
    target = tmp_path / "filter"
    old = _old_outputs(target)
    with pytest.raises(KeyboardInterrupt):
        with stage_folder(target) as tmp:
            (tmp / "summary.json").write_text("{}")
            raise KeyboardInterrupt
    assert _tree(target) == old
    assert sorted(p.name for p in tmp_path.iterdir()) == ["filter"]


def _dead_pid() -> int:
    import subprocess
    import sys

    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    return child.pid


def test_leftovers_of_killed_runs_are_removed_and_live_runs_kept(tmp_path):
    """A SIGKILLed run leaves ``.filter.<pid>.<random>.part`` (and, between its renames, ``.filter.old-…``);
    the next run removes those whose process is gone, not a concurrent run's, nor a user's hidden files."""
    target = tmp_path / "filter"
    dead, alive = _dead_pid(), os.getpid()
    left = [tmp_path / f".filter.{dead}.abc123.part", tmp_path / f".filter.old-.filter.{dead}.x9.part"]
    for folder in left:
        folder.mkdir()
        (folder / "markers.csv").write_text("half")
    (tmp_path / f".filter.{dead}.f1.part").write_text("a half-written file")
    live = tmp_path / f".filter.{alive}.zz.part"
    live.mkdir()
    mine = tmp_path / ".filter.notes"
    mine.write_text("a user's file")
    with stage_folder(target) as tmp:
        (tmp / "summary.json").write_text("{}")
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([".filter.notes", live.name, "filter"])


def test_a_file_at_the_output_folder_is_refused_and_kept(tmp_path):
    target = tmp_path / "filter"
    target.write_text("the user's own notes")
    with pytest.raises(InputError, match="filter: is a file"):
        with stage_folder(target):
            raise AssertionError("not reached")
    assert target.read_text() == "the user's own notes" and sorted(p.name for p in tmp_path.iterdir()) == ["filter"]
    with pytest.raises(InputError, match="gait_out: is a file"):
        (tmp_path / "gait_out").write_text("x")
        with stage_folder(tmp_path / "gait_out" / "filter"):
            raise AssertionError("not reached")


def test_a_run_replaces_only_the_files_its_manifest_names(tmp_path):
    """A folder gait wrote lists its files with their digests (``.gait_files``); any other file, even with one
    of gait's suffixes, or one of its files changed since, is the user's: refused before anything moves. A folder
    without a manifest is kept whole beside the new one (before issue 53 gait's suffixes were taken as gait's:
    the user's my.csv deleted)."""
    target = tmp_path / "out" / "filter"
    with stage_folder(target) as tmp:
        write_json(tmp / "summary.json", {"frames": 20})
        (tmp / "plots").mkdir()
        (tmp / "plots" / "grf.png").write_bytes(b"png")
    digests = json.loads((target / MANIFEST).read_text())
    assert digests == {"plots/grf.png": hashlib.sha256(b"png").hexdigest(),
                       "summary.json": hashlib.sha256((target / "summary.json").read_bytes()).hexdigest()}
    check_replaceable(target)  # only gait's files: replaceable
    (target / "plots" / "grf.png").write_bytes(b"my own figure")  # the user's file under gait's name
    with pytest.raises(InputError, match=r"grf\.png: was changed since gait wrote it"):
        with stage_folder(target):
            pytest.fail("the user's file must stop the run before it starts")
    assert (target / "plots" / "grf.png").read_bytes() == b"my own figure"
    (target / "plots" / "grf.png").write_bytes(b"png")
    (target / "my.csv").write_text("time_s\n0\n")
    before = _tree(target)
    with pytest.raises(InputError, match=r"my\.csv: is not an output of gait"):
        with stage_folder(target):
            pytest.fail("the user's file must stop the run before it starts")
    assert _tree(target) == before
    (target / MANIFEST).write_text('["plots/grf.png", "summary.json", "my.csv"]')  # names only: no digests
    (target / "summary.json").write_text("{}")
    check_replaceable(target)
    (target / MANIFEST).write_text("not json")  # a damaged manifest is not gait's
    (target / "notes.txt").write_text("mine\n")
    check_replaceable(target)  # nothing refused: the folder is kept whole (below)
    (target / MANIFEST).unlink()  # as an older gaitcli left it, or the user deleted it (issue 53, item 4)
    before = _tree(target)
    with pytest.warns(GaitWarning, match=r"held files without gait's list of its own \(\.gait_files\): kept whole"):
        with stage_folder(target) as tmp:
            write_json(tmp / "summary.json", {"frames": 21})
    (kept,) = tmp_path.joinpath("out").glob("filter.kept-*")
    assert _tree(kept) == before  # my.csv, notes.txt and the rest, unchanged
    assert sorted(p.name for p in target.iterdir()) == [MANIFEST, "summary.json"]


def test_outputs_get_the_usual_permissions(tmp_path):
    previous = os.umask(0o022)
    try:
        with stage_folder(tmp_path / "filter") as tmp:
            write_json(tmp / "summary.json", {})
    finally:
        os.umask(previous)
    assert stat.S_IMODE((tmp_path / "filter").stat().st_mode) == 0o755
    assert stat.S_IMODE((tmp_path / "filter" / "summary.json").stat().st_mode) == 0o644


@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="needs Linux /proc")
def test_a_folder_that_cannot_be_made_is_refused_before_any_work_even_for_root(tmp_path):
    """/proc's permission bits say writable to root, yet no folder can be made there: the check tries one."""
    with pytest.raises(InputError, match="gait_out: cannot be created"):
        check_output_folder("/proc/gait_out/filter")
    check_output_folder(tmp_path / "new" / "filter")
    assert list(tmp_path.iterdir()) == []  # the probe leaves nothing behind


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write anywhere")
def test_an_unwritable_output_folder_is_an_input_error(tmp_path):
    (tmp_path / "locked").mkdir(mode=0o555)
    with pytest.raises(InputError, match="locked: is not writable"):
        with stage_folder(tmp_path / "locked" / "filter"):
            raise AssertionError("not reached")


# ------------------------------------------------------------------------------------ HDF5


def _datasets():
    rng = np.random.default_rng(3)
    return {
        "markers/time": Dataset(np.arange(5) / 100.0, "s"),
        "markers/filtered": Dataset(rng.normal(size=(5, 2, 3)), "m", {"cutoff_hz": 6.0}),
        "markers/labels": Dataset(np.array(["CAr", "FMr"]), "1"),
        "plates/plate1/force": Dataset(rng.normal(size=(5, 3)), "N", {"rate_hz": 100.0}),
        "plates/plate1/foot": Dataset(np.array(["", "r", "r", "r", ""]), "1"),
        "lab_to_model": Dataset(np.eye(3), "1", {"meaning": "v_model = R @ v_lab"}),
    }


def test_write_h5_units_attrs_and_values(tmp_path):
    data = _datasets()
    attrs = provenance("filter:\n  cutoff_hz: 6.0\n", {"trial.c3d": "ab" * 32})
    path = write_h5(tmp_path / "stage.h5", data, attrs)
    with h5py.File(path, "r") as h5:
        found = []
        h5.visititems(lambda name, obj: found.append(name) if isinstance(obj, h5py.Dataset) else None)
        assert sorted(found) == sorted(data)
        for name, ds in data.items():
            assert h5[name].attrs["units"] == ds.units, name
            for key, value in ds.attrs.items():
                assert h5[name].attrs[key] == value
            stored = h5[name].asstr()[()] if ds.values.dtype.kind == "U" else h5[name][()]
            np.testing.assert_array_equal(stored, ds.values, err_msg=name)
        for key, value in attrs.items():
            assert h5.attrs[key] == value


def test_provenance_attributes():
    config = "stages: [filter]\nfilter:\n  cutoff_hz: 6.0\n"
    inputs = {"trial.c3d": "0" * 64, "subject.yaml": "f" * 64}
    attrs = provenance(config, inputs)
    assert set(attrs) >= {"gaitcli_version", "config_yaml", "input_sha256", "created_utc"}
    assert attrs["gaitcli_version"] == __version__
    assert yaml.safe_load(attrs["config_yaml"]) == yaml.safe_load(config)
    assert json.loads(attrs["input_sha256"]) == inputs
    created = datetime.fromisoformat(attrs["created_utc"])
    assert created.utcoffset().total_seconds() == 0
    assert abs((datetime.now(timezone.utc) - created).total_seconds()) < 60


def test_write_h5_failure_leaves_previous_file(tmp_path):
    path = tmp_path / "stage.h5"
    write_h5(path, _datasets(), {"gaitcli_version": "old"})
    before = path.read_bytes()
    bad = {**_datasets(), "broken": Dataset(np.array([{"a": 1}], dtype=object), "1")}
    with pytest.raises(TypeError):  # h5py cannot store a dict
        write_h5(path, bad, {"gaitcli_version": "new"})
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["stage.h5"]


# ------------------------------------------------------------------------------ CSV and JSON


def test_write_table_order_nan_and_precision(tmp_path):
    t = np.arange(4) / 100.0
    x = np.array([0.123456789, np.nan, -1.5e-7, 12345.678])
    path = write_table(tmp_path / "t.csv", {"time_s": t, "pelvis_x_m": x, "side": np.array(["r", "", "l", "r"])})
    lines = path.read_text().splitlines()
    assert lines[0] == "time_s,pelvis_x_m,side"
    assert lines[1] == "0,0.123457,r"
    assert lines[2].split(",")[1] == "NaN"
    back = pd.read_csv(path, keep_default_na=False, na_values=["NaN"])
    np.testing.assert_allclose(back["pelvis_x_m"], x, rtol=5e-6)
    assert back["side"].tolist() == ["r", "", "l", "r"]


def test_write_table_failure_leaves_previous_file(tmp_path):
    path = write_table(tmp_path / "t.csv", {"time_s": np.arange(3.0)})
    before = path.read_bytes()
    with pytest.raises(ValueError):
        write_table(path, {"time_s": np.arange(3.0), "x_m": np.arange(4.0)})  # unequal lengths
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.csv"]


def test_write_json_converts_numpy_and_non_finite(tmp_path):
    data = {"frames": np.int64(432), "rate_hz": np.float64(100.0), "cutoff_hz": 6.0, "bad": math.nan,
            "inf": np.inf, "events": [{"frame": np.int32(3), "ok": np.bool_(True)}], "path": tmp_path,
            "array": np.array([1.5, np.nan])}
    path = write_json(tmp_path / "summary.json", data)
    back = json.loads(path.read_text())  # strict JSON: no NaN tokens
    assert back == {"frames": 432, "rate_hz": 100.0, "cutoff_hz": 6.0, "bad": None, "inf": None,
                    "events": [{"frame": 3, "ok": True}], "path": str(tmp_path), "array": [1.5, None]}
    assert "NaN" not in path.read_text()
