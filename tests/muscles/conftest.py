"""A realistic synthetic walking cycle for the muscle-stage tests (and benchmarks/bench_muscles.py).

Normal walking of a 65 kg, 1.70 m man at 1.25 m/s with a 1.1 s stride
(stride length 1.375 m), sampled at 100 Hz, right side:

- sagittal angles: 6-harmonic Fourier series fitted (least squares, on a
  periodic cubic spline through the key points) to key points shaped like
  Winter's normative natural-cadence curves (Winter, *Biomechanics and Motor
  Control of Human Movement*): knee flexion 18° at 15 % (loading response),
  5° at 42 %, 62° at 72 % (swing); ankle dorsiflexion −6° at 7 %, 11° at 45 %,
  −17° at 66 %; thigh angle (absolute, from the vertical) 24° at heel strike,
  −15.5° at 55 %, 26° at 87 %, its stance values chosen so that the ankle
  stays within 5 cm of one spot of the floor from 10 % to 45 % (foot flat)
  at the stride length 1.375 m;
- hip centre: forward at the mean speed with a ±1 cm fluctuation twice per
  stride, vertical excursion ±2 cm peaking in mid-stance (30 % and 80 %), the
  mean height set so the ankle is 7 cm above the floor at 30 %;
- ground reaction in stance (0–62 % of the cycle, heel strike at 0 and 1.1 s,
  toe off at 0.682 s): vertical force ∝ sin^1.5(πs)·(2.2 − 1.6 sin²(πs)) over
  stance s ∈ [0, 1] (double hump, 1.16 BW at 17 % of the cycle, valley
  0.82 BW; zero with zero slope at heel strike and toe off; scaled so that the
  two legs' impulse equals BW × period), centre of pressure from 5 cm behind
  to 15 cm ahead of the ankle (heel → toe), fore–aft force such that the
  ground reaction points at a virtual pivot 0.3 m above the hip centre (as in
  inverted-pendulum walking; braking −0.18 BW at 14 %, propulsion +0.15 BW at
  51 %, net impulse −0.009 BW·s); zero force and NaN COP in swing.
  The joint moments follow Winter's pattern: hip extensor in loading
  (−30 N·m at 14 %) and flexor in pre-swing (+45 N·m at 58 %), knee extensor
  in loading (−34 N·m), ankle dorsiflexor at loading (+18 N·m) and
  plantarflexor at push-off (−80 N·m = 1.2 N·m/kg at 48 %).

The subject's size, the push-off timing and the smooth unloading were chosen
so that the Table A.1 muscles can follow the moments within 0 ≤ u ≤ 1 also
frame by frame (MSO); a 75 kg subject with the same kinematics exceeds the
hip flexors and soleus at push-off.

The table covers 0.3 s before and after the cycle (the functions are
periodic), so a non-periodic interval such as the swing phase has data for its
extra nodes.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import CubicSpline

from gaitcli.dynamics.sagittal import SagittalMotion
from gaitcli.muscles.limb import LimbParameters

MASS_KG, STATURE_M = 65.0, 1.70
PERIOD_S, SPEED_M_S, RATE_HZ = 1.1, 1.25, 100.0
STANCE_FRACTION = 0.62
VPP_HEIGHT_M = 0.3
HARMONICS = 6

# (percent of cycle, degrees), Winter's normative natural-cadence curves
_HIP = [(0, 24), (5, 25), (10, 24.5), (20, 17), (30, 4), (40, -7.5), (45, -11.8), (50, -14.5), (55, -15.5),
        (60, -12), (65, -5), (70, 4), (75, 13), (80, 20), (87, 26), (95, 25.5)]
_KNEE = [(0, 4), (5, 10), (15, 18), (25, 13), (35, 7), (42, 5), (50, 10), (60, 38), (65, 52), (72, 62),
         (80, 50), (90, 20), (97, 4)]
_ANKLE = [(0, 0), (7, -6), (15, 2), (30, 8), (45, 11), (52, 9), (57, 2), (62, -10), (66, -17), (72, -12),
          (80, -3), (90, 0)]


def _fourier_fit(points):
    """Coefficients (a0, a_k, b_k) of a HARMONICS-term series through the key points."""
    pct = np.array([p[0] for p in points] + [100.0])
    val = np.array([p[1] for p in points] + [points[0][1]], float)
    spline = CubicSpline(pct / 100.0, val, bc_type="periodic")
    s = np.linspace(0, 1, 400, endpoint=False)
    basis = [np.ones_like(s)]
    for k in range(1, HARMONICS + 1):
        basis += [np.cos(2 * np.pi * k * s), np.sin(2 * np.pi * k * s)]
    coef, *_ = np.linalg.lstsq(np.column_stack(basis), spline(s), rcond=None)
    return coef


def _fourier(coef, phase):
    out = np.full_like(phase, coef[0])
    for k in range(1, HARMONICS + 1):
        out += coef[2 * k - 1] * np.cos(2 * np.pi * k * phase) + coef[2 * k] * np.sin(2 * np.pi * k * phase)
    return out


def _vertical_shape(s):
    """Double-hump vertical force over stance s ∈ [0, 1], zero with zero slope at both ends."""
    sin = np.sin(np.pi * s)
    return sin ** 1.5 * (2.2 - 1.6 * sin ** 2)


def _vertical_shape_impulse():
    """Scale making the two legs' vertical impulse equal body weight × period."""
    s = np.linspace(0.0, 1.0, 4001)
    return 2 * STANCE_FRACTION * np.trapezoid(_vertical_shape(s), s)


def synthetic_gait_table(side: str = "r", margin_s: float = 0.3):
    """The sagittal table (dict of columns) and events {"heel_strike_s", "toe_off_s"}."""
    limb = LimbParameters.from_anthropometry(MASS_KG, STATURE_M, "male")
    t = np.round(np.arange(-margin_s, PERIOD_S + margin_s + 1e-9, 1.0 / RATE_HZ), 10)
    phase = t / PERIOD_S
    hip_deg, knee_deg, ankle_deg = (_fourier(_fourier_fit(p), phase) for p in (_HIP, _KNEE, _ANKLE))
    th, kn = np.deg2rad(hip_deg), np.deg2rad(knee_deg)
    # the ankle relative to the hip (x forward)
    ankle_dx = limb.thigh_length_m * np.sin(th) + limb.shank_length_m * np.sin(th - kn)
    mid = 0.30
    th30, kn30 = (np.deg2rad(_fourier(_fourier_fit(p), np.array([mid])))[0] for p in (_HIP, _KNEE))
    dz30 = -limb.thigh_length_m * np.cos(th30) - limb.shank_length_m * np.cos(th30 - kn30)
    z_amp = 0.02
    hip_z = (0.07 - dz30 - z_amp) + z_amp * np.cos(4 * np.pi * (phase - mid))
    hip_x = SPEED_M_S * t + 0.01 * np.sin(4 * np.pi * (phase - mid))
    # ground reaction during stance
    weight = MASS_KG * 9.81
    cyc = np.mod(phase, 1.0)
    s = cyc / STANCE_FRACTION
    stance = s < 1.0
    grf_z = np.where(stance, weight * _vertical_shape(np.clip(s, 0, 1)) / _vertical_shape_impulse(), 0.0)
    cop_x = np.where(stance, hip_x + ankle_dx - 0.05 + 0.20 * s, np.nan)
    # the ground reaction points at a virtual pivot VPP_HEIGHT_M above the hip centre
    grf_x = np.where(stance, -grf_z * (np.nan_to_num(cop_x) - hip_x) / (hip_z + VPP_HEIGHT_M), 0.0)
    table = {
        "time_s": t,
        f"hip_x_{side}_m": hip_x, f"hip_z_{side}_m": hip_z,
        f"thigh_angle_{side}_deg": hip_deg, f"knee_flexion_{side}_deg": knee_deg,
        f"ankle_dorsiflexion_{side}_deg": ankle_deg,
        f"grf_x_{side}_N": grf_x, f"grf_z_{side}_N": grf_z, f"cop_x_{side}_m": cop_x,
    }
    events = {"heel_strike_s": (0.0, PERIOD_S), "toe_off_s": (STANCE_FRACTION * PERIOD_S,)}
    return table, events


def synthetic_gait():
    """(SagittalMotion, LimbParameters) of the synthetic cycle."""
    table, events = synthetic_gait_table()
    motion = SagittalMotion.from_table(table, "r", path="synthetic_gait", **events)
    return motion, LimbParameters.from_anthropometry(MASS_KG, STATURE_M, "male")


@pytest.fixture(scope="session")
def gait_table():
    return synthetic_gait_table()


@pytest.fixture(scope="session")
def gait():
    return synthetic_gait()
