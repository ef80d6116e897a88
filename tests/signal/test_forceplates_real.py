"""Cross-check of the COP and free moment against OpenSim's reading of a real trial (walking2.c3d).

``std_cop_walking2_grfs.sto`` is OpenSim's own output for the plates of
``walking2.c3d``: force, COP and free moment, lab axes, mm, no filtering, every
0.05 s. The plate wrench is taken from ezc3d (force in N, moment in N mm about
the centre of the top surface, lab axes) without going through gaitcli's reader,
so this checks the COP formula and its sign conventions only.
"""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.core.recording import ForcePlate
from gaitcli.signal.forceplates import centre_of_pressure, plate_load

pytestmark = pytest.mark.shared
ANALOG_HZ = 2000.0


@pytest.fixture(scope="module")
def walking2(shared_c3d_dir):
    ezc3d = pytest.importorskip("ezc3d")
    c3d = ezc3d.c3d(str(shared_c3d_dir / "walking2.c3d"), extract_forceplat_data=True)
    assert c3d["header"]["analogs"]["frame_rate"] == ANALOG_HZ
    plates = []
    for i, p in enumerate(c3d["data"]["platform"]):
        corners = p["corners"].T / 1000.0
        plates.append(ForcePlate(f"FP{i + 1}", p["force"].T.copy(), p["moment"].T / 1000.0, corners.mean(axis=0),
                                 corners, ANALOG_HZ))
    sto = np.loadtxt(shared_c3d_dir / "std_cop_walking2_grfs.sto", skiprows=6)
    return plates, sto


def test_cop_and_free_moment_match_opensim(walking2):
    plates, sto = walking2
    rows = np.rint(sto[:, 0] * ANALOG_HZ).astype(int)
    for i, plate in enumerate(plates):
        force, cop, free = (sto[:, 1 + 9 * i:4 + 9 * i], sto[:, 4 + 9 * i:7 + 9 * i] / 1000.0,
                            sto[:, 9 + 9 * i] / 1000.0)
        loaded = force[:, 2] > 100.0
        assert loaded.sum() >= 9
        np.testing.assert_allclose(plate.force_N[rows[loaded]], force[loaded], atol=1e-6)
        ours, ours_free = centre_of_pressure(plate.force_N[rows], plate.moment_Nm[rows], plate.centre_m)
        np.testing.assert_allclose(ours[loaded], cop[loaded], atol=1e-9)  # metres
        np.testing.assert_allclose(ours_free[loaded], free[loaded], atol=1e-6)  # N m
        # filtered at 6 Hz before forming the COP: within 5 mm of the unfiltered COP away from the
        # loading edges (measured 0.3-4 mm above 400 N; 22 mm at a heel strike row with 294 N)
        load = plate_load(plate, cutoff_hz=6.0, threshold_N=20.0)
        strong = force[:, 2] > 400.0
        error_m = np.linalg.norm(load.cop_m[rows[strong]] - cop[strong], axis=1)
        assert error_m.max() < 5e-3
