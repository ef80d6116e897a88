"""What ``filter.h5`` and ``idyn.h5`` hold beside their hand-off records, read back typed.

The hand-offs (``trial/``, ``sagittal/``, ``strides/``) are records (:func:`gaitcli.io.h5.read_result`). Beside
them the writers (:mod:`gaitcli.signal.outputs`, :mod:`gaitcli.dynamics.outputs`) store what figures and exports
show people: the raw markers and each plate's signals, and the tables of angles, moments and powers in the signs
of the CSVs, their column names in an attribute. This module is the one place that knows those dataset names;
figures, exports and the reference read the files through it, so a damaged or foreign file is an
:class:`~gaitcli.errors.InputError` (:func:`gaitcli.io.h5.open_h5`).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gaitcli.core.container import Trial
from gaitcli.io.h5 import ColumnTable, checked, column_table, open_h5, read_record, strings


@dataclass(frozen=True)
class PlateSignals:
    """One plate of ``filter.h5``: force (N) and centre of pressure (m) at the marker rate, model axes; the
    unfiltered vertical force (N) at the analog rate ``analog_rate_hz`` (empty for a CSV trial)."""

    force_N: np.ndarray
    cop_m: np.ndarray
    raw_vertical_force_N: np.ndarray
    analog_rate_hz: float


@dataclass(frozen=True)
class FilterSignals:
    """``filter.h5``: the filtered :class:`~gaitcli.core.container.Trial`, the markers as read (frames,
    markers, 3; m, model axes), the filter's cut-off (Hz) and each plate's signals by name (``plate1``, ...)."""

    trial: Trial
    raw_markers_m: np.ndarray
    cutoff_hz: float
    plates: dict[str, PlateSignals]


def read_filter_signals(path: str | Path) -> FilterSignals:
    """The :class:`FilterSignals` of a ``filter.h5``."""
    with open_h5(path, "gait filter") as h5:
        trial = read_record(h5["trial"], Trial)
        plates = {}
        for name in (h5["plates"] if "plates" in h5 else []):
            analog = h5[f"plates/{name}/analog/raw_vertical_force"]
            plates[name] = PlateSignals(checked(h5[f"plates/{name}/force"])[()], checked(h5[f"plates/{name}/cop"])[()],
                                        checked(analog)[()], float(analog.attrs["rate_hz"]))
        return FilterSignals(trial, checked(h5["markers/raw"])[()],
                             float(h5["trial/markers/positions_m"].attrs["cutoff_hz"]), plates)


@dataclass(frozen=True)
class GaitCycles:
    """``idyn.h5``'s ``gait_cycle/``: gait_cycle.csv's rows, every stride at 0–100 % of its cycle one block;
    ``cycle_pct`` (%), ``side`` (``"r"``, ``"l"``), ``stride`` (1, 2, … in time order) and ``start_s`` (s) per
    row, and ``values`` its columns (angles deg, moments N·m/kg, powers W/kg, ground reactions % body weight)."""

    cycle_pct: np.ndarray
    side: np.ndarray
    stride: np.ndarray
    start_s: np.ndarray
    values: ColumnTable


def read_gait_cycles(group) -> GaitCycles:
    """The :class:`GaitCycles` of an open ``idyn.h5``'s ``gait_cycle`` group."""
    side = group["side"]
    return GaitCycles(checked(group["cycle_pct"])[()], strings(side) if side.dtype.kind == "O" else
                      checked(side)[()].astype(str), checked(group["stride"])[()].astype(int),
                      checked(group["start_s"])[()], column_table(group["values"]))


@dataclass(frozen=True)
class IdynTables:
    """``idyn.h5``'s tables for people, over ``time_s`` (frames,).

    ``coordinates``: the 27 coordinates in clinical signs (m, deg); ``angles``: the joint angles the tables
    show (deg; the anatomical angles, or the coordinates with ``angles: posture``); ``moments``: the 21 joint
    moments the tables show (N·m; Plug-in Gait's or the coordinates' senses, as ``moments.convention`` says);
    ``coordinate_moments``: the 21 moments in the coordinates' senses (N·m); ``moment_known`` (frames, 7) where
    the load each joint's moment depends on is known; ``powers``: total joint power per joint (W, generated
    positive; None in files without it); the pelvis residual force (N) and moment (N·m), model axes; the body
    mass (kg) and the trial folder's name; ``cycles`` gait_cycle.csv's table (None in files older than it).
    """

    time_s: np.ndarray
    coordinates: ColumnTable
    angles: ColumnTable
    moments: ColumnTable
    coordinate_moments: ColumnTable
    moment_known: np.ndarray
    powers: ColumnTable | None
    residual_force_N: np.ndarray
    residual_moment_Nm: np.ndarray
    body_mass_kg: float
    trial: str = ""
    cycles: GaitCycles | None = None

    def known_moments_Nm(self, table: ColumnTable | None = None) -> np.ndarray:
        """``table``'s 21 moments (default: :attr:`moments`) with NaN where their load is unknown."""
        table = self.moments if table is None else table
        return np.where(np.repeat(self.moment_known, 3, axis=1), table.values, np.nan)

    def known_powers_W(self) -> np.ndarray:
        """:attr:`powers` (frames, 7) with NaN where the joint's moment is unknown (all NaN without powers)."""
        if self.powers is None:
            return np.full(self.moment_known.shape, np.nan)
        return np.where(self.moment_known, self.powers.values, np.nan)


def read_idyn_tables(path: str | Path) -> IdynTables:
    """The :class:`IdynTables` of an ``idyn.h5`` (files older than the anatomical angles: the coordinates
    and their moments stand in)."""
    with open_h5(path, "gait idyn") as h5:
        coordinates = column_table(h5["coordinates_clinical"])
        coordinate_moments = column_table(h5["joint_moments_clinical"])
        return IdynTables(
            time_s=checked(h5["time"])[()], coordinates=coordinates,
            angles=column_table(h5["angles"]) if "angles" in h5 else coordinates,
            moments=column_table(h5["joint_moments_shown"]) if "joint_moments_shown" in h5 else coordinate_moments,
            coordinate_moments=coordinate_moments,
            moment_known=checked(h5["joint_moments_known"])[()].astype(bool),
            powers=column_table(h5["joint_powers"], "joints") if "joint_powers" in h5 else None,
            residual_force_N=checked(h5["residuals/force"])[()], residual_moment_Nm=checked(h5["residuals/moment"])[()],
            body_mass_kg=float(h5["segments/mass"].attrs["body_mass_kg"]), trial=str(h5.attrs.get("trial", "")),
            cycles=read_gait_cycles(h5["gait_cycle"]) if "gait_cycle" in h5 else None)


@dataclass(frozen=True)
class IdynModel:
    """What ``idyn.h5`` holds of the model itself, for exporting it: the 27 coordinates ``q`` (frames, 27; m and
    rad, the model's signs, 3.1), the joint moments (frames, 7, 3; proximal on distal, global axes, N·m), the
    pelvis residual force (N) and moment about the pelvis CoM (N·m), global; where each joint's load is known
    (frames, 7) and where every contact's is (frames,); the segments' masses (8,) kg, inertias (8, 3, 3) kg·m²
    about their CoMs in their axes, joint centres in the parent's and the child's frame (7, 3) m; gravity (m/s²)."""

    time_s: np.ndarray
    q: np.ndarray
    joint_moments_global_Nm: np.ndarray
    residual_force_N: np.ndarray
    residual_moment_Nm: np.ndarray
    moment_known: np.ndarray
    all_contacts_measured: np.ndarray
    mass_kg: np.ndarray
    inertia_kgm2: np.ndarray
    joint_in_parent_m: np.ndarray
    joint_in_child_m: np.ndarray
    gravity_m_s2: float
    trial: str = ""


def read_idyn_model(path: str | Path) -> IdynModel:
    """The :class:`IdynModel` of an ``idyn.h5`` (gravity: the run's configuration, 9.81 m/s² where it is not
    recorded)."""
    with open_h5(path, "gait idyn") as h5:
        try:
            gravity = float(json.loads(h5.attrs.get("stage_key", "{}"))["config"]["idyn"]["gravity_m_s2"])
        except (KeyError, TypeError, ValueError):
            gravity = 9.81
        return IdynModel(
            time_s=checked(h5["time"])[()], q=checked(h5["coordinates"])[()],
            joint_moments_global_Nm=checked(h5["joint_moments_global"])[()],
            residual_force_N=checked(h5["residuals/force"])[()], residual_moment_Nm=checked(h5["residuals/moment"])[()],
            moment_known=checked(h5["joint_moments_known"])[()].astype(bool),
            all_contacts_measured=checked(h5["residuals/all_contacts_measured"])[()].astype(bool),
            mass_kg=checked(h5["segments/mass"])[()], inertia_kgm2=checked(h5["segments/inertia"])[()],
            joint_in_parent_m=checked(h5["segments/joint_in_parent"])[()],
            joint_in_child_m=checked(h5["segments/joint_in_child"])[()], gravity_m_s2=gravity,
            trial=str(h5.attrs.get("trial", "")))
