"""Sagittal export for the muscle stage (4.5.1): per side thigh, knee and ankle angles, hip path, GRF.

The idyn stage hands the muscle stage a :class:`SagittalExport` (SI, radians);
``sagittal.csv`` (degrees) is written from it for people and other tools, and
:meth:`SagittalMotion.from_table` reads such a table back.

The thigh and shank angles are planar, in the model's x–z plane (x forward along
the walk), from the joint centres: the thigh angle is the hip→knee line's angle
from the downward vertical, positive when the knee is in front of the hip; knee
flexion is the thigh angle minus the shank angle (knee→ankle line, positive when
the ankle is in front of the knee). The foot has no such line through joint
centres, so ankle dorsiflexion is the 3-D model's ankle flexion coordinate
(clinical sign): zero in the calibration posture, which for a standing static
trial is the foot flat and ⟂ the shank, the muscle model's neutral (A.9).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gaitcli.core.container import Trial
from gaitcli.core.events import SIDES, Events
from gaitcli.errors import InputError, shown
from gaitcli.kinematics.conventions import coordinates_to_clinical
from gaitcli.kinematics.model import COORDINATES, JOINTS, BodyParameters

SAGITTAL_COLUMNS = ("hip_x_{s}_m", "hip_z_{s}_m", "thigh_angle_{s}_deg", "knee_flexion_{s}_deg",
                    "ankle_dorsiflexion_{s}_deg", "grf_x_{s}_N", "grf_z_{s}_N", "cop_x_{s}_m")


@dataclass(frozen=True)
class SagittalMotion:
    """Sagittal kinematics and ground reaction of one leg (the idyn stage's ``sagittal.csv``).

    Arrays over frames (SI, radians): hip centre ``hip_x_m``, ``hip_z_m``;
    ``thigh_angle_rad``, ``knee_flexion_rad``, ``ankle_dorsiflexion_rad``;
    ground reaction on the foot ``grf_x_N``, ``grf_z_N`` and centre of pressure
    ``cop_x_m`` (NaN in swing). Events in s: ``heel_strike_s``, ``toe_off_s``.
    """

    time_s: np.ndarray
    hip_x_m: np.ndarray
    hip_z_m: np.ndarray
    thigh_angle_rad: np.ndarray
    knee_flexion_rad: np.ndarray
    ankle_dorsiflexion_rad: np.ndarray
    grf_x_N: np.ndarray
    grf_z_N: np.ndarray
    cop_x_m: np.ndarray
    side: str = "r"
    heel_strike_s: tuple[float, ...] = ()
    toe_off_s: tuple[float, ...] = ()
    source: str | None = None

    @classmethod
    def from_table(cls, table, side: str, *, path: str | Path | None = None,
                   heel_strike_s=(), toe_off_s=()) -> "SagittalMotion":
        """Read one side (``"r"`` or ``"l"``) from a DataFrame or dict of columns.

        Columns: ``time_s`` and ``hip_x_{s}_m, hip_z_{s}_m, thigh_angle_{s}_deg,
        knee_flexion_{s}_deg, ankle_dorsiflexion_{s}_deg, grf_x_{s}_N, grf_z_{s}_N,
        cop_x_{s}_m``. NaN is checked later, in the analysed interval only
        (:meth:`check_finite`).
        """
        if side not in ("r", "l"):
            raise InputError(path, "side", f"got {shown(side)} (expected 'r' or 'l')")
        names = ["time_s"] + [c.format(s=side) for c in SAGITTAL_COLUMNS]
        cols = {}
        for name in names:
            if name not in table:
                raise InputError(path, name, "missing column (the sagittal table needs "
                                 + ", ".join(names) + ")")
            try:
                cols[name] = np.asarray(table[name], dtype=float).reshape(-1)
            except (TypeError, ValueError):
                raise InputError(path, name, "expected numbers") from None
        t = cols["time_s"]
        if t.size < 4:
            raise InputError(path, "time_s", f"got {t.size} frames (expected at least 4)")
        if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
            raise InputError(path, "time_s", "expected finite, strictly increasing times")
        deg = np.pi / 180.0
        return cls(time_s=t,
                   hip_x_m=cols[names[1]], hip_z_m=cols[names[2]],
                   thigh_angle_rad=cols[names[3]] * deg, knee_flexion_rad=cols[names[4]] * deg,
                   ankle_dorsiflexion_rad=cols[names[5]] * deg,
                   grf_x_N=cols[names[6]], grf_z_N=cols[names[7]], cop_x_m=cols[names[8]],
                   side=side, heel_strike_s=tuple(float(x) for x in heel_strike_s),
                   toe_off_s=tuple(float(x) for x in toe_off_s),
                   source=None if path is None else str(path))

    @property
    def angles_rad(self) -> np.ndarray:
        """(frames, 3): thigh angle, knee flexion, ankle dorsiflexion."""
        return np.column_stack([self.thigh_angle_rad, self.knee_flexion_rad, self.ankle_dorsiflexion_rad])

    def column_name(self, key: str) -> str:
        """Table column of a field, e.g. ``"knee_flexion"`` → ``knee_flexion_r_deg``."""
        for c in SAGITTAL_COLUMNS:
            if c.startswith(key):
                return c.format(s=self.side)
        return key

    def check_finite(self, first: int, last: int) -> None:
        """Raise InputError for NaN in frames ``first..last`` (inclusive).

        NaN centre of pressure is allowed where the vertical force is zero (swing).
        """
        sl = slice(first, last + 1)
        fields = {"hip_x": self.hip_x_m, "hip_z": self.hip_z_m, "thigh_angle": self.thigh_angle_rad,
                  "knee_flexion": self.knee_flexion_rad, "ankle_dorsiflexion": self.ankle_dorsiflexion_rad,
                  "grf_x": self.grf_x_N, "grf_z": self.grf_z_N}
        bad_cols, bad = [], np.zeros(last - first + 1, bool)
        for key, arr in fields.items():
            nan = ~np.isfinite(arr[sl])
            if nan.any():
                bad_cols.append(self.column_name(key))
                bad |= nan
        loaded = (np.abs(self.grf_x_N[sl]) + np.abs(self.grf_z_N[sl])) > 0  # False where NaN
        nan_cop = ~np.isfinite(self.cop_x_m[sl]) & loaded
        if nan_cop.any():
            bad_cols.append(self.column_name("cop_x"))
            bad |= nan_cop
        if bad_cols:
            idx = np.flatnonzero(bad) + first
            t = self.time_s
            raise InputError(self.source, ", ".join(bad_cols),
                             f"NaN in frames {idx[0]}–{idx[-1]} (t = {t[idx[0]]:.3f}–{t[idx[-1]]:.3f} s) "
                             f"of the analysed interval {t[first]:.3f}–{t[last]:.3f} s "
                             "(expected finite values; the centre of pressure may be NaN only without load)")


def _from_vertical(upper, lower):
    """Angle (rad) of the line upper→lower from the downward vertical, positive when lower is in front."""
    d = lower - upper
    return np.arctan2(d[:, 0], -d[:, 2])


@dataclass(frozen=True)
class SagittalExport:
    """What the muscle stage takes from the idyn stage (4.5.1).

    ``legs[side]``: that leg's :class:`SagittalMotion` (SI, radians) with its
    events; ``load_known[side]`` (n,) frames in which that foot's load is known;
    ``parameters``: the 3-D model's segment parameters (de Leva with measured
    lengths and added masses); ``body_mass_kg``; ``events`` of both feet;
    ``history``: the processing steps that made it.
    """

    legs: dict[str, SagittalMotion]
    load_known: dict[str, np.ndarray]
    events: Events
    parameters: BodyParameters
    body_mass_kg: float
    history: tuple[str, ...] = ()

    @property
    def time_s(self) -> np.ndarray:
        return self.legs["r"].time_s


def sagittal_export(trial: Trial, joint_centres_m, q, parameters: BodyParameters, *,
                    body_mass_kg: float) -> SagittalExport:
    """Each leg's planar motion and ground reaction from the 3-D model (4.5.1).

    ``joint_centres_m`` (n, 7, 3) from the model's forward kinematics of the
    coordinates ``q`` (n, 27); the ankle's dorsiflexion is the clinical sign of the
    3-D ankle flexion coordinate (:mod:`gaitcli.kinematics.conventions`).
    """
    clinical = coordinates_to_clinical(q)
    legs = {}
    for s in SIDES:
        hip = joint_centres_m[:, JOINTS.index(f"hip_{s}")]
        knee = joint_centres_m[:, JOINTS.index(f"knee_{s}")]
        ankle = joint_centres_m[:, JOINTS.index(f"ankle_{s}")]
        thigh = _from_vertical(hip, knee)
        shank = _from_vertical(knee, ankle)
        load = trial.feet[s]
        force = np.nan_to_num(load.force_N)
        legs[s] = SagittalMotion(
            time_s=trial.time_s, hip_x_m=hip[:, 0], hip_z_m=hip[:, 2], thigh_angle_rad=thigh,
            knee_flexion_rad=thigh - shank,
            ankle_dorsiflexion_rad=np.radians(clinical[:, COORDINATES.index(f"ankle_{s}_flexion")]),
            grf_x_N=force[:, 0], grf_z_N=force[:, 2], cop_x_m=np.asarray(load.cop_m)[:, 0], side=s,
            heel_strike_s=tuple(trial.events.times(s, "heel_strike")),
            toe_off_s=tuple(trial.events.times(s, "toe_off")))
    return SagittalExport(legs=legs, load_known={s: trial.load_known(s) for s in SIDES}, events=trial.events,
                          parameters=parameters, body_mass_kg=float(body_mass_kg), history=trial.history)


def sagittal_columns(export: SagittalExport) -> dict[str, np.ndarray]:
    """The columns of ``sagittal.csv`` (angles in degrees): :data:`SAGITTAL_COLUMNS` per side."""
    columns = {"time_s": export.time_s}
    for s in SIDES:
        leg = export.legs[s]
        values = (leg.hip_x_m, leg.hip_z_m, np.degrees(leg.thigh_angle_rad), np.degrees(leg.knee_flexion_rad),
                  np.degrees(leg.ankle_dorsiflexion_rad), leg.grf_x_N, leg.grf_z_N, leg.cop_x_m)
        columns.update({name.format(s=s): v for name, v in zip(SAGITTAL_COLUMNS, values)})
    return columns
