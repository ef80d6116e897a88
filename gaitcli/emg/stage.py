"""The ``emg`` stage: a trial's EMG channels → linear envelopes, on/off and their mean ± SD over strides
(Diss. 4.5.4 compares EID's activations with EMG envelopes).

A pure function from the trial's analog channels, its gait events and the ``{channel label: muscle}`` map to an
:class:`EmgResult`. Each channel: in volts (``ANALOG:UNITS`` V, mV or µV), the linear envelope and on/off of
:mod:`gaitcli.emg.processing`, normalised (the peak of its stride-averaged envelope, or the same channel's envelope
in an MVC trial: :func:`mvc_reference`), then cut into its own side's strides (heel strike to heel strike of the
muscle's foot) and time-normalised to 0–100 % of the cycle.

Checked before anything is computed: the channels of the map are in the trial (and in the MVC trial), the
analog rate carries EMG (at least :data:`MIN_RATE_HZ`). Warned and left out: a channel without a finite sample
or without variation. Warned and kept: a channel that clips (its extreme value reached in more than one
sample, :func:`clipped_channels`).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from gaitcli.core.events import Events
from gaitcli.core.recording import Analogs
from gaitcli.core.validate import parameter
from gaitcli.emg.channels import channel_map
from gaitcli.emg.processing import BAND_HZ, ENVELOPE_CUTOFF_HZ, MIN_BURST_S, ONSET_FRACTION, envelope_and_activity
from gaitcli.errors import GaitWarning, InputError
from gaitcli.signal.cycles import CYCLE_POINTS, Stride, normalise, strides

#: an analog rate below this carries no surface EMG (its power lies up to ~450 Hz), Hz
MIN_RATE_HZ = 500.0
#: ANALOG:UNITS (upper case, µ as U) → volts
VOLTS = {"V": 1.0, "MV": 1e-3, "UV": 1e-6}
#: a channel clips where at least this many samples lie within CLIP_TOLERANCE (relative) of its largest |value|
CLIP_SAMPLES = 2
CLIP_TOLERANCE = 1e-4
NORMALISATIONS = ("auto", "peak", "mvc")
#: an MVC trial's reference: the highest mean of its linear envelope over this long a window, s (a single
#: sample's peak would add the envelope's own ripple, ~20 % over a few seconds)
MVC_WINDOW_S = 0.5


@dataclass(frozen=True)
class EmgConfig:
    """Parameters of ``gait emg`` (4.5.4)."""

    band_low_hz: float = parameter(BAND_HZ[0], low=0.0, low_open=True,
                                   help="Band-pass lower edge, Hz (zero-lag, −3 dB there).")
    band_high_hz: float = parameter(BAND_HZ[1], low=0.0, low_open=True,
                                    help="Band-pass upper edge, Hz (at most 0.9 of the Nyquist frequency).")
    envelope_cutoff_hz: float = parameter(ENVELOPE_CUTOFF_HZ, low=0.0, low_open=True,
                                          help="Linear envelope's zero-lag low-pass cut-off, Hz.")
    onset_fraction: float = parameter(ONSET_FRACTION, low=0.0, high=1.0, low_open=True,
                                      help="On above baseline + this fraction of the envelope's range.")
    min_burst_s: float = parameter(MIN_BURST_S, low=0.0, help="Bursts and gaps shorter than this are dropped, s.")
    normalise: str = parameter("auto", choices=NORMALISATIONS,
                               help="Envelopes as a fraction of: the peak of the stride-averaged envelope (peak), "
                                    "the MVC trial's highest 0.5 s mean envelope (mvc: subject.yaml's emg_mvc), or "
                                    "mvc where subject.yaml names one, else peak (auto).")

    @property
    def band_hz(self) -> tuple[float, float]:
        return (self.band_low_hz, self.band_high_hz)


@dataclass(frozen=True)
class EmgResult:
    """Processed EMG of one trial; one column per channel (``channels`` its labels, ``muscles`` the sided
    muscle each records).

    ``raw_V`` (samples, channels) as recorded, in volts; ``envelope`` (samples, channels) the linear envelope
    normalised by ``reference_V`` (the envelope in volts that is 1); ``on`` (samples, channels). Strides (both
    feet, time order): ``stride_side``, ``stride_start_s``, ``stride_end_s``; ``stride_envelope`` and
    ``stride_on`` (strides, 101, channels) each stride's 0–100 % (every channel on every stride: a channel's
    own are those of its side); ``cycle_mean``, ``cycle_sd`` (101, channels) over its side's strides (NaN
    without any); ``cycle_on`` (101, channels) the fraction of its side's strides on at each %.
    """

    channels: tuple[str, ...]
    muscles: tuple[str, ...]
    rate_hz: float
    raw_V: np.ndarray
    envelope: np.ndarray
    on: np.ndarray
    reference_V: np.ndarray
    normalisation: str
    stride_side: np.ndarray
    stride_start_s: np.ndarray
    stride_end_s: np.ndarray
    stride_envelope: np.ndarray
    stride_on: np.ndarray
    cycle_mean: np.ndarray
    cycle_sd: np.ndarray
    cycle_on: np.ndarray
    clipped: tuple[str, ...] = ()
    config: EmgConfig = EmgConfig()
    history: tuple[str, ...] = ()

    @property
    def time_s(self) -> np.ndarray:
        return np.arange(self.raw_V.shape[0]) / self.rate_hz

    def side_of(self, k: int) -> str:
        """The foot of channel ``k``'s muscle: ``"r"`` or ``"l"``."""
        return self.muscles[k][-1]

    def own_strides(self, k: int) -> np.ndarray:
        """(strides,) which strides are channel ``k``'s side's."""
        return self.stride_side == self.side_of(k)


def in_volts(analogs: Analogs, columns: list[int], source=None) -> np.ndarray:
    """The ``columns`` of ``analogs`` (samples, len(columns)) in volts, by each channel's ANALOG:UNITS (none
    given: volts, and a warning); a unit that is no voltage is an InputError naming the channel."""
    out = np.empty((analogs.n_samples, len(columns)))
    for j, k in enumerate(columns):
        unit = analogs.units[k].strip() if k < len(analogs.units) else ""
        if not unit:
            warnings.warn(f"{source or 'trial'}: EMG channel {analogs.labels[k]} has no unit (ANALOG:UNITS): read "
                          "as volts", GaitWarning, stacklevel=3)
            unit = "V"
        scale = VOLTS.get(unit.upper().replace("\u039c", "U"))
        if scale is None:
            raise InputError(source, f"ANALOG:UNITS of {analogs.labels[k]}",
                             f"got {unit!r} (expected V, mV or µV for an EMG channel)")
        out[:, j] = analogs.values[:, k] * scale
    return out


def clipped_channels(raw: np.ndarray, labels) -> tuple[str, ...]:
    """The channels whose largest |value| is reached (within :data:`CLIP_TOLERANCE`) in at least
    :data:`CLIP_SAMPLES` samples: an amplifier or converter at its limit (band-limited EMG does not return to
    the same extreme; a pure tone sampled in phase would)."""
    out = []
    for k, label in enumerate(labels):
        x = np.abs(raw[:, k][np.isfinite(raw[:, k])])
        top = x.max() if x.size else 0.0
        if top > 0 and np.count_nonzero(x >= top * (1 - CLIP_TOLERANCE)) >= CLIP_SAMPLES:
            out.append(label)
    return tuple(out)


def _usable(raw: np.ndarray, labels, source) -> list[int]:
    """The columns worth processing; a warning naming each channel left out (no finite sample, no variation)
    or with missing samples."""
    keep = []
    for k, label in enumerate(labels):
        finite = np.isfinite(raw[:, k])
        if not finite.any() or np.ptp(raw[finite, k]) == 0:
            what = "has no finite sample" if not finite.any() else "is constant"
            warnings.warn(f"{source}: EMG channel {label} {what}: left out", GaitWarning, stacklevel=3)
            continue
        if not finite.all():
            warnings.warn(f"{source}: EMG channel {label} has {np.count_nonzero(~finite)} missing samples: its "
                          "envelope is NaN there", GaitWarning, stacklevel=3)
        keep.append(k)
    return keep


def _check_unique(labels, found: dict[str, str], source) -> None:
    """An InputError where two analog channels carry the label of one EMG channel ``found`` uses (only the first
    would be read, silently)."""
    labels = [str(label).strip() for label in labels]
    for label, muscle in found.items():
        numbers = [k + 1 for k, other in enumerate(labels) if other == label]
        if len(numbers) > 1:
            raise InputError(source, "ANALOG:LABELS", f"channels {' and '.join(map(str, numbers))} are both labelled "
                                                      f"{label!r} ({muscle}; expected one channel per label: rename "
                                                      "one in the lab's software)")


def _check_cutoffs(cfg: EmgConfig, rate_hz: float, source) -> None:
    """The band and the envelope's cutoff below the EMG channels' Nyquist frequency, each named as the pipeline
    YAML and the command line set it."""
    for key, option, value in (("envelope_cutoff_hz", "--envelope-cutoff", cfg.envelope_cutoff_hz),
                               ("band_high_hz", None, cfg.band_high_hz), ("band_low_hz", None, cfg.band_low_hz)):
        if not value < rate_hz / 2:
            raise InputError(source, f"emg.{key}" + (f" ({option})" if option else ""),
                             f"got {value:g} Hz (expected below the Nyquist frequency {rate_hz / 2:g} Hz of the EMG "
                             f"channels' {rate_hz:g} Hz)")


def _check_rate(analogs: Analogs, labels, source) -> None:
    if analogs.rate_hz < MIN_RATE_HZ:
        raise InputError(source, "ANALOG:RATE", f"EMG channels {', '.join(labels)} sampled at "
                                                f"{analogs.rate_hz:g} Hz (expected at least {MIN_RATE_HZ:g} Hz: "
                                                "surface EMG's power lies up to ~450 Hz)")


def envelopes(raw_V: np.ndarray, rate_hz: float, cfg: EmgConfig) -> tuple[np.ndarray, np.ndarray]:
    """The linear envelope (V) and on/off of raw EMG in volts (samples, channels) with ``cfg``'s settings."""
    return envelope_and_activity(raw_V, rate_hz=rate_hz, band_hz=cfg.band_hz,
                                 envelope_cutoff_hz=cfg.envelope_cutoff_hz, fraction=cfg.onset_fraction,
                                 min_burst_s=cfg.min_burst_s)


def mvc_reference(mvc: Analogs, channels, cfg: EmgConfig, source=None) -> np.ndarray:
    """Each channel's reference in the MVC trial, V: the highest mean of its linear envelope over
    :data:`MVC_WINDOW_S` (the whole trial where shorter); an InputError naming a channel it lacks or in which
    it is silent."""
    labels = [label.strip() for label in mvc.labels]
    missing = [c for c in channels if c not in labels]
    if missing:
        raise InputError(source, "emg_mvc", f"the MVC trial has no channel {', '.join(missing)} (its analog "
                                             f"channels: {', '.join(labels) or 'none'})")
    _check_rate(mvc, channels, source)
    columns = [labels.index(c) for c in channels]
    envelope, _ = envelopes(in_volts(mvc, columns, source), mvc.rate_hz, cfg)
    window = max(1, min(envelope.shape[0], int(round(MVC_WINDOW_S * mvc.rate_hz))))
    sums = np.cumsum(np.vstack([np.zeros((1, envelope.shape[1])), envelope]), axis=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # NaN samples: those windows are not counted
        peak = np.nanmax((sums[window:] - sums[:-window]) / window, axis=0)
    flat = [c for c, p in zip(channels, peak) if not p > 0]
    if flat:
        raise InputError(source, "emg_mvc", f"channel {', '.join(flat)} is silent in the MVC trial (expected a "
                                            "maximal contraction)")
    return peak


def _cycles(values: np.ndarray, time_s: np.ndarray, found: list[Stride]) -> np.ndarray:
    """(strides, 101, channels) of ``values`` (samples, channels) time-normalised per stride."""
    if not found:
        return np.zeros((0, CYCLE_POINTS, values.shape[1]))
    return np.stack([normalise(values, time_s, s) for s in found])


def _over_own_strides(per_stride: np.ndarray, own: np.ndarray, reduce, minimum: int = 1) -> np.ndarray:
    """(101, channels): ``reduce`` of each channel's cycles (``per_stride`` (strides, 101, channels)) over its own
    strides (``own`` (strides, channels)); NaN where it has fewer than ``minimum``."""
    out = np.full(per_stride.shape[1:], np.nan)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a percentage no stride covers (NaN at the record's end)
        for k in np.flatnonzero(own.sum(axis=0) >= minimum):
            out[:, k] = reduce(per_stride[own[:, k], :, k])
    return out


def run_emg(analogs: Analogs | None, events: Events, mapping: dict[str, str] | None, cfg: EmgConfig, *,
            mvc: Analogs | None = None, source=None, map_source=None, mvc_source=None,
            history: tuple[str, ...] = ()) -> EmgResult:
    """The emg stage (module docstring): ``analogs`` the trial's non-plate channels, ``events`` its gait events,
    ``mapping`` ``{channel label: sided muscle}`` (None or empty: the labels' presets), ``mvc`` the MVC trial's
    channels where normalised to it. ``source``, ``map_source``, ``mvc_source``: the trial, the file of the map
    and the MVC trial, for messages."""
    if analogs is None or not analogs.labels:
        raise InputError(source, "emg", "the trial has no analog channels besides its force plates (expected EMG "
                                        "channels)")
    found = channel_map(analogs.labels, mapping, where="emg", source=map_source if mapping else source)
    if not found:
        raise InputError(source, "emg", f"no analog channel is named as a muscle's EMG (its channels: "
                                        f"{', '.join(analogs.labels)}; expected an emg: map in subject.yaml, "
                                        "channel label: muscle_side)")
    _check_unique(analogs.labels, found, source)
    _check_rate(analogs, list(found), source)
    _check_cutoffs(cfg, analogs.rate_hz, source)
    normalisation = cfg.normalise if cfg.normalise != "auto" else "mvc" if mvc is not None else "peak"
    if normalisation == "mvc" and mvc is None:
        raise InputError(map_source, "emg_mvc", "not given (expected the MVC trial's file name, for "
                                                "emg.normalise: mvc)")
    labels = [label.strip() for label in analogs.labels]
    columns = [labels.index(label) for label in found]
    raw = in_volts(analogs, columns, source)
    keep = _usable(raw, list(found), source or "trial")
    channels = tuple(list(found)[j] for j in keep)
    if not channels:
        raise InputError(source, "emg", "no EMG channel has data (every mapped channel is empty or constant)")
    muscles = tuple(found[c] for c in channels)
    raw = raw[:, keep]
    reference = mvc_reference(mvc, channels, cfg, mvc_source) if normalisation == "mvc" else None
    clipped = clipped_channels(raw, channels)
    for label in clipped:
        warnings.warn(f"{source or 'trial'}: EMG channel {label} clips (its extreme value recurs): its envelope "
                      "is too low where it does", GaitWarning, stacklevel=2)

    envelope_V, on = envelopes(raw, analogs.rate_hz, cfg)
    time_s = np.arange(raw.shape[0]) / analogs.rate_hz
    cycles = [s for s in strides(events) if s.start_s >= time_s[0] and s.end_s <= time_s[-1]]
    side = np.array([s.side for s in cycles], dtype="<U1")
    own = (side[:, None] == np.array([m[-1] for m in muscles])[None, :]).reshape(len(cycles), len(muscles))
    stride_envelope_V = _cycles(envelope_V, time_s, cycles)
    mean_V = _over_own_strides(stride_envelope_V, own, lambda x: np.nanmean(x, axis=0))
    if reference is None:  # the peak of the stride-averaged envelope; without strides, of the envelope
        peak_of_mean = np.max(np.where(np.isfinite(mean_V), mean_V, -np.inf), axis=0)
        reference = np.where(np.isfinite(peak_of_mean), peak_of_mean, np.nanmax(envelope_V, axis=0))
    for k in np.flatnonzero(~own.any(axis=0)):
        warnings.warn(f"{source or 'trial'}: EMG channel {channels[k]} ({muscles[k]}): no complete stride of its "
                      "foot in the trial: no cycle average, normalised to its peak", GaitWarning, stacklevel=2)
    stride_envelope = stride_envelope_V / reference
    stride_on = _cycles(on.astype(float), time_s, cycles) > 0.5
    sd = _over_own_strides(stride_envelope, own, lambda x: np.nanstd(x, axis=0, ddof=1), minimum=2)
    on_share = _over_own_strides(stride_on.astype(float), own, lambda x: x.mean(axis=0))
    step = (f"emg: {len(channels)} channels, band {cfg.band_low_hz:g}–{cfg.band_high_hz:g} Hz, envelope "
            f"{cfg.envelope_cutoff_hz:g} Hz, normalised to {'the MVC trial' if normalisation == 'mvc' else 'peak'}"
            f", {len(cycles)} strides")
    return EmgResult(channels=channels, muscles=muscles, rate_hz=float(analogs.rate_hz), raw_V=raw,
                     envelope=envelope_V / reference, on=on, reference_V=np.asarray(reference, float),
                     normalisation=normalisation, stride_side=side,
                     stride_start_s=np.array([s.start_s for s in cycles]),
                     stride_end_s=np.array([s.end_s for s in cycles]), stride_envelope=stride_envelope,
                     stride_on=stride_on, cycle_mean=mean_V / reference, cycle_sd=sd, cycle_on=on_share,
                     clipped=clipped, config=cfg, history=history + (step,))
