"""Write the shipped walks ``gait predict`` starts from: subject 1's default prediction at each speed group's speed.

    python scripts/make_speed_walks.py [slow free fast default]

For each group (``gaitcli/predict/data/schwartz2008_groups.csv``) at its speed v̂·√(g·L) for subject 1, and for
``gait predict``'s default speed (``default``: 1.1275 m/s, so that the default prediction starts from its own
solution), tracking the reference of that speed (``speed_reference.py``) with the stride bounded by its
group's stride ± 1 SD (5.44): the prediction with the stride free from the default start
(``guess.shipped_walk``), then the lower bound raised towards the group's by at most :data:`STEP_M` per solve,
each solve starting from the last (from a start whose stride is far outside the bound IPOPT wanders: J 11 → 73
and no convergence after 300 iterations at 1.325 m/s); the default speed's bounded at once from the nearest
group's walk. The last solution is written, with a header saying how it was made, to
``gaitcli/predict/data/walk_<group>_nn18.csv``; ``guess.shipped_walk`` starts from the walk of the nearest speed.
"""

from __future__ import annotations

import dataclasses
import sys
import time
from pathlib import Path

import numpy as np

from gaitcli.predict.model import WalkerParameters
from gaitcli.predict.settings import PredictSettings
from gaitcli.predict.speed_reference import SpeedGroups, speed_reference
from gaitcli.predict.stage import PredictConfig, run_predict

#: the most the stride's lower bound is raised per solve, m
STEP_M = 0.06
OUT = Path(__file__).resolve().parent.parent / "gaitcli" / "predict" / "data"


def walk(group: str) -> tuple[np.ndarray, str]:
    """The converged walk of ``group`` and its header."""
    groups = SpeedGroups.read()
    params = WalkerParameters.subject_1()
    leg, gravity = params.leg_length_m, params.limb.gravity_m_s2
    speed = (PredictSettings.speed_m_s if group == "default" else
             round(float(groups.mean["speed"][groups.names.index(group)] * np.sqrt(gravity * leg)), 4))
    at = speed_reference(speed, leg, gravity)
    low, high = at.stride_range_m
    cfg = dataclasses.replace(PredictConfig(), speed_m_s=speed, max_iterations=3000)
    # the first solve from the default start (guess.shipped_walk); the default speed's bounded at once: its start,
    # the free group's walk, lies inside its bounds (the continuation ended in a worse optimum: J 4.913 at 1.221 m
    # against 4.754 at 1.275 m)
    x, bound = None, (low if group == "default" else 0.0)
    while True:
        began = time.perf_counter()
        r = run_predict(dataclasses.replace(cfg, stride_range_m=(bound, high) if bound else None),
                        reference=at.reference, init=x)
        stride = r.stride_m
        print(f"{group}: lower bound {bound:.3f} m → stride {stride:.3f} m, J {r.objective:.4f}, converged "
              f"{r.converged}, {r.iterations} iterations, {time.perf_counter() - began:.0f} s", flush=True)
        if not r.converged:
            raise SystemExit(f"{group}: the solve at the lower bound {bound:.3f} m did not converge")
        x = r.design
        if bound >= low or stride >= low:
            break
        bound = min(stride + STEP_M, low)
    whose = "the default speed" if group == "default" else f"Schwartz et al. 2008's {group} group"
    header = (f"speed_m_s: {speed}\nThe shipped walk of {whose}: the symmetric "
              f"model's design vector chi (DesignLayout order) of `gait predict --speed {speed}` for subject 1\n"
              f"(nn = 18, weights 4/3,2/3), tracking that speed's reference (v̂ {at.speed_dimensionless:.3f}), "
              f"the stride within {low}–{high} m (the group's ± 1 SD), solved by\n"
              f"scripts/make_speed_walks.py: stride {stride:.4f} m, J {r.objective:.4f}, Et "
              f"{r.cost_of_transport_J_per_m:.1f} J/m, Jdev {r.deviation:.3f}.")
    return x, header


def main(groups: list[str]) -> None:
    for group in groups or ["slow", "free", "fast", "default"]:
        x, header = walk(group)
        out = OUT / f"walk_{group}_nn18.csv"
        np.savetxt(out, x, header=header)
        print(f"wrote {out}")


if __name__ == "__main__":
    main(sys.argv[1:])
