"""Hostile inputs that once ended in "internal error" (exit 1): exit 2, one line naming the file and the field,
no traceback, nothing written (issue 35, item 3).

Each case builds its folder and runs one ``gait`` command in it; all of them run once, in the session's runner
processes (:func:`gait_many`), and every case fails before any work. Unreadable files and a full disk cannot
be made for root (which reads any file) nor on a real file system cheaply: those run ``gait`` in this process
with ``open`` or the write refusing, as the operating system would.
"""

from __future__ import annotations

import errno
import hashlib
import io
import os
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import h5py
import numpy as np
import pytest

from gaitcli.resources import sample_trial

from .conftest import Result, build_once, gait_many, snapshot

SAMPLE = sample_trial("normal")
SUBJECT = (SAMPLE / "subject.yaml").read_text()
DIGITS_400 = "1" + "0" * 399


@dataclass
class Case:
    build: Callable[..., None]  # fills the case folder (the working directory)
    args: tuple
    names: str  # the file the message must name
    says: tuple = ()  # further text the message must contain
    emg_trial: bool = False  # ``build`` also takes the session's ``gait synth --emg`` trial (conftest's synth_emg)


def _trial(subject: str = SUBJECT, c3d: bool = True) -> Callable[[Path], None]:
    def build(case: Path) -> None:
        (case / "trial").mkdir()
        if c3d:
            shutil.copy(SAMPLE / "trial.c3d", case / "trial" / "trial.c3d")
        (case / "trial" / "subject.yaml").write_text(subject)
    return build


def _with(build_trial, relative: str, content: str | bytes) -> Callable[[Path], None]:
    def build(case: Path) -> None:
        build_trial(case)
        path = case / relative
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(content if isinstance(content, bytes) else content.encode())
    return build


def _files(files: dict) -> Callable[[Path], None]:
    """Files relative to the case folder: text, bytes, or a callable writing the path (HDF5)."""
    def build(case: Path) -> None:
        for relative, content in files.items():
            path = case / relative
            path.parent.mkdir(parents=True, exist_ok=True)
            if callable(content):
                content(path)
            else:
                path.write_bytes(content if isinstance(content, bytes) else content.encode())
    return build


def _h5(**datasets) -> Callable[[Path], None]:
    def write(path: Path) -> None:
        with h5py.File(path, "w") as h5:
            for name, value in datasets.items():
                h5[name.replace("__", "/")] = value
    return write


def _link_loop(case: Path) -> None:
    _trial(SUBJECT + "trial: loop.c3d\n")(case)
    (case / "trial" / "loop.c3d").symlink_to("loop.c3d")


def _out_below_a_file(case: Path) -> None:
    _trial()(case)
    (case / "results.txt").write_text("the user's own file\n")


def _init_stored_elsewhere(how: str) -> Callable[[Path], None]:
    """x.h5 whose result/design lies outside it: external storage in a FIFO (reading it would block for ever), a
    virtual dataset, or an external link (issue 53, item 7)."""
    def build(case: Path) -> None:
        with h5py.File(case / "src.h5", "w") as h5:
            h5["d"] = np.zeros(69)
        with h5py.File(case / "x.h5", "w") as h5:
            if how == "fifo":
                os.mkfifo(case / "fifo")
                h5.create_dataset("result/design", shape=(69,), dtype="f8", external=[("fifo", 0, 69 * 8)])
            elif how == "virtual":
                layout = h5py.VirtualLayout(shape=(69,), dtype="f8")
                layout[:] = h5py.VirtualSource("src.h5", "d", shape=(69,))
                h5.create_virtual_dataset("result/design", layout)
            else:
                h5["result/design"] = h5py.ExternalLink("src.h5", "d")
    return build


def _damaged_reference(case: Path) -> None:
    """The shipped free-speed reference with 'abc' before the first data row's second cell."""
    from gaitcli.predict.speed_reference import group_file

    lines = group_file("free").read_text().splitlines()
    row = next(i for i, line in enumerate(lines) if line[:1].isdigit())
    cells = lines[row].split(",")
    cells[1] = "abc" + cells[1]
    lines[row] = ",".join(cells)
    (case / "ref.csv").write_text("\n".join(lines) + "\n")


def _sparse(relative: str, size: int) -> Callable[[Path], None]:
    """A file of ``size`` NUL bytes (sparse: nothing written to the disk)."""
    def build(case: Path) -> None:
        path = case / relative
        path.parent.mkdir(parents=True, exist_ok=True)
        with open(path, "wb") as f:
            f.truncate(size)
    return build


def _both(*builds) -> Callable[[Path], None]:
    def build(case: Path) -> None:
        for b in builds:
            b(case)
    return build


def _lab_with_summary_folder(case: Path) -> None:
    _trial()(case)
    (case / "lab").mkdir()
    shutil.move(case / "trial", case / "lab" / "t1")
    (case / "lab" / "batch_summary.csv").mkdir()


def _random_events(case: Path) -> None:
    """The sample walk with 255 random Foot Strike / Foot Off events in its EVENT group (issue 53, item 2)."""
    import ezc3d

    _trial()(case)
    path = case / "trial" / "trial.c3d"
    c = ezc3d.c3d(str(path))
    rng = np.random.default_rng(0)
    rate = float(c["parameters"]["POINT"]["RATE"]["value"][0])
    first, last = c["header"]["points"]["first_frame"], c["header"]["points"]["last_frame"]
    for t in np.sort(rng.uniform(first / rate, (last + 1) / rate, 255)):
        c.add_event([0, float(t)], context=str(rng.choice(["Right", "Left"])),
                    label=str(rng.choice(["Foot Strike", "Foot Off"])))
    c.write(str(path))


def _analog_rate_zero(case: Path) -> None:
    """The sample walk with ANALOG:RATE 0 in its parameter section's bytes (issue 53, item 1: before, exit 0 with
    no plates and 3022 gaps filled)."""
    import struct

    from gaitcli.io.c3d.header import check_parameters

    _trial()(case)
    path = case / "trial" / "trial.c3d"
    data = bytearray(path.read_bytes())
    record = check_parameters(path, (data[0] - 1) * 512, data[(data[0] - 1) * 512 + 2], len(data))[("ANALOG", "RATE")]
    data[record.data_offset:record.data_offset + 4] = struct.pack("<f", 0.0)
    path.write_bytes(bytes(data))


def _emg_label_twice(case: Path, emg_trial: Path) -> None:
    """A synthetic walk with EMG (a copy of the session's) whose second channel carries the first one's label
    (issue 53, item 3: before, one of them silently never read)."""
    import ezc3d

    shutil.copytree(emg_trial, case / "trial")
    path = case / "trial" / "trial.c3d"
    c = ezc3d.c3d(str(path))
    labels = list(c["parameters"]["ANALOG"]["LABELS"]["value"])
    emg = [k for k, label in enumerate(labels) if label.strip() == "R TA"]
    labels[emg[0] + 1] = labels[emg[0]]
    c["parameters"]["ANALOG"]["LABELS"]["value"] = labels
    c.write(str(path))
    subject = case / "trial" / "subject.yaml"  # the map without the channel renamed
    subject.write_text("".join(line for line in subject.read_text().splitlines(keepends=True)
                               if not line.strip().startswith("R SOL:")))


def _lab(case: Path) -> None:
    _trial()(case)
    (case / "lab").mkdir()
    shutil.move(case / "trial", case / "lab" / "t1")


BATCH_HEADER = "trial,stage,status,exit_code,reason,wall_time_s,input_key\n"
STUDY_HEADER = "case,speed_m_s,weights,condition,objective,cost_of_transport_J_per_m,deviation,converged\n"
FILTER = ("filter", "trial")
CASES = {
    **{f"subject_{name}": Case(_trial(SUBJECT.replace("sex: male", f"sex: ma{char}le")), FILTER, "subject.yaml",
                               ("line 5", f"U+{ord(char):04X}"))
       for name, char in (("nul", "\0"), ("esc", "\x1b"), ("bel", "\x07"), ("form_feed", "\x0c"))},
    "pipeline_nul": Case(_with(_trial(), "p.yaml", "filter:\n  events: au\0to\n"), (*FILTER, "--pipeline", "p.yaml"),
                         "p.yaml", ("line 2", "U+0000")),
    "tolerances_esc": Case(_files({"a/x.csv": "t_s\n1\n", "b/x.csv": "t_s\n1\n", "tol.yaml": "ignore: [\x1b]\n"}),
                           ("compare", "a", "b", "--tolerances", "tol.yaml"), "tol.yaml", ("U+001B",)),
    "mass_400_digits": Case(_trial(SUBJECT.replace("75.0", DIGITS_400)), FILTER, "subject.yaml",
                            ("mass_kg", "400-digit integer")),
    "pipeline_400_digits": Case(_with(_trial(), "p.yaml", f"filter:\n  cutoff_hz: {DIGITS_400}\n"),
                                (*FILTER, "--pipeline", "p.yaml"), "p.yaml", ("filter.cutoff_hz", "400-digit")),
    "static_frames_1e40": Case(_trial(SUBJECT + "static_frames: [1, 1e40]\n"), ("idyn", "--no-plots", "trial"),
                               "subject.yaml", ("static_frames",)),
    "static_frames_400_digits": Case(_trial(SUBJECT + f"static_frames: [1, {DIGITS_400}]\n"),
                                     ("idyn", "--no-plots", "trial"), "subject.yaml", ("static_frames", "at most")),
    "trial_name_nul": Case(_trial(SUBJECT + 'trial: "walk\\0.c3d"\n'), FILTER, "subject.yaml", ("trial", "NUL")),
    "trial_name_300": Case(_trial(SUBJECT + f"trial: {'w' * 296}.c3d\n"), FILTER, "subject.yaml",
                           ("trial", "too long")),
    "trial_name_5000": Case(_trial(SUBJECT + f"trial: {'w' * 4996}.c3d\n"), FILTER, "subject.yaml",
                            ("trial", "too long")),
    "trial_a_link_loop": Case(_link_loop, FILTER, "subject.yaml", ("trial", "loop")),
    "out_below_a_file": Case(_out_below_a_file, (*FILTER, "-o", "results.txt/out"), "results.txt", ("is a file",)),
    "out_under_dev_null": Case(_trial(), (*FILTER, "-o", "/dev/null/out"), "/dev/null", ("is a file",)),
    "out_under_proc": Case(_trial(), (*FILTER, "-o", "/proc/gait_out"), "/proc/gait_out", ("cannot be created",)),
    "study_out_under_dev_null": Case(_files({"s.yaml": "name: s\nspeeds_m_s: [1.2]\nweights: [a]\n"
                                                       "conditions: [normal]\n"}),
                                     ("predict", "--study", "s.yaml", "-o", "/dev/null/out"), "/dev/null",
                                     ("is a file",)),
    "out_256_characters": Case(_trial(), (*FILTER, "-o", "o" * 256), "ooo", ("too long",)),
    "out_near_path_max": Case(_trial(), (*FILTER, "-o", "/".join(["p" * 200] * 20)), "ppp", ("too long",)),
    "compare_100000_deep": Case(_files({"a/summary.json": "[" * 100_000 + "]" * 100_000, "b/summary.json": "[]"}),
                                ("compare", "a", "b"), "summary.json", ("nested",)),
    "compare_5000_digits": Case(_files({"a/summary.json": '{"x": ' + "7" * 5000 + "}", "b/summary.json": "{}"}),
                                ("compare", "a", "b"), "summary.json", ("5000-digit",)),
    "report_summary_truncated": Case(_files({"o/idyn/summary.json": '{"speed_m_s": '}), ("report", "o"),
                                     "summary.json", ("not valid JSON",)),
    "report_summary_a_list": Case(_files({"o/idyn/summary.json": "[1, 2]"}), ("report", "o"), "summary.json",
                                  ("list",)),
    "report_summary_not_utf8": Case(_files({"o/idyn/summary.json": b'{"a": "\xff\xfe"}'}), ("report", "o"),
                                    "summary.json", ("UnicodeDecodeError",)),
    "report_summary_text_number": Case(_files({"o/predict/summary.json": '{"objective": "low"}',
                                               "o/predict/predict.h5": b"x"}), ("report", "o"), "summary.json",
                                       ("objective", "'low'")),
    "report_h5_damaged": Case(_files({"o/idyn/summary.json": '{"speed_m_s": 1.3}',
                                      "o/idyn/idyn.h5": b"\x89HDF\r\n\x1a\n" + bytes(200)}), ("report", "o"),
                              "idyn.h5", ("HDF5",)),
    "report_h5_foreign": Case(_files({"o/idyn/summary.json": "{\"speed_m_s\": 1.3}",
                                      "o/idyn/idyn.h5": _h5(other=np.arange(3.0))}), ("report", "o"), "idyn.h5",
                              ("gait idyn", "KeyError")),
    "report_predict_h5_damaged": Case(_files({"o/predict/summary.json": "{}", "o/predict/predict.h5": b"HDF5?"}),
                                      ("report", "o"), "predict.h5", ("HDF5",)),
    "report_batch_summary_foreign": Case(_files({"lab/batch_summary.csv": "a,b\n1,2\n"}), ("report", "lab"),
                                         "batch_summary.csv", ("trial", "missing")),
    "report_batch_summary_not_utf8": Case(_files({"lab/batch_summary.csv": BATCH_HEADER.encode() + b"\xff\xfe\n"}),
                                          ("report", "lab"), "batch_summary.csv", ("UnicodeDecodeError",)),
    "report_study_foreign": Case(_files({"st/study.csv": "a,b\n1,2\n"}), ("report", "st"), "study.csv",
                                 ("case", "missing")),
    "report_study_text_number": Case(_files({"st/study.csv": STUDY_HEADER + "c1,1.3,\"1,1\",normal,high,1,1,True\n"}),
                                     ("report", "st"), "study.csv", ("line 2: objective", "'high'")),
    "init_text_design": Case(_files({"x.h5": _h5(result__design=np.array([b"a", b"b"]))}),
                             ("predict", "--init", "x.h5", "--nodes", "6"), "x.h5", ("--init",)),
    "init_damaged": Case(_files({"x.h5": b"\x89HDF\r\n\x1a\n" + bytes(100)}), ("predict", "--init", "x.h5"), "x.h5",
                         ("--init",)),
    # issue 53, items 7–13
    "init_external_fifo": Case(_init_stored_elsewhere("fifo"), ("predict", "--init", "x.h5", "--nodes", "6"), "x.h5",
                               ("--init: result/design", "external storage")),
    "init_virtual_dataset": Case(_init_stored_elsewhere("virtual"), ("predict", "--init", "x.h5", "--nodes", "6"),
                                 "x.h5", ("--init: result/design", "virtual dataset")),
    "init_external_link": Case(_init_stored_elsewhere("link"), ("predict", "--init", "x.h5", "--nodes", "6"), "x.h5",
                               ("--init: result/design", "outside the file")),
    "init_nan_design": Case(_files({"x.h5": _h5(result__design=np.full(69, np.nan))}),
                            ("predict", "--init", "x.h5", "--nodes", "6"), "x.h5", ("--init", "not finite")),
    "prosthesis_400_digits": Case(_files({"p.yaml": f"a_p: {DIGITS_400}\nb_p: 1\nc0: 1\na_n: 1\nb_n: 1\n"}),
                                  ("predict", "--prosthesis", "p.yaml", "--nodes", "6"), "p.yaml",
                                  ("a_p", "400-digit integer")),
    "reference_text_cell": Case(_damaged_reference, ("predict", "--reference", "ref.csv", "--nodes", "6"), "ref.csv",
                                ("line 2", "'abc", "expected a number")),
    "reference_3_gib": Case(_sparse("ref.csv", 3 << 30), ("predict", "--reference", "ref.csv", "--nodes", "6"),
                            "ref.csv", ("3,221,225,472 bytes",)),
    "study_reference_3_gib": Case(_both(_files({"s.yaml": "name: s\nspeeds_m_s: [1.2]\nweights: [a]\n"
                                                          "conditions: [normal]\nreferences: {1.2: ref.csv}\n"}),
                                        _sparse("ref.csv", 3 << 30)),
                                  ("predict", "--study", "s.yaml", "--nodes", "6"), "ref.csv", ("bytes",)),
    "study_5000_speeds": Case(_files({"s.yaml": "name: s\nspeeds_m_s: [" + ", ".join(["1.2"] * 5000) + "]\n"
                                                "weights: [a]\nconditions: [normal]\n"}),
                              ("predict", "--study", "s.yaml", "--nodes", "6"), "s.yaml",
                              ("speeds_m_s", "5,000 values", "at most 100")),
    "study_speed_twice": Case(_files({"s.yaml": "name: s\nspeeds_m_s: [1.2, 1.3, 1.2]\nweights: [a]\n"
                                                "conditions: [normal]\n"}),
                              ("predict", "--study", "s.yaml", "--nodes", "6"), "s.yaml",
                              ("speeds_m_s", "1.2 is given twice")),
    "folder_with_a_newline": Case(lambda case: None, ("filter", "no\nsuch"), "no\\nsuch", ("trial folder not found",)),
    "c3d_analog_rate_0": Case(_analog_rate_zero, FILTER, "trial.c3d", ("ANALOG:RATE", "got 0", "expected 1000 Hz")),
    "emg_label_twice": Case(_emg_label_twice, ("emg", "trial"), "trial.c3d", ("ANALOG:LABELS", "both labelled 'R TA'"),
                            emg_trial=True),
    "random_events": Case(_random_events, FILTER, "trial.c3d", ("EVENT", "strides cannot be walking")),
    "batch_scheduler_nonsense": Case(_lab, ("batch", "lab", "--scheduler", "nonsense://x"), "--scheduler",
                                     ("nonsense://x", "tcp://")),
    "batch_summary_a_folder": Case(_lab_with_summary_folder, ("batch", "lab", "--no-plots"), "batch_summary.csv",
                                   ("is a folder",)),
}


def _snapshot(folder: Path) -> dict[str, str]:
    """:func:`snapshot`, with symbolic links as where they point (a loop cannot be read), FIFOs and files over
    16 MiB by what they are."""
    out = {}
    for path in sorted(folder.rglob("*")):
        rel = path.relative_to(folder).as_posix()
        if path.is_symlink():
            out[rel] = f"-> {os.readlink(path)}"
        elif path.is_dir():
            out[rel] = "<dir>"
        elif not path.is_file():  # a FIFO: reading it would block
            out[rel] = "<special>"
        elif path.stat().st_size > 1 << 24:  # a sparse giant: its size and time, not 3 GiB of reading
            out[rel] = f"<{path.stat().st_size} bytes, {path.stat().st_mtime_ns}>"
        else:
            out[rel] = hashlib.sha256(path.read_bytes()).hexdigest()
    return out


def _build(root: Path, emg_trial: Path) -> dict:
    jobs, before = {}, {}
    for name, case in CASES.items():
        folder = root / name
        folder.mkdir()
        if case.emg_trial:
            case.build(folder, emg_trial)
        else:
            case.build(folder)
        before[name] = _snapshot(folder)
        jobs[name] = (case.args, folder)
    results = gait_many(jobs)
    return {"results": {k: r.to_json() for k, r in results.items()}, "before": before,
            "after": {name: _snapshot(root / name) for name in jobs}}


@pytest.fixture(scope="module")
def outcomes(tmp_path_factory, synth_emg):
    _, record = build_once(tmp_path_factory, "hostile_inputs", lambda root: _build(root, synth_emg[0]))
    record["results"] = {k: Result.from_json(v) for k, v in record["results"].items()}
    return record


def _one_line_exit_2(result: Result, names: str, says=()) -> str:
    assert result.returncode == 2, result.describe()
    assert "Traceback" not in result.stderr and "internal error" not in result.stderr, result.describe()
    assert len(result.stderr_lines) == 1, result.describe()
    message = result.stderr_lines[0]
    assert message.startswith("gait: error: ") and names in message, message
    for text in says:
        assert text in message, message
    assert len(message) < 400, message  # paths and values are shortened
    return message


@pytest.mark.parametrize("name", list(CASES))
def test_hostile_input_exit_2_one_line_nothing_written(outcomes, name):
    case = CASES[name]
    _one_line_exit_2(outcomes["results"][name], case.names, case.says)
    assert outcomes["after"][name] == outcomes["before"][name]


# ------------------------------------------------------------------ in this process: what root cannot make

def _gait_here(monkeypatch, capsys, cwd: Path, *args) -> Result:
    from gaitcli.cli import main

    monkeypatch.chdir(cwd)
    code = main([str(a) for a in args])
    captured = capsys.readouterr()
    return Result(tuple(map(str, args)), code, captured.out, captured.err, cwd)


def _refuse_reading(monkeypatch, *paths: Path) -> None:
    """``open`` of these files fails as for a file of mode 000 read by another user."""
    import builtins

    refused = {os.path.realpath(p) for p in paths}
    real_open = builtins.open

    def fake_open(file, *args, **kwargs):
        if isinstance(file, (str, os.PathLike)) and os.path.realpath(file) in refused:
            raise PermissionError(errno.EACCES, "Permission denied", str(file))
        return real_open(file, *args, **kwargs)

    monkeypatch.setattr(builtins, "open", fake_open)
    monkeypatch.setattr(io, "open", fake_open)  # what pathlib calls
    monkeypatch.setattr(os, "access", lambda p, mode, **k: os.path.realpath(p) not in refused)


@pytest.mark.parametrize("which", ["trial.c3d", "static.c3d"])
def test_an_unreadable_trial_file_is_exit_2_naming_it(tmp_path, monkeypatch, capsys, which):
    shutil.copytree(SAMPLE, tmp_path / "trial", ignore=shutil.ignore_patterns("gait_out", "truth"))
    before = snapshot(tmp_path)
    _refuse_reading(monkeypatch, tmp_path / "trial" / which)
    result = _gait_here(monkeypatch, capsys, tmp_path, "filter", "trial")
    _one_line_exit_2(result, which, ("cannot be read", "Permission denied"))
    monkeypatch.undo()
    assert snapshot(tmp_path) == before


@pytest.mark.parametrize("which", ["a/x/summary.json", "b/x/t.csv"])
def test_an_unreadable_compare_input_is_exit_2_naming_it(tmp_path, monkeypatch, capsys, which):
    for side in "ab":
        (tmp_path / side / "x").mkdir(parents=True)
        (tmp_path / side / "x" / "summary.json").write_text('{"a": 1}')
        (tmp_path / side / "x" / "t.csv").write_text("time_s\n0\n")
    _refuse_reading(monkeypatch, tmp_path / which)
    result = _gait_here(monkeypatch, capsys, tmp_path, "compare", "a", "b")
    _one_line_exit_2(result, which, ("cannot be read",))


def test_an_unreadable_compare_folder_is_exit_2_naming_it(tmp_path, monkeypatch, capsys):
    """Issue 53, item 14: b/idyn cannot be listed (mode 000 for another user, simulated: root lists anything).
    Before, exit 1 "differ", its files taken as "only in a"."""
    for side in "ab":
        (tmp_path / side / "idyn").mkdir(parents=True)
        (tmp_path / side / "idyn" / "summary.json").write_text('{"a": 1}')
    refused, real_scandir = os.path.realpath(tmp_path / "b" / "idyn"), os.scandir

    def scandir(path="."):
        if os.path.realpath(path) == refused:
            raise PermissionError(errno.EACCES, "Permission denied", str(path))
        return real_scandir(path)

    monkeypatch.setattr(os, "scandir", scandir)
    result = _gait_here(monkeypatch, capsys, tmp_path, "compare", "a", "b")
    _one_line_exit_2(result, "b/idyn", ("cannot be read", "Permission denied"))


@pytest.mark.skipif(os.geteuid() == 0, reason="root reads a file of mode 000; simulated above")
def test_a_file_of_mode_000_is_exit_2(outcomes, tmp_path):
    shutil.copytree(SAMPLE, tmp_path / "trial", ignore=shutil.ignore_patterns("gait_out", "truth"))
    (tmp_path / "trial" / "trial.c3d").chmod(0)
    result = gait_many({"run": (("filter", "trial"), tmp_path)})["run"]
    _one_line_exit_2(result, "trial.c3d", ("cannot be read",))


def test_a_full_disk_is_exit_2_and_keeps_the_earlier_results(tmp_path, monkeypatch, capsys):
    """A study page written again while the disk is full: the write fails as the system's would (ENOSPC)."""
    study = tmp_path / "st"
    study.mkdir()
    (study / "study.csv").write_text(STUDY_HEADER + 'c1,1.3,"1,1",normal,1.5,2.5,0.5,True\n')
    first = _gait_here(monkeypatch, capsys, tmp_path, "report", "st")
    assert first.returncode == 0, first.describe()
    before = snapshot(tmp_path)
    real_write_text = Path.write_text

    def full(self, *args, **kwargs):
        if self.name.endswith(".part"):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real_write_text(self, *args, **kwargs)

    monkeypatch.setattr(Path, "write_text", full)
    result = _gait_here(monkeypatch, capsys, tmp_path, "report", "st")
    _one_line_exit_2(result, "report.html", ("No space left on device",))
    assert snapshot(tmp_path) == before  # the earlier page, no temporary file
