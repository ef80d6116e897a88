"""Figures a clinician can read: units on every axis, events marked, right in red / left in blue."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from gaitcli.io.atomic import atomic_path  # noqa: E402

SIDE_COLOUR = {"r": "tab:red", "l": "tab:blue"}
SIDE_NAME = {"r": "right", "l": "left"}


def save(fig, path: Path) -> Path:
    """Save a figure atomically as PNG and close it."""
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)
    return path


def mark_events(ax, events, *, sides=("r", "l")) -> None:
    """Vertical lines at heel strikes (solid) and toe offs (dashed), coloured by side."""
    for t, side, kind in zip(events.time_s, events.side, events.kind):
        if side in sides:
            ax.axvline(t, color=SIDE_COLOUR.get(side, "grey"), lw=0.8, alpha=0.6,
                       ls="-" if kind == "heel_strike" else "--")


def filter_figures(folder: Path, result, *, title: str = "") -> list[Path]:
    """``markers.png`` (raw vs filtered, a few foot and pelvis landmarks) and ``grf.png`` (per foot, events)."""
    folder = Path(folder)
    written = []
    raw, smooth = result.raw_markers, result.markers
    wanted = [n for n in ("CAr", "FMr", "CAl", "FMl", "ASISr", "LMr") if n in smooth.labels]
    if not wanted:
        wanted = list(smooth.labels[:4])
    wanted = wanted[:4]
    if wanted:
        fig, axes = plt.subplots(len(wanted), 2, figsize=(10, 2.2 * len(wanted)), sharex=True, squeeze=False)
        t = smooth.time_s
        for row, name in enumerate(wanted):
            i = smooth.index(name)
            for col, (k, axis) in enumerate(((0, "forward x"), (2, "vertical z"))):
                ax = axes[row, col]
                ax.plot(t, raw.positions_m[:, i, k] * 1000, ".", ms=2, color="0.6", label="raw")
                ax.plot(t, smooth.positions_m[:, i, k] * 1000, color="k", lw=1.2, label="filtered")
                mark_events(ax, result.events)
                ax.set_ylabel(f"{name} {axis} (mm)")
        axes[0, 0].legend(loc="best", fontsize=8)
        for ax in axes[-1]:
            ax.set_xlabel("time (s)")
        fig.suptitle(f"Markers, raw vs filtered ({result.config.cutoff_hz:g} Hz zero-lag) {title}", fontsize=10)
        written.append(save(fig, folder / "markers.png"))

    loads = result.feet or {f"plate {i + 1}": p for i, p in enumerate(result.plates)}
    if loads:
        fig, axes = plt.subplots(3, 1, figsize=(10, 7), sharex=True)
        for name, load in loads.items():
            colour = SIDE_COLOUR.get(name, None)
            label = SIDE_NAME.get(name, name)
            t = np.arange(load.force_N.shape[0]) / load.rate_hz
            axes[0].plot(t, load.force_N[:, 2], color=colour, label=label)
            axes[1].plot(t, load.force_N[:, 0], color=colour, label=label)
            axes[2].plot(t, load.cop_m[:, 0], color=colour, label=label)
        for plate in result.plates:
            if plate.raw_vertical_force_N is not None:
                t = np.arange(plate.raw_vertical_force_N.shape[0]) / plate.raw_rate_hz
                axes[0].plot(t, plate.raw_vertical_force_N, color="0.7", lw=0.6, zorder=0)
        for ax in axes:
            mark_events(ax, result.events)
        axes[0].set_ylabel("vertical GRF (N)")
        axes[1].set_ylabel("fore-aft GRF (N)")
        axes[2].set_ylabel("COP forward x (m)")
        axes[2].set_xlabel("time (s)  —  solid: heel strike, dashed: toe off; grey: unfiltered plates")
        axes[0].legend(loc="upper right", fontsize=8)
        fig.suptitle(f"Ground reactions per foot {title}", fontsize=10)
        written.append(save(fig, folder / "grf.png"))
    return written


def idyn_figures(folder: Path, result, *, title: str = "") -> list[Path]:
    """``cycle.png``: sagittal hip/knee/ankle angles and moments over the gait cycle (mean ± SD per side);
    ``residuals.png``: the pelvis residual force and moment over time."""
    from gaitcli.kinematics.conventions import coordinates_to_clinical, moments_to_clinical
    from gaitcli.kinematics.model import COORDINATES, MOMENTS
    from gaitcli.signal.cycles import normalise

    folder = Path(folder)
    written = []
    kin = coordinates_to_clinical(result.q)
    mom = moments_to_clinical(result.joint_moments_Nm) / result.mass_kg
    joints = (("hip", "hip flexion"), ("knee", "knee flexion"), ("ankle", "ankle dorsiflexion"))
    fig, axes = plt.subplots(2, 3, figsize=(12, 6), sharex=True)
    pct = np.arange(101)
    for col, (joint, label) in enumerate(joints):
        for side in ("r", "l"):
            ks = [s for s in result.strides if s.side == side]
            known = result.foot_measured[side]
            # moments only from strides whose stance was measured throughout (on a plate, or in swing)
            kk = [s for s in ks if known[(result.time_s >= s.start_s) & (result.time_s <= s.end_s)].all()]
            a = [normalise(kin[:, COORDINATES.index(f"{joint}_{side}_flexion")], result.time_s, s) for s in ks]
            m = [normalise(mom[:, MOMENTS.index(f"{joint}_{side}_flexion_moment")], result.time_s, s) for s in kk]
            for row, values, count in ((0, a, len(ks)), (1, m, len(kk))):
                if not values:
                    continue
                values = np.array(values)
                mean, sd = np.nanmean(values, axis=0), np.nanstd(values, axis=0)
                ax = axes[row, col]
                ax.plot(pct, mean, color=SIDE_COLOUR[side], label=f"{SIDE_NAME[side]} (n={count})")
                ax.fill_between(pct, mean - sd, mean + sd, color=SIDE_COLOUR[side], alpha=0.15, lw=0)
        axes[0, col].set_title(label, fontsize=10)
        axes[0, col].set_ylabel("angle (deg)")
        axes[1, col].set_ylabel("moment (N·m/kg)")
        axes[1, col].set_xlabel("gait cycle (%)")
        for row in (0, 1):
            axes[row, col].axhline(0, color="0.8", lw=0.6)
    for row in (0, 1):
        for ax in axes[row]:
            ax.legend(fontsize=7, loc="best")
    fig.suptitle(f"Sagittal angles and moments over the gait cycle, mean ± SD (moments: strides with the stance "
                 f"on a plate; + = flexion / dorsiflexion) {title}", fontsize=9)
    fig.tight_layout(rect=(0, 0, 1, 0.95))
    written.append(save(fig, folder / "cycle.png"))

    fig, axes = plt.subplots(2, 1, figsize=(10, 5), sharex=True)
    for k, axis in enumerate("xyz"):
        axes[0].plot(result.time_s, result.residual_force_N[:, k], label=axis)
        axes[1].plot(result.time_s, result.residual_moment_Nm[:, k], label=axis)
    for ax in axes:
        ax.fill_between(result.time_s, 0, 1, where=~result.measured, transform=ax.get_xaxis_transform(),
                        color="0.9", lw=0, label="a foot on the ground off the plates")
        mark_events(ax, result.events)
    axes[0].set_ylabel("pelvis residual force (N)")
    axes[1].set_ylabel("pelvis residual moment (N·m)")
    axes[1].set_xlabel("time (s)")
    axes[0].legend(fontsize=8, ncol=4)
    fig.suptitle(f"Pelvis residuals (3.22): what the model and the measured ground reactions leave unexplained "
                 f"{title}", fontsize=9)
    written.append(save(fig, folder / "residuals.png"))
    return written


def muscle_figures(folder: Path, result, events, *, title: str = "") -> list[Path]:
    """Figs. 4.7–4.9: force, activation and excitation of each muscle over the interval (heel strikes and toe
    offs of the analysed side marked), and ``metabolic_cost.png``: the metabolic energy of each muscle."""
    folder = Path(folder)
    written = []
    names = result.muscle_names
    t = result.time_s
    side_events = type(events)(frame=events.frame[events.side == result.side],
                               time_s=events.time_s[events.side == result.side],
                               side=events.side[events.side == result.side],
                               kind=events.kind[events.side == result.side],
                               source=events.source[events.side == result.side])
    for name, values, label, limits in (
            ("forces.png", result.forces_N, "force (N)", None),
            ("activations.png", result.activations, "activation", (-0.05, 1.05)),
            ("excitations.png", result.excitations, "excitation", None)):
        fig, axes = plt.subplots(2, 4, figsize=(13, 5.5), sharex=True)
        for k, ax in enumerate(axes.ravel()[: len(names)]):
            ax.plot(t, values[:, k], color=SIDE_COLOUR.get(result.side, "k"))
            if label != "force (N)":
                ax.axhspan(0, 1, color="0.93", zorder=0)
            mark_events(ax, side_events, sides=(result.side,))
            for j in result.infeasible_frames:  # MSO frames whose excitations had to leave [0, 1]
                ax.axvspan(t[max(j - 1, 0)], t[min(j + 1, t.size - 1)], color="tab:red", alpha=0.12, lw=0)
            ax.set_xlim(t[0], t[-1])
            if limits is not None and np.all(np.isfinite(values)) and values.min() >= -0.05 and values.max() <= 1.05:
                ax.set_ylim(*limits)
            ax.set_title(names[k], fontsize=10)
        for ax in axes[:, 0]:
            ax.set_ylabel(label)
        for ax in axes[-1]:
            ax.set_xlabel("time (s)")
        infeasible = "; red: infeasible frames" if result.infeasible_frames else ""
        fig.suptitle(f"{result.method.upper()}: muscle {label.split(' ')[0]}s, {SIDE_NAME.get(result.side, '')} leg "
                     f"(solid: heel strike, dashed: toe off; grey band: the physiological range [0, 1]{infeasible}) "
                     f"{title}", fontsize=9)
        fig.tight_layout(rect=(0, 0, 1, 0.94))
        written.append(save(fig, folder / name))
    fig, ax = plt.subplots(figsize=(7, 3.8))
    rows = np.arange(len(names))[::-1]  # Table A.1 order from the top
    if np.isfinite(result.metabolic_cost_J):
        ax.barh(rows, result.metabolic_energy_J, color=SIDE_COLOUR.get(result.side, "k"))
        total = f"one leg total {result.metabolic_cost_J:.1f} J"
    else:
        ax.text(0.5, 0.5, "not given: excitations or activations outside [0, 1],\nwhere the energetics model "
                "does not apply", transform=ax.transAxes, ha="center", va="center", fontsize=9)
        total = "not given"
    ax.set_yticks(rows, [n.replace("_", " ") for n in names])
    ax.set_xlabel("metabolic energy (J)")
    ax.set_title(f"{result.method.upper()}: metabolic energy per muscle over the interval; {total} {title}",
                 fontsize=9)
    fig.tight_layout()
    written.append(save(fig, folder / "metabolic_cost.png"))
    return written
