"""The figures of a comparison of conditions (``OUT/compare/``: ``cycle.csv``, ``spm.csv``), one pair per side:
each condition's mean ± SD over its strides against the grey normal band (the first condition black, the others
in colour), and under the curves a bar in a condition's colour wherever SPM finds it differs from the first
(:mod:`gaitcli.run.conditions`); the kinematics of pelvis, hip, knee, ankle and foot in three planes, the moments
in three planes, the powers and the ground reactions."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from gaitcli.core.events import SIDE_NAMES
from gaitcli.report.plots import draw_band, plt, save
from gaitcli.report.session_plots import GRF, JOINTS, KINEMATICS, PLANES, band_variable
from gaitcli.signal.bands import Band
from gaitcli.signal.cycles import CYCLE_PCT

#: the conditions' colours, the first (the one the others are compared with) black
CONDITION_COLOURS = ("black", "tab:orange", "tab:green", "tab:purple", "tab:brown", "tab:pink", "tab:olive",
                     "tab:cyan", "tab:red", "tab:blue")


def _draw(ax, cycle: pd.DataFrame, spans: pd.DataFrame, column: str, variable: str | None, band: Band | None,
          names: list[str]) -> bool:
    """One variable of one side: the band, each condition's mean ± SD, the spans that differ; True when drawn."""
    if variable:
        draw_band(ax, band, variable, label=False)
    drawn = False
    for k, name in enumerate(names):
        block = cycle[cycle.condition == name]
        if f"{column}_mean" not in block or not np.isfinite(block[f"{column}_mean"]).any():
            continue
        colour = CONDITION_COLOURS[k % len(CONDITION_COLOURS)]
        mean, sd = block[f"{column}_mean"].to_numpy(), block[f"{column}_sd"].to_numpy()
        ax.plot(CYCLE_PCT, mean, color=colour, lw=1.2, label=f"{name} (n={int(np.nanmax(block[f'{column}_n']))})")
        ax.fill_between(CYCLE_PCT, mean - sd, mean + sd, color=colour, alpha=0.1, lw=0)
        drawn = True
    if not drawn:
        return False
    low, high = ax.get_ylim()
    step = 0.035 * (high - low)
    for k, name in enumerate(names[1:], start=1):
        for span in spans[(spans.condition == name) & (spans.variable == column)].itertuples():
            y = low + step * k
            ax.plot([span.start_pct, span.end_pct], [y, y], color=CONDITION_COLOURS[k % len(CONDITION_COLOURS)],
                    lw=3, solid_capstyle="butt")
    ax.set_ylim(low, high)
    ax.axhline(0, color="0.7", lw=0.6)
    return True


def compare_figures(compare: Path, folder: Path, *, band: Band | None = None) -> list[Path]:
    """``kinematics_<side>.png`` (deg) and ``kinetics_<side>.png`` (N·m/kg, W/kg) of the comparison folder
    ``compare`` into ``folder``."""
    cycle = pd.read_csv(compare / "cycle.csv")
    spans = pd.read_csv(compare / "spm.csv")
    names = list(dict.fromkeys(cycle.condition.astype(str)))
    cycle = cycle.assign(condition=cycle.condition.astype(str))
    spans = spans.assign(condition=spans.condition.astype(str))
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for side in ("r", "l"):
        rows = cycle[cycle.side == side]
        on_side = spans[spans.side == side]
        fig, axes = plt.subplots(len(KINEMATICS), 3, figsize=(12, 2.3 * len(KINEMATICS)), sharex=True)
        for row, (part, columns) in enumerate(KINEMATICS):
            for col, pattern in enumerate(columns):
                ax = axes[row, col]
                column = pattern.format(s=side) if pattern else None
                if column is None or not _draw(ax, rows, on_side, column, band_variable(pattern), band, names):
                    ax.axis("off")
                    continue
                ax.set_title(f"{part} {pattern.split('_')[-1]}", fontsize=9)
                ax.set_ylabel("deg")
        for col, plane in enumerate(PLANES):
            bottom = max(row for row, (_, columns) in enumerate(KINEMATICS) if columns[col] is not None)
            axes[bottom, col].set_xlabel("gait cycle (%)")
            axes[bottom, col].tick_params(labelbottom=True)
            axes[0, col].annotate(plane, (0.5, 1.25), xycoords="axes fraction", ha="center", fontsize=11)
        _finish(fig, axes, f"{SIDE_NAMES[side]} side: kinematics, mean ± SD per condition; bars: differs from "
                           f"{names[0]}")
        written.append(save(fig, folder / f"kinematics_{side}.png"))

        fig, axes = plt.subplots(len(JOINTS) + 2, 3, figsize=(12, 2.3 * (len(JOINTS) + 2)), sharex=True)
        for col, (pattern, name) in enumerate(GRF):
            ax = axes[len(JOINTS) + 1, col]
            if _draw(ax, rows, on_side, pattern.format(s=side), None, band, names):
                ax.set_title(name, fontsize=9)
                ax.set_ylabel("% body weight")
            else:
                ax.axis("off")
            ax.set_xlabel("gait cycle (%)")
        for row, joint in enumerate(JOINTS):
            moments = [c[:-len("_mean")] for c in rows.columns
                       if c.startswith(f"{joint}_{side}_") and c.endswith("_moment_per_kg_mean")]
            for col in range(3):
                ax = axes[row, col]
                column = moments[col] if col < len(moments) else None
                pattern = column.replace(f"{joint}_{side}_", f"{joint}_{{s}}_", 1) if column else None
                if column is None or not _draw(ax, rows, on_side, column, band_variable(pattern), band, names):
                    ax.axis("off")
                    continue
                ax.set_title(column.replace(f"{joint}_{side}_", f"{joint} ").replace("_moment_per_kg", " moment")
                             .replace("_", " "), fontsize=9)
                ax.set_ylabel("N·m/kg")
            power = axes[len(JOINTS), row]
            pattern = f"{joint}_{{s}}_power_W_per_kg"
            if _draw(power, rows, on_side, pattern.format(s=side), band_variable(pattern), band, names):
                power.set_title(f"{joint} power (+ generated)", fontsize=9)
                power.set_ylabel("W/kg")
            else:
                power.axis("off")
        _finish(fig, axes, f"{SIDE_NAMES[side]} side: moments, powers, ground reactions; bars: differs from "
                           f"{names[0]}")
        written.append(save(fig, folder / f"kinetics_{side}.png"))
    return written


def _finish(fig, axes, title: str) -> None:
    handles, labels = next(((h, lab) for ax in axes.flat for h, lab in [ax.get_legend_handles_labels()] if h),
                           ([], []))
    if handles:
        fig.legend(handles, labels, loc="upper right", fontsize=8)
    fig.suptitle(title, fontsize=11)
    fig.tight_layout(rect=(0, 0, 0.86 if handles else 1, 0.95))
