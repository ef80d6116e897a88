"""A session's figures from ``gait_out/session/`` (``cycle.csv``, ``strides.csv``): each side's mean ± SD over
the strides of every walk against the grey normal band, right red, left blue, with each side's foot off (the
mean stance % of its strides, dashed; normal walking's dash-dotted grey): the kinematics of pelvis, hip, knee,
ankle and foot in three planes, and the moments of hip, knee and ankle in three planes with their powers and each
foot's ground reaction (% body weight)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd

from gaitcli.core.events import SIDE_NAMES
from gaitcli.report.plots import SIDE_COLOUR, draw_band, mark_foot_off, plt, save
from gaitcli.signal.bands import Band, leg_variable
from gaitcli.signal.cycles import CYCLE_PCT

PLANES = ("sagittal", "frontal", "transverse")
#: kinematics: (segment or joint, its cycle.csv columns per plane with {s} for the side; None: not drawn)
KINEMATICS = (("pelvis", ("pelvis_tilt", "pelvis_obliquity", "pelvis_rotation")),
              ("hip", ("hip_{s}_flexion", "hip_{s}_adduction", "hip_{s}_rotation")),
              ("knee", ("knee_{s}_flexion", "knee_{s}_adduction", "knee_{s}_rotation")),
              ("ankle", ("ankle_{s}_flexion", "ankle_{s}_inversion", "ankle_{s}_rotation")),
              ("foot", (None, None, "foot_{s}_progression")))
JOINTS = ("hip", "knee", "ankle")
#: the ground reaction's row: (cycle.csv column pattern, title)
GRF = (("grf_{s}_vertical_pct_body_weight", "vertical GRF"), ("grf_{s}_anterior_pct_body_weight", "anterior GRF"),
       ("grf_{s}_medial_pct_body_weight", "medial GRF"))


def band_variable(pattern: str | None) -> str | None:
    """The band's variable of a cycle.csv column pattern (``{s}`` for the side): ``knee_{s}_flexion`` →
    ``knee_flexion_deg``; the pelvis's angles have no side (``pelvis_tilt`` → ``pelvis_tilt_deg``)."""
    if pattern is None:
        return None
    leg = leg_variable(pattern.format(s="r"))
    return leg[1] if leg else f"{pattern}_deg"


def _draw(ax, cycle: pd.DataFrame, pattern: str, band: Band | None, foot_off: dict) -> bool:
    """One variable: the band, each side's mean ± SD and foot off; True when a side had it."""
    drawn = False
    draw_band(ax, band, band_variable(pattern), label=False)
    for side in ("r", "l"):
        column = pattern.format(s=side)
        block = cycle[cycle.side == side]
        if f"{column}_mean" not in block or not np.isfinite(block[f"{column}_mean"]).any():
            continue
        mean, sd = block[f"{column}_mean"].to_numpy(), block[f"{column}_sd"].to_numpy()
        n = int(np.nanmax(block[f"{column}_n"]))
        ax.plot(CYCLE_PCT, mean, color=SIDE_COLOUR[side], lw=1.2, label=f"{SIDE_NAMES[side]} (n={n})")
        ax.fill_between(CYCLE_PCT, mean - sd, mean + sd, color=SIDE_COLOUR[side], alpha=0.15, lw=0)
        drawn = True
    if drawn:
        mark_foot_off(ax, foot_off_pct={side: pct for side, pct in foot_off.items()})
    ax.axhline(0, color="0.7", lw=0.6)
    return drawn


def moment_patterns(columns, joint: str) -> list[str]:
    """The moment columns of ``joint`` in a cycle table (``<joint>_<side>_<sense>_moment_per_kg_mean``) as
    patterns with ``{s}`` for the side, in the table's order, each sense once."""
    found = []
    for column in columns:
        match = re.match(rf"^{joint}_[rl]_(\w+)_moment_per_kg_mean$", column)
        if match and f"{joint}_{{s}}_{match[1]}_moment_per_kg" not in found:
            found.append(f"{joint}_{{s}}_{match[1]}_moment_per_kg")
    return found


def kinematics_grid(draw) -> tuple:
    """The kinematics figure's grid (:data:`KINEMATICS` × the three planes): ``draw(ax, pattern)`` draws one
    variable (``pattern`` with ``{s}`` for the side) and says whether it had any; (figure, axes)."""
    fig, axes = plt.subplots(len(KINEMATICS), 3, figsize=(12, 2.3 * len(KINEMATICS)), sharex=True)
    for row, (part, columns) in enumerate(KINEMATICS):
        for col, pattern in enumerate(columns):
            ax = axes[row, col]
            if pattern is None or not draw(ax, pattern):
                ax.axis("off")
                continue
            ax.set_title(f"{part} {pattern.split('_')[-1]}", fontsize=9)
            ax.set_ylabel("deg")
    for col, plane in enumerate(PLANES):
        bottom = max(row for row, (_, columns) in enumerate(KINEMATICS) if columns[col] is not None)
        axes[bottom, col].set_xlabel("gait cycle (%)")
        axes[bottom, col].tick_params(labelbottom=True)
        axes[0, col].annotate(plane, (0.5, 1.25), xycoords="axes fraction", ha="center", fontsize=11)
    return fig, axes


def kinetics_grid(draw, columns) -> tuple:
    """The kinetics figure's grid: each joint's moments in three planes (those of the table ``columns``,
    :func:`moment_patterns`), the joints' powers, the ground reaction (:data:`GRF`); ``draw`` as
    :func:`kinematics_grid`'s; (figure, axes)."""
    fig, axes = plt.subplots(len(JOINTS) + 2, 3, figsize=(12, 2.3 * (len(JOINTS) + 2)), sharex=True)
    for row, joint in enumerate(JOINTS):
        patterns = moment_patterns(columns, joint)
        for col in range(3):
            ax = axes[row, col]
            if col >= len(patterns) or not draw(ax, patterns[col]):
                ax.axis("off")
                continue
            ax.set_title(patterns[col].replace(f"{joint}_{{s}}_", f"{joint} ").replace("_moment_per_kg", " moment")
                         .replace("_", " "), fontsize=9)
            ax.set_ylabel("N·m/kg")
        power = axes[len(JOINTS), row]
        if draw(power, f"{joint}_{{s}}_power_W_per_kg"):
            power.set_title(f"{joint} power (+ generated)", fontsize=9)
            power.set_ylabel("W/kg")
        else:
            power.axis("off")
    grf = [draw(axes[len(JOINTS) + 1, col], pattern) for col, (pattern, _) in enumerate(GRF)]
    for col, (_, name) in enumerate(GRF):
        ax = axes[len(JOINTS) + 1, col]
        if grf[col]:
            ax.set_title(name, fontsize=9)
            ax.set_ylabel("% body weight")
        else:
            ax.axis("off")
        # the cycle axis under the lowest drawn row (tables made before the ground reactions were: the powers)
        bottom = ax if any(grf) else axes[len(JOINTS), col]
        bottom.set_xlabel("gait cycle (%)")
        bottom.tick_params(labelbottom=True)
    return fig, axes


def session_figures(session: Path, folder: Path, *, title: str = "", band: Band | None = None) -> list[Path]:
    """``kinematics.png`` (deg) and ``kinetics.png`` (N·m/kg, W/kg, % body weight) of the session folder
    ``session`` (``gait_out/session``) into ``folder``."""
    cycle = pd.read_csv(session / "cycle.csv")
    strides = pd.read_csv(session / "strides.csv")
    complete = strides[strides.status != "rejected"]
    foot_off = {side: float(g.stance_pct.mean()) for side, g in complete.groupby("side")}
    folder.mkdir(parents=True, exist_ok=True)

    def draw(ax, pattern):
        return _draw(ax, cycle, pattern, band, foot_off)

    fig, axes = kinematics_grid(draw)
    _legend(fig, axes)
    fig.suptitle(f"{title}: kinematics, mean ± SD of every stride; foot off dashed, normal's dash-dot".strip(": "),
                 fontsize=11)
    written = [save(fig, folder / "kinematics.png")]
    fig, axes = kinetics_grid(draw, cycle.columns)
    _legend(fig, axes)
    fig.suptitle(f"{title}: moments, powers and ground reactions, strides with the foot on the plates".strip(": "),
                 fontsize=11)
    written.append(save(fig, folder / "kinetics.png"))
    return written


def _legend(fig, axes) -> None:
    handles, labels = next(((h, lab) for ax in axes.flat for h, lab in [ax.get_legend_handles_labels()] if h),
                           ([], []))
    if handles:
        fig.legend(handles, labels, loc="upper right", fontsize=8)
    fig.tight_layout(rect=(0, 0, 1, 0.95))
