"""The reference a prediction tracks by default: the walk of people at its own speed (Diss. 5.3.3 tracks
Winter's slow, natural and fast data at 1.00, 1.33 and 1.68 m/s; gaitcli ships Schwartz et al. 2008's five
speed groups, ``predict/data/README.md``).

Speeds are compared as Hof's dimensionless speed v̂ = v/√(g·L), L the walker's leg length (hip to ground:
:attr:`gaitcli.predict.model.WalkerParameters.leg_length_m`), so that one group stands for walkers of any size.
At v̂ between two groups' mean v̂ the reference's means and SDs are interpolated linearly in v̂ between theirs,
at every 1 % of the cycle; below the slowest or above the fastest group the nearest group is taken as it is.
The groups' dimensionless step length ŝ = s/L and cadence f̂ = f·√(L/g) (steps per unit time) are interpolated
alike, giving the stride 2·ŝ·L that people walk at that speed and its SD.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gaitcli.errors import InputError
from gaitcli.predict.reference import VARIABLES, as_reference, read_reference
from gaitcli.signal.bands import Band

DATA = Path(__file__).resolve().parent / "data"
#: the groups' table (``scripts/make_speed_references.py``): per group its dimensionless gait parameters
GROUPS_FILE = DATA / "schwartz2008_groups.csv"
PARAMETERS = ("speed", "cadence", "step_length")


def group_file(group: str) -> Path:
    """The reference table of one speed group (``free``, ``fast`` ...)."""
    return DATA / f"schwartz2008_{group}.csv"


@dataclass(frozen=True)
class SpeedGroups:
    """Speed groups in order of speed: names and each dimensionless parameter's (mean, SD) per group."""

    names: tuple[str, ...]
    mean: dict[str, np.ndarray]
    sd: dict[str, np.ndarray]

    @classmethod
    def read(cls, path: Path = GROUPS_FILE) -> SpeedGroups:
        """The groups' table (columns ``group``, ``<parameter>_mean``, ``<parameter>_sd``); one-line errors."""
        import pandas as pd

        try:
            table = pd.read_csv(path)
        except (OSError, ValueError, UnicodeDecodeError) as err:
            raise InputError(path, None, f"cannot read the speed groups' table ({err})") from None
        columns = ["group"] + [f"{p}_{s}" for p in PARAMETERS for s in ("mean", "sd")]
        for column in columns:
            if column not in table.columns:
                raise InputError(path, column, "missing column (expected group and <speed|cadence|step_length>_"
                                               "mean, _sd)")
        try:
            values = table[columns[1:]].to_numpy(float)
        except ValueError:
            raise InputError(path, None, "expected numbers in every column but group") from None
        speeds = values[:, 0]
        if len(table) == 0 or not np.all(np.isfinite(values)) or np.any(values <= 0) or np.any(np.diff(speeds) <= 0):
            raise InputError(path, None, "expected positive numbers, the groups in rising speed_mean")
        return cls(tuple(str(g) for g in table["group"]),
                   {p: table[f"{p}_mean"].to_numpy(float) for p in PARAMETERS},
                   {p: table[f"{p}_sd"].to_numpy(float) for p in PARAMETERS})

    def weights(self, speed_dimensionless: float) -> list[tuple[int, float]]:
        """The groups (index, weight) whose curves make the reference at ``speed_dimensionless`` (module
        docstring): two adjacent groups with linear weights, or the nearest one at the ends."""
        speeds = self.mean["speed"]
        if speed_dimensionless <= speeds[0]:
            return [(0, 1.0)]
        if speed_dimensionless >= speeds[-1]:
            return [(len(speeds) - 1, 1.0)]
        upper = int(np.searchsorted(speeds, speed_dimensionless))
        w = (speed_dimensionless - speeds[upper - 1]) / (speeds[upper] - speeds[upper - 1])
        return [(upper - 1, 1.0 - w), (upper, w)]


@dataclass(frozen=True)
class SpeedReference:
    """The reference at one speed for one walker, and the gait people walk there: stride (m) and cadence
    (steps/min) with their SDs, from the groups' dimensionless ones."""

    reference: Band
    speed_dimensionless: float
    stride_m: float
    stride_sd_m: float
    cadence_steps_per_min: float
    cadence_sd_steps_per_min: float
    groups: tuple[tuple[str, float], ...]  # (group, weight)

    @property
    def stride_range_m(self) -> tuple[float, float]:
        """The stride ± 1 SD, m, to 0.1 mm: 5.44's bounds (``PredictConfig.stride_range_m``)."""
        return round(self.stride_m - self.stride_sd_m, 4), round(self.stride_m + self.stride_sd_m, 4)

    def summary(self) -> dict:
        """What summary.json says of it."""
        return {"reference": self.reference.source, "reference_stride_m": round(self.stride_m, 4),
                "reference_stride_sd_m": round(self.stride_sd_m, 4),
                "reference_cadence_steps_per_min": round(self.cadence_steps_per_min, 2)}


def speed_reference(speed_m_s: float, leg_length_m: float, gravity_m_s2: float = 9.81, *,
                    groups_file: Path = GROUPS_FILE) -> SpeedReference:
    """The reference of a walker with legs ``leg_length_m`` long at ``speed_m_s`` (module docstring)."""
    groups = SpeedGroups.read(groups_file)
    scale = np.sqrt(gravity_m_s2 * leg_length_m)
    v_hat = speed_m_s / scale
    weights = groups.weights(v_hat)
    tables = [read_reference(groups_file.parent / group_file(groups.names[k]).name).arrays(VARIABLES)
              for k, _ in weights]
    mean = sum(w * t[0] for (_, w), t in zip(weights, tables))
    sd = sum(w * t[1] for (_, w), t in zip(weights, tables))

    def blend(parameter: str, stat: dict) -> float:
        return float(sum(w * stat[parameter][k] for k, w in weights))

    step, step_sd = blend("step_length", groups.mean), blend("step_length", groups.sd)
    cadence, cadence_sd = blend("cadence", groups.mean), blend("cadence", groups.sd)
    per_min = 60.0 * np.sqrt(gravity_m_s2 / leg_length_m)
    named = tuple((groups.names[k], round(float(w), 4)) for k, w in weights)
    source = ("Schwartz et al. 2008, " + " + ".join(f"{w:.2f}×{g}" for g, w in named)
              + f" (v̂ {v_hat:.3f}, leg {leg_length_m:.3f} m)")
    return SpeedReference(as_reference(mean, sd, np.zeros(len(VARIABLES), int), source), float(v_hat),
                          2.0 * step * leg_length_m, 2.0 * step_sd * leg_length_m, cadence * per_min,
                          cadence_sd * per_min, named)
