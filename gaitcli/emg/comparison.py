"""Estimated activations against the same trial's EMG (Diss. 4.5.4, Fig. 4.13 sets EID's activations beside EMG
linear envelopes).

Per muscle of the model whose EMG was recorded on the analysed leg, over the analysed span (the muscle
result's nodes):

- ``correlation``: Pearson's r between the activation and the normalised linear envelope at the nodes;
- ``lag_s``: the delay τ in ±:data:`MAX_LAG_S` that maximises r between a(t) and e(t − τ) (τ > 0: the EMG
  leads, as the electromechanical delay makes it), and ``lagged_correlation`` that r;
- ``on_off_agreement_pct``: the share of the nodes at which both are on or both off, each on by the same rule
  (above its 5th percentile + :data:`~gaitcli.emg.processing.ONSET_FRACTION` of its range over the span; the EMG's
  own on/off from the emg stage).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gaitcli.emg.processing import on_threshold
from gaitcli.emg.stage import EmgResult

#: the cross-correlation's lags are searched within ±this, s, in steps of :data:`LAG_STEP_S`
MAX_LAG_S = 0.15
LAG_STEP_S = 0.001


@dataclass(frozen=True)
class EmgAgreement:
    """Activations against EMG (module docstring); arrays over the compared muscles (``muscles``, the model's
    names; ``channels`` their EMG channels), and at the nodes ``time_s``: the ``envelope`` (n, m) and both
    on/off (``emg_on``, ``activation_on``)."""

    muscles: tuple[str, ...]
    channels: tuple[str, ...]
    correlation: np.ndarray
    lag_s: np.ndarray
    lagged_correlation: np.ndarray
    on_off_agreement_pct: np.ndarray
    time_s: np.ndarray
    envelope: np.ndarray
    emg_on: np.ndarray
    activation_on: np.ndarray


def _r(x: np.ndarray, y: np.ndarray) -> float:
    ok = np.isfinite(x) & np.isfinite(y)
    if ok.sum() < 3 or np.ptp(x[ok]) == 0 or np.ptp(y[ok]) == 0:
        return float("nan")
    return float(np.corrcoef(x[ok], y[ok])[0, 1])




def compare_with_emg(time_s: np.ndarray, activations: np.ndarray, muscle_names, side: str,
                     emg: EmgResult) -> EmgAgreement | None:
    """Activations (n, m) of the model's ``muscle_names`` on leg ``side`` at ``time_s`` against ``emg``; None
    where no muscle of that leg has EMG."""
    time_s = np.asarray(time_s, float)
    pairs = [(k, emg.muscles.index(f"{name}_{side}")) for k, name in enumerate(muscle_names)
             if f"{name}_{side}" in emg.muscles]
    if not pairs:
        return None
    t_emg = emg.time_s
    lags = np.arange(-MAX_LAG_S, MAX_LAG_S + LAG_STEP_S / 2, LAG_STEP_S)
    rows = {key: [] for key in ("r", "lag", "r_lag", "agree")}
    envelope = np.column_stack([np.interp(time_s, t_emg, emg.envelope[:, j], left=np.nan, right=np.nan)
                                for _, j in pairs])
    emg_on = np.column_stack([np.interp(time_s, t_emg, emg.on[:, j].astype(float)) > 0.5 for _, j in pairs])
    a = np.asarray(activations, float)[:, [k for k, _ in pairs]]
    activation_on = a > on_threshold(a)
    for c, (_, j) in enumerate(pairs):
        shifted = [_r(a[:, c], np.interp(time_s - lag, t_emg, emg.envelope[:, j], left=np.nan, right=np.nan))
                   for lag in lags]
        best = int(np.nanargmax(shifted)) if np.isfinite(shifted).any() else len(lags) // 2
        rows["r"].append(_r(a[:, c], envelope[:, c]))
        rows["lag"].append(float(lags[best]))
        rows["r_lag"].append(float(shifted[best]))
        rows["agree"].append(float(100 * np.mean(emg_on[:, c] == activation_on[:, c])))
    return EmgAgreement(muscles=tuple(muscle_names[k] for k, _ in pairs),
                        channels=tuple(emg.channels[j] for _, j in pairs),
                        correlation=np.array(rows["r"]), lag_s=np.array(rows["lag"]),
                        lagged_correlation=np.array(rows["r_lag"]), on_off_agreement_pct=np.array(rows["agree"]),
                        time_s=time_s, envelope=envelope, emg_on=emg_on, activation_on=activation_on)
