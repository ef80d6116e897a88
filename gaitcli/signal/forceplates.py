"""Ground-reaction load per plate and per foot: filtered force, centre of pressure, free moment.

A plate measures the resultant force ``F`` and moment ``M`` about the centre ``C``
of its top surface (3.1.2). Where the pressure on the surface is compressive,
the same load is a force ``F`` applied at the centre of pressure (COP) on the
surface plus a free moment ``T_z`` about the vertical:

    r = COP - C:  r_x = -M_y / F_z,   r_y = M_x / F_z,   r_z = 0
    T_z = M_z - (r_x F_y - r_y F_x)

Following 3.1.4 the force and moment signals are low-pass filtered (zero-lag
Butterworth) first, at the analog rate, and the COP and free moment are formed from
the filtered signals, only where the plate is loaded (below).

Decisions (documented here once):

* **Unloaded frames**: below the threshold the reading is offset and noise and no
  foot is on the plate, so inverse dynamics must see no load. The raw wrench is set
  to 0 where its vertical force is below the threshold *before* filtering, so that
  the filtered load runs continuously down to 0 at a contact's edges (cutting the
  filtered force at the threshold instead steps a 20 N load, ~4 N·m at the hip, to 0
  in one frame at toe-off). A frame counts as loaded where the filtered vertical
  force exceeds ``LOADED_FRACTION`` × threshold; elsewhere ``force_N`` is exactly 0
  and ``cop_m`` and ``free_moment_Nm`` are NaN.
* **Resampling to the marker frames**: the filtered signals are taken at the frame
  times, i.e. the first analog sample of each frame when the analog rate is an
  integer multiple of the marker rate (C3D stores ``rate_analog/rate_point``
  samples per frame, the first one at the frame's own time). The mean over a frame
  would be centred half a frame late (5 ms at 100 Hz). After a 6 Hz filter there
  is nothing left to alias at marker rates of 50 Hz and up. Other ratios are
  linearly interpolated at the frame times.
* The unfiltered vertical force is kept at the analog rate
  (``raw_vertical_force_N``) for timing foot contacts: a zero-lag filter spreads
  the steep loading edge symmetrically in time, which would move a threshold
  crossing by 1-2 frames (:mod:`gaitcli.signal.contacts`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gaitcli.core.numerics import true_runs
from gaitcli.core.recording import ForcePlate
from gaitcli.errors import InputError, shown
from gaitcli.signal.butterworth import lowpass

#: the filtered vertical force, as a fraction of the threshold, above which a frame counts as loaded: the
#: filter spreads each contact's edges over a few frames in which the load is small but real
LOADED_FRACTION = 1e-3

__all__ = ["PlateLoad", "centre_of_pressure", "plate_load", "combine_loads", "resample_to_frames",
           "resting_offsets"]


@dataclass
class PlateLoad:
    """Filtered load of one plate (or one foot) at ``rate_hz``, in model axes, SI units.

    ``force_N`` (n, 3): ground-on-subject force, 0 where not loaded. ``cop_m`` (n, 3):
    centre of pressure on the plate surface, NaN where not loaded. ``free_moment_Nm``
    (n,): vertical free moment about the COP, NaN where not loaded. ``loaded`` (n,):
    the frames of a contact (raw vertical force above ``threshold_N``) and the filter's run-in and run-out
    beside it (module docstring). ``corners_m`` (4, 3): the plate
    outline (None for a per-foot sum). ``raw_vertical_force_N`` (m,): the unfiltered
    vertical force at ``raw_rate_hz`` for contact timing (None for a per-foot sum).
    """

    name: str
    force_N: np.ndarray
    cop_m: np.ndarray
    free_moment_Nm: np.ndarray
    loaded: np.ndarray
    rate_hz: float
    threshold_N: float = 0.0
    corners_m: np.ndarray | None = None
    raw_vertical_force_N: np.ndarray | None = None
    raw_rate_hz: float | None = None

    @property
    def n_frames(self) -> int:
        return self.force_N.shape[0]

    @property
    def time_s(self) -> np.ndarray:
        return np.arange(self.n_frames) / self.rate_hz

    def moment_about_origin_Nm(self) -> np.ndarray:
        """Moment (n, 3) of the load about the model origin: ``COP x F + (0, 0, T_z)``; 0 where not loaded."""
        cop = np.where(self.loaded[:, None], self.cop_m, 0.0)
        free = np.where(self.loaded, self.free_moment_Nm, 0.0)
        moment = np.cross(cop, self.force_N)
        moment[:, 2] += free
        return moment


def centre_of_pressure(force_N, moment_Nm, point_m) -> tuple[np.ndarray, np.ndarray]:
    """COP (n, 3) on the horizontal plane through ``point_m`` and free moment (n,) about the vertical (3.1.2).

    ``moment_Nm`` (n, 3) is the moment of the load about ``point_m`` (3,) or (n, 3).
    ``r_x = -M_y/F_z``, ``r_y = M_x/F_z``, ``T_z = M_z - (r_x F_y - r_y F_x)``.
    Frames with ``F_z = 0`` give non-finite values; callers mask them.
    """
    force = np.asarray(force_N, dtype=float)
    moment = np.asarray(moment_Nm, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        r_x = -moment[:, 1] / force[:, 2]
        r_y = moment[:, 0] / force[:, 2]
    free = moment[:, 2] - (r_x * force[:, 1] - r_y * force[:, 0])
    cop = np.broadcast_to(np.asarray(point_m, dtype=float), force.shape).copy()
    cop[:, 0] += r_x
    cop[:, 1] += r_y
    return cop, free


def _frames_and_step(n_samples: int, ratio: float) -> tuple[int, int]:
    """The frames at ``k / rate_hz`` within ``n_samples`` samples ``ratio`` = source rate / frame rate apart, and
    the ratio as a whole number of samples (0 where it is not one)."""
    n_frames = int(np.floor((n_samples - 1) / ratio + 1e-9)) + 1 if n_samples else 0
    step = round(ratio)
    return n_frames, step if step >= 1 and abs(ratio - step) <= 1e-9 * ratio else 0


def resample_to_frames(x, /, *, source_rate_hz: float, rate_hz: float) -> np.ndarray:
    """Values of ``x`` (samples, ...) at the frame times ``k / rate_hz`` inside the record.

    With an integer ratio ``r = source_rate_hz / rate_hz`` this is ``x[::r]`` (the
    first sample of each frame); otherwise linear interpolation at the frame times.
    """
    x = np.asarray(x, dtype=float)
    ratio = source_rate_hz / rate_hz
    n_frames, step = _frames_and_step(x.shape[0], ratio)
    if step:
        return x[::step][:n_frames].copy()
    source_t = np.arange(x.shape[0]) / source_rate_hz
    frame_t = np.arange(n_frames) / rate_hz
    flat = x.reshape(x.shape[0], -1)
    out = np.stack([np.interp(frame_t, source_t, flat[:, j]) for j in range(flat.shape[1])], axis=1)
    return out.reshape((n_frames,) + x.shape[1:])


def _frame_means(x, /, *, source_rate_hz: float, rate_hz: float) -> np.ndarray:
    """Each frame's mean of the samples of ``x`` (samples, ...) centred on its time ``k / rate_hz``: with an integer
    ratio ``r = source_rate_hz / rate_hz`` the ``r`` samples from ``k·r − r//2`` (fewer at the record's ends), as
    Vicon Nexus forms its per-frame ground reaction from unfiltered plates; otherwise :func:`resample_to_frames`."""
    x = np.asarray(x, dtype=float)
    n_frames, step = _frames_and_step(x.shape[0], source_rate_hz / rate_hz)
    if step < 2:
        return resample_to_frames(x, source_rate_hz=source_rate_hz, rate_hz=rate_hz)
    # frame k's window is padded[k·step : (k+1)·step], the samples before the first and after the last counting 0
    padded = np.zeros((n_frames * step,) + x.shape[1:])
    counted = np.zeros(n_frames * step)
    begin = step // 2
    kept = min(x.shape[0], n_frames * step - begin)
    padded[begin:begin + kept], counted[begin:begin + kept] = x[:kept], 1.0
    sums = padded.reshape((n_frames, step) + x.shape[1:]).sum(axis=1)
    counts = counted.reshape(n_frames, step).sum(axis=1)
    return sums / counts.reshape((-1,) + (1,) * (x.ndim - 1))


def plate_load(plate: ForcePlate, /, *, cutoff_hz: float, threshold_N: float,
               rate_hz: float | None = None, frame_means: bool = False) -> PlateLoad:
    """Filter a plate's wrench at the analog rate, then form COP and free moment where loaded (3.1.4).

    Parameters
    ----------
    plate : ForcePlate
        The plate as read (model axes, SI).
    cutoff_hz : float
        Net cut-off of the zero-lag Butterworth filter, Hz (0: no filtering).
    threshold_N : float
        Vertical force above which the plate counts as loaded, N.
    rate_hz : float, optional
        The marker rate to resample to, Hz (None keeps the plate's own rate).
    frame_means : bool
        Each frame's value the mean of the samples centred on it (:func:`_frame_means`), not the sample at it.

    Returns
    -------
    PlateLoad
        Force, COP and free moment at ``rate_hz``, with the unfiltered vertical force at the
        analog rate for contact timing.
    """
    force = np.asarray(plate.force_N, dtype=float)
    moment = np.asarray(plate.moment_Nm, dtype=float)
    if force.ndim != 2 or force.shape[1] != 3 or moment.shape != force.shape:
        raise InputError(None, f"{plate.name}.force_N",
                         f"got force {force.shape} and moment {moment.shape} (expected two (samples, 3) arrays)")
    if not (np.isfinite(threshold_N) and threshold_N >= 0):
        raise InputError(None, "threshold_N", f"got {shown(threshold_N)} (expected a force >= 0 N)")
    out_rate = plate.rate_hz if rate_hz is None else float(rate_hz)
    if not (np.isfinite(out_rate) and out_rate > 0):
        raise InputError(None, "rate_hz", f"got {shown(rate_hz)} (expected a marker rate > 0 Hz)")
    if cutoff_hz and not cutoff_hz < out_rate / 2:
        raise InputError(None, "cutoff_hz",
                         f"got {shown(cutoff_hz)} Hz (expected below the output Nyquist frequency {out_rate / 2:g} Hz)")
    wrench = np.concatenate([force, moment], axis=1)
    # off the plate the reading is offset and noise: zeroed before the filter, so that the filtered load
    # falls continuously to 0 at the contact's edges instead of being cut off at the threshold
    off_plate = (np.nan_to_num(force[:, 2], nan=np.inf) <= threshold_N) & np.isfinite(wrench).all(axis=1)
    wrench = np.where(off_plate[:, None], 0.0, wrench)
    if cutoff_hz:  # 0 or None: unfiltered (exact synthetic data)
        wrench = lowpass(wrench, rate_hz=plate.rate_hz, cutoff_hz=cutoff_hz)
    wrench = (_frame_means if frame_means else resample_to_frames)(wrench, source_rate_hz=plate.rate_hz,
                                                                    rate_hz=out_rate)
    force_f, moment_f = wrench[:, :3], wrench[:, 3:]
    touched = resample_to_frames((~off_plate).astype(float), source_rate_hz=plate.rate_hz, rate_hz=out_rate) > 0
    loaded = _runs_touching(np.nan_to_num(force_f[:, 2], nan=-np.inf) > LOADED_FRACTION * threshold_N, touched)
    cop, free = centre_of_pressure(force_f, moment_f, plate.centre_m)
    return PlateLoad(
        name=plate.name,
        # unloaded samples are 0 N; samples whose channels are not finite stay NaN (their load is unknown)
        force_N=np.where(loaded[:, None], force_f, np.where(np.isfinite(force_f), 0.0, np.nan)),
        cop_m=np.where(loaded[:, None], cop, np.nan),
        free_moment_Nm=np.where(loaded, free, np.nan),
        loaded=loaded,
        rate_hz=out_rate,
        threshold_N=float(threshold_N),
        corners_m=np.asarray(plate.corners_m, dtype=float),
        raw_vertical_force_N=force[:, 2].copy(),
        raw_rate_hz=float(plate.rate_hz),
    )


def resting_offsets(vertical_force_N, /, *, quiet, rate_hz: float, limit_N: float,
                    min_s: float = 0.1) -> list[tuple[int, int, float, float]]:
    """Runs of frames in which a plate reads a load with no foot near it: an offset or drift of its zero.

    ``vertical_force_N`` (n,): the plate's vertical force at the ``rate_hz`` frames, low-pass filtered (its
    noise, 5-17 N SD on real plates, averaged out); ``quiet`` (n,): the frames with no foot near the plate.
    Returns (first frame, last frame, lowest N, highest N) of each run of quiet frames at least ``min_s`` long
    whose |force| is at least ``limit_N``.
    """
    fz = np.asarray(vertical_force_N, dtype=float)
    with np.errstate(invalid="ignore"):
        off = np.asarray(quiet, bool) & (np.abs(fz) >= limit_N)
    out = []
    for start, stop in zip(*true_runs(off)):
        if stop - start >= min_s * rate_hz:
            out.append((int(start), int(stop - 1), float(np.min(fz[start:stop])), float(np.max(fz[start:stop]))))
    return out


def _runs_touching(positive: np.ndarray, touched: np.ndarray) -> np.ndarray:
    """``positive`` without its runs that hold no ``touched`` frame: the filter's ringing lobes beside a
    contact."""
    starts, stops = true_runs(positive)
    keep = np.zeros_like(positive)
    for start, stop in zip(starts, stops):
        if touched[start:stop].any():
            keep[start:stop] = True
    return keep


def combine_loads(loads: list[PlateLoad], owner) -> dict[str, PlateLoad]:
    """Per-foot load: the sum of the wrenches of the plates each foot stands on, frame by frame.

    ``owner`` (n_plates, n) holds ``'r'``, ``'l'`` or ``''`` per plate and frame. For
    each side the forces and the moments about the origin of the owned, loaded plates
    are summed; the COP of the sum lies on the horizontal plane at the force-weighted
    mean height of the plates' COPs, and the free moment is taken about it. Returns
    ``{'r': PlateLoad, 'l': PlateLoad}`` named ``'r'``/``'l'``, loaded where any owned
    plate is loaded.
    """
    owner = np.asarray(owner)
    if not loads:
        raise InputError(None, "loads", "got no plate loads (expected at least one)")
    n = loads[0].n_frames
    if owner.shape != (len(loads), n):
        raise InputError(None, "owner", f"got shape {owner.shape} (expected {(len(loads), n)})")
    rates = {load.rate_hz for load in loads}
    if len(rates) != 1 or any(load.n_frames != n for load in loads):
        raise InputError(None, "loads", "got plates with different rates or lengths (expected one common frame grid)")
    force = np.stack([np.nan_to_num(load.force_N) for load in loads])  # (plates, n, 3); NaN: unknown, not 0 N
    moment = np.stack([np.nan_to_num(load.moment_about_origin_Nm()) for load in loads])
    cop_z = np.stack([np.nan_to_num(load.cop_m[:, 2]) for load in loads])
    loaded = np.stack([load.loaded for load in loads])
    result = {}
    for side in ("r", "l"):
        use = (owner == side) & loaded
        f = (force * use[..., None]).sum(axis=0)
        m = (moment * use[..., None]).sum(axis=0)
        on = use.any(axis=0) & (f[:, 2] > 0)
        weight = np.abs(force[..., 2]) * use
        with np.errstate(divide="ignore", invalid="ignore"):
            height = (cop_z * weight).sum(axis=0) / weight.sum(axis=0)
        point = np.zeros((n, 3))
        point[:, 2] = np.where(on, height, 0.0)
        cop, free = centre_of_pressure(f, m - np.cross(point, f), point)
        result[side] = PlateLoad(
            name=side,
            force_N=np.where(on[:, None], f, 0.0),
            cop_m=np.where(on[:, None], cop, np.nan),
            free_moment_Nm=np.where(on, free, np.nan),
            loaded=on,
            rate_hz=loads[0].rate_hz,
            threshold_N=max(load.threshold_N for load in loads),
        )
    return result
