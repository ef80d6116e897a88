"""A prediction study's figures: the objective per condition, weight set and speed (as Fig. 5.15) and the optimal
prostheses' curves beside the commercial feet (as Fig. 5.16); and the study table as text for the terminal."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gaitcli.predict.prosthesis import COMMERCIAL_FEET, DEFAULT_LAW
from gaitcli.report.plots import plt, save

#: bar colours per condition (the normal gait black, the optimal device dark grey, the feet lighter)
CONDITION_COLOUR = {"normal": "k", "foot_mass": "tab:orange", "sach": "#9ecae1", "seattle": "#4292c6",
                    "flex": "#08519c", "optimal": "0.4"}


def study_figures(rows: list[dict], folder: Path, *, title: str = "") -> list[Path]:
    """study.png and, when the study has optimal prostheses, curves.png into ``folder``."""
    folder = Path(folder)
    written = [objective_bars(rows, folder / "study.png", title)]
    if any(r["condition"] == "optimal" for r in rows):
        written.append(optimal_curves(rows, folder / "curves.png", title))
    return written


def objective_bars(rows: list[dict], path: Path, title: str) -> Path:
    """J per condition (bars) for each weight set (groups), one panel per speed; hatched bars did not converge."""
    speeds = sorted({r["speed_m_s"] for r in rows})
    weights = list(dict.fromkeys(r["weights"] for r in rows))
    conditions = list(dict.fromkeys(r["condition"] for r in rows))
    fig, axes = plt.subplots(1, len(speeds), figsize=(4.5 * len(speeds) + 1, 4), sharey=True, squeeze=False)
    width = 0.8 / len(conditions)
    for ax, speed in zip(axes[0], speeds):
        for c, condition in enumerate(conditions):
            for g, w in enumerate(weights):
                row = next((r for r in rows if r["speed_m_s"] == speed and r["weights"] == w
                            and r["condition"] == condition), None)
                if row is None:
                    continue
                ax.bar(g + (c - (len(conditions) - 1) / 2) * width, row["objective"], width,
                       color=CONDITION_COLOUR.get(condition, "0.7"), hatch=None if row["converged"] else "//",
                       edgecolor="k" if not row["converged"] else None,
                       label=condition if g == 0 else None)
        ax.set_xticks(range(len(weights)), [f"weights {w}" for w in weights], fontsize=8)
        ax.set_title(f"{speed:.2f} m/s", fontsize=9)
    axes[0, 0].set_ylabel("objective J (5.29)")
    axes[0, -1].legend(fontsize=7, frameon=False)
    fig.suptitle(f"Objective per condition (hatched: not converged) — {title}", fontsize=9)
    fig.subplots_adjust(left=0.08, right=0.98, top=0.86, bottom=0.12, wspace=0.08)
    return save(fig, path)


def optimal_curves(rows: list[dict], path: Path, title: str) -> Path:
    """Each optimal device's plantarflexor moment against dorsiflexion (colour per weight set, line style per
    speed) beside Table A.7's feet (grey)."""
    dorsiflexion = np.linspace(-20.0, 30.0, 201)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for foot, style in zip(COMMERCIAL_FEET.values(), (":", "--", "-.")):
        ax.plot(dorsiflexion, foot.plantarflexor_moment_Nm(np.radians(dorsiflexion)), color="0.6", ls=style, lw=1.2,
                label=f"{foot.name} (Table A.7)")
    weights = list(dict.fromkeys(r["weights"] for r in rows))
    speeds = sorted({r["speed_m_s"] for r in rows})
    styles = ("-", "--", ":", "-.")
    for r in rows:
        if r["condition"] != "optimal":
            continue
        curve = DEFAULT_LAW.from_values("optimal", [r[f"prosthesis_{k}"] for k in DEFAULT_LAW.COEFFICIENTS])
        colour = plt.get_cmap("viridis")(weights.index(r["weights"]) / max(1, len(weights) - 1))
        ax.plot(dorsiflexion, curve.plantarflexor_moment_Nm(np.radians(dorsiflexion)), color=colour,
                ls=styles[speeds.index(r["speed_m_s"]) % len(styles)], lw=1.5,
                label=f"optimal, {r['speed_m_s']:.2f} m/s, weights {r['weights']}")
    ax.axhline(0, color="k", lw=0.5)
    ax.axvline(0, color="k", lw=0.5)
    ax.set_xlabel("ankle dorsiflexion (deg)")
    ax.set_ylabel("plantarflexor moment (N·m)")
    ax.set_ylim(-150, 400)
    ax.legend(fontsize=6, frameon=False, loc="upper left", ncol=2)
    ax.set_title(f"Optimal prosthetic ankles beside the commercial feet (5.58) — {title}", fontsize=9)
    fig.subplots_adjust(left=0.11, right=0.98, top=0.9, bottom=0.12)
    return save(fig, path)


def _shown(value, width: int, digits: int) -> str:
    """A number right-aligned in ``width``, or "-" where a row has none."""
    return f"{value:>{width}.{digits}f}" if isinstance(value, (int, float)) else f"{'-':>{width}}"


def study_text(rows: list[dict]) -> str:
    """The study table (as Table 5.3) as aligned text: one line per case; unconverged cases marked '*'."""
    head = (f"{'speed':>6} {'weights':>8} {'condition':>10} {'J':>8} {'Et J/m':>8} {'Jdev':>8} {'stride m':>8}"
            f" {'steps/min':>9}  status")
    lines = [head, "-" * len(head)]
    for r in rows:
        status = ("converged" if r["converged"] else "* NOT CONVERGED") + (" (reused)" if r["reused"] else "")
        lines.append(f"{r['speed_m_s']:>6.2f} {r['weights']:>8} {r['condition']:>10} {r['objective']:>8.3f} "
                     f"{r['cost_of_transport_J_per_m']:>8.1f} {r['deviation']:>8.2f} {_shown(r.get('stride_m'), 8, 3)}"
                     f" {_shown(r.get('cadence_steps_per_min'), 9, 1)}  {status}")
    return "\n".join(lines)
