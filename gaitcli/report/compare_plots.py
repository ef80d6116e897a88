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
from gaitcli.report.plots import draw_band, save
from gaitcli.report.session_plots import band_variable, kinematics_grid, kinetics_grid
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

        def draw(ax, pattern, rows=rows, on_side=on_side, side=side):
            return _draw(ax, rows, on_side, pattern.format(s=side), band_variable(pattern), band, names)

        fig, axes = kinematics_grid(draw)
        _finish(fig, axes, f"{SIDE_NAMES[side]} side: kinematics, mean ± SD per condition; bars: differs from "
                           f"{names[0]}")
        written.append(save(fig, folder / f"kinematics_{side}.png"))
        fig, axes = kinetics_grid(draw, rows.columns)
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
