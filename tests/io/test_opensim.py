"""OpenSim's .trc and .mot/.sto files: OpenSim's header lines, and round trips to the written precision."""

from __future__ import annotations

import numpy as np

from gaitcli.io.opensim import read_motion, read_trc, write_motion, write_trc

RNG = np.random.default_rng(5)


def test_a_trc_file_has_opensims_header_and_reads_back(tmp_path):
    positions = RNG.normal(500.0, 300.0, (7, 2, 3))
    positions[3, 1] = np.nan  # a marker not seen in one frame: empty cells
    path = write_trc(tmp_path / "walk.trc", ("RASI", "LASI"), positions, 100.0, first_frame=11)
    lines = path.read_text().splitlines()
    assert lines[0] == "PathFileType\t4\t(X/Y/Z)\twalk.trc"
    assert lines[1] == ("DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame\t"
                        "OrigNumFrames")
    assert lines[2] == "100\t100\t7\t2\tmm\t100\t11\t7"
    assert lines[3] == "Frame#\tTime\tRASI\t\t\tLASI" and lines[4] == "\t\tX1\tY1\tZ1\tX2\tY2\tZ2" and lines[5] == ""
    assert lines[6].startswith("11\t0.00000\t") and lines[9].endswith("\t\t\t")
    header, labels, time, back = read_trc(path)
    assert header["NumFrames"] == "7" and header["Units"] == "mm" and labels == ("RASI", "LASI")
    np.testing.assert_allclose(time, np.arange(7) / 100.0)
    np.testing.assert_allclose(back, positions, atol=5e-6, equal_nan=True)  # 5 decimals of a mm


def test_mot_and_sto_files_have_opensims_header_and_read_back(tmp_path):
    columns = {"time": np.arange(5) / 100.0, "hip_r_flexion": RNG.normal(0, 20, 5),
               "knee_r_flexion": RNG.normal(0, 20, 5)}
    for name, degrees in (("coordinates.mot", True), ("joint_moments.sto", False)):
        path = write_motion(tmp_path / name, columns, in_degrees=degrees)
        lines = path.read_text().splitlines()
        assert lines[:6] == [path.stem, "version=1", "nRows=5", "nColumns=3", f"inDegrees={'yes' if degrees else 'no'}",
                             "endheader"]
        assert lines[6] == "time\thip_r_flexion\tknee_r_flexion"
        header, back = read_motion(path)
        assert header["nRows"] == "5" and list(back) == list(columns)
        for key in columns:
            np.testing.assert_allclose(back[key], columns[key], rtol=1e-7)  # 8 significant digits
