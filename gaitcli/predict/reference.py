"""Reference gait for the deviation term Jdev (Diss. 5.2.7, 5.28): mean and SD over the gait cycle.

Ten variables over the cycle from right heel strike to the next (0–100 %,
101 points), in clinical signs (docs/prediction.md, "Jdev"): the hip and knee
flexion and ankle dorsiflexion of both legs in degrees, and each foot's
fore-aft and vertical ground reaction in N per kg of body mass. A reference is
made from the idyn outputs of one or more trials (``gait reference``): every
right stride contributes its angles, and its ground reactions where that foot's
load was known throughout the stride. A reference holds the SDs as measured (``sd_floor``: raised to the
floors). The dissertation's σ are inter-subject SDs (Winter); the strides of one subject vary far less, which
would make Jdev explode and change what the weights mean, so Jdev divides by each SD raised to a floor
(:func:`jdev_sd`; :data:`gaitcli.signal.bands.SD_FLOOR`, our choice: about the smallest of Winter's
inter-subject SDs over the cycle, 3° for the angles and 0.3 N/kg for the forces).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from gaitcli.errors import InputError
from gaitcli.signal.bands import Band, check_band_size, floor_of, read_band
from gaitcli.signal.cycles import CYCLE_PCT

if TYPE_CHECKING:  # annotations only: importing the idyn stage would slow the start of every prediction process
    from gaitcli.dynamics.outputs import IdynOutput

ANGLES = ("hip_r_flexion_deg", "knee_r_flexion_deg", "ankle_r_dorsiflexion_deg",
          "hip_l_flexion_deg", "knee_l_flexion_deg", "ankle_l_dorsiflexion_deg")
FORCES = ("grf_x_r_N_per_kg", "grf_z_r_N_per_kg", "grf_x_l_N_per_kg", "grf_z_l_N_per_kg")
VARIABLES = ANGLES + FORCES


def as_reference(mean: np.ndarray, sd: np.ndarray, strides, source: str = "") -> Band:
    """A reference of :data:`VARIABLES` from means and SDs (101, 10) in that order and stride counts (10,)."""
    return Band({v: mean[:, k] for k, v in enumerate(VARIABLES)}, {v: sd[:, k] for k, v in enumerate(VARIABLES)},
                source, {v: int(n) for v, n in zip(VARIABLES, strides)})


LEG_VARIABLES = ("hip_{s}_flexion_deg", "knee_{s}_flexion_deg", "ankle_{s}_dorsiflexion_deg",
                 "grf_x_{s}_N_per_kg", "grf_z_{s}_N_per_kg")


def _side_statistics(cycles: list[np.ndarray], side: str):
    """Mean, SD (ddof 1; 0 for one stride) and counts of one leg's (101, 5) stride arrays, NaN-aware per column."""
    names = [v.format(s=side) for v in LEG_VARIABLES]
    if not cycles:
        raise InputError(None, "reference", f"no complete {'right' if side == 'r' else 'left'} stride in the "
                                            "trials (expected a heel strike and the next of the same foot)")
    stack = np.stack(cycles)
    given = np.all(np.isfinite(stack), axis=1)
    counts = given.sum(axis=0)
    missing = [names[k] for k in np.flatnonzero(counts == 0)]
    if missing:
        raise InputError(None, "reference", f"no stride gives {', '.join(missing)} (expected that foot's load "
                                            "recorded on a plate throughout at least one of its strides)")
    mean = np.column_stack([stack[given[:, k], :, k].mean(axis=0) for k in range(len(names))])
    sd = np.column_stack([stack[given[:, k], :, k].std(axis=0, ddof=1) if counts[k] > 1 else np.zeros(101)
                          for k in range(len(names))])
    return mean, sd, counts


def _shift(curve: np.ndarray, offset_pct: float) -> np.ndarray:
    """A periodic (101, n) curve over its own cycle, seen from a cycle that starts ``offset_pct`` % earlier."""
    source = (CYCLE_PCT - offset_pct) % 100.0
    return np.column_stack([np.interp(source, CYCLE_PCT[:-1], curve[:-1, k], period=100.0)
                            for k in range(curve.shape[1])])


#: samples of the cycle before 0 % and after 100 % (wrapped) that make the cubic periodic in effect at its ends
WRAPPED_SAMPLES = 10


def reference_curves(reference: Band) -> tuple[ca.Function, ca.Function]:
    """The reference's mean and Jdev's SD (:func:`jdev_sd`) of :data:`VARIABLES` between its 1 % samples:
    Functions of the cycle percentage (0–100; a row of n percentages gives 10 × n), numeric or CasADi alike.

    Cubic B-splines through the samples, the cycle wrapped by :data:`WRAPPED_SAMPLES` at either end: C2, so that
    Jdev (5.28) is smooth in the phase durations. A linear interpolant's slope jumps wherever an instant
    crosses a sample; IPOPT stalled at such kinks (e.g. Flex-Foot at 1.33 m/s, c): J fixed to 6 digits for
    1 000+ iterations, converged in 117 with the cubic; ``benchmarks/README.md``)."""
    mean, sd = reference.arrays(VARIABLES)
    wrap = WRAPPED_SAMPLES
    grid = np.concatenate([CYCLE_PCT[-1 - wrap:-1] - 100.0, CYCLE_PCT, CYCLE_PCT[1:1 + wrap] + 100.0])

    def curve(name, table):
        wrapped = np.vstack([table[-1 - wrap:-1], table, table[1:1 + wrap]])
        return ca.interpolant(name, "bspline", [grid], wrapped.ravel())  # row-major: the variables fastest

    return curve("reference_mean", mean), curve("reference_sd", jdev_sd(sd))


def jdev_sd(sd: np.ndarray) -> np.ndarray:
    """The σ Jdev (5.28) divides by: each SD of :data:`VARIABLES` (columns of ``sd``) raised to its floor
    (:data:`gaitcli.signal.bands.SD_FLOOR`; module docstring)."""
    return np.maximum(sd, np.array([floor_of(v) for v in VARIABLES]))


def build_reference(right: list[np.ndarray], left: list[np.ndarray], *, left_offset_pct: float = 50.0,
                    sources=(), sd_floor: bool = False) -> Band:
    """The reference from each leg's strides over its own cycle ((101, 5) arrays in :data:`LEG_VARIABLES`
    order, NaN where a stride does not give a variable); the left leg's curves are moved to the right-heel-
    strike cycle by ``left_offset_pct`` (where the left heel strikes in it). With ``sd_floor`` each SD is
    raised to its floor (:func:`jdev_sd`)."""
    mean_r, sd_r, n_r = _side_statistics(right, "r")
    mean_l, sd_l, n_l = _side_statistics(left, "l")
    mean_l, sd_l = _shift(mean_l, left_offset_pct), _shift(sd_l, left_offset_pct)
    order = [VARIABLES.index(v.format(s=s)) for s in ("r", "l") for v in LEG_VARIABLES]
    mean, sd, counts = np.zeros((101, 10)), np.zeros((101, 10)), np.zeros(10, int)
    mean[:, order] = np.column_stack([mean_r, mean_l])
    sd[:, order] = np.column_stack([sd_r, sd_l])
    counts[order] = np.concatenate([n_r, n_l])
    return as_reference(mean, jdev_sd(sd) if sd_floor else sd, counts, ", ".join(map(str, sources)))


def leg_cycles(time_s, values, load_known, strides) -> list[np.ndarray]:
    """One (101, 5) array per stride of one leg, normalised from its heel strike to the next.

    ``values`` (n, 5) over ``time_s`` (n,) in :data:`LEG_VARIABLES` order; the two force columns are NaN in
    a stride where the foot's load (``load_known`` (n,)) was not known throughout.
    """
    t = np.asarray(time_s, float)
    values = np.asarray(values, float)
    out = []
    for start, end in strides:
        grid = start + (end - start) * CYCLE_PCT / 100.0
        cycle = np.column_stack([np.interp(grid, t, values[:, k], left=np.nan, right=np.nan)
                                 for k in range(values.shape[1])])
        if not np.asarray(load_known, bool)[(t >= start) & (t <= end)].all():
            cycle[:, 3:] = np.nan
        out.append(cycle)
    return out


def idyn_reference_strides(idyn: IdynOutput) -> tuple[list[np.ndarray], list[np.ndarray], list[float]]:
    """Each leg's :func:`leg_cycles` of one trial's idyn output (the hip, knee and ankle flexion of its
    clinical coordinates, deg; each foot's ground reaction per kg), and where (%) the left heel strikes in each
    right stride."""
    export, strides, coordinates = idyn.sagittal, idyn.strides, idyn.tables.coordinates
    mass = export.body_mass_kg
    cycles = {}
    for s in ("r", "l"):
        angles = coordinates.values[:, [coordinates.index(f"{j}_{s}_flexion") for j in ("hip", "knee", "ankle")]]
        leg = export.legs[s]
        values = np.column_stack([angles, leg.grf_x_N / mass, leg.grf_z_N / mass])
        cycles[s] = leg_cycles(export.time_s, values, export.load_known[s],
                               [(st.start_s, st.end_s) for st in strides if st.side == s])
    left_strikes = export.events.times("l", "heel_strike")
    offsets = []
    for st in (st for st in strides if st.side == "r"):
        inside = left_strikes[(left_strikes > st.start_s) & (left_strikes < st.end_s)]
        if inside.size:
            offsets.append(100.0 * (inside[0] - st.start_s) / st.period_s)
    return cycles["r"], cycles["l"], offsets


def read_reference(path: str | Path) -> Band:
    """Read ``ref.csv`` (columns ``cycle_pct``, ``<variable>_mean``, ``<variable>_sd`` for every one of
    :data:`VARIABLES`, finite, SD ≥ 0); one-line errors."""
    path = Path(path)
    if not path.is_file():
        raise InputError(path, None, "reference file not found")
    import pandas as pd

    check_band_size(path)
    try:
        header = set(pd.read_csv(path, nrows=0).columns)
    except (ValueError, UnicodeDecodeError):
        raise InputError(path, None, "not a CSV table (expected the columns gait reference writes)") from None
    for column in ["cycle_pct"] + [f"{v}_{stat}" for v in VARIABLES for stat in ("mean", "sd")]:
        if column not in header:
            raise InputError(path, column, "missing column (expected cycle_pct and <variable>_mean, _sd for "
                                           + ", ".join(VARIABLES) + ")")
    band = read_band(path, side_free=False)
    mean, sd = band.arrays(VARIABLES)
    if not (np.all(np.isfinite(mean)) and np.all(np.isfinite(sd))):
        raise InputError(path, None, "expected finite numbers in every column")
    return as_reference(mean, sd, np.zeros(len(VARIABLES), int), str(path))


def reference_from_idyn(outputs: Sequence[IdynOutput], sources=(), *, sd_floor: bool = False
                        ) -> tuple[Band, int, int]:
    """The reference of every stride in the trials' idyn ``outputs``, and how many right and left strides it
    has; the left leg moved by the mean offset of its heel strikes (50 % where none was seen); ``sd_floor`` as
    :func:`build_reference`."""
    right, left, offsets = [], [], []
    for idyn in outputs:
        r, left_strides, o = idyn_reference_strides(idyn)
        right, left, offsets = right + r, left + left_strides, offsets + o
    reference = build_reference(right, left, left_offset_pct=float(np.mean(offsets)) if offsets else 50.0,
                                sources=list(sources), sd_floor=sd_floor)
    return reference, len(right), len(left)
