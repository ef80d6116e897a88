"""C3D reader: one shared test over every real file, OpenSim cross-check, synthetic files with known content."""

from __future__ import annotations

import shutil
import warnings
from pathlib import Path

import ezc3d
import numpy as np
import pytest

from gaitcli.errors import GaitWarning, InputError
from gaitcli.io.c3d import read_c3d
from gaitcli.io.tables import read_mot
from tests.conftest import SHARED_C3D

SHARED_FILES = sorted(p.name for p in SHARED_C3D.glob("*.c3d")) or ["walking2.c3d"]
REFUSED = {"sgi_int.c3d": "MIPS/SGI processor format is not supported; expected Intel or DEC (re-export the file)"}


def _read_quietly(path, **kw):
    """read_c3d with its GaitWarnings captured; returns (recording, warning messages)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", GaitWarning)
        rec = read_c3d(path, **kw)
    return rec, [str(w.message) for w in caught if issubclass(w.category, GaitWarning)]


def _cop_and_free_moment(plate):
    """COP (n, 3) and free moment T_z (n,) from a z-up plate wrench about its surface centre."""
    F, M = plate.force_N, plate.moment_Nm
    with np.errstate(divide="ignore", invalid="ignore"):
        rx, ry = -M[:, 1] / F[:, 2], M[:, 0] / F[:, 2]
        tz = M[:, 2] - (rx * F[:, 1] - ry * F[:, 0])
    return plate.centre_m + np.stack([rx, ry, np.zeros_like(rx)], axis=1), tz


# --------------------------------------------------------------- shared files


@pytest.mark.shared
@pytest.mark.parametrize("name", SHARED_FILES)
def test_every_shared_file_is_read_plausibly_or_refused_clearly(shared_c3d_dir, name):
    path = shared_c3d_dir / name
    if name in REFUSED:
        with pytest.raises(InputError) as info:
            read_c3d(path)
        assert str(path) in str(info.value) and REFUSED[name] in str(info.value)
        assert "\n" not in str(info.value) and info.value.exit_code == 2
        return
    rec, _ = _read_quietly(path)
    R = rec.lab_to_model
    assert np.allclose(R @ R.T, np.eye(3)) and np.isclose(np.linalg.det(R), 1.0)
    p = rec.markers.positions_m
    assert p.shape == (rec.markers.n_frames, len(rec.markers.labels), 3)
    assert len(set(rec.markers.labels)) == len(rec.markers.labels)
    assert np.isfinite(p).any()
    assert np.nanmax(np.abs(p)) < 20.0  # metres, not millimetres
    assert -0.05 < np.nanmin(p[..., 2]) and np.nanmax(p[..., 2]) < 2.5  # heights above the floor, z up
    for plate in rec.plates:
        assert np.isfinite(plate.force_N).all() and np.isfinite(plate.moment_Nm).all()
        assert plate.corners_m.shape == (4, 3)
        np.testing.assert_allclose(plate.centre_m, plate.corners_m.mean(axis=0))
        assert abs(plate.centre_m[2]) < 0.02  # plates are in the floor
        assert plate.force_N[:, 2].min() > -60.0  # ground-on-subject: never strongly downward
        assert plate.rate_hz == pytest.approx(rec.markers.rate_hz * plate.n_samples / rec.markers.n_frames)
        cop, _ = _cop_and_free_moment(plate)
        loaded = plate.force_N[:, 2] > 100.0
        if loaded.any():  # under load the COP lies on the plate (5 cm margin)
            lo, hi = plate.corners_m.min(axis=0) - 0.05, plate.corners_m.max(axis=0) + 0.05
            assert np.all((cop[loaded, :2] >= lo[:2]) & (cop[loaded, :2] <= hi[:2]))


@pytest.mark.shared
def test_duplicate_labels_are_renamed_and_warned(shared_c3d_dir):
    with pytest.warns(GaitWarning) as record:
        rec = read_c3d(shared_c3d_dir / "duplicate_labels.c3d")
    messages = [str(w.message) for w in record]
    dup = next(m for m in messages if "duplicate marker labels" in m)
    assert "T8 (points 1, 47, 48) -> T8, T8_2, T8_3" in dup
    assert "PSRG (points 13, 30, 38, 41, 44) -> PSRG, PSRG_2, PSRG_3, PSRG_4, PSRG_5" in dup
    assert any("markers only" in m for m in messages) and rec.plates == []
    assert dup in rec.notes
    labels = rec.markers.labels
    assert len(labels) == 48 and len(set(labels)) == 48
    assert labels[0] == "T8" and labels[46:] == ("T8_2", "T8_3")


@pytest.mark.shared
def test_bts_has_six_plates_and_labels_with_spaces(shared_c3d_dir):
    rec, messages = _read_quietly(shared_c3d_dir / "BTS.c3d")
    assert [p.name for p in rec.plates] == [f"plate{k}" for k in range(1, 7)]
    assert "r should" in rec.markers.labels and "l asis" in rec.markers.labels
    for k in (2, 3, 6):
        assert any(f"plate {k} never sees a load" in m for m in messages)
    # BTS is y-up in the lab: model z is lab y, the walk goes along lab +x
    np.testing.assert_allclose(rec.lab_to_model, [[1, 0, 0], [0, 0, -1], [0, 1, 0]])


@pytest.mark.shared
@pytest.mark.shared
def test_the_subject_data_a_file_records_are_read(shared_c3d_dir):
    rec, _ = _read_quietly(shared_c3d_dir / "Eb015pr.c3d")  # c3d.org Sample01: SUBJECT:WEIGHT, HEIGHT
    assert rec.subject_metadata == {"SUBJECT:WEIGHT": pytest.approx(82.7), "SUBJECT:HEIGHT": pytest.approx(1.63)}
    rec, _ = _read_quietly(shared_c3d_dir / "Qualisys.c3d")  # a PROCESSING group with no subject data
    assert rec.subject_metadata == {}


def test_walking2_matches_opensim(shared_c3d_dir):
    """Lab axes, unfiltered: force within 1 N, COP within 1 mm, free moment within 1 N·mm where Fz > 20 N."""
    rec, _ = _read_quietly(shared_c3d_dir / "walking2.c3d", to_model_axes=False)
    np.testing.assert_allclose(rec.lab_to_model, np.eye(3))
    names, sto = read_mot(shared_c3d_dir / "std_cop_walking2_grfs.sto")
    assert names[:4] == ("time", "f1_1", "f1_2", "f1_3")
    _, at_origin = read_mot(shared_c3d_dir / "std_walking2_grfs.sto")
    assert sto.shape == (101, 19)
    n_loaded = 0
    for k, plate in enumerate(rec.plates):
        rows = np.round(sto[:, 0] * plate.rate_hz).astype(int)
        F = plate.force_N[rows]
        cop, tz = _cop_and_free_moment(plate)
        loaded = F[:, 2] > 20.0
        n_loaded += loaded.sum()
        cols = slice(1 + 9 * k, 10 + 9 * k)
        f_sto, p_sto, m_sto = np.split(sto[:, cols], 3, axis=1)
        assert np.abs(F - f_sto).max() < 1.0
        assert np.abs(cop[rows][loaded] * 1000.0 - p_sto[loaded]).max() < 1.0
        assert np.abs(tz[rows][loaded] * 1000.0 - m_sto[loaded, 2]).max() < 1.0
        np.testing.assert_allclose(m_sto[:, :2], 0.0)  # the .sto's moment at the COP is the free moment only
        # second file: the raw wrench at the plate "origin", which OpenSim puts at the surface centre
        o_f, o_p, o_m = np.split(at_origin[:, cols], 3, axis=1)
        np.testing.assert_allclose(o_p, np.tile(plate.centre_m * 1000.0, (101, 1)), atol=1e-3)
        assert np.abs(plate.moment_Nm[rows] * 1000.0 - o_m).max() < 1.0
    assert n_loaded >= 20  # the comparison did look at loaded samples of both plates


@pytest.mark.shared
def test_integer_and_float_storage_of_one_trial_agree(shared_c3d_dir):
    pi, _ = _read_quietly(shared_c3d_dir / "Eb015pi.c3d")
    pr, _ = _read_quietly(shared_c3d_dir / "Eb015pr.c3d")
    assert pi.markers.labels == pr.markers.labels
    np.testing.assert_array_equal(np.isnan(pi.markers.positions_m), np.isnan(pr.markers.positions_m))
    assert np.nanmax(np.abs(pi.markers.positions_m - pr.markers.positions_m)) < 1e-4  # integer step 0.083 mm
    for a, b in zip(pi.plates, pr.plates):
        np.testing.assert_allclose(a.force_N, b.force_N, atol=1e-6)
    # FORCE_PLATFORM:ZERO = frames 1-10 removes the 20-30 N offsets of the unloaded plates
    assert any("ZERO baseline" in n for n in pr.notes)
    for plate in pr.plates:
        np.testing.assert_allclose(plate.force_N[:40].mean(axis=0), 0.0, atol=1.0)


@pytest.mark.shared
def test_kistler_type3_keeps_ezc3d_corrected_cop(shared_c3d_dir):
    path = shared_c3d_dir / "FP_Type3.c3d"
    rec, messages = _read_quietly(path, to_model_axes=False)
    assert [p.plate_type for p in rec.plates] == [3, 3]
    assert any("plate 2 never sees a load" in m for m in messages)
    pf = ezc3d.c3d(str(path), extract_forceplat_data=True)["data"]["platform"][0]
    cop, _ = _cop_and_free_moment(rec.plates[0])
    expected = pf["center_of_pressure"].T / 1000.0
    uncorrected = rec.plates[0].centre_m + _plate_frame_cop(pf)
    assert np.abs(cop[:, :2] - expected[:, :2]).max() < 1e-6
    assert np.abs(uncorrected[:, :2] - expected[:, :2]).max() > 2e-4  # the correction is ~0.4 mm here


def _plate_frame_cop(pf):
    """COP offset from the centre (m, lab) without FPCOPPOLY, from ezc3d's moment (independent path)."""
    c = pf["corners"].T
    x, y = c[0] - c[1], c[0] - c[3]
    z = np.cross(x, y)
    y = np.cross(z, x)
    R = np.stack([v / np.linalg.norm(v) for v in (x, y, z)], axis=1)
    Fp, Mp = R.T @ pf["force"], R.T @ pf["moment"]
    r = np.stack([-Mp[1] / Fp[2], Mp[0] / Fp[2], 0 * Fp[0]])
    return (R @ r).T / 1000.0


@pytest.mark.shared
def test_reading_does_not_modify_the_input(shared_c3d_dir, tmp_path):
    copy = tmp_path / "FP_Type3.c3d"
    shutil.copy2(shared_c3d_dir / "FP_Type3.c3d", copy)
    before, mtime = copy.read_bytes(), copy.stat().st_mtime_ns
    _read_quietly(copy)
    assert copy.read_bytes() == before and copy.stat().st_mtime_ns == mtime


@pytest.mark.shared
@pytest.mark.parametrize(
    "cut, field",
    [(700, "parameters"), (3000, "parameters"), (0.5, "data"), (0.999, "data")],
)
def test_truncated_files_are_refused(shared_c3d_dir, tmp_path, cut, field):
    """ezc3d hangs on a cut parameter section and silently drops frames of a cut data section."""
    data = (shared_c3d_dir / "walking2.c3d").read_bytes()
    n = cut if isinstance(cut, int) else int(len(data) * cut)
    path = tmp_path / "cut.c3d"
    path.write_bytes(data[:n])
    with pytest.raises(InputError, match="truncated") as info:
        read_c3d(path)
    assert info.value.field == field and str(path) in str(info.value)


# ------------------------------------------------------------ bad inputs


def test_missing_and_non_c3d_files_are_refused(tmp_path):
    with pytest.raises(InputError, match="file not found"):
        read_c3d(tmp_path / "absent.c3d")
    text = tmp_path / "notes.c3d"
    text.write_text("time_s,x\n" * 100)
    with pytest.raises(InputError, match="not a C3D file") as info:
        read_c3d(text)
    assert str(text) in str(info.value) and info.value.exit_code == 2
    pdf = tmp_path / "report.c3d"
    pdf.write_bytes(b"%PDF-1.7\n" + b"x" * 2000)  # byte 2 is 'P' = 0x50, C3D's key: once called "truncated"
    with pytest.raises(InputError, match="not a C3D file: it is a PDF document"):
        read_c3d(pdf)
    short = tmp_path / "short.c3d"
    short.write_text("hello")
    with pytest.raises(InputError, match="shorter than the 512-byte header"):
        read_c3d(short)


# ------------------------------------------------------- synthetic C3D files

RATE_HZ, SUB = 100.0, 10
# plate corners in C3D order (x = c1 - c2 along lab +x, y = c1 - c4 along lab -y, z into the floor)
CORNERS_MM = np.array([[800.0, 300.0, 0.0], [200.0, 300.0, 0.0], [200.0, 700.0, 0.0], [800.0, 700.0, 0.0]])
R_PLATE = np.array([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]])  # columns: plate axes in lab


def _raw_c3d(path, labels, positions_mm, *, extra_point=None, units="mm", plate_type=None, channels=None,
             analog_units=None, length_per_mm=1.0):
    """Write a C3D with ezc3d directly (not through gaitcli): points and optionally one plate.

    ``length_per_mm`` scales positions, corners and ORIGIN into the file's POINT:UNITS.
    """
    n_frames = positions_mm.shape[0]
    c = ezc3d.c3d()
    params = c["parameters"]
    params["POINT"]["RATE"]["value"] = np.array([RATE_HZ])
    params["POINT"]["LABELS"]["value"] = list(labels)
    params["POINT"]["DESCRIPTIONS"]["value"] = [""] * len(labels)
    params["POINT"]["UNITS"]["value"] = [units]
    pts = np.ones((4, len(labels), n_frames))
    pts[:3] = np.transpose(np.nan_to_num(positions_mm), (2, 1, 0)) * length_per_mm
    c["data"]["points"] = pts
    c["data"]["meta_points"]["residuals"] = np.where(np.isnan(positions_mm).any(axis=2), -1.0, 0.0).T[None]
    c["data"]["meta_points"]["camera_masks"] = np.zeros((7, len(labels), n_frames), dtype=bool)
    if plate_type is None:
        params["ANALOG"]["RATE"]["value"] = np.array([RATE_HZ])
        c["data"]["analogs"] = np.zeros((1, 0, n_frames))
    else:
        n_ch = channels.shape[0]
        params["ANALOG"]["RATE"]["value"] = np.array([RATE_HZ * SUB])
        params["ANALOG"]["LABELS"]["value"] = [f"ch{i + 1}" for i in range(n_ch)]
        params["ANALOG"]["UNITS"]["value"] = analog_units or ["N"] * n_ch
        params["ANALOG"]["SCALE"]["value"] = np.ones(n_ch)
        fp = params["FORCE_PLATFORM"]
        fp["USED"]["value"] = np.array([1])
        fp["TYPE"]["value"] = np.array([plate_type])
        fp["ZERO"]["value"] = np.array([0, 0])
        fp["CORNERS"]["value"] = CORNERS_MM.T[:, :, None] * length_per_mm
        fp["ORIGIN"]["value"] = np.array([[3.0], [-2.0], [-40.0]]) * length_per_mm
        fp["CHANNEL"]["value"] = np.arange(1, n_ch + 1).reshape(n_ch, 1)
        c["data"]["analogs"] = channels[None]
    for name, value in (extra_point or {}).items():
        c.add_parameter("POINT", name, value)
    c.write(str(path))
    return path


def _standing_markers(n_frames=20):
    """Four markers above the plate walking slowly along +x (mm), lab z up."""
    base = np.array([[500.0, 500.0, 1700.0], [500.0, 420.0, 950.0], [500.0, 580.0, 950.0], [520.0, 450.0, 60.0]])
    return base[None] + np.arange(n_frames)[:, None, None] * np.array([20.0, 0.0, 0.0])


def test_model_outputs_dropped_subject_prefix_units_and_missing(tmp_path):
    pos = np.concatenate([_standing_markers(), np.full((20, 1, 3), 30.0)], axis=1)
    pos[3, 1] = np.nan  # residual -1
    pos[4, 2] = 0.0  # exactly (0, 0, 0): missing too
    labels = ["Pat: LFHD", "Pat:LASI ", " Pat:RASI", "Pat:LTOE", "Pat:LHipAngles"]
    path = _raw_c3d(tmp_path / "pig.c3d", labels, pos / 10.0, units="cm",
                    extra_point={"ANGLES": ["Pat:LHipAngles"]})
    with pytest.warns(GaitWarning, match="markers only"):
        rec = read_c3d(path, to_model_axes=False)
    assert rec.markers.labels == ("LFHD", "LASI", "RASI", "LTOE")
    assert any("'Pat:'" in n for n in rec.notes) and any("model-output points dropped" in n for n in rec.notes)
    expected = pos[:, :4] / 1000.0
    expected[3, 1] = np.nan
    expected[4, 2] = np.nan
    np.testing.assert_allclose(rec.markers.positions_m, expected, atol=1e-6)


def test_all_nan_marker_is_warned_by_name(tmp_path):
    pos = np.concatenate([_standing_markers(), np.full((20, 1, 3), np.nan)], axis=1)
    path = _raw_c3d(tmp_path / "gone.c3d", ["A", "B", "C", "D", "GHOST"], pos)
    with pytest.warns(GaitWarning) as record:
        rec = read_c3d(path)
    assert any("never seen" in str(w.message) and "GHOST" in str(w.message) for w in record)
    assert np.isnan(rec.markers.get("GHOST")).all()


def test_type1_plate_gives_the_stored_cop_and_free_moment(tmp_path):
    """TYPE 1 channels (Fx, Fy, Fz, COPx, COPy, Tz in plate axes, z into the floor) → known lab wrench."""
    n = 20 * SUB
    t = np.arange(n) / (RATE_HZ * SUB)
    f_lab = np.stack([60 * np.sin(9 * t), -25 * np.cos(4 * t), 300 + 400 * np.sin(np.pi * t / t[-1])], axis=1)
    r_lab_mm = np.stack([120 * np.cos(3 * t), 40 * np.sin(5 * t), 0 * t], axis=1)  # COP - centre
    tz_up_Nmm = 2000 * np.sin(7 * t)  # free moment about lab +z
    f_plate = f_lab @ R_PLATE  # rows R^T f
    r_plate = r_lab_mm @ R_PLATE
    channels = np.stack([*f_plate.T, r_plate[:, 0], r_plate[:, 1], -tz_up_Nmm])  # Tz about plate z (down)
    path = _raw_c3d(tmp_path / "t1.c3d", ["A", "B", "C", "D"], _standing_markers(), plate_type=1, channels=channels)
    rec, messages = _read_quietly(path, to_model_axes=False)
    assert messages == []
    plate = rec.plates[0]
    assert plate.plate_type == 1
    np.testing.assert_allclose(plate.force_N, f_lab, atol=1e-3)
    cop, tz = _cop_and_free_moment(plate)
    np.testing.assert_allclose(cop, CORNERS_MM.mean(axis=0) / 1000 + r_lab_mm / 1000, atol=1e-6)
    np.testing.assert_allclose(tz, tz_up_Nmm / 1000, atol=1e-5)


def test_downward_plate_force_is_negated_to_ground_on_subject(tmp_path):
    """A file storing the subject-on-plate force gives the same ForcePlate as one storing the reaction."""
    n = 20 * SUB
    t = np.arange(n) / (RATE_HZ * SUB)
    f_lab = np.stack([30 + 0 * t, 10 * np.sin(t), 500 + 100 * np.sin(6 * t)], axis=1)
    m_lab_Nmm = np.stack([40000 * np.sin(3 * t), -30000 + 0 * t, 500 * np.cos(t)], axis=1)  # about the centre
    origin = np.array([3.0, -2.0, -40.0])  # negative z: ezc3d takes it as transducer origin -> surface centre
    files = []
    for sign in (1.0, -1.0):
        f_p = sign * f_lab @ R_PLATE
        m_p = sign * m_lab_Nmm @ R_PLATE - np.cross(f_p, origin)  # moment about the transducer origin
        channels = np.concatenate([f_p, m_p], axis=1).T
        files.append(_raw_c3d(tmp_path / f"s{sign:+.0f}.c3d", ["A", "B", "C", "D"], _standing_markers(),
                              plate_type=2, channels=channels))
    reaction, _ = _read_quietly(files[0], to_model_axes=False)
    action, _ = _read_quietly(files[1], to_model_axes=False)
    assert any("negated" in n for n in action.notes) and not any("negated" in n for n in reaction.notes)
    for rec in (reaction, action):
        np.testing.assert_allclose(rec.plates[0].force_N, f_lab, atol=1e-3)
        np.testing.assert_allclose(rec.plates[0].moment_Nm, m_lab_Nmm / 1000, atol=1e-4)


def test_moment_channels_in_nmm_with_positions_in_metres(tmp_path):
    """POINT:UNITS m but moment channels in N·mm: ezc3d mixes the units, the reader rescales them."""
    n = 20 * SUB
    t = np.arange(n) / (RATE_HZ * SUB)
    f_lab = np.stack([20 * np.sin(5 * t), 15 + 0 * t, 400 + 300 * np.sin(2 * t)], axis=1)
    m_lab_Nmm = np.stack([30000 * np.cos(3 * t), -20000 * np.sin(t), 800 + 0 * t], axis=1)
    origin_mm = np.array([3.0, -2.0, -40.0])
    f_p = f_lab @ R_PLATE
    m_p = m_lab_Nmm @ R_PLATE - np.cross(f_p, origin_mm)
    channels = np.concatenate([f_p, m_p], axis=1).T
    units = ["N", "N", "N", "Nmm", "Nmm", "Nmm"]
    path = _raw_c3d(tmp_path / "m.c3d", ["A", "B", "C", "D"], _standing_markers(), units="m", plate_type=2,
                    channels=channels, analog_units=units, length_per_mm=1e-3)
    rec, _ = _read_quietly(path, to_model_axes=False)
    assert any("rescaled" in n for n in rec.notes)
    np.testing.assert_allclose(rec.plates[0].force_N, f_lab, atol=1e-3)
    np.testing.assert_allclose(rec.plates[0].moment_Nm, m_lab_Nmm / 1000, atol=1e-4)
    np.testing.assert_allclose(rec.plates[0].centre_m, CORNERS_MM.mean(axis=0) / 1000, atol=1e-9)


def test_unsupported_plate_type_is_refused_with_a_warning(tmp_path):
    channels = np.zeros((6, 20 * SUB))
    path = _raw_c3d(tmp_path / "t5.c3d", ["A", "B", "C", "D"], _standing_markers(), plate_type=5, channels=channels)
    with pytest.warns(GaitWarning) as record:
        rec = read_c3d(path)
    messages = [str(w.message) for w in record]
    assert any("plate 1 (TYPE 5) refused" in m and "TYPE 1-4" in m for m in messages)
    assert rec.plates == [] and rec.markers.n_frames == 20


def test_unknown_point_units_are_refused(tmp_path):
    path = _raw_c3d(tmp_path / "inch.c3d", ["A", "B", "C", "D"], _standing_markers(), units="in")
    with pytest.raises(InputError, match=r"POINT:UNITS: got 'in' \(expected mm, cm or m\)"):
        read_c3d(path)


def test_missing_point_units_are_guessed_with_a_warning(tmp_path):
    path = _raw_c3d(tmp_path / "nounit.c3d", ["A", "B", "C", "D"], _standing_markers(), units="")
    rec, messages = _read_quietly(path)
    assert any("POINT:UNITS missing" in m for m in messages)
    assert 0.0 < np.nanmax(rec.markers.positions_m[..., 2]) < 2.0  # taken as mm


def test_file_name_is_in_every_refusal(tmp_path):
    path = tmp_path / "folder.c3d"
    path.mkdir()
    with pytest.raises(InputError, match="not a file"):
        read_c3d(path)
    assert Path(path).is_dir()


# ------------------------------------------------------- damaged files, read in a child process

def test_a_latin1_label_is_read_as_text(tmp_path):
    """A label byte that is not UTF-8 (Latin-1 'é' = 0xE9) reaches gait as 'é', not as a surrogate escape that no
    CSV or HDF5 writer accepts (once exit 1, UnicodeEncodeError, an empty gait_out/)."""
    path = _raw_c3d(tmp_path / "t.c3d", ["LHEEX", "RHEE"], _standing_markers()[:, :2])
    data = bytearray(path.read_bytes())
    at = data.find(b"LHEEX")
    data[at + 4] = 0xE9
    path.write_bytes(bytes(data))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", GaitWarning)
        labels = read_c3d(path).markers.labels
    assert labels[0] == "LHEE\u00e9" and labels[0].encode("utf-8")


def _misbehaving_reader(monkeypatch, behaviour):
    """read_c3d's child runs ``behaviour`` instead of the C3D library (fork copies the patched module)."""
    import gaitcli.io.c3d as c3d_module

    monkeypatch.setattr(c3d_module, "read_c3d_here", lambda *args, **kwargs: behaviour())


def _sample_path():
    from gaitcli.resources import sample_trial

    return sample_trial("normal") / "trial.c3d"


def test_a_crash_in_the_c3d_library_is_an_input_error(monkeypatch):
    import os
    import signal

    _misbehaving_reader(monkeypatch, lambda: os.kill(os.getpid(), signal.SIGSEGV))
    with pytest.raises(InputError, match="the C3D library crashed on it") as info:
        read_c3d(_sample_path())
    assert "\n" not in str(info.value)


def test_a_hang_is_stopped_at_the_time_limit(monkeypatch):
    import multiprocessing
    import time

    import gaitcli.io.c3d as c3d_module

    # the wall-time limit at once (no waiting on for a child that computes: this one sleeps), 0.5 s
    monkeypatch.setattr(c3d_module, "READ_TIME_S", 0.1)
    monkeypatch.setattr(c3d_module, "READ_WALL_FACTOR", 1.0)
    _misbehaving_reader(monkeypatch, lambda: time.sleep(60))
    with pytest.raises(InputError, match="took longer than"):
        read_c3d(_sample_path())
    assert not multiprocessing.active_children()  # the sleeping child was killed, not left behind


def test_a_runaway_allocation_is_capped(monkeypatch):
    _misbehaving_reader(monkeypatch, lambda: np.ones((1 << 31,)))  # 16 GB
    with pytest.raises(InputError, match="needs more than 1.0 GB"):
        read_c3d(_sample_path())


def test_warnings_of_the_read_reach_the_caller(tmp_path):
    path = _raw_c3d(tmp_path / "t.c3d", ["A", "B"], _standing_markers()[:, :2])
    with pytest.warns(GaitWarning, match="no usable force plates"):
        read_c3d(path)


@pytest.mark.parametrize("offset,value,says", [(512 + 2, 0x01, "at byte .*run past the section's end"),
                                              (512 + 2, 0x00, "holds 0 blocks")])
def test_parameter_records_past_the_section_are_refused_before_the_library(tmp_path, offset, value, says):
    data = bytearray(_sample_path().read_bytes())
    data[offset] = value
    path = tmp_path / "damaged.c3d"
    path.write_bytes(bytes(data))
    with pytest.raises(InputError, match=says):
        read_c3d(path)


@pytest.mark.skipif(__import__("os").geteuid() == 0, reason="root reads any file")
def test_an_unreadable_file_is_an_input_error(tmp_path):
    path = tmp_path / "trial.c3d"
    shutil.copy(_sample_path(), path)
    path.chmod(0)
    with pytest.raises(InputError, match="cannot be read \\(permission denied\\)"):
        read_c3d(path)


def test_a_busy_read_is_stopped_at_its_processor_time(monkeypatch):
    """A read that computes for ever ends at its processor-time limit (SIGXCPU), however loaded the machine."""
    import multiprocessing

    import gaitcli.io.c3d as c3d_module

    def spin():
        while True:
            pass

    monkeypatch.setattr(c3d_module, "READ_TIME_S", 0.01)  # with the file's 0.4 MB: 1 s of processor time
    _misbehaving_reader(monkeypatch, spin)
    with pytest.raises(InputError, match=r"took longer than \d+ s of processor time"):
        read_c3d(_sample_path())
    assert not multiprocessing.active_children()
