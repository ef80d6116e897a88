"""Is a predicted gait a walk a clinician recognises? Checks on the right leg's curves over one cycle.

Each check returns its measured value and whether it lies in the range of normal walking:

- ``stance_pct``: right stance 55–68 % of the cycle (Perry: about 60 %);
- ``double_support_pct``: both feet down, > 0 % (a walk, not a run);
- ``knee_swing_peak_deg``: the knee's largest flexion in swing, ≥ 55° (Perry: about 60°);
- ``vertical_grf``: two peaks above body weight (loading response, pre-swing) with a valley below it in
  single stance between them: the value is (first peak, valley, second peak) in body weights;
- ``ankle_moment_peak_pct``: the plantarflexion moment peaks in late stance, after 60 % of stance
  (push-off): the value is where, in % of the cycle.
"""

from __future__ import annotations

import numpy as np

from gaitcli.core.physics import GRAVITY_M_S2


def gait_checks(cycle_pct, knee_flexion_deg, grf_z_N_per_kg, grf_pct, ankle_moment_Nm, moment_pct,
                stance_pct: float, double_support_pct: float) -> dict:
    """The checks of the module docstring: {name: {"value": …, "ok": bool}}.

    ``knee_flexion_deg`` at ``cycle_pct``; the right foot's vertical reaction (N/kg) at ``grf_pct``; the right
    ankle moment (N·m, dorsiflexion positive: plantarflexion is negative) at ``moment_pct``; the cycle starts
    at right heel strike.
    """
    pct, knee = np.asarray(cycle_pct, float), np.asarray(knee_flexion_deg, float)
    swing = pct >= stance_pct
    knee_peak = float(knee[swing].max()) if swing.any() else float("nan")
    fz_pct, fz = np.asarray(grf_pct, float), np.asarray(grf_z_N_per_kg, float) / GRAVITY_M_S2
    stance = fz_pct <= stance_pct
    s_pct, s_fz = fz_pct[stance], fz[stance]
    half = stance_pct / 2
    first = float(s_fz[s_pct <= half].max()) if np.any(s_pct <= half) else float("nan")
    second = float(s_fz[s_pct > half].max()) if np.any(s_pct > half) else float("nan")
    if np.isfinite(first) and np.isfinite(second):
        i1 = int(np.flatnonzero(s_pct <= half)[np.argmax(s_fz[s_pct <= half])])
        i2 = int(np.flatnonzero(s_pct > half)[np.argmax(s_fz[s_pct > half])])
        valley = float(s_fz[i1:i2 + 1].min())
    else:
        valley = float("nan")
    m_pct, moment = np.asarray(moment_pct, float), np.asarray(ankle_moment_Nm, float)
    in_stance = m_pct <= stance_pct
    peak_pct = float(m_pct[in_stance][np.argmin(moment[in_stance])]) if in_stance.any() else float("nan")
    return {
        "stance_pct": {"value": float(stance_pct), "ok": bool(55.0 <= stance_pct <= 68.0)},
        "double_support_pct": {"value": float(double_support_pct), "ok": bool(double_support_pct > 0.0)},
        "knee_swing_peak_deg": {"value": knee_peak, "ok": bool(knee_peak >= 55.0)},
        "vertical_grf": {"value": [first, valley, second],
                         "ok": bool(first > 1.0 and second > 1.0 and valley < 1.0)},
        "ankle_moment_peak_pct": {"value": peak_pct, "ok": bool(peak_pct >= 0.6 * stance_pct)},
    }


def failed_checks(checks) -> list[str]:
    """The names of the checks :func:`gait_checks` gave (as summary.json holds them) that failed; a value that
    is not such a mapping (a damaged summary) gives none."""
    if not isinstance(checks, dict):
        return []
    return [name for name, check in checks.items() if isinstance(check, dict) and not check.get("ok", True)]
