"""``gaitcli.run.compare`` on small hand-made trees with known differences (the CLI: tests/cli/test_compare_cli.py)."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import pytest

from gaitcli.errors import InputError
from gaitcli.run.compare import (
    DEFAULT_TOLERANCES,
    FAMILIES,
    VOLATILE_KEYS,
    compare_trees,
    finding_rows,
    read_tolerances,
    split_path,
    unit_of,
)

MOMENTS = ("time_s,hip_r_flexion_moment,hip_r_flexion_moment_per_kg,knee_r_flexion,side\n"
           "0,10.0,0.1333,5.0,r\n"
           "0.01,12.0,0.16,NaN,r\n"
           "0.02,14.0,0.1867,7.0,l\n")
SUMMARY = {"frames": 3, "speed_m_s": 1.1, "elapsed_s": 0.2, "converged": True, "metabolic_cost_J": None,
           "segment_rms_marker_error_mm": {"pelvis": 1.05}, "interval_s": [2.11, 3.31],
           "events": [{"time_s": 0.31, "side": "l"}], "notes": ["de Leva (1996) male table"]}


def write_tree(root: Path, *, moments: str = MOMENTS, summary: dict | None = None) -> Path:
    """A lab folder with one trial: normal/gait_out/idyn/{joint_moments.csv, summary.json, idyn.h5, plots/}."""
    idyn = root / "normal" / "gait_out" / "idyn"
    (idyn / "plots").mkdir(parents=True)
    (idyn / "joint_moments.csv").write_text(moments)
    (idyn / "summary.json").write_text(json.dumps(SUMMARY if summary is None else summary))
    (idyn / "idyn.h5").write_bytes(b"\x89HDF binary")
    (idyn / "plots" / "cycle.png").write_bytes(b"png")
    return root


@pytest.fixture
def trees(tmp_path):
    return write_tree(tmp_path / "a"), write_tree(tmp_path / "b")


def edit_csv(root: Path, old: str, new: str) -> None:
    path = root / "normal" / "gait_out" / "idyn" / "joint_moments.csv"
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new, 1))


def test_identical_trees_have_no_findings(trees):
    a, b = trees
    (b / "normal" / "gait_out" / "idyn" / "idyn.h5").write_bytes(b"another binary")  # HDF5 is not compared
    (b / "normal" / "gait_out" / "idyn" / ".joint_moments.csv.123.abc.part").write_text("x")  # nor leftovers
    result = compare_trees(a, b)
    assert result.ok and result.findings == ()
    assert result.files == ("normal/gait_out/idyn/joint_moments.csv", "normal/gait_out/idyn/summary.json")
    assert result.summary_line() == "2 files compared, 0 differ"


def test_a_moment_beyond_its_tolerance_is_named_with_difference_and_where(trees):
    a, b = trees
    edit_csv(b, "0.01,12.0,", "0.01,12.8,")  # 0.8 N·m > 0.5 N·m
    edit_csv(b, "0,10.0,0.1333", "0,10.4,0.1373")  # 0.4 N·m and 0.004 N·m/kg: within
    result = compare_trees(a, b)
    assert not result.ok and result.differing == ("normal/gait_out/idyn/joint_moments.csv",)
    (f,) = result.findings
    assert (f.trial, f.stage, f.file, f.column, f.problem) == ("normal", "idyn", "joint_moments.csv",
                                                              "hip_r_flexion_moment", "value")
    assert f.difference == pytest.approx(0.8) and f.tolerance_text == "0.5 N·m"
    assert f.where == "time_s=0.01 side=r (line 3)"
    assert finding_rows(result)[0][:4] == ("normal", "idyn", "joint_moments.csv", "hip_r_flexion_moment")
    assert result.summary_line() == "2 files compared, 1 differ"


def test_a_per_kg_moment_has_its_own_tolerance(trees):
    a, b = trees
    edit_csv(b, "0.1867", "0.2067")  # 0.02 N·m/kg > 0.01
    (f,) = compare_trees(a, b).findings
    assert f.column == "hip_r_flexion_moment_per_kg" and f.difference == pytest.approx(0.02)
    assert f.tolerance_text == "0.01 N·m/kg" and f.where.startswith("time_s=0.02 side=l")


def test_nan_equals_nan_but_nan_on_one_side_differs(trees):
    a, b = trees
    assert compare_trees(a, b).ok  # knee_r_flexion has a NaN on both sides
    edit_csv(b, "NaN,r", "6.0,r")
    (f,) = compare_trees(a, b).findings
    assert (f.column, f.problem, f.difference) == ("knee_r_flexion", "nan", math.inf)
    assert "NaN in A, 6 in B" in f.detail


def test_text_columns_must_be_equal(trees):
    a, b = trees
    edit_csv(b, "7.0,l", "7.0,r")
    (f,) = compare_trees(a, b).findings
    assert (f.column, f.problem) == ("side", "text") and "'l' in A, 'r' in B" in f.detail


def test_row_counts_and_columns_on_one_side_are_findings(tmp_path):
    a = write_tree(tmp_path / "a")
    b = write_tree(tmp_path / "b", moments=MOMENTS + "0.03,15.0,0.2,8.0,l\n")
    (f,) = compare_trees(a, b).findings
    assert f.problem == "rows" and f.detail == "3 rows in A, 4 in B"
    c = write_tree(tmp_path / "c", moments=MOMENTS.replace(",side", ",foot"))
    found = {(f.column, f.problem) for f in compare_trees(a, c).findings}
    assert found == {("side", "column_only_in_a"), ("foot", "column_only_in_b")}


def test_missing_files_and_stage_folders_are_reported(trees):
    a, b = trees
    (b / "normal" / "gait_out" / "idyn" / "summary.json").unlink()
    muscles = a / "normal" / "gait_out" / "muscles" / "so"
    muscles.mkdir(parents=True)
    (muscles / "forces.csv").write_text("time_s,soleus_force_N\n0,100\n")
    (muscles / "summary.json").write_text("{}")
    (b / "extra.csv").write_text("x\n1\n")
    result = compare_trees(a, b)
    found = [(f.path, f.trial, f.stage, f.file, f.problem) for f in result.findings]
    assert found == [("extra.csv", "", "", "extra.csv", "only_in_b"),
                     ("normal/gait_out/idyn/summary.json", "normal", "idyn", "summary.json", "only_in_a"),
                     ("normal/gait_out/muscles/", "normal", "muscles", "", "only_in_a")]
    assert result.findings[2].detail == "folder of 2 file(s) only in A"
    assert result.summary_line() == "5 files compared, 4 differ"


def test_summary_values_keys_and_types(tmp_path):
    a = write_tree(tmp_path / "a")
    assert set(VOLATILE_KEYS) >= {"elapsed_s", "solve_time_s"}
    changed = json.loads(json.dumps(SUMMARY))
    changed.update({"elapsed_s": 9.9, "speed_m_s": 1.1005, "frames": 4, "converged": False, "metabolic_cost_J": 3.0,
                    "new_key": 1, "interval_s": [2.11, 3.31, 4.5]})
    changed["segment_rms_marker_error_mm"]["pelvis"] = 2.5  # mm, from the parent key: > 1 mm
    changed["events"][0]["time_s"] = 0.3105  # within 1 ms
    changed["notes"] = "de Leva"
    b = write_tree(tmp_path / "b", summary=changed)
    found = {f.column: f for f in compare_trees(a, b).findings}
    assert set(found) == {"frames", "converged", "metabolic_cost_J", "new_key", "interval_s",
                          "segment_rms_marker_error_mm.pelvis", "notes"}  # not elapsed_s, speed, events
    assert found["frames"].problem == "value" and found["frames"].tolerance_text == "1e-05 rel"
    assert found["converged"].problem == "text" and "True in A, False in B" in found["converged"].detail
    assert found["metabolic_cost_J"].problem == "nan"
    assert found["new_key"].problem == "key_only_in_b"
    assert found["interval_s"].problem == "length" and found["interval_s"].detail == "2 items in A, 3 in B"
    assert found["segment_rms_marker_error_mm.pelvis"].tolerance_text == "1 mm"
    assert found["notes"].problem == "type" and found["notes"].detail == "list in A, text in B"


def test_unitless_values_are_compared_relative(tmp_path):
    a = write_tree(tmp_path / "a", summary={"objective": 1000.0, "small": 1e-12})
    within = write_tree(tmp_path / "b", summary={"objective": 1000.009, "small": -1e-12})
    beyond = write_tree(tmp_path / "c", summary={"objective": 1000.02, "small": 0.0})
    assert compare_trees(a, within).ok
    (f,) = compare_trees(a, beyond).findings
    assert f.column == "objective" and f.difference == pytest.approx(0.02)


@pytest.mark.parametrize("relative, expected", [
    ("normal/gait_out/idyn/joint_moments.csv", ("normal", "idyn", "joint_moments.csv")),
    ("lab/s01/walk2/gait_out/muscles/eid/forces.csv", ("lab/s01/walk2", "muscles/eid", "forces.csv")),
    ("idyn/summary.json", ("", "idyn", "summary.json")),
    ("gait_out/filter/grf.csv", ("", "filter", "grf.csv")),
    ("batch_summary.csv", ("", "", "batch_summary.csv")),
])
def test_trial_and_stage_come_from_the_relative_path(relative, expected):
    assert split_path(relative) == expected


@pytest.mark.parametrize("name, family, unit", [
    ("hip_r_flexion_moment", "moment", "N·m"), ("ankle_l_flexion_moment_per_kg", "moment_per_kg", "N·m/kg"),
    ("hip_moment_Nm", "moment", "N·m"), ("plate1_free_moment_Nm", "moment", "N·m"),
    ("residual_force_x_N", "force", "N"), ("right_fz_N_per_kg", "force_per_kg", "N/kg"),
    ("grf_z_r_N_per_kg_mean", "force_per_kg", "N/kg"), ("pelvis_x", "length", "m"), ("cop_x_r_m", "length", "m"),
    ("joint_centre_gap_mm", "length", "mm"), ("pelvis_rot_z", "angle", "deg"), ("knee_l_adduction", "angle", "deg"),
    ("thigh_angle_r_deg", "angle", "deg"), ("thigh_angle_rad", "angle", "rad"), ("time_s", "time", "s"),
    ("speed_m_s", "speed", "m/s"), ("cycle_pct", "percent", "%"), ("metabolic_cost_J", "cost", "J"),
    ("cost_of_transport_J_per_m", "cost_per_m", "J/m"), ("total_metabolic_rate_W", "power", "W"),
    ("soleus_activation", "fraction", ""), ("max_excitation", "fraction", ""), ("marker_rate_hz", "frequency", "Hz"),
    ("mass_kg", "mass", "kg"),
])
def test_the_unit_family_comes_from_the_name(name, family, unit):
    assert unit_of(name)[:2] == (family, unit)


def test_tolerances_convert_to_the_column_unit():
    assert DEFAULT_TOLERANCES.rule("pelvis_x").tolerance == pytest.approx(0.001)  # 1 mm in m
    assert DEFAULT_TOLERANCES.rule("thigh_angle_rad").tolerance == pytest.approx(math.radians(0.1))
    assert unit_of("frames") is None and DEFAULT_TOLERANCES.rule("frames").relative


def test_a_tolerance_file_overrides_families_columns_and_ignores(trees, tmp_path):
    a, b = trees
    edit_csv(b, "0.01,12.0,0.16,NaN", "0.01,12.8,0.16,NaN")  # moment +0.8 N·m
    edit_csv(b, "0,10.0,0.1333,5.0", "0,10.0,0.1333,5.3")  # knee angle +0.3 deg
    assert {f.column for f in compare_trees(a, b).findings} == {"hip_r_flexion_moment", "knee_r_flexion"}
    path = tmp_path / "tol.yaml"
    path.write_text("families:\n  angle: 0.5\ncolumns:\n  'hip_*_moment': 1.0\n  '*': 0\nignore: [frames]\n")
    tol = read_tolerances(path)
    assert tol.families["angle"] == 0.5 and tol.families["force"] == FAMILIES["force"].tolerance
    assert compare_trees(a, b, tolerances=tol).ok is False  # '*': 0 catches knee_r_flexion before the family
    path.write_text("families:\n  angle: 0.5\ncolumns:\n  'hip_*_moment': 1.0\n")
    assert compare_trees(a, b, tolerances=read_tolerances(path)).ok
    path.write_text("ignore: ['hip_r_*', knee_r_flexion]\n")
    assert compare_trees(a, b, tolerances=read_tolerances(path)).ok
    path.write_text("")
    assert read_tolerances(path) == DEFAULT_TOLERANCES


@pytest.mark.parametrize("text, message", [
    ("families:\n  angel: 0.5\n", "tol.yaml: families.angel: unknown key; did you mean 'angle'?"),
    ("families:\n  force: -1\n", "tol.yaml: families.force: got -1 (expected a number ≥ 0)"),
    ("columns:\n  knee_*: fast\n", "tol.yaml: columns.knee_*: got 'fast' (expected a number ≥ 0)"),
    ("tolerance:\n  angle: 1\n", "tol.yaml: tolerance: unknown key"),
    ("- angle\n", "tol.yaml: a list (expected a mapping"),
    ("ignore: frames\n", "tol.yaml: ignore: a str (expected a list"),
])
def test_a_bad_tolerance_file_is_one_input_error_naming_file_and_key(tmp_path, text, message):
    path = tmp_path / "tol.yaml"
    path.write_text(text)
    with pytest.raises(InputError) as err:
        read_tolerances(path)
    assert str(err.value).startswith(str(tmp_path / message.split(":")[0]) + message[len("tol.yaml"):]), str(err.value)
    assert "\n" not in str(err.value)


def test_bad_roots_and_unreadable_files_are_input_errors(trees, tmp_path):
    a, b = trees
    with pytest.raises(InputError, match="not found"):
        compare_trees(a, tmp_path / "missing")
    with pytest.raises(InputError, match="no CSV or summary.json"):
        compare_trees(tmp_path / "a" / "normal" / "gait_out" / "idyn" / "plots",
                      tmp_path / "b" / "normal" / "gait_out" / "idyn" / "plots")
    (b / "normal" / "gait_out" / "idyn" / "summary.json").write_text("{not json")
    with pytest.raises(InputError, match="summary.json: not valid JSON"):
        compare_trees(a, b)
    shutil.rmtree(b)
    b.write_text("a file")
    with pytest.raises(InputError, match="not a folder"):
        compare_trees(a, b)


README = Path(__file__).resolve().parents[1] / "README.md"


def test_the_readme_documents_the_default_tolerances_and_a_valid_file(tmp_path):
    text = README.read_text(encoding="utf-8").split("### Comparing two output trees", 1)[1].split("\n## ", 1)[0]
    rows = [line.split("|")[1:4] for line in text.splitlines() if line.startswith("| ") and "---" not in line]
    documented = {name.strip(): (unit.strip(), float(default.split()[0])) for name, unit, default in rows[1:]}
    assert documented == {n: (f.unit or "—", f.tolerance) for n, f in FAMILIES.items()}
    example = text.split("```yaml\n", 1)[1].split("```", 1)[0]
    (tmp_path / "tol.yaml").write_text(example)
    tol = read_tolerances(tmp_path / "tol.yaml")
    assert tol.families["angle"] == 0.5 and tol.columns[0] == ("knee_*_moment", 2.0) and tol.ignore == ("notes",)


def test_empty_cells_are_nan_and_a_number_against_text_differs(tmp_path):
    a = write_tree(tmp_path / "a", moments="time_s,plate1_foot,grf_z_N\n0,,1.0\n0.01,r,\n")
    same = write_tree(tmp_path / "b", moments="time_s,plate1_foot,grf_z_N\n0,,1.0\n0.01,r,NaN\n")
    assert compare_trees(a, same).ok
    other = write_tree(tmp_path / "c", moments="time_s,plate1_foot,grf_z_N\n0,,1.0\n0.01,r,heavy\n")
    (f,) = compare_trees(a, other).findings
    assert (f.column, f.problem, f.where) == ("grf_z_N", "text", "time_s=0.01 (line 3)")


def test_an_infinity_equals_only_the_same_infinity(tmp_path):
    """A unit-less value's tolerance is relative to its size, so an infinity would allow anything; the
    summary's NaN and Infinity tokens (json.dumps writes them) are numbers like the CSV's."""
    a = write_tree(tmp_path / "a", moments="time_s,ratio,grf_z_N\n0,inf,inf\n0.01,2.5,-inf\n",
                   summary={"objective": math.inf, "ratio": math.inf, "same": -math.inf, "missing": math.nan})
    b = write_tree(tmp_path / "b", moments="time_s,ratio,grf_z_N\n0,2.5,inf\n0.01,2.5,inf\n",
                   summary={"objective": 2.5, "ratio": -math.inf, "same": -math.inf, "missing": math.nan})
    found = {(f.file, f.column): (f.problem, f.detail) for f in compare_trees(a, b).findings}
    assert found == {("joint_moments.csv", "ratio"): ("value", "inf in A, 2.5 in B (1 of 2 rows beyond tolerance)"),
                     ("joint_moments.csv", "grf_z_N"): ("value", "-inf in A, inf in B (1 of 2 rows beyond tolerance)"),
                     ("summary.json", "objective"): ("value", "inf in A, 2.5 in B"),
                     ("summary.json", "ratio"): ("value", "inf in A, -inf in B")}


@pytest.mark.parametrize("cell, summary", [("1e400", "1e400"), ("-2.5e999", "-2.5e999"), ("9" * 400 + ".0", None)])
def test_a_number_beyond_a_double_is_an_input_error_not_infinity(tmp_path, cell, summary):
    """Read as a float, 1e400 becomes inf and would equal inf, 1e401 and every other overflow."""
    a = write_tree(tmp_path / "a", moments="time_s,grf_z_N\n0,inf\n")
    b = write_tree(tmp_path / "b", moments=f"time_s,grf_z_N\n0,{cell}\n")
    with pytest.raises(InputError, match=r"grf_z_N.*on line 2 is beyond the range of a double"):
        compare_trees(a, b)
    if summary is not None:
        c = write_tree(tmp_path / "c")
        (c / "normal" / "gait_out" / "idyn" / "summary.json").write_text(f'{{"objective": {summary}}}')
        with pytest.raises(InputError, match="is beyond the range of a double"):
            compare_trees(write_tree(tmp_path / "d"), c)


def test_a_batch_summarys_run_state_is_not_compared(tmp_path):
    """Two labs of the same results: one ran its trials, the other found them current (status skipped), and a
    failure's reason names each lab's own path; their exit codes and figures still count."""
    header = "trial,stage,status,exit_code,reason,wall_time_s,input_key,speed_m_s\n"
    a, b = write_tree(tmp_path / "a"), write_tree(tmp_path / "b")
    (a / "batch_summary.csv").write_text(header + "normal,idyn,ok,0,,1.2,k1,1.31\n"
                                                  f"bad,filter,failed,2,{a}/bad/trial.c3d: not a C3D,0.1,k2,\n")
    (b / "batch_summary.csv").write_text(header + "normal,idyn,skipped,0,,0,k1,1.31\n"
                                                  f"bad,filter,failed,2,{b}/bad/trial.c3d: not a C3D,0,k2,\n")
    assert not compare_trees(a, b).findings
    (b / "batch_summary.csv").write_text(header + "normal,idyn,unconverged,3,,0,k1,1.29\n"
                                                  f"bad,filter,failed,2,{b}/bad/trial.c3d: not a C3D,0,k2,\n")
    assert {f.column for f in compare_trees(a, b).findings} == {"exit_code", "speed_m_s"}
