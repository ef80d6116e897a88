"""The emg stage's figures, drawn from ``emg.h5``: raw EMG with its envelope and on/off over time
(``emg_raw.png``), and each muscle's envelope over the gait cycle, mean ± SD of its foot's strides, with its
on/off bars per stride (``emg_cycle.png``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gaitcli.core.events import SIDE_NAMES
from gaitcli.emg.stage import EmgResult
from gaitcli.io.h5 import read_result
from gaitcli.report.plots import SIDE_COLOUR, plt, save
from gaitcli.signal.cycles import CYCLE_PCT


def muscle_title(muscle: str) -> str:
    """``tibialis_anterior_r`` → ``tibialis anterior (right)``; a name without a side as it is."""
    side = {"_r": " (right)", "_l": " (left)"}.get(muscle[-2:])
    return f"{muscle[:-2].replace('_', ' ')}{side}" if side else muscle.replace("_", " ")


def _grid(n: int):
    columns = 2 if n > 3 else 1
    rows = int(np.ceil(n / columns))
    fig, axes = plt.subplots(rows, columns, figsize=(10 if columns == 2 else 7, 1.9 * rows + 0.8), sharex=True,
                             squeeze=False)
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    return fig, axes


def emg_figures(h5_path: Path, folder: Path, *, title: str = "") -> list[Path]:
    """``emg_raw.png`` and ``emg_cycle.png`` (module docstring) of an ``emg.h5``."""
    result: EmgResult = read_result(h5_path, EmgResult)
    folder = Path(folder)
    order = np.argsort([m[-1] + m for m in result.muscles], kind="stable")  # right, then left … by name
    order = np.concatenate([order[[result.muscles[k].endswith("_r") for k in order]],
                            order[[not result.muscles[k].endswith("_r") for k in order]]])
    written = []

    fig, axes = _grid(len(order))
    t = result.time_s
    for ax, k in zip(axes.T.flat, order):
        raw_mV = 1e3 * (result.raw_V[:, k] - np.nanmean(result.raw_V[:, k]))
        envelope_mV = 1e3 * result.envelope[:, k] * result.reference_V[k]
        ax.plot(t, raw_mV, color="0.75", lw=0.4)
        ax.plot(t, envelope_mV, color="k", lw=1.0)
        top = np.nanmax(np.abs(raw_mV)) if np.isfinite(raw_mV).any() else 1.0
        ax.fill_between(t, -top, -0.85 * top, where=result.on[:, k], color=SIDE_COLOUR[result.side_of(k)],
                        lw=0, step="mid")
        ax.set_ylabel("mV", fontsize=8)
        clipped = " — clips" if result.channels[k] in result.clipped else ""
        ax.set_title(f"{muscle_title(result.muscles[k])}: {result.channels[k]}{clipped}", fontsize=9)
    for ax in axes[-1]:
        ax.set_xlabel("time (s)")
    fig.suptitle(f"EMG: raw (DC removed, grey), linear envelope (black), on (bar) — {title}", fontsize=10)
    fig.tight_layout()
    written.append(save(fig, folder / "emg_raw.png"))

    if result.stride_side.size:
        fig, axes = _grid(len(order))
        for ax, k in zip(axes.T.flat, order):
            own = np.flatnonzero(result.own_strides(k))
            colour = SIDE_COLOUR[result.side_of(k)]
            mean, sd = result.cycle_mean[:, k], result.cycle_sd[:, k]
            for j in own:
                ax.plot(CYCLE_PCT, result.stride_envelope[j, :, k], color=colour, lw=0.5, alpha=0.4)
            ax.fill_between(CYCLE_PCT, mean - sd, mean + sd, color=colour, alpha=0.2, lw=0)
            ax.plot(CYCLE_PCT, mean, color=colour, lw=1.6)
            for row, j in enumerate(own):  # on/off bars, one row per stride, below zero
                y = -0.08 * (row + 1)
                ax.fill_between(CYCLE_PCT, y - 0.03, y + 0.03, where=result.stride_on[j, :, k], color=colour,
                                lw=0, step="mid")
            ax.axhline(0, color="0.6", lw=0.5)
            ax.set_xlim(0, 100)
            ax.set_title(f"{muscle_title(result.muscles[k])}, {own.size} strides", fontsize=9)
            if not own.size:
                ax.text(50, 0, "no complete stride of this foot", ha="center", va="center", fontsize=9,
                        color="0.4")
            ax.set_ylabel("envelope / ref.", fontsize=8)
        for ax in axes[-1]:
            ax.set_xlabel("% gait cycle (heel strike to heel strike of the muscle's foot)")
        reference = "the MVC trial's peak" if result.normalisation == "mvc" else "the peak of the mean"
        fig.suptitle(f"EMG envelopes over the cycle, mean ± SD (normalised to {reference}); bars: on, per stride "
                     f"— {title}", fontsize=10)
        fig.tight_layout()
        written.append(save(fig, folder / "emg_cycle.png"))
    return written


def activation_emg_figure(result, folder: Path, *, title: str = "") -> Path:
    """``activations_emg.png``: a muscle result's activations over the same trial's EMG envelopes (Fig. 4.13),
    one panel per compared muscle with r, the lag and the on/off agreement; bars: on (activation above, EMG
    below)."""
    agreement = result.emg
    fig, axes = plt.subplots(2, 4, figsize=(13, 5.5), sharex=True, sharey=True)
    colour = SIDE_COLOUR.get(result.side, "k")
    t = agreement.time_s
    for ax, k in zip(axes.ravel(), range(len(agreement.muscles))):
        activation = result.activations[:, result.muscle_names.index(agreement.muscles[k])]
        ax.plot(t, activation, color=colour, lw=1.6, label="activation")
        ax.plot(t, agreement.envelope[:, k], color="k", lw=1.0, label="EMG envelope")
        ax.fill_between(t, -0.10, -0.05, where=agreement.activation_on[:, k], color=colour, lw=0, step="mid")
        ax.fill_between(t, -0.17, -0.12, where=agreement.emg_on[:, k], color="k", lw=0, step="mid")
        ax.set_title(f"{agreement.muscles[k].replace('_', ' ')} ({agreement.channels[k]})\n"
                     f"r {agreement.correlation[k]:.2f}, lag {1e3 * agreement.lag_s[k]:+.0f} ms, "
                     f"on/off {agreement.on_off_agreement_pct[k]:.0f} %", fontsize=9)
    for ax in axes.ravel()[len(agreement.muscles):]:
        ax.set_visible(False)
    axes[0, 0].legend(loc="upper right", fontsize=7)
    for ax in axes[-1]:
        ax.set_xlabel("time (s)")
    fig.suptitle(f"{result.method.upper()} activations against the trial's EMG envelopes (normalised to the peak of "
                 f"the mean over strides; lag > 0: the EMG leads), {SIDE_NAMES.get(result.side, result.side)} leg "
                 f"— {title}", fontsize=9)
    fig.tight_layout()
    return save(fig, Path(folder) / "activations_emg.png")
