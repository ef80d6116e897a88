"""Figures a clinician can read: units on every axis, events marked, right in red / left in blue.

Every figure is drawn from a stage's HDF5 output (``filter.h5``, ``idyn.h5``,
``muscles.h5``), so that reports can draw them again from results on disk.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
# titles at a fixed height: matplotlib's automatic placement measures every axis (benchmarks/README.md, "Figures")
matplotlib.rcParams["axes.titley"] = 1.0
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from gaitcli.core.events import SIDE_NAMES  # noqa: E402
from gaitcli.core.physics import GRAVITY_M_S2  # noqa: E402
from gaitcli.io.atomic import atomic_path  # noqa: E402
from gaitcli.io.h5 import read_result  # noqa: E402
from gaitcli.io.stage_files import IdynTables, read_filter_signals, read_idyn_tables  # noqa: E402
from gaitcli.signal.bands import Band  # noqa: E402
from gaitcli.signal.cycles import CYCLE_PCT  # noqa: E402

SIDE_COLOUR = {"r": "tab:red", "l": "tab:blue"}


def save(fig, path: Path) -> Path:
    """Save a figure atomically as PNG and close it (at most 5 ticks per axis: readable, and quick to draw)."""
    from matplotlib.ticker import AutoLocator, MaxNLocator

    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            if type(axis.get_major_locator()) is AutoLocator:  # not where ticks were set by name
                axis.set_major_locator(MaxNLocator(5))
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=100)
    plt.close(fig)
    return path


def mark_events(ax, events, *, sides=("r", "l")) -> None:
    """Vertical lines at heel strikes (solid) and toe offs (dashed), coloured by side (one collection each)."""
    for side in sides:
        for kind, style in (("heel_strike", "solid"), ("toe_off", "dashed")):
            times = events.times(side, kind)
            if times.size:
                ax.vlines(times, 0, 1, transform=ax.get_xaxis_transform(), colors=SIDE_COLOUR.get(side, "grey"),
                          linewidths=0.8, alpha=0.6, linestyles=style)


#: foot off in normal walking, % of the cycle (the dissertation's 3.3.3: stance 61 %)
NORMAL_FOOT_OFF_PCT = 61.0


def mark_foot_off(ax, strides=None, *, foot_off_pct: dict[str, float] | None = None) -> None:
    """Each side's mean foot off (% of its cycle; from its strides' toe offs, or given) dashed in its colour, and
    normal walking's (:data:`NORMAL_FOOT_OFF_PCT`) dash-dotted grey."""
    if foot_off_pct is None:
        foot_off_pct = {}
        for side in ("r", "l"):
            offs = [100 * (s.toe_off_s - s.start_s) / s.period_s for s in strides or () if s.side == side]
            offs = [o for o in offs if np.isfinite(o)]
            if offs:
                foot_off_pct[side] = float(np.mean(offs))
    ax.axvline(NORMAL_FOOT_OFF_PCT, color="0.55", ls="-.", lw=0.9, zorder=0.4)
    for side, pct in foot_off_pct.items():
        ax.axvline(pct, color=SIDE_COLOUR[side], ls="--", lw=0.8)


def draw_band(ax, band: Band | None, variable: str, *, label: bool = True) -> bool:
    """Grey mean ± 1 SD of ``variable`` behind whatever ``ax`` shows over 0–100 % (True when drawn)."""
    got = None if band is None else band.get(variable)
    if got is None:
        return False
    mean, sd = got
    ax.fill_between(CYCLE_PCT, mean - sd, mean + sd, color="0.82", lw=0, zorder=0,
                    label="normal ± 1 SD" if label else None)
    ax.plot(CYCLE_PCT, mean, color="0.6", lw=0.8, ls=":", zorder=0.5)
    return True


def filter_figures(h5_path: Path, folder: Path, *, title: str = "", body_mass_kg: float | None = None) -> list[Path]:
    """``markers.png`` (raw vs filtered, a few foot and pelvis landmarks) and ``grf.png`` (per foot, events: the
    vertical, fore-aft and mediolateral force, in % of body weight given ``body_mass_kg``, else N, and the
    centre of pressure)."""
    signals = read_filter_signals(h5_path)
    trial, raw, cutoff_hz = signals.trial, signals.raw_markers_m, signals.cutoff_hz
    folder = Path(folder)
    written = []
    smooth = trial.markers
    events = trial.events
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
                ax.plot(t, raw[:, i, k] * 1000, ".", ms=2, color="0.6", label="raw")
                ax.plot(t, smooth.positions_m[:, i, k] * 1000, color="k", lw=1.2, label="filtered")
                mark_events(ax, events)
                ax.set_ylabel(f"{name} {axis} (mm)")
        axes[0, 0].legend(loc="best", fontsize=8)
        for ax in axes[-1]:
            ax.set_xlabel("time (s)")
        fig.suptitle(f"Markers, raw vs filtered ({cutoff_hz:g} Hz zero-lag) — {title}", fontsize=10)
        fig.subplots_adjust(left=0.08, right=0.98, top=0.94, bottom=0.08, hspace=0.15, wspace=0.25)
        written.append(save(fig, folder / "markers.png"))

    loads = {side: (load.force_N, load.cop_m) for side, load in trial.feet.items() if load.on_plates} \
        or {name: (plate.force_N, plate.cop_m) for name, plate in signals.plates.items()}
    if loads:
        scale, unit = (100.0 / (body_mass_kg * GRAVITY_M_S2), "% body weight") if body_mass_kg else (1.0, "N")
        fig, axes = plt.subplots(4, 1, figsize=(10, 8.5), sharex=True)
        t = trial.time_s
        for name, (force, cop) in loads.items():
            colour = SIDE_COLOUR.get(name, None)
            label = SIDE_NAMES.get(name, name)
            for row, component in enumerate((2, 0, 1)):
                axes[row].plot(t, scale * force[:, component], color=colour, label=label)
            axes[3].plot(t, cop[:, 0], color=colour, label=label)
        for plate in signals.plates.values():
            raw_fz = plate.raw_vertical_force_N
            if raw_fz.size:
                axes[0].plot(np.arange(raw_fz.size) / plate.analog_rate_hz, scale * raw_fz, color="0.7", lw=0.6,
                             zorder=0)
        for ax in axes:
            mark_events(ax, events)
        for row, direction in enumerate(("vertical", "fore-aft", "mediolateral, + left")):
            axes[row].set_ylabel(f"{direction} GRF\n({unit})", fontsize=9)
        axes[3].set_ylabel("COP forward x (m)", fontsize=9)
        axes[3].set_xlabel("time (s)  —  solid: heel strike, dashed: toe off; grey: unfiltered plates")
        axes[0].legend(loc="upper right", fontsize=8)
        fig.suptitle(f"Ground reactions per foot — {title}", fontsize=10)
        fig.subplots_adjust(left=0.09, right=0.98, top=0.95, bottom=0.07, hspace=0.12)
        written.append(save(fig, folder / "grf.png"))
    return written


#: each plane's figure: (joint, title, the angle's senses, the moment's senses), the first sense the tables have
#: naming the column (anatomical/Plug-in Gait names first, then the coordinates' of ``angles: posture`` and
#: ``moments: coordinate``)
PLANES = {"sagittal": (("hip", "hip flexion", ("flexion",), ("extensor", "flexion")),
                       ("knee", "knee flexion", ("flexion",), ("extensor", "flexion")),
                       ("ankle", "ankle dorsiflexion", ("flexion",), ("plantarflexor", "flexion"))),
          "frontal": (("hip", "hip adduction", ("adduction",), ("abductor", "adduction")),
                      ("knee", "knee adduction (varus)", ("adduction",), ("abductor", "adduction")),
                      ("ankle", "ankle inversion", ("inversion", "adduction"), ("everter", "adduction")))}


def _column(columns: list[str], joint: str, side: str, senses, suffix: str = "") -> tuple[int, str]:
    """(index, sense) of the first ``<joint>_<side>_<sense><suffix>`` in ``columns``."""
    sense = next(s for s in senses if f"{joint}_{side}_{s}{suffix}" in columns)
    return columns.index(f"{joint}_{side}_{sense}{suffix}"), sense


def cycle_figure(h5_path: Path, plane: str = "sagittal", *, title: str = "", band=None):
    """Angles (deg), moments (N·m/kg) and, in the sagittal figure, total joint powers (W/kg) of hip, knee and
    ankle in ``plane`` over the gait cycle, mean ± SD of each side's strides (right red, left blue) over the grey
    normal ``band`` (:mod:`gaitcli.signal.bands`, the variable of the same name); moments and powers blank where
    the foot's load is unknown. Returns the matplotlib figure."""
    from gaitcli.signal.cycles import Stride

    strides = read_result(h5_path, list[Stride], "strides", what="gait idyn")
    return _cycle_figure(read_idyn_tables(h5_path), strides, plane, title=title, band=band)


def _cycle_figure(tables: IdynTables, strides, plane: str, *, title: str, band):
    """:func:`cycle_figure` of the tables and strides read from ``idyn.h5``."""
    from gaitcli.signal.cycles import normalise

    kin, angle_columns = tables.angles.values, tables.angles.columns
    mom = tables.known_moments_Nm() / tables.body_mass_kg  # blank where the foot's load is unknown
    moment_columns, convention = tables.moments.columns, tables.moments.convention
    power = None
    if plane == "sagittal" and tables.powers is not None:  # total joint power (W/kg), generated positive
        power = tables.known_powers_W() / tables.body_mass_kg
        power_joints = tables.powers.columns
    time_s = tables.time_s
    rows = 2 if power is None else 3
    fig, axes = plt.subplots(rows, 3, figsize=(12, 3 * rows), sharex=True)
    pct = CYCLE_PCT
    banded = False
    for col, (joint, label, angle_senses, moment_senses) in enumerate(PLANES[plane]):
        angle_sense = _column(angle_columns, joint, "r", angle_senses)[1]
        moment_sense = _column(moment_columns, joint, "r", moment_senses, "_moment")[1]
        banded |= draw_band(axes[0, col], band, f"{joint}_{angle_sense}_deg")
        banded |= draw_band(axes[1, col], band, f"{joint}_{moment_sense}_moment_per_kg")
        if power is not None:
            banded |= draw_band(axes[2, col], band, f"{joint}_power_W_per_kg")
        for side in ("r", "l"):
            ks = [s for s in strides if s.side == side]
            a_col = _column(angle_columns, joint, side, angle_senses)[0]
            m_col = _column(moment_columns, joint, side, moment_senses, "_moment")[0]
            curves = [[normalise(kin[:, a_col], time_s, s) for s in ks],
                      [normalise(mom[:, m_col], time_s, s) for s in ks]]
            if power is not None:
                p_col = power_joints.index(f"{joint}_{side}")
                curves.append([normalise(power[:, p_col], time_s, s) for s in ks])
            for row, values in enumerate(curves):
                if not values:
                    continue
                values = np.array(values)
                with warnings.catch_warnings():  # a percentage no stride's load is known at stays blank
                    warnings.simplefilter("ignore", RuntimeWarning)
                    mean, sd = np.nanmean(values, axis=0), np.nanstd(values, axis=0)
                ax = axes[row, col]
                ax.plot(pct, mean, color=SIDE_COLOUR[side], label=f"{SIDE_NAMES[side]} (n={len(ks)})")
                ax.fill_between(pct, mean - sd, mean + sd, color=SIDE_COLOUR[side], alpha=0.15, lw=0)
        axes[0, col].set_title(label, fontsize=10)
        axes[0, col].set_ylabel("angle (deg)")
        axes[1, col].set_ylabel(f"{joint} {moment_sense.replace('_', ' ')} moment (N·m/kg)")
        if power is not None:
            axes[2, col].set_ylabel(f"{joint} power (W/kg, + generated)")
        axes[rows - 1, col].set_xlabel("gait cycle (%)")
        for row in range(rows):
            axes[row, col].axhline(0, color="0.7", lw=0.6)
    for ax in axes.flat:
        mark_foot_off(ax, strides)
    for row in range(rows):
        for ax in axes[row]:
            ax.legend(fontsize=7, loc="best")
    sign = "flexion / dorsiflexion" if plane == "sagittal" else "adduction / varus / inversion"
    if convention.startswith("Plug-in Gait"):
        sign += ("; moments + = extensor / plantarflexor (Plug-in Gait)" if plane == "sagittal"
                 else "; moments + = abductor / everter (Plug-in Gait)")
    normal = "grey: normal ± 1 SD; " if banded else ""
    shown = "angles, moments and powers" if power is not None else "angles and moments"
    fig.suptitle(f"{plane.capitalize()} {shown} over the gait cycle — {title}\nmean ± SD of each side's strides; "
                 f"moments blank where the foot's load is unknown; + = {sign}\n{normal}dashed: each side's foot "
                 f"off; dash-dot: 3.3.3's walkers' ({NORMAL_FOOT_OFF_PCT:g} %)", fontsize=9)
    fig.subplots_adjust(left=0.07, right=0.98, top=0.86, bottom=0.09, hspace=0.12, wspace=0.3)
    return fig


def idyn_figures(h5_path: Path, folder: Path, *, title: str = "", band="default") -> list[Path]:
    """``cycle.png`` and ``cycle_frontal.png``: hip/knee/ankle angles and moments over the gait cycle
    (:func:`cycle_figure`, over the package's normal band unless ``band`` is given or None);
    ``residuals.png``: the pelvis residual force and moment over time."""
    from gaitcli.dynamics.outputs import read_idyn_output
    from gaitcli.signal.bands import default_band

    band = default_band() if band == "default" else band
    idyn = read_idyn_output(h5_path)
    tables = idyn.tables
    residual_force, residual_moment, time_s = tables.residual_force_N, tables.residual_moment_Nm, tables.time_s
    events = idyn.sagittal.events
    measured = idyn.sagittal.load_known["r"] & idyn.sagittal.load_known["l"]
    folder = Path(folder)
    written = [save(_cycle_figure(tables, idyn.strides, "sagittal", title=title, band=band), folder / "cycle.png"),
               save(_cycle_figure(tables, idyn.strides, "frontal", title=title, band=band),
                    folder / "cycle_frontal.png")]

    fig, axes = plt.subplots(2, 1, figsize=(10, 5), sharex=True)
    residual_force, residual_moment = (np.where(measured[:, None], r, np.nan) for r in (residual_force,
                                                                                        residual_moment))
    for k, axis in enumerate("xyz"):
        axes[0].plot(time_s, residual_force[:, k], label=axis)
        axes[1].plot(time_s, residual_moment[:, k], label=axis)
    for ax in axes:
        ax.fill_between(time_s, 0, 1, where=~measured, transform=ax.get_xaxis_transform(),
                        color="0.9", lw=0, label="a foot on the ground off the plates")
        mark_events(ax, events)
    axes[0].set_ylabel("pelvis residual force (N)")
    axes[1].set_ylabel("pelvis residual moment (N·m)")
    axes[1].set_xlabel("time (s)")
    axes[0].legend(fontsize=8, ncol=4)
    fig.suptitle(f"Pelvis residuals (3.22): what the model and the measured ground reactions leave unexplained "
                 f"— {title}", fontsize=9)
    fig.subplots_adjust(left=0.08, right=0.98, top=0.92, bottom=0.1, hspace=0.1)
    written.append(save(fig, folder / "residuals.png"))
    return written


def muscle_figures(h5_path: Path, folder: Path, *, title: str = "") -> list[Path]:
    """Figs. 4.7–4.9: force, activation and excitation of each muscle over the interval (heel strikes and toe
    offs of the analysed side marked), ``metabolic_cost.png``: the metabolic energy of each muscle, and where the
    trial has EMG ``activations_emg.png`` (Fig. 4.13)."""
    from gaitcli.muscles.stage import MuscleResult

    result = read_result(h5_path, MuscleResult, what="gait muscles")
    folder = Path(folder)
    written = []
    names = result.muscle_names
    t = result.time_s
    side_events = result.events
    for name, values, label, limits in (
            ("forces.png", result.forces_N, "force (N)", None),
            ("activations.png", result.activations, "activation", (-0.05, 1.05)),
            ("excitations.png", result.excitations, "excitation", None)):
        # activations and excitations on one scale: muscles compare at a glance (and fewer labels to draw)
        fig, axes = plt.subplots(2, 4, figsize=(13, 5.5), sharex=True, sharey=label != "force (N)")
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
        fig.suptitle(f"{result.method.upper()}: muscle {label.split(' ')[0]}s, {SIDE_NAMES.get(result.side, '')} leg "
                     f"(solid: heel strike, dashed: toe off; grey band: the physiological range [0, 1]{infeasible}) "
                     f"— {title}", fontsize=9)
        fig.subplots_adjust(left=0.07, right=0.98, top=0.88, bottom=0.1, hspace=0.3, wspace=0.3)
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
    ax.set_title(f"{result.method.upper()}: metabolic energy per muscle over the interval; {total} — {title}",
                 fontsize=9)
    fig.subplots_adjust(left=0.25, right=0.97, top=0.9, bottom=0.14)
    written.append(save(fig, folder / "metabolic_cost.png"))
    if result.emg is not None:
        from gaitcli.report.emg_plots import activation_emg_figure

        written.append(activation_emg_figure(result, folder, title=title))
    return written
