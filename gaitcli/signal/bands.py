"""Normal bands: mean ± 1 SD over the gait cycle of a reference group, which figures draw grey behind a trial's
curves (:func:`gaitcli.report.plots.draw_band`) and the Gait Profile Score measures against.

A band holds side-free variables over 0–100 % of a stride (both legs alike, in the names and signs of the
tables it was made from, the side dropped): angles ``<joint>_<sense>_deg`` (``pelvis_tilt_deg``,
``hip_flexion_deg``, ``foot_progression_deg``, ...; the pelvis as each side's cycle reports it), moments
``<joint>_<sense>_moment_per_kg`` (N·m/kg: ``knee_extensor_moment_per_kg`` ...), total joint powers
``<joint>_power_W_per_kg`` (W/kg) and the ground reaction ``grf_x_N_per_kg``, ``grf_z_N_per_kg``. It is read
from a band file (``cycle_pct`` then ``<variable>_mean`` and ``<variable>_sd``; ``gait reference ... --band FILE``
writes one from idyn outputs) or from a ``gait reference`` table, whose right-leg columns give the sagittal
angles and forces. The package's band (``signal/data/normal_band.csv``) is Schwartz et al. (2008)'s
free-speed group of 83 typically developing children and adolescents in Plug-in Gait's components
(``signal/data/README.md``: source, subjects, speed, licence, conversion). ``gait reference --sd-floor`` raises
each SD to a floor (3°, 0.1 N·m/kg, 0.2 W/kg, 0.3 N/kg, :data:`SD_FLOOR`), for a band of one subject's strides.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from gaitcli.errors import InputError, shown
from gaitcli.signal.cycles import CYCLE_PCT

#: a gait_cycle.csv column a band pools over both legs: ``<joint>_<side>_<sense>`` (deg),
#: ``<joint>_<side>_<sense>_moment_per_kg`` or ``<joint>_<side>_power_W_per_kg`` (the pelvis columns have no side:
#: each stride's holds the pelvis as its side reports it, :data:`PELVIS_COLUMNS`)
LEG_COLUMN = re.compile(r"^(hip|knee|ankle|foot)_([rl])_(\w+?)(_moment_per_kg|_W_per_kg)?$")
PELVIS_COLUMNS = ("pelvis_tilt", "pelvis_obliquity", "pelvis_rotation")
#: SD floors by the variable's unit suffix
SD_FLOOR = {"_deg": 3.0, "_moment_per_kg": 0.1, "_W_per_kg": 0.2, "_N_per_kg": 0.3}
BAND_FILE = Path(__file__).resolve().parent / "data" / "normal_band.csv"
#: the largest band or reference table read (a 101-row table of a hundred variables is about 200 kB)
BAND_MAX_BYTES = 20_000_000
#: a gait reference table's right-leg columns → band variables
REFERENCE_COLUMNS = {"hip_r_flexion_deg": "hip_flexion_deg", "knee_r_flexion_deg": "knee_flexion_deg",
                     "ankle_r_dorsiflexion_deg": "ankle_flexion_deg", "grf_x_r_N_per_kg": "grf_x_N_per_kg",
                     "grf_z_r_N_per_kg": "grf_z_N_per_kg"}


@dataclass(frozen=True)
class Band:
    """Mean and SD {variable: (101,)} over :data:`CYCLE_PCT`, in the variables' own units: a normal band
    behind a figure's curves, or the reference a prediction tracks (:mod:`gaitcli.predict.reference`).
    ``source``: where it came from (captions); ``strides``: how many strides gave each variable."""

    mean: dict[str, np.ndarray]
    sd: dict[str, np.ndarray]
    source: str = ""
    strides: dict[str, int] = field(default_factory=dict)

    @property
    def variables(self) -> tuple[str, ...]:
        return tuple(self.mean)

    def get(self, variable: str) -> tuple[np.ndarray, np.ndarray] | None:
        """(mean, SD) of ``variable`` or None when the band has none."""
        return (self.mean[variable], self.sd[variable]) if variable in self.mean else None

    def arrays(self, variables=None) -> tuple[np.ndarray, np.ndarray]:
        """Means and SDs (101, n) of ``variables`` (default: all, in the band's order), one column each."""
        names = self.variables if variables is None else tuple(variables)
        return (np.column_stack([self.mean[v] for v in names]), np.column_stack([self.sd[v] for v in names]))

    def digest(self) -> str:
        """SHA-256 of the means and SDs in the band's order: what a prediction sees of it (cache and study
        keys)."""
        import hashlib

        mean, sd = self.arrays()
        return hashlib.sha256(mean.tobytes() + sd.tobytes()).hexdigest()

    def columns(self) -> dict[str, np.ndarray]:
        """The band file's table: ``cycle_pct``, then ``<variable>_mean`` and ``<variable>_sd``."""
        out = {"cycle_pct": CYCLE_PCT}
        for name in self.mean:
            out[f"{name}_mean"], out[f"{name}_sd"] = self.mean[name], self.sd[name]
        return out


def floor_of(variable: str) -> float:
    """The SD floor of ``variable`` by its unit suffix (:data:`SD_FLOOR`; 0 for other units)."""
    return next((v for suffix, v in SD_FLOOR.items() if variable.endswith(suffix)), 0.0)


def leg_variable(column: str) -> tuple[str, str] | None:
    """(side, band variable) of a gait_cycle.csv leg column (:data:`LEG_COLUMN`): ``knee_r_flexion`` →
    ("r", "knee_flexion_deg"), ``hip_l_power_W_per_kg`` → ("l", "hip_power_W_per_kg"); None for another."""
    leg = LEG_COLUMN.match(column)
    return (leg[2], f"{leg[1]}_{leg[3]}{leg[4] or '_deg'}") if leg else None


def stride_statistics(stack: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mean, SD (ddof 1) and count at each point over the strides (rows) of ``stack`` that give it there
    (finite; NaN: a stride that does not, e.g. a moment where its foot's load is unknown): the mean NaN where no
    stride does, the SD where fewer than two do."""
    count = np.isfinite(stack).sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(count > 0, np.nansum(stack, axis=0) / np.maximum(count, 1), np.nan)
        spread = np.sqrt(np.nansum((stack - mean) ** 2, axis=0) / np.maximum(count - 1, 1))
    return mean, np.where(count > 1, spread, np.nan), count


def band_from_gait_cycles(paths, *, source: str = "", sd_floor: bool = False) -> Band:
    """The band of every stride in idyn's ``gait_cycle.csv`` files (both legs pooled, each over its own cycle;
    at each percentage the strides that give the variable there: a moment where its foot's load is known, NaN
    where none does); with ``sd_floor`` each SD raised to its floor (:data:`SD_FLOOR`)."""
    import pandas as pd

    stacks: dict[str, list[np.ndarray]] = {}
    for path in paths:
        table = pd.read_csv(path, keep_default_na=False, na_values=["NaN"])
        for (side, _), block in table.groupby(["side", "stride"], sort=True):
            if len(block) != CYCLE_PCT.size:
                continue
            for column in block.columns:
                leg = leg_variable(column)
                if column in PELVIS_COLUMNS:
                    leg = (side, f"{column}_deg")
                if leg and leg[0] == side:
                    stacks.setdefault(leg[1], []).append(block[column].to_numpy(float))
    mean, sd, strides = {}, {}, {}
    for name, curves in stacks.items():
        if not curves:
            continue
        average, spread, count = stride_statistics(np.stack(curves))
        if not count.any():
            continue
        mean[name] = average
        floor = floor_of(name) if sd_floor else 0.0
        sd[name] = np.where(count > 0, np.maximum(np.where(count > 1, spread, 0.0), floor), np.nan)
        strides[name] = int(count.max())
    if not mean:
        raise InputError(None, "band", "no complete stride in the trials' gait_cycle.csv (expected idyn outputs)")
    return Band(mean, sd, source, strides)


def check_band_size(path: Path) -> None:
    """Refuse a band or reference file larger than :data:`BAND_MAX_BYTES` before any of it is read."""
    size = Path(path).stat().st_size
    if size > BAND_MAX_BYTES:
        raise InputError(path, None, f"{size:,} bytes (expected a band or reference CSV of at most "
                                     f"{BAND_MAX_BYTES:,} bytes: 101 rows of means and SDs)")


def read_band(path: str | Path, *, side_free: bool = True) -> Band:
    """A band file, or a ``gait reference`` table; one-line errors. ``side_free``: of a reference table only
    its right-leg sagittal angles and forces, under the band's side-free names (a figure's band); else every
    column pair as it is named."""
    import pandas as pd

    path = Path(path)
    if not path.is_file():
        raise InputError(path, "--reference", "file not found (expected a band or reference CSV)")
    check_band_size(path)
    try:
        table = pd.read_csv(path)
    except (ValueError, UnicodeDecodeError):
        raise InputError(path, None, "not a CSV table (expected cycle_pct and <variable>_mean, _sd)") from None
    for column in table.columns:
        if not pd.api.types.is_numeric_dtype(table[column]):  # a cell that is not a number
            cells = pd.to_numeric(table[column], errors="coerce")
            row = int(np.flatnonzero(cells.isna() & table[column].notna())[0]) + 2
            raise InputError(path, f"line {row}: {column}", f"got {shown(str(table[column].iloc[row - 2]))} "
                                                           "(expected a number)")
    if "cycle_pct" not in table:
        raise InputError(path, "cycle_pct", "missing column (expected cycle_pct and <variable>_mean, _sd)")
    pct = table["cycle_pct"].to_numpy(float)
    if pct.size < 2 or pct[0] != 0.0 or pct[-1] != 100.0 or np.any(np.diff(pct) <= 0):
        raise InputError(path, "cycle_pct", "expected increasing values from 0 to 100")
    rename = REFERENCE_COLUMNS if side_free and any(f"{c}_mean" in table for c in REFERENCE_COLUMNS) else {}
    mean, sd = {}, {}
    for column in table.columns:
        if not column.endswith("_mean") or f"{column[:-5]}_sd" not in table:
            continue
        name = column[:-5]
        if rename and name not in rename:
            continue
        m, s = table[column].to_numpy(float), table[f"{name}_sd"].to_numpy(float)
        if not (np.isfinite(m).any() and np.array_equal(np.isfinite(m), np.isfinite(s))
                and np.all(s[np.isfinite(s)] >= 0)):
            raise InputError(path, f"{name}_sd", "expected means and standard deviations ≥ 0 (NaN where a band has "
                                                 "no stride, in both)")
        mean[rename.get(name, name)] = np.interp(CYCLE_PCT, pct, m)
        sd[rename.get(name, name)] = np.interp(CYCLE_PCT, pct, s)
    if not mean:
        raise InputError(path, None, "no <variable>_mean and _sd columns (expected a band or reference CSV)")
    return Band(mean, sd, path.name)


#: the package band's caption
BAND_SOURCE = "Schwartz et al. 2008, 83 typically developing children, free speed"
#: the frames the package band's angles were measured in (Plug-in Gait's: ``IdynResult.angle_convention``'s names)
BAND_ANGLE_CONVENTION = "plug_in_gait"
#: the band's walking speed, dimensionless (v / √(g·leg length)): Schwartz et al.'s free group, mean and SD
#: (``gaitcli/predict/data/schwartz2008_groups.csv``); a trial beyond 4 SD of it walks otherwise than the band
BAND_SPEED_DIMENSIONLESS = (0.429, 0.026)


def speed_outside_band(speed_m_s: float, leg_length_m: float, gravity_m_s2: float = 9.81) -> str | None:
    """Why a trial at ``speed_m_s`` is not walking as the package band's subjects walked (None when it is):
    its dimensionless speed beyond 4 SD of :data:`BAND_SPEED_DIMENSIONLESS` (for :func:`default_band` only)."""
    mean, sd = BAND_SPEED_DIMENSIONLESS
    v = speed_m_s / np.sqrt(gravity_m_s2 * leg_length_m)
    if abs(v - mean) <= 4 * sd:
        return None
    return (f"this trial's speed, {speed_m_s:.2f} m/s ({v:.2f} in leg lengths, Hof's v̂), lies far "
            f"{'below' if v < mean else 'above'} the band's free walking ({mean:.3f} ± {sd:.3f}): compare its "
            "curves with the band with care")


def default_band() -> Band:
    """The package's band (:data:`BAND_FILE`; module docstring)."""
    band = read_band(BAND_FILE)
    return Band(band.mean, band.sd, BAND_SOURCE)
