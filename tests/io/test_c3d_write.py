"""C3D writer: write → read_c3d round trips (two lab orientations) and ezc3d's own COP on the written file."""

from __future__ import annotations

import ezc3d
import numpy as np
import pytest

from gaitcli.core.recording import ForcePlate, Markers
from gaitcli.errors import GaitWarning, InputError
from gaitcli.io.c3d import read_c3d
from gaitcli.io.c3d.header import check_parameters
from gaitcli.io.c3d_write import DEFAULT_ORIGIN_MM, add_points, write_c3d

RATE_HZ, SUB, N_FRAMES = 100.0, 10, 60
Y_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])  # model_to_lab: model z -> lab +y


def _trial(rng):
    """A walker along model +x over two plates with a known COP path and free moment."""
    t = np.arange(N_FRAMES) / RATE_HZ
    body = np.array([[0.0, 0.0, 1.7], [0.0, 0.2, 1.45], [0.0, -0.2, 1.45], [0.0, 0.1, 0.95], [0.1, 0.1, 0.06]])
    pos = body[None] + 1.2 * t[:, None, None] * np.array([1.0, 0.0, 0.0]) + rng.normal(0, 0.002, (N_FRAMES, 5, 3))
    pos[7, 2] = np.nan
    pos[30:35, 4] = np.nan
    markers = Markers(("HEAD", "LSHO", "RSHO", "SACR", "LTOE"), pos, RATE_HZ, first_frame=11)
    ts = np.arange(N_FRAMES * SUB) / (RATE_HZ * SUB)
    plates, truth = [], []
    for k, cx in enumerate((0.3, 0.9)):
        # corners in C3D order for a z-up model: x = c1 - c2 along +x, y = c1 - c4 along -y (plate z down)
        corners = np.array([[cx + 0.25, -0.2, 0], [cx - 0.25, -0.2, 0], [cx - 0.25, 0.2, 0], [cx + 0.25, 0.2, 0]])
        centre = corners.mean(axis=0)
        stance = np.clip(np.sin(np.pi * (ts - 0.1 * k) / 0.45), 0.0, None) * ((ts - 0.1 * k) < 0.45)
        force = np.stack([80 * np.cos(9 * ts), -30 * np.sin(5 * ts), 5 + 750 * stance], axis=1)
        cop = centre + np.stack([-0.12 + 0.24 * ts / ts[-1], 0.03 * np.sin(4 * ts), 0 * ts], axis=1)
        free = 4.0 * np.sin(11 * ts)
        moment = np.cross(cop - centre, force) + free[:, None] * np.array([0.0, 0.0, 1.0])
        plates.append(ForcePlate(f"plate{k + 1}", force, moment, centre, corners, RATE_HZ * SUB))
        truth.append((cop, free))
    return markers, plates, truth


@pytest.fixture(scope="module")
def trial():
    return _trial(np.random.default_rng(7))


@pytest.mark.parametrize("model_to_lab", [None, Y_UP], ids=["z_up", "y_up"])
def test_write_then_read_returns_the_input(tmp_path, trial, model_to_lab):
    markers, plates, truth = trial
    path = write_c3d(tmp_path / "trial.c3d", markers, plates, model_to_lab=model_to_lab)
    rec = read_c3d(path)
    expected_R = np.eye(3) if model_to_lab is None else model_to_lab.T
    np.testing.assert_allclose(rec.lab_to_model, expected_R, atol=1e-12)
    assert rec.markers.labels == markers.labels and rec.markers.first_frame == 11
    assert rec.markers.rate_hz == RATE_HZ
    np.testing.assert_array_equal(np.isnan(rec.markers.positions_m), np.isnan(markers.positions_m))
    assert np.nanmax(np.abs(rec.markers.positions_m - markers.positions_m)) < 1e-4  # float32 mm storage
    for plate, back, (cop, free) in zip(plates, rec.plates, truth):
        assert back.rate_hz == RATE_HZ * SUB and back.plate_type == 2
        np.testing.assert_allclose(back.force_N, plate.force_N, atol=1e-3)
        np.testing.assert_allclose(back.moment_Nm, plate.moment_Nm, atol=1e-3)
        np.testing.assert_allclose(back.centre_m, plate.centre_m, atol=1e-6)
        np.testing.assert_allclose(back.corners_m, plate.corners_m, atol=1e-6)
        loaded = back.force_N[:, 2] > 20.0
        F, M = back.force_N[loaded], back.moment_Nm[loaded]
        rx, ry = -M[:, 1] / F[:, 2], M[:, 0] / F[:, 2]
        np.testing.assert_allclose(back.centre_m[:2] + np.stack([rx, ry], 1), cop[loaded, :2], atol=1e-4)
        np.testing.assert_allclose(M[:, 2] - (rx * F[:, 1] - ry * F[:, 0]), free[loaded], atol=1e-3)


def test_ezc3d_cop_and_origin_on_the_written_file(tmp_path, trial):
    """ezc3d (and so OpenSim) sees the ground reaction, the known COP (0.1 mm) and our ORIGIN."""
    markers, plates, truth = trial
    path = write_c3d(tmp_path / "trial.c3d", markers, plates, model_to_lab=Y_UP)
    c = ezc3d.c3d(str(path), extract_forceplat_data=True)
    fp = c["parameters"]["FORCE_PLATFORM"]
    assert list(fp["TYPE"]["value"]) == [2, 2]
    np.testing.assert_allclose(fp["ORIGIN"]["value"][:, 0], DEFAULT_ORIGIN_MM)
    assert c["parameters"]["POINT"]["UNITS"]["value"] == ["mm"]
    assert c["parameters"]["ANALOG"]["UNITS"]["value"][:6] == ["N", "N", "N", "Nmm", "Nmm", "Nmm"]
    for pf, plate, (cop, _) in zip(c["data"]["platform"], plates, truth):
        np.testing.assert_allclose(pf["origin"], -np.asarray(DEFAULT_ORIGIN_MM))  # ezc3d flips a positive z
        loaded = plate.force_N[:, 2] > 20.0
        np.testing.assert_allclose(pf["force"].T, plate.force_N @ Y_UP.T, atol=1e-3)  # reaction, lab axes
        np.testing.assert_allclose(pf["center_of_pressure"].T[loaded], cop[loaded] @ Y_UP.T * 1000.0, atol=0.1)
    # the channels hold the moment about the transducer origin, not about the surface centre
    raw = c["data"]["analogs"][0, 3:6]
    assert np.abs(raw.T - plates[0].moment_Nm @ Y_UP.T * 1000.0).max() > 100.0


def test_markers_only_file_and_reversed_corners(tmp_path, trial):
    markers, plates, _ = trial
    path = write_c3d(tmp_path / "markers_only.c3d", markers, [])
    with pytest.warns(GaitWarning, match="markers only"):
        rec = read_c3d(path)
    assert rec.plates == [] and rec.markers.n_frames == N_FRAMES
    # corners given with the plate z up are written in C3D order; the wrench is unchanged
    flipped = ForcePlate("p", plates[0].force_N, plates[0].moment_Nm, plates[0].centre_m,
                         plates[0].corners_m[[0, 3, 2, 1]], plates[0].rate_hz)
    back = read_c3d(write_c3d(tmp_path / "flip.c3d", markers, [flipped])).plates[0]
    np.testing.assert_allclose(back.corners_m, plates[0].corners_m, atol=1e-6)
    np.testing.assert_allclose(back.moment_Nm, plates[0].moment_Nm, atol=1e-3)


def test_bad_rates_and_rotations_are_refused_and_nothing_is_written(tmp_path, trial):
    markers, plates, _ = trial
    slow = ForcePlate("p", plates[0].force_N[:-5], plates[0].moment_Nm[:-5], plates[0].centre_m,
                      plates[0].corners_m, 995.0)
    target = tmp_path / "bad.c3d"
    with pytest.raises(InputError, match="not an integer multiple"):
        write_c3d(target, markers, [slow])
    with pytest.raises(InputError, match="proper 3x3 rotation"):
        write_c3d(target, markers, plates, model_to_lab=np.diag([1.0, 1.0, -1.0]))
    assert list(tmp_path.iterdir()) == []


def test_a_latin1_analog_unit_is_copied_as_text(tmp_path):
    """A unit byte that is not UTF-8 (Latin-1 'µV') comes from ezc3d as a surrogate escape, which ezc3d's writer
    refuses ("Value in parameters ANALOG:UNITS could not be converted to string"); the copy writes it as 'µV'."""
    n = 40
    markers = Markers(("A", "B"), np.tile([[[0.5, 0.1, 1.0], [0.5, -0.1, 1.0]]], (n, 1, 1)), 100.0)
    c = ezc3d.c3d(str(write_c3d(tmp_path / "a.c3d", markers, [])))
    c["parameters"]["ANALOG"]["RATE"]["value"] = np.array([200.0])
    c["parameters"]["ANALOG"]["LABELS"]["value"] = ["EMG1", "EMG2"]
    c["parameters"]["ANALOG"]["UNITS"]["value"] = ["xV", "V"]
    c["parameters"]["ANALOG"]["SCALE"]["value"] = np.ones(2)
    c["parameters"]["ANALOG"]["OFFSET"]["value"] = np.zeros(2, dtype=int)
    c["data"]["analogs"] = np.zeros((1, 2, 2 * n))
    path = tmp_path / "emg.c3d"
    c.write(str(path))
    data = bytearray(path.read_bytes())
    offset = (data[0] - 1) * 512
    units = check_parameters(path, offset, data[offset + 2], len(data))[("ANALOG", "UNITS")]
    assert data[units.data_offset] == ord("x")
    data[units.data_offset] = 0xB5  # Latin-1 'µ'
    path.write_bytes(bytes(data))
    raw = ezc3d.c3d(str(path))
    with pytest.raises(ValueError, match="ANALOG:UNITS could not be converted to string"):
        raw.write(str(tmp_path / "plain.c3d"))
    copy = add_points(path, tmp_path / "copy.c3d", {"X": np.zeros((n, 3))})
    assert ezc3d.c3d(str(copy))["parameters"]["ANALOG"]["UNITS"]["value"] == ["\u00b5V", "V"]


def test_points_added_beyond_255_read_back(tmp_path):
    """A file of 250 points (a full-body Plug-in Gait trial with Vicon's outputs holds 239) given 22 described
    points: the copy reads back with all 272 labels and the added values (the C3D library splits labels beyond
    255 into LABELS2; non-empty descriptions there made an unreadable file)."""
    n = 4
    labels = tuple(f"M{k:03d}" for k in range(250))
    source = write_c3d(tmp_path / "many.c3d", Markers(labels, np.ones((n, 250, 3)), 100.0), [])
    added = {f"P{k:02d}": np.full((n, 3), float(k)) for k in range(22)}
    copy = add_points(source, tmp_path / "copy.c3d", added, descriptions={k: f"gaitcli {k}" for k in added})
    c = ezc3d.c3d(str(copy))
    point = c["parameters"]["POINT"]
    got = list(point["LABELS"]["value"]) + list(point.get("LABELS2", {}).get("value", []))
    assert got == list(labels) + list(added)
    np.testing.assert_allclose(c["data"]["points"][:3, 250 + 21], 21.0)


def test_points_the_file_already_holds_are_replaced_one_label_each(tmp_path):
    """A C3D holding Vicon's RKneeAngles (and a list POINT:ANGLES naming it and RNeckAngles): the copy holds
    RKneeAngles once, with the new values, the file's other points and RNeckAngles untouched, the new point
    appended, POINT:ANGLES extended, and a warning names the replaced point."""
    n = 30
    rng = np.random.default_rng(3)
    old = rng.normal(size=(n, 3, 3))
    markers = Markers(("LASI", "RKneeAngles", "RNeckAngles"), old, 100.0)
    c = ezc3d.c3d(str(write_c3d(tmp_path / "vicon.c3d", markers, [])))
    c.add_parameter("POINT", "ANGLES", ["RKneeAngles", "RNeckAngles"])
    c.write(str(tmp_path / "vicon.c3d"))
    knee, hip = rng.normal(size=(n, 3)) * 30, rng.normal(size=(n, 3)) * 30
    knee[4] = np.nan
    with pytest.warns(GaitWarning, match=r"vicon.c3d: its own points RKneeAngles are replaced"):
        add_points(tmp_path / "vicon.c3d", tmp_path / "copy.c3d", {"RKneeAngles": knee, "RHipAngles": hip},
                   parameters={"POINT:ANGLES": ["RKneeAngles", "RHipAngles"]}, merged=("POINT:ANGLES",))
    back = ezc3d.c3d(str(tmp_path / "copy.c3d"))
    labels = back["parameters"]["POINT"]["LABELS"]["value"]
    assert labels == ["LASI", "RKneeAngles", "RNeckAngles", "RHipAngles"]
    assert back["parameters"]["POINT"]["ANGLES"]["value"] == ["RKneeAngles", "RNeckAngles", "RHipAngles"]
    points = back["data"]["points"][:3]
    fine = np.isfinite(knee).all(axis=1)
    np.testing.assert_allclose(points[:, 1, fine].T, knee[fine], rtol=1e-6, atol=1e-4)  # float32
    assert back["data"]["meta_points"]["residuals"][0, 1, 4] < 0
    np.testing.assert_allclose(points[:, 3].T, hip, rtol=1e-6, atol=1e-4)
    for j in (0, 2):
        np.testing.assert_allclose(points[:, j].T, old[:, j] * 1000.0, rtol=1e-6, atol=1e-3)  # stored in mm


def test_more_than_255_points_continue_in_labels2_and_descriptions2(tmp_path):
    """A C3D parameter counts its entries in one byte: 250 points plus 10 described ones are written as LABELS
    (255) + LABELS2 (5) and DESCRIPTIONS + DESCRIPTIONS2 (ezc3d split the labels but not the descriptions, and
    wrote a file it could not read back); a copy of that copy keeps all 265."""
    n = 5
    markers = Markers(tuple(f"M{k}" for k in range(250)), np.ones((n, 250, 3)), 100.0)
    source = write_c3d(tmp_path / "many.c3d", markers, [])
    added = {f"A{k}": np.full((n, 3), float(k)) for k in range(10)}
    add_points(source, tmp_path / "copy.c3d", added, descriptions={lab: "gaitcli" for lab in added})
    back = ezc3d.c3d(str(tmp_path / "copy.c3d"))
    point = back["parameters"]["POINT"]
    assert back["data"]["points"].shape[1] == 260
    assert point["LABELS"]["value"] + point["LABELS2"]["value"] == list(markers.labels) + list(added)
    assert point["DESCRIPTIONS2"]["value"] == ["gaitcli"] * 5
    with pytest.warns(GaitWarning, match="its own points A9 are replaced"):
        add_points(tmp_path / "copy.c3d", tmp_path / "again.c3d", {"A9": np.zeros((n, 3)), "B": np.ones((n, 3))})
    again = ezc3d.c3d(str(tmp_path / "again.c3d"))
    labels = again["parameters"]["POINT"]["LABELS"]["value"] + again["parameters"]["POINT"]["LABELS2"]["value"]
    assert labels == list(markers.labels) + list(added) + ["B"]
    np.testing.assert_array_equal(again["data"]["points"][:3, labels.index("A9")], 0.0)
