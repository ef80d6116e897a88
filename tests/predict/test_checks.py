"""The clinical checks of a predicted gait (gaitcli/predict/checks.py): normal walking passes every check (the
bundled reference's knee curve, measured on the sample trial, and a textbook vertical GRF: the sample trial walks
at 0.88 m/s, where the second peak stays at 0.98 body weights); curves with one known fault fail that one."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.predict.checks import gait_checks
from gaitcli.predict.reference import read_reference
from gaitcli.resources import bundled_reference

PCT = np.arange(101.0)
#: an ankle moment (N·m, dorsiflexion positive) with its plantarflexion peak at 48 % of the cycle
PUSH_OFF = -100 * np.exp(-((PCT - 48) / 8) ** 2)
#: a textbook vertical GRF in body weights (Perry: 1.15 at loading response, 0.75 in mid stance, 1.1 at push-off)
TEXTBOOK_FZ = 9.81 * np.interp(PCT, [0, 5, 13, 30, 48, 57, 62, 100], [0, 0.6, 1.15, 0.75, 1.1, 0.5, 0, 0])


@pytest.fixture(scope="module")
def normal():
    ref = read_reference(bundled_reference())
    knee, fz = ref.mean["knee_r_flexion_deg"], ref.mean["grf_z_r_N_per_kg"]
    stance = float(PCT[np.flatnonzero(fz > 0.2)[-1]])
    return knee, TEXTBOOK_FZ, stance


def test_normal_walking_passes_every_check(normal):
    knee, fz, stance = normal
    checks = gait_checks(PCT, knee, fz, PCT, PUSH_OFF, PCT, stance_pct=stance, double_support_pct=11.0)
    assert all(c["ok"] for c in checks.values()), checks
    first, valley, second = checks["vertical_grf"]["value"]
    assert first > 1.0 and second > 1.0 and valley < 1.0


def test_each_fault_fails_its_check(normal):
    knee, fz, stance = normal
    base = dict(stance_pct=stance, double_support_pct=11.0)
    single_hump = 1.05 * 9.81 * np.sin(np.pi * np.clip(PCT / stance, 0, 1))  # no valley, one peak
    assert not gait_checks(PCT, knee, single_hump, PCT, PUSH_OFF, PCT, **base)["vertical_grf"]["ok"]
    assert not gait_checks(PCT, 0.8 * knee, fz, PCT, PUSH_OFF, PCT, **base)["knee_swing_peak_deg"]["ok"]
    early = -100 * np.exp(-((PCT - 15) / 8) ** 2)  # the plantarflexion peak in the loading response
    assert not gait_checks(PCT, knee, fz, PCT, early, PCT, **base)["ankle_moment_peak_pct"]["ok"]
    assert not gait_checks(PCT, knee, fz, PCT, PUSH_OFF, PCT, stance_pct=75.0, double_support_pct=25.0
                           )["stance_pct"]["ok"]
    assert not gait_checks(PCT, knee, fz, PCT, PUSH_OFF, PCT, stance_pct=stance, double_support_pct=0.0
                           )["double_support_pct"]["ok"]
