"""A seeded generator of hostile inputs run through the CLI: mutated subject.yaml, pipeline, summary.json, CSV
tables and HDF5 files end in exit 0, 2 or 3 (1 for ``gait compare``: the trees differ), never in an internal
error or a traceback, and an error is one line.

Every command fails fast: a trial folder without its C3D (so subject.yaml and the pipeline are validated and
then the trial file is missing), ``gait report`` on an output tree without the HDF5 files its figures need,
``gait predict --init`` with a subject file that does not exist (read after the start). All cases run once in
the session's runner processes (:func:`gait_many`).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import h5py
import numpy as np
import pytest

from gaitcli.resources import sample_trial

from .conftest import Result, build_once, gait_many

SEED = 35
#: cases per kind of file
COUNTS = {"subject": 30, "pipeline": 20, "summary_report": 10, "summary_compare": 10, "batch_csv": 8,
          "study_csv": 6, "table_compare": 6, "h5_init": 15}
SUBJECT = (sample_trial("normal") / "subject.yaml").read_text() + (
    "static_frames: [1, 20]\nmarker_map:\n  RHEE: RCAL\nknee_width_mm: [100, 101]\n"
    "disturbances:\n  - {segment: shank_r, mass_kg: 1.5, com_offset_m: [0, 0, -0.1]}\n")
PIPELINE = (Path(__file__).parents[2] / "pipelines" / "standard.yaml").read_text()
BASELINE = Path(__file__).parents[1] / "baseline" / "normal" / "gait_out" / "idyn"
SUMMARY = (BASELINE / "summary.json").read_text()
TABLE = "\n".join((BASELINE / "joint_moments.csv").read_text().splitlines()[:6]) + "\n"
BATCH_CSV = ("trial,stage,status,exit_code,reason,wall_time_s,input_key\nwalk,filter,ok,0,,1.5,abc\n"
             "walk,idyn,ok,0,,2.0,abc\nbad,filter,failed,2,\"subject.yaml: mass_kg: got 0\",0.1,def\n")
STUDY_CSV = ("case,speed_m_s,weights,condition,objective,cost_of_transport_J_per_m,deviation,converged\n"
             "v1.1_w1,1.1,\"1,1\",normal,1.25,250.5,0.5,True\nv1.3_w1,1.3,\"1,1\",sach,1.5,260.1,0.7,False\n")

HOSTILE_NUMBERS = ("1" + "0" * 399, "-" + "9" * 5000, "1e400", "-1e400", ".nan", ".inf", "-.inf", "NaN",
                   "Infinity", "1e40", "-0", "0x7fffffffffffffff", "1_000", "4e-400", "0.0000001")
HOSTILE_TOKENS = ("\0", "\x1b", "\x07", "\x0c", "\ufeff", "\u202e", "\t", "\r", "&a", "*a",
                  "!!python/object/apply:os.system ['true']", "<<: *b", "? ", "- ", "{", "[", "]", "}", "~", "'", '"',
                  "\\", ":", ",", "#", "%YAML 1.1\n---\n",
                  "!!binary aGVsbG8=", "!!set {a, b}", "2001-12-14t21:59:43.10-05:00", "../../../etc/passwd")


def _mutate_text(text: str, rng: np.random.Generator, numbers=HOSTILE_NUMBERS) -> str | bytes:
    """One to three random mutations of ``text``."""
    for _ in range(int(rng.integers(1, 4))):
        kind = int(rng.integers(0, 10))
        at = int(rng.integers(0, len(text) + 1))
        found = list(re.finditer(r"-?\d+(?:\.\d+)?(?:e[-+]?\d+)?", text))
        if kind == 0 and found:  # a number replaced
            m = found[int(rng.integers(len(found)))]
            text = text[:m.start()] + str(rng.choice(numbers)) + text[m.end():]
        elif kind == 1:
            text = text[:at] + str(rng.choice(HOSTILE_TOKENS)) + text[at:]
        elif kind == 2:
            text = text[:at]
        elif kind == 3:
            lines = text.splitlines(keepends=True) or [""]
            k = int(rng.integers(len(lines)))
            lines.insert(k, lines[k])
            text = "".join(lines)
        elif kind == 4:
            lines = text.splitlines(keepends=True) or [""]
            del lines[int(rng.integers(len(lines)))]
            text = "".join(lines)
        elif kind == 5:
            depth = int(rng.choice([50, 500, 5000]))
            text = text[:at] + "[" * depth + "]" * depth + text[at:]
        elif kind == 6:
            text = text[:at] + "x" * int(rng.choice([300, 5000])) + text[at:]
        elif kind == 7 and found:  # a number replaced by text
            m = found[int(rng.integers(len(found)))]
            text = text[:m.start()] + str(rng.choice(["abc", "true", "null", "[]", "{}", "''"])) + text[m.end():]
        elif kind == 8:
            data = bytearray(text.encode())
            if data:
                data[min(at, len(data) - 1)] = int(rng.choice([0xFF, 0xC3, 0x80, 0x00]))
            return bytes(data)
        else:
            text = text.replace(":", str(rng.choice([" :", "::", ":\t", "=", ""])), 1 + int(rng.integers(3)))
    return text


def _write(path: Path, content: str | bytes) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(content if isinstance(content, bytes) else content.encode("utf-8", "surrogatepass"))


def _predict_h5(path: Path, rng: np.random.Generator) -> None:
    """A predict.h5-like file (result/design), structurally or byte-wise damaged."""
    kind = int(rng.integers(0, 9))
    design = rng.normal(size=40)
    with h5py.File(path, "w") as h5:
        h5.attrs["trial"] = "walk"
        if kind == 0:
            h5["result/design"] = np.array([b"a", b"b"])
        elif kind == 1:
            h5["result/design"] = design.reshape(8, 5)
        elif kind == 2:
            h5["result/design"] = np.array([np.nan, np.inf, 1e308])
        elif kind == 3:
            h5.create_group("result/design")
        elif kind == 4:
            h5["result/design"] = h5py.ExternalLink("/nonexistent.h5", "/x")
        elif kind == 5:
            h5["result/design"] = h5py.SoftLink("/result/design")
        elif kind == 6:
            h5["result/design"] = design.astype(complex)
        else:
            h5["result/design"] = design
    if kind >= 7:  # bytes flipped or the file cut
        data = bytearray(path.read_bytes())
        if kind == 7:
            for k in rng.integers(0, len(data), 20):
                data[int(k)] ^= 0xFF
        else:
            data = data[:int(rng.integers(8, len(data)))]
        path.write_bytes(bytes(data))


def _cases(root: Path) -> dict:
    rng = np.random.default_rng(SEED)
    jobs = {}
    for k in range(COUNTS["subject"]):
        case = root / f"subject_{k}"
        _write(case / "trial" / "subject.yaml", _mutate_text(SUBJECT, rng))
        jobs[case.name] = (("filter", "trial"), case)
    for k in range(COUNTS["pipeline"]):
        case = root / f"pipeline_{k}"
        _write(case / "trial" / "subject.yaml", SUBJECT)
        _write(case / "p.yaml", _mutate_text(PIPELINE, rng))
        jobs[case.name] = (("filter", "trial", "--pipeline", "p.yaml"), case)
    json_numbers = ("1" + "0" * 399, "9" * 5000, "1e400", "-1e400", "NaN", "Infinity", "-Infinity", "1e308", "-0")
    for k in range(COUNTS["summary_report"]):
        case = root / f"summary_report_{k}"
        _write(case / "o" / "idyn" / "summary.json", _mutate_text(SUMMARY, rng, json_numbers))
        jobs[case.name] = (("report", "o"), case)
    for k in range(COUNTS["summary_compare"]):
        case = root / f"summary_compare_{k}"
        _write(case / "a" / "gait_out" / "idyn" / "summary.json", SUMMARY)
        _write(case / "b" / "gait_out" / "idyn" / "summary.json", _mutate_text(SUMMARY, rng, json_numbers))
        jobs[case.name] = (("compare", "a", "b"), case)
    for k in range(COUNTS["batch_csv"]):
        case = root / f"batch_csv_{k}"
        _write(case / "lab" / "batch_summary.csv", _mutate_text(BATCH_CSV, rng))
        jobs[case.name] = (("report", "lab"), case)
    for k in range(COUNTS["study_csv"]):
        case = root / f"study_csv_{k}"
        _write(case / "st" / "study.csv", _mutate_text(STUDY_CSV, rng))
        jobs[case.name] = (("report", "st"), case)
    for k in range(COUNTS["table_compare"]):
        case = root / f"table_compare_{k}"
        _write(case / "a" / "gait_out" / "idyn" / "joint_moments.csv", TABLE)
        _write(case / "b" / "gait_out" / "idyn" / "joint_moments.csv", _mutate_text(TABLE, rng))
        jobs[case.name] = (("compare", "a", "b"), case)
    for k in range(COUNTS["h5_init"]):
        case = root / f"h5_init_{k}"
        case.mkdir()
        _predict_h5(case / "init.h5", rng)
        jobs[case.name] = (("predict", "--init", "init.h5", "--subject", "absent.yaml"), case)
    return jobs


def _build(root: Path) -> dict:
    results = gait_many(_cases(root))
    return {k: r.to_json() for k, r in results.items()}


@pytest.fixture(scope="module")
def results(tmp_path_factory) -> dict[str, Result]:
    _, record = build_once(tmp_path_factory, "hostile_generator", _build)
    return {k: Result.from_json(v) for k, v in record.items()}


def test_at_least_100_cases(results):
    assert len(results) == sum(COUNTS.values()) >= 100


def test_no_internal_error_and_no_traceback(results):
    bad = []
    for name, r in results.items():
        allowed = {0, 1, 2, 3} if r.args[0] == "compare" else {0, 2, 3}
        one_line = r.returncode != 2 or len(r.stderr_lines) == 1
        if r.returncode not in allowed or "Traceback" in r.stderr or "internal error" in r.stderr or not one_line:
            bad.append(f"{name}: {r.describe()}")
    assert not bad, f"{len(bad)} of {len(results)} cases:\n" + "\n".join(bad[:5])


def test_most_mutations_are_refused_by_name(results):
    """The generator reaches the validators: most cases end in exit 2 naming the file they mutated."""
    refused = [r for r in results.values() if r.returncode == 2]
    assert len(refused) > len(results) / 2
    assert all(r.stderr_lines[0].startswith("gait: error: ") for r in refused)


def test_the_generator_is_seeded():
    a, b = _mutate_text(SUBJECT, np.random.default_rng(SEED)), _mutate_text(SUBJECT, np.random.default_rng(SEED))
    assert a == b
    assert json.loads(SUMMARY)  # the baseline summary the mutations start from is valid
