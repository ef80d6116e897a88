"""CSV trial reader, OpenSim .trc/.mot round trips and bad-table messages."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.core.recording import Markers
from gaitcli.errors import GaitWarning, InputError
from gaitcli.io.tables import (
    PLATE_SIZE_M,
    read_csv_trial,
    read_markers_csv,
    read_mot,
    read_trc,
    write_mot,
    write_trc,
)

RATE_HZ, FORCE_RATE_HZ, N = 100.0, 500.0, 80
# the CSV lab: z up, the subject walks along lab -y, so model x = -lab y, model y = lab x
LAB_TO_MODEL = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])


def _csv(path, header, rows):
    path.write_text(",".join(header) + "\n" + "\n".join(",".join(r) for r in rows) + "\n")
    return path


def _fmt(v):
    return "" if not np.isfinite(v) else repr(float(v))


@pytest.fixture()
def csv_trial(tmp_path):
    """markers.csv + forces.csv in the lab above, with their exact content (lab axes)."""
    rng = np.random.default_rng(5)
    t = np.arange(N) / RATE_HZ
    body = np.array([[0.0, 0.0, 1.7], [0.2, 0.0, 1.4], [-0.2, 0.0, 1.4], [0.1, 0.0, 0.07]])
    pos = body[None] + t[:, None, None] * np.array([0.0, -1.25, 0.0]) + rng.normal(0, 0.001, (N, 4, 3))
    pos[10, 1] = np.nan
    labels = ["HEAD", "LSHO", "RSHO", "LTOE"]
    header = ["time_s"] + [f"{lab}_{a}_m" for lab in labels for a in "xyz"]
    rows = [[_fmt(t[i])] + [_fmt(v) for v in pos[i].ravel()] for i in range(N)]
    markers_csv = _csv(tmp_path / "markers.csv", header, rows)

    ts = np.arange(N * 5) / FORCE_RATE_HZ
    stance = np.clip(np.sin(np.pi * (ts - 0.1) / 0.5), 0, None) * (ts > 0.1) * (ts < 0.6)
    force = np.stack([15 * np.cos(4 * ts), -90 * np.sin(6 * ts), 2 + 720 * stance], axis=1)
    cop = np.stack([0.05 + 0.02 * np.sin(3 * ts), -0.2 - 0.25 * ts, 0 * ts], axis=1)
    free = 3.0 * np.cos(7 * ts)
    unloaded = force[:, 2] <= 20.0
    cop_csv, free_csv = cop.copy(), free.copy()
    cop_csv[unloaded] = np.nan  # COP and free moment left empty where there is no load
    free_csv[unloaded] = np.nan
    header = ["time_s"] + [f"plate1_{f}" for f in
                           ("force_x_N", "force_y_N", "force_z_N", "cop_x_m", "cop_y_m", "free_moment_Nm")]
    rows = [[_fmt(ts[i]), *map(_fmt, force[i]), _fmt(cop_csv[i, 0]), _fmt(cop_csv[i, 1]), _fmt(free_csv[i])]
            for i in range(ts.size)]
    forces_csv = _csv(tmp_path / "forces.csv", header, rows)
    return markers_csv, forces_csv, pos, force, cop, free, ~unloaded


def test_csv_trial_in_model_axes_recovers_markers_force_cop_and_free_moment(csv_trial):
    markers_csv, forces_csv, pos, force, cop, free, loaded = csv_trial
    rec = read_csv_trial(markers_csv, forces_csv)
    np.testing.assert_allclose(rec.lab_to_model, LAB_TO_MODEL, atol=1e-12)
    assert rec.markers.labels == ("HEAD", "LSHO", "RSHO", "LTOE") and rec.markers.rate_hz == pytest.approx(RATE_HZ)
    np.testing.assert_allclose(rec.markers.positions_m, pos @ LAB_TO_MODEL.T, atol=1e-12)
    (plate,) = rec.plates
    assert plate.rate_hz == pytest.approx(FORCE_RATE_HZ)
    np.testing.assert_allclose(plate.force_N, force @ LAB_TO_MODEL.T, atol=1e-9)
    # centre = mean loaded COP on the floor; corners a 0.6 x 0.4 m rectangle around it (rotated with the lab)
    np.testing.assert_allclose(plate.centre_m, LAB_TO_MODEL @ cop[loaded].mean(axis=0), atol=1e-12)
    extent = np.ptp(plate.corners_m @ LAB_TO_MODEL, axis=0)
    np.testing.assert_allclose(extent, [*PLATE_SIZE_M, 0.0], atol=1e-12)
    F, M = plate.force_N[loaded], plate.moment_Nm[loaded]
    rx, ry = -M[:, 1] / F[:, 2], M[:, 0] / F[:, 2]
    np.testing.assert_allclose(plate.centre_m[:2] + np.stack([rx, ry], 1), (cop[loaded] @ LAB_TO_MODEL.T)[:, :2],
                               atol=1e-9)
    np.testing.assert_allclose(M[:, 2] - (rx * F[:, 1] - ry * F[:, 0]), free[loaded], atol=1e-9)
    np.testing.assert_allclose(plate.moment_Nm[~loaded, :2], 0.0)  # no COP → moment about the centre is T_z only


def test_csv_trial_without_forces_warns(csv_trial):
    markers_csv = csv_trial[0]
    with pytest.warns(GaitWarning, match="markers only"):
        rec = read_csv_trial(markers_csv, to_model_axes=False)
    np.testing.assert_allclose(rec.lab_to_model, np.eye(3))
    np.testing.assert_allclose(rec.markers.positions_m, csv_trial[2])


BAD_MARKERS = {
    "no_time": (["t", "A_x_m", "A_y_m", "A_z_m"], [["0", "1", "2", "3"]], "time_s", "column missing"),
    "time_not_first": (["A_x_m", "time_s", "A_y_m", "A_z_m"], [["0", "1", "2", "3"]], "time_s", "first column"),
    "text_cell": (["time_s", "A_x_m", "A_y_m", "A_z_m"], [["0", "1", "2", "3"], ["0.01", "1", "abc", "3"]],
                  "A_y_m", "line 3: got 'abc' (expected a number)"),
    "incomplete": (["time_s", "A_x_m", "A_y_m"], [["0", "1", "2"], ["0.01", "1", "2"]], "A_z_m", "column missing"),
    "unknown": (["time_s", "A_x_m", "A_y_m", "A_z_m", "B_x"], [["0", "1", "2", "3", "4"]], "B_x", "unexpected"),
    "short_row": (["time_s", "A_x_m", "A_y_m", "A_z_m"], [["0", "1", "2", "3"], ["0.01", "1", "2"]],
                  "A_z_m", "line 3 has fewer cells"),
    "uneven_time": (["time_s", "A_x_m", "A_y_m", "A_z_m"], [["0", "1", "2", "3"], ["0.01", "1", "2", "3"],
                                                            ["0.05", "1", "2", "3"]], "time_s", "uniformly"),
    "duplicate": (["time_s", "A_x_m", "A_x_m", "A_y_m", "A_z_m"], [["0", "1", "1", "2", "3"]],
                  "A_x_m", "more than once"),
}


@pytest.mark.parametrize("case", list(BAD_MARKERS))
def test_bad_markers_csv_names_file_and_column(tmp_path, case):
    header, rows, column, text = BAD_MARKERS[case]
    path = _csv(tmp_path / "markers.csv", header, rows)
    with pytest.raises(InputError) as info:
        read_markers_csv(path)
    message = str(info.value)
    assert message.startswith(f"{path}: {column}: ") and text in message and "\n" not in message


def test_long_row_and_forces_problems(tmp_path, csv_trial):
    path = tmp_path / "m.csv"
    path.write_text("time_s,A_x_m,A_y_m,A_z_m\n0,1,2,3\n0.01,1,2,3,4\n")
    with pytest.raises(InputError, match=r"m\.csv: malformed CSV: line 3 has 5 cells, the header 4"):
        read_markers_csv(path)
    markers_csv, forces_csv = csv_trial[:2]
    lines = forces_csv.read_text().splitlines()
    loaded_row = next(i for i, line in enumerate(lines[1:], start=1) if float(line.split(",")[3]) > 100)
    cells = lines[loaded_row].split(",")
    cells[4] = ""
    lines[loaded_row] = ",".join(cells)
    forces_csv.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError, match=rf"plate1_cop_x_m: line {loaded_row + 1}: missing where the plate is loaded"):
        read_csv_trial(markers_csv, forces_csv)
    shifted = tmp_path / "shifted.csv"
    shifted.write_text("time_s,plate1_force_x_N,plate1_force_y_N,plate1_force_z_N,plate1_cop_x_m,plate1_cop_y_m,"
                       "plate1_free_moment_Nm\n0.5,0,0,0,,,\n0.502,0,0,0,,,\n")
    with pytest.raises(InputError, match="time_s: starts at 0.5 s but markers.csv starts at 0 s"):
        read_csv_trial(markers_csv, shifted)


def test_trc_round_trip_and_opensim_header(tmp_path):
    rng = np.random.default_rng(9)
    pos = rng.normal(0, 0.5, (12, 3, 3))
    pos[4, 1] = np.nan
    markers = Markers(("LASI", "RASI", "C7"), pos, 120.0, first_frame=7)
    for units in ("mm", "m"):
        path = write_trc(tmp_path / f"walk_{units}.trc", markers, units=units)
        lines = path.read_text().splitlines()
        assert lines[0] == f"PathFileType\t4\t(X/Y/Z)\t{path.name}"
        assert lines[1].split("\t") == ["DataRate", "CameraRate", "NumFrames", "NumMarkers", "Units",
                                        "OrigDataRate", "OrigDataStartFrame", "OrigNumFrames"]
        assert lines[2].split("\t") == ["120", "120", "12", "3", units, "120", "7", "12"]
        assert lines[3] == "Frame#\tTime\tLASI\t\t\tRASI\t\t\tC7\t\t"
        assert lines[4] == "\t\tX1\tY1\tZ1\tX2\tY2\tZ2\tX3\tY3\tZ3"
        assert lines[5] == "" and lines[6].startswith("7\t0\t")
        assert lines[10].split("\t")[5:8] == ["", "", ""]  # frame 11: RASI missing → empty cells
        back = read_trc(path)
        assert back.labels == markers.labels and back.rate_hz == 120.0 and back.first_frame == 7
        np.testing.assert_array_equal(np.isnan(back.positions_m), np.isnan(pos))
        np.testing.assert_allclose(back.positions_m, pos, atol=1e-12, equal_nan=True)


def test_mot_round_trip_and_legacy_sto(tmp_path, shared_c3d_dir):
    t = np.arange(50) / 100.0
    cols = {"hip_flexion_r": np.sin(t) * 30, "knee_angle_r": -np.cos(t) * 40, "ground_force_vy": t * 700}
    path = write_mot(tmp_path / "ik.mot", t, cols, in_degrees=True)
    head = path.read_text().splitlines()[:7]
    assert head == ["ik.mot", "version=1", "nRows=50", "nColumns=4", "inDegrees=yes", "endheader",
                    "time\thip_flexion_r\tknee_angle_r\tground_force_vy"]
    names, data = read_mot(path)
    assert names == ("time", *cols)
    np.testing.assert_allclose(data, np.column_stack([t, *cols.values()]), rtol=1e-9)
    names, data = read_mot(shared_c3d_dir / "std_cop_walking2_grfs.sto")  # OpenSim's legacy header
    assert len(names) == 19 and data.shape == (101, 19) and data[-1, 0] == pytest.approx(4.9955)


def test_bad_opensim_files(tmp_path):
    bad = tmp_path / "bad.mot"
    bad.write_text("name\nversion=1\ntime\tq\n0\t1\n")
    with pytest.raises(InputError, match="no 'endheader'"):
        read_mot(bad)
    bad.write_text("x\nendheader\ntime\tq\n0\t1\n0.01\tup\n")
    with pytest.raises(InputError, match=r"bad\.mot: q: line 5: got 'up' \(expected a number\)"):
        read_mot(bad)
    with pytest.raises(InputError, match="knee: 2 values"):
        write_mot(tmp_path / "x.mot", [0.0, 0.1, 0.2], {"knee": [1.0, 2.0]})
    trc = tmp_path / "bad.trc"
    trc.write_text("hello\n")
    with pytest.raises(InputError, match="not a TRC file"):
        read_trc(trc)
    assert not (tmp_path / "x.mot").exists()


def test_markers_beyond_the_labs_reach_are_gaps(tmp_path):
    """A coordinate of 3·10³⁵ m is a damaged sample, not a position: a gap, warned, the rest kept."""
    path = _csv(tmp_path / "markers.csv", ["time_s", "A_x_m", "A_y_m", "A_z_m", "B_x_m", "B_y_m", "B_z_m"],
                [["0", "1", "2", "0.9", "1", "2", "1"], ["0.01", "1", "3e35", "0.9", "1", "2", "1"],
                 ["0.02", "1", "2", "0.9", "-9999.9", "2", "1"]])
    with pytest.warns(GaitWarning, match=r"markers\.csv: 1 marker samples beyond 10000 m .* read as gaps \(A\)"):
        markers = read_markers_csv(path)
    assert np.isnan(markers.positions_m[1, 0]).all() and np.isfinite(markers.positions_m[[0, 2]]).all()
    assert markers.positions_m[2, 1, 0] == pytest.approx(-9999.9)
