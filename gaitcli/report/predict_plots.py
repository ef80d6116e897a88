"""Figures of a predicted gait (Diss. Figs. 5.7–5.12), drawn from ``predict.h5``: right in red, left in blue,
the reference's mean ± SD as a grey band, cycle in % from right heel strike."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from gaitcli.core.physics import GRAVITY_M_S2
from gaitcli.io.h5 import read_result
from gaitcli.report.plots import SIDE_COLOUR, plt, save
from gaitcli.signal.cycles import CYCLE_PCT

ANGLE_LABELS = ("hip flexion (°)", "knee flexion (°)", "ankle dorsiflexion (°)")
GRF_LABELS = ("fore-aft GRF (N/kg)", "vertical GRF (N/kg)")
MOMENT_LABELS = ("hip flexion moment (N·m)", "knee flexion moment (N·m)", "ankle dorsiflexion moment (N·m)")
#: segments of the stick figure: pairs of point names
STICKS = (("hip", "hat_com"), ("hip", "knee_r"), ("knee_r", "ankle_r"), ("ankle_r", "heel_r"), ("heel_r", "mtp_r"),
          ("ankle_r", "mtp_r"), ("hip", "knee_l"), ("knee_l", "ankle_l"), ("ankle_l", "heel_l"), ("heel_l", "mtp_l"),
          ("ankle_l", "mtp_l"))


def _band(ax, reference_mean, reference_sd, k):
    pct = CYCLE_PCT
    m, s = reference_mean[:, k], reference_sd[:, k]
    ax.fill_between(pct, m - s, m + s, color="0.85", lw=0, label="reference ± SD")
    ax.plot(pct, m, color="0.55", lw=0.8)


def _against_reference(r, pct, values, first_reference, labels, path: Path, title: str, *, figsize, left, wspace,
                       body_weight: bool = False) -> Path:
    """A 2 × len(labels) figure, right leg above left: ``values`` (n, 2·len(labels)) at ``pct`` over the
    reference band of columns ``first_reference`` + k; a dotted body-weight line on vertical forces."""
    columns = len(labels)
    fig, axes = plt.subplots(2, columns, figsize=figsize, sharex=True)
    for side, row in (("r", 0), ("l", 1)):
        for k in range(columns):
            ax = axes[row, k]
            _band(ax, r.reference_mean, r.reference_sd, first_reference + columns * row + k)
            ax.plot(pct, values[:, columns * row + k], color=SIDE_COLOUR[side], lw=1.5)
            if body_weight and labels[k].startswith("vertical"):
                ax.axhline(GRAVITY_M_S2, color="k", lw=0.6, ls=":")
            _stance_end(ax, r)
            ax.set_ylabel(f"{'right' if side == 'r' else 'left'} {labels[k]}", fontsize=9)
            ax.set_xlim(0, 100)
    for ax in axes[-1]:
        ax.set_xlabel("gait cycle (%)")
    fig.suptitle(title, fontsize=9)
    fig.subplots_adjust(left=left, right=0.98, top=0.92, bottom=0.09, hspace=0.15, wspace=wspace)
    return save(fig, path)


def _stance_end(ax, result):
    """The right toe off (end of phase 6) and the left heel strike (end of phase 4) as vertical lines."""
    d = result.phase_durations_s
    for pct, side in ((100 * d[:6].sum() / d.sum(), "r"), (100 * d[:4].sum() / d.sum(), "l")):
        ax.axvline(pct, color=SIDE_COLOUR[side], lw=0.7, ls="--", alpha=0.6)


def predict_figures(h5_path: Path, folder: Path, *, title: str = "") -> list[Path]:
    """angles.png (Fig. 5.8), grf.png (5.9), moments.png (5.10), muscles.png (5.12), stick.png (5.7) and the
    animated walk.gif."""
    from gaitcli.predict.stage import PredictResult

    r = read_result(h5_path, PredictResult, what="gait predict")
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    state = "" if r.converged else " (NOT CONVERGED)"
    caption = (f"predicted gait{state}, {r.speed_m_s:.2f} m/s — {title}; dashed: right toe off (red), left heel "
               "strike (blue)")
    written = []
    pct_i = r.cycle_pct
    pct_p = 100 * r.point_time_s / r.period_s

    written.append(_against_reference(r, pct_i, r.clinical_angles_deg, 0, ANGLE_LABELS, folder / "angles.png",
                                      f"Joint angles: {caption}", figsize=(12, 6), left=0.07, wspace=0.3))
    written.append(_against_reference(r, pct_p, r.grf_N / r.body_mass_kg, 6, GRF_LABELS, folder / "grf.png",
                                      f"Ground reactions (dotted: body weight): {caption}", figsize=(10, 6),
                                      left=0.08, wspace=0.25, body_weight=True))

    fig, axes = plt.subplots(2, 3, figsize=(12, 6), sharex=True)
    for side, row in (("r", 0), ("l", 1)):
        for k in range(3):
            ax = axes[row, k]
            ax.plot(pct_p, r.joint_moments_Nm[:, 3 * row + k], color="k", lw=1.2, label="inverse dynamics")
            ax.plot(pct_p, r.muscle_moments_Nm[:, 3 * row + k], color=SIDE_COLOUR[side], lw=1.2, ls="--",
                    label="muscles + passive")
            _stance_end(ax, r)
            ax.set_ylabel(f"{'right' if side == 'r' else 'left'} {MOMENT_LABELS[k]}", fontsize=8)
            ax.set_xlim(0, 100)
    axes[0, 0].legend(fontsize=8, frameon=False)
    for ax in axes[-1]:
        ax.set_xlabel("gait cycle (%)")
    fig.suptitle(f"Joint moments, inverse dynamics vs muscles (5.49–5.51): {caption}", fontsize=9)
    fig.subplots_adjust(left=0.07, right=0.98, top=0.92, bottom=0.09, hspace=0.15, wspace=0.3)
    written.append(save(fig, folder / "moments.png"))

    fig, axes = plt.subplots(2, 4, figsize=(13, 5.5), sharex=True, sharey=True)
    right = [k for k, name in enumerate(r.muscle_names) if name.endswith("_r")]  # 6 with prostheses
    for ax in axes.ravel()[len(right):]:
        ax.set_visible(False)
    for k, ax in zip(right, axes.ravel()):
        ax.axhspan(0, 1, color="0.93", zorder=0)
        ax.plot(pct_i, r.activations[:, k], color=SIDE_COLOUR["r"], lw=1.3, label="activation")
        ax.plot(pct_i, r.excitations[:, k], color="k", lw=0.9, ls="--", label="excitation")
        _stance_end(ax, r)
        ax.set_title(r.muscle_names[k].removesuffix("_r").replace("_", " "), fontsize=9)
        ax.set_xlim(0, 100)
    axes[0, 0].legend(fontsize=7, frameon=False)
    for ax in axes[-1]:
        ax.set_xlabel("gait cycle (%)")
    fig.suptitle(f"Right-leg activations and excitations (grey: [0, 1]): {caption}", fontsize=9)
    fig.subplots_adjust(left=0.05, right=0.98, top=0.88, bottom=0.1, hspace=0.3, wspace=0.15)
    written.append(save(fig, folder / "muscles.png"))

    index = {name: k for k, name in enumerate(r.point_names)}
    fig, ax = plt.subplots(figsize=(13, 3.4))
    frames = [int(np.argmin(np.abs(r.cycle_pct - pct))) for pct in range(0, 100, 10)]
    opening = _opening_points(r)
    for k, i in enumerate(frames):  # side by side, each about its own hip
        _draw_stick(ax, r, index, i, opening, shift=0.8 * k - r.points_m[i, index["hip"], 0])
        ax.text(0.8 * k, -0.12, f"{r.cycle_pct[i]:.0f} %", ha="center", fontsize=8)
    ax.axhline(0, color="k", lw=0.8)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_ylabel("up (m)")
    ax.set_title(f"Stick figure every 10 % of the cycle, ground reactions as arrows (1 m per 1000 N): {caption}",
                 fontsize=8)
    fig.subplots_adjust(left=0.06, right=0.99, top=0.9, bottom=0.15)
    written.append(save(fig, folder / "stick.png"))
    written.append(_walk_gif(r, index, opening, folder / "walk.gif"))
    if r.prosthesis is not None:
        written.append(prosthesis_figure(r, folder / "prosthesis.png", caption))
    return written


def prosthesis_figure(r, path: Path, caption: str) -> Path:
    """The device's spring moment against ankle dorsiflexion beside Table A.7's feet (as Fig. 5.16), with the
    moment the right prosthesis gave over the predicted cycle (spring and damping, 5.59)."""
    from gaitcli.predict.prosthesis import COMMERCIAL_FEET

    dorsiflexion = np.linspace(-20.0, 30.0, 201)  # deg, clinical (y = −dorsiflexion)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for foot, style in zip(COMMERCIAL_FEET.values(), (":", "--", "-.")):
        ax.plot(dorsiflexion, foot.plantarflexor_moment_Nm(np.radians(dorsiflexion)), color="0.45", ls=style,
                lw=1.1, label=f"{foot.name} (Table A.7)")
    ax.plot(dorsiflexion, r.prosthesis.plantarflexor_moment_Nm(np.radians(dorsiflexion)), color="k", lw=1.8,
            label=f"this run's device ({r.prosthesis.name})")
    ax.plot(r.clinical_angles_deg[:, 2], r.ankle_moment_Nm[:, 0], color=SIDE_COLOUR["r"], lw=1.2,
            label="right prosthesis over the cycle (with damping)")
    ax.axhline(0, color="k", lw=0.5)
    ax.axvline(0, color="k", lw=0.5)
    ax.set_xlabel("ankle dorsiflexion (deg)")
    ax.set_ylabel("plantarflexor moment (N·m)")
    ax.set_xlim(dorsiflexion[0], dorsiflexion[-1])
    ax.set_ylim(-150, 400)
    ax.legend(fontsize=8, frameon=False, loc="upper left")
    ax.set_title(f"Prosthetic ankle, moment against angle (5.58–5.59): {caption}", fontsize=8)
    fig.subplots_adjust(left=0.11, right=0.98, top=0.9, bottom=0.12)
    return save(fig, path)


def _opening_points(r) -> np.ndarray:
    """The control point that opens each instant (the first with that time)."""
    _, first = np.unique(np.round(r.point_time_s, 12), return_index=True)
    return first[:len(r.time_s)]


def _stick_colour(point: str) -> str:
    """A stick's colour by the side of its distal point (black for the trunk)."""
    side = "l" if point.endswith("_l") else "r" if point.endswith("_r") else None
    return SIDE_COLOUR.get(side, "k")


def _draw_stick(ax, r, index, i, opening, *, alpha=1.0, shift=0.0):
    p = r.points_m[i] + np.array([shift, 0.0])
    for a, b in STICKS:
        ax.plot([p[index[a], 0], p[index[b], 0]], [p[index[a], 1], p[index[b], 1]],
                color=_stick_colour(b), lw=1.2, alpha=alpha)
    j = opening[i] if i < len(opening) else 0
    for k, side in enumerate(("r", "l")):
        fx, fz = r.grf_N[j, 2 * k], r.grf_N[j, 2 * k + 1]
        if fz > 5.0:
            heel, mtp = p[index[f"heel_{side}"]], p[index[f"mtp_{side}"]]
            x0 = 0.5 * (heel[0] + mtp[0])
            ax.arrow(x0, 0.0, fx / 1000, fz / 1000, color=SIDE_COLOUR[side], width=0.004, alpha=0.6,
                     length_includes_head=True)


def _walk_gif(r, index, opening, path: Path) -> Path:
    """The cycle animated, 20 frames per second, in a window that travels with the hip (floor marks every 0.5 m
    show the progression). The artists are made once and only their data change from frame to frame."""
    from PIL import Image

    fig, ax = plt.subplots(figsize=(6, 4))
    hip = r.points_m[:, index["hip"], 0]
    ax.axhline(0, color="k", lw=0.8)
    ax.set_xlim(-1.0, 1.0)
    ax.set_ylim(-0.1, 1.8)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_ylabel("height, m")
    sticks = [ax.plot([], [], color=_stick_colour(b), lw=1.2)[0] for _, b in STICKS]
    floor = ax.plot([], [], color="0.5", lw=0.8)[0]
    forces = ax.quiver([0.0, 0.0], [0.0, 0.0], [0.0, 0.0], [0.0, 0.0], color=[SIDE_COLOUR["r"], SIDE_COLOUR["l"]],
                       angles="xy", scale_units="xy", scale=1000.0, width=0.006, alpha=0.6)
    title = ax.set_title("", fontsize=9)
    marks = np.arange(np.floor(hip.min()) - 1.0, np.ceil(hip.max()) + 1.5, 0.5)

    def frame(i):
        p = r.points_m[i] - np.array([hip[i], 0.0])
        for line, (a, b) in zip(sticks, STICKS):
            line.set_data([p[index[a], 0], p[index[b], 0]], [p[index[a], 1], p[index[b], 1]])
        x = np.repeat(marks - hip[i], 3)
        floor.set_data(x, np.tile([0.0, -0.03, np.nan], marks.size))
        j = opening[i] if i < len(opening) else 0
        at, load = np.full((2, 2), 10.0), np.zeros((2, 2))  # an unloaded foot's arrow off the axes
        for k, side in enumerate(("r", "l")):
            fx, fz = r.grf_N[j, 2 * k], r.grf_N[j, 2 * k + 1]
            if fz > 5.0:
                at[k] = 0.5 * (p[index[f"heel_{side}"], 0] + p[index[f"mtp_{side}"], 0]), 0.0
                load[k] = fx, fz
        forces.set_offsets(at)
        forces.set_UVC(load[:, 0], load[:, 1])
        title.set_text(f"{r.cycle_pct[i]:5.1f} % of the cycle")

    # blitted by hand: the axes, ticks and labels are drawn once; each frame restores them and draws only the
    # moving artists, several times faster than redrawing everything (benchmarks/README.md, "Figures")
    moving = [*sticks, floor, forces, title]
    for artist in moving:
        artist.set_animated(True)
    fig.canvas.draw()
    background = fig.canvas.copy_from_bbox(fig.bbox)
    images = []
    for i in range(len(r.time_s)):
        frame(i)
        fig.canvas.restore_region(background)
        for artist in moving:
            ax.draw_artist(artist)
        images.append(Image.fromarray(np.asarray(fig.canvas.buffer_rgba())[..., :3].copy()))
    tmp = path.with_name(f".{path.stem}.part.gif")
    try:
        images[0].save(tmp, format="GIF", save_all=True, append_images=images[1:], duration=50, loop=0)
        os.replace(tmp, path)
    finally:
        plt.close(fig)
        tmp.unlink(missing_ok=True)
    return path
