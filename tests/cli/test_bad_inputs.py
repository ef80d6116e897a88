"""Bad inputs to ``gait filter``: exit code 2, one line naming the file (no traceback), nothing written.

Each case builds a trial folder under ``case/trial/`` (plus, for some, a pipeline file in
``case/``) and runs ``gait filter case/trial`` with ``case/`` as the working directory.
"Nothing written" means: afterwards ``case/`` holds exactly the files it held before,
byte for byte (so no ``gait_out`` in the trial folder or in the working directory).
All cases run once, several processes at a time. Further bad values are unit-tested
in-process (tests/test_trial.py, tests/test_config.py) to keep this module quick.
"""

from __future__ import annotations

import re
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import pytest

from gaitcli.resources import sample_trial

from .conftest import MINIMAL_SUBJECT, Result, build_once, gait_many, snapshot

SAMPLE = sample_trial("normal")


@dataclass
class Case:
    build: Callable[[Path], None]  # fills case/trial/ (and case/)
    args: tuple = ()  # extra arguments after `filter case/trial`
    names: str = "subject.yaml"  # the file the message must name
    says: tuple = ()  # further text the message must contain
    needs_shared: bool = False


def _sample(trial: Path, subject_edit: Callable[[str], str] | None = None, c3d: bool = True) -> None:
    trial.mkdir(parents=True)
    if c3d:
        shutil.copy(SAMPLE / "trial.c3d", trial / "trial.c3d")
    text = (SAMPLE / "subject.yaml").read_text()
    (trial / "subject.yaml").write_text(subject_edit(text) if subject_edit else text)


def _missing_c3d(trial):
    _sample(trial, c3d=False)


def _missing_subject(trial):
    trial.mkdir(parents=True)
    shutil.copy(SAMPLE / "trial.c3d", trial / "trial.c3d")


def _text_as_c3d(trial):
    _sample(trial, c3d=False)
    (trial / "trial.c3d").write_text("frame,x,y,z\n" + "1,0.1,0.2,0.3\n" * 200)  # > 512 bytes of text


def _truncated_c3d(trial):
    _sample(trial, c3d=False)
    data = (SAMPLE / "trial.c3d").read_bytes()
    (trial / "trial.c3d").write_bytes(data[:len(data) // 2])


def _sgi(shared: Path):
    def build(trial):
        trial.mkdir(parents=True)
        shutil.copy(shared / "sgi_int.c3d", trial / "trial.c3d")
        (trial / "subject.yaml").write_text(MINIMAL_SUBJECT)
    return build


def _subject(edit):
    return lambda trial: _sample(trial, edit)


def _pipeline(text):
    def build(trial):
        _sample(trial)
        (trial.parent / "pipeline.yaml").write_text(text)
    return build


def _with_file(relative: str, text: str = "the user's own file\n"):
    """The sample trial, and a file of the user's at ``relative`` (from the case folder)."""
    def build(trial):
        _sample(trial)
        (trial.parent / relative).write_text(text)
    return build


def _outside_trial(trial):
    _sample(trial, lambda s: s + "trial: ../other.c3d\n")
    shutil.copy(SAMPLE / "trial.c3d", trial.parent / "other.c3d")


ALIAS_BOMB = "".join([f"{chr(97 + k)}: &{chr(97 + k)} [" + ",".join([f"*{chr(96 + k)}"] * 9 if k else ['"x"'] * 9)
                      + "]\n" for k in range(9)])

CASES = {  # the ones that read the C3D first: they take longest
    "text_file_as_c3d": Case(_text_as_c3d, names="trial.c3d", says=("C3D",)),
    "truncated_c3d": Case(_truncated_c3d, names="trial.c3d", says=("truncated",)),
    "sgi_c3d": Case(None, names="trial.c3d", says=("MIPS",), needs_shared=True),
    "marker_map_unknown_labels": Case(_subject(lambda s: s + "marker_map:\n  RHEE: CAr\n  LHEE: CAl\n"),
                                      says=("marker_map", "RHEE", "LHEE")),
    "cutoff_above_nyquist": Case(_sample, args=("--cutoff", "60"), names="", says=("cutoff", "60", "Nyquist")),
    "cutoff_below_the_recording": Case(_sample, args=("--cutoff", "1e-9"), names="",
                                       says=("cutoff", "1e-09", "1/duration")),  # once minutes, then MemoryError
    "missing_trial_c3d": Case(_missing_c3d, names="trial.c3d", says=("not found",)),
    "missing_subject_yaml": Case(_missing_subject, names="subject.yaml", says=("not found",)),
    "mass_wrong_type": Case(_subject(lambda s: re.sub(r"mass_kg: .*", 'mass_kg: "heavy"', s)),
                            says=("mass_kg", "heavy")),
    "mass_zero": Case(_subject(lambda s: re.sub(r"mass_kg: .*", "mass_kg: 0", s)), says=("mass_kg",)),
    "stature_in_cm": Case(_subject(lambda s: re.sub(r"stature_m: .*", "stature_m: 175", s)),
                          says=("stature_m", "175")),
    "unknown_subject_key": Case(_subject(lambda s: s.replace("mass_kg:", "mass_kgs:")),
                                 says=("mass_kgs", "did you mean 'mass_kg'")),
    "out_is_a_file": Case(_with_file("results"), args=("-o", "results"), names="results", says=("is a file",)),
    "gait_out_is_a_file": Case(_with_file("trial/gait_out"), names="gait_out", says=("is a file",)),
    "trial_outside_the_folder": Case(_outside_trial, says=("trial", "outside the trial folder")),
    "subject_duplicate_key": Case(_subject(lambda s: s + "sex: female\n"), says=("line", "'sex' given twice")),
    "subject_alias_bomb": Case(_subject(lambda s: s + ALIAS_BOMB), says=("aliases expand it",)),
    "pipeline_unknown_key": Case(_pipeline("filter:\n  cutof_hz: 8\n"), args=("--pipeline", "pipeline.yaml"),
                                 names="pipeline.yaml", says=("cutof_hz", "did you mean 'cutoff_hz'")),
}


def _build(root: Path) -> dict:
    """Build every case, snapshot it, run them all, snapshot again."""
    from ..conftest import SHARED_C3D

    jobs, before, skipped = {}, {}, []
    for name, case in CASES.items():
        case_dir = root / name
        case_dir.mkdir()
        trial = case_dir / "trial"
        if case.needs_shared:
            if not SHARED_C3D.is_dir():
                skipped.append(name)
                continue
            _sgi(SHARED_C3D)(trial)
        else:
            case.build(trial)
        before[name] = snapshot(case_dir)
        jobs[name] = (("filter", "trial", *case.args), case_dir)
    results = gait_many(jobs)
    after = {name: snapshot(root / name) for name in jobs}
    return {"results": {k: r.to_json() for k, r in results.items()}, "before": before, "after": after,
            "skipped": skipped}


@pytest.fixture(scope="module")
def outcomes(tmp_path_factory):
    _, record = build_once(tmp_path_factory, "bad_inputs", _build)
    record["results"] = {k: Result.from_json(v) for k, v in record["results"].items()}
    return record


@pytest.mark.parametrize("name", list(CASES))
def test_bad_input_exit_2_one_line_nothing_written(outcomes, name, request):
    if name in outcomes["skipped"]:
        request.getfixturevalue("shared_c3d_dir")  # skips cleanly where ../shared/data/c3d is absent
    case = CASES[name]
    result = outcomes["results"][name]
    assert result.returncode == 2, result.describe()
    assert "Traceback" not in result.stderr, result.describe()
    assert len(result.stderr_lines) == 1, result.describe()
    message = result.stderr_lines[0]
    assert message.startswith("gait: error: "), message
    assert case.names in message, message
    for text in case.says:
        assert text in message, message
    assert result.stdout == ""
    # nothing written: the case folder (trial folder, working directory) is byte-identical
    assert outcomes["after"][name] == outcomes["before"][name], result.describe()


def test_cutoff_above_nyquist_names_the_trial_file(outcomes):
    message = outcomes["results"]["cutoff_above_nyquist"].stderr_lines[0]
    assert "trial.c3d" in message, message
