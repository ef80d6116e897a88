"""C3D reader: markers and force plates in SI units, lab axes mapped to model axes.

:func:`read_c3d` composes the package's parts: :mod:`.header` checks the file
before ezc3d opens it and reads parameters, :mod:`.markers` converts the points
(units, labels, missing samples) and :mod:`.plates` the force platforms (ezc3d's
force-platform module, with the corrections described there), :mod:`.events` the lab's gait events (the
EVENT group); the lab → model
rotation comes from :mod:`gaitcli.io.axes`.
"""

from __future__ import annotations

import faulthandler
import math
import multiprocessing
import os
import signal
import warnings
from pathlib import Path

import ezc3d
import numpy as np

try:
    import resource
except ImportError:  # Windows: no address-space cap
    resource = None

from gaitcli.core.interrupts import end_with_parent
from gaitcli.core.recording import Analogs, Recording
from gaitcli.errors import InputError
from gaitcli.io.axes import apply_rotation, infer_lab_to_model
from gaitcli.io.c3d.events import read_events
from gaitcli.io.c3d.header import C3D_MAX_NUMBERS, check_file, one_line, param, strings, warn
from gaitcli.io.c3d.long import HEADER_FRAMES, chunk_files, planned_frames
from gaitcli.io.c3d.markers import MODEL_OUTPUT_GROUPS, check_body_size, point_length_m, read_markers
from gaitcli.io.c3d.plates import PLATFORM_SAMPLES, plate_axes, plates_from, platform_outputs

__all__ = ["read_c3d", "read_c3d_here", "MODEL_OUTPUT_GROUPS", "plate_axes"]


#: limits of one C3D read in its child process: processor time (plus a second per MB: the library's Python layer
#: converts frame by frame, ~0.4 s per MB of a trial with two 1 kHz plates; READ_WALL_FACTOR times that in wall
#: time for a child that waits instead of computing, so that a loaded machine does not cut a good read short),
#: and address space above the
#: parent's (plus READ_BYTES_PER_BYTE of file: the library's objects for one part at most, PART_NUMBERS, and the
#: trial's arrays twice, as built and as sent); the file's bytes counted up to what C3D_MAX_NUMBERS allows
READ_TIME_S = 10.0
READ_WALL_FACTOR = 5.0
READ_MEMORY_BYTES = 1 << 30
READ_BYTES_PER_BYTE = 24


def read_c3d(path, *, to_model_axes: bool = True) -> Recording:
    """Read a C3D trial into a :class:`Recording` (:func:`read_c3d_here`) in a child process with a time
    limit and a memory cap (``READ_TIME_S``, ``READ_MEMORY_BYTES``): a damaged file that crashes, hangs or
    floods the C3D library is an :class:`InputError` of one line, not a dead or stuck ``gait``. Warnings of
    the read are given again here."""
    path = Path(path)
    header_frames = check_file(path)  # the usual one-line errors without a child process
    # Windows (no fork), and a daemonic process such as a Dask worker, which may not have children: the checks
    # above, then in-process
    if "fork" not in multiprocessing.get_all_start_methods() or multiprocessing.current_process().daemon:
        return read_c3d_here(path, to_model_axes=to_model_axes, header_frames=header_frames)
    # the limits grow with the data, which the ceiling bounds, not with whatever the file holds after them
    size = min(path.stat().st_size, 4 * C3D_MAX_NUMBERS + (1 << 20))
    context = multiprocessing.get_context("fork")
    receive, send = context.Pipe(duplex=False)
    memory_bytes = READ_MEMORY_BYTES + READ_BYTES_PER_BYTE * size
    cpu_s = READ_TIME_S + size / 1e6
    child = context.Process(target=_child_read, daemon=True, args=(path, to_model_axes, header_frames, send,
                                                                   receive, memory_bytes, cpu_s, os.getpid()))
    child.start()
    send.close()
    try:
        wall_s = (READ_WALL_FACTOR if resource is not None else 1.0) * cpu_s
        if not receive.poll(wall_s) and not _still_computing(child.pid, receive, wall_s):
            raise InputError(path, None, f"cannot read C3D: reading it took longer than {wall_s:.0f} s "
                                         "(a damaged parameter section?)")
        try:
            kind, *payload = receive.recv()
        except EOFError:
            child.join(5.0)
            if child.exitcode == -signal.SIGXCPU:
                raise InputError(path, None, f"cannot read C3D: reading it took longer than {cpu_s:.0f} s of "
                                             "processor time (a damaged parameter section?)") from None
            raise InputError(path, None, f"cannot read C3D: the C3D library crashed on it (exit "
                                         f"{child.exitcode}; a damaged parameter section?)") from None
    finally:
        if child.is_alive():
            child.kill()
        child.join(5.0)
        receive.close()
    if kind == "input":
        raise InputError(*payload)
    if kind == "memory":
        raise InputError(path, None, f"cannot read C3D: reading it needs more than {payload[0] / 2**30:.1f} GB "
                                     "(a damaged parameter section?)")
    if kind == "error":
        raise RuntimeError(f"reading {path}: {payload[0]}")
    recording, caught = payload
    for message, category in caught:
        warnings.warn(message, category, stacklevel=2)
    return recording


def _processor_s(pid: int) -> float | None:
    """The processor time (s) process ``pid`` has used, from /proc (None where there is none)."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")  # utime + stime, in ticks
    except (OSError, ValueError, IndexError):
        return None


def _still_computing(pid: int, receive, wall_s: float) -> bool:
    """After the wall-time limit: wait on while the child keeps computing (a busy machine gives it less than a
    core; its processor-time limit ends it), at most READ_WALL_FACTOR times longer; False as soon as a second
    passes without its processor time growing (a hang), or without /proc to tell. True when it answered."""
    for _ in range(int(READ_WALL_FACTOR * wall_s)):
        before = _processor_s(pid)
        if receive.poll(1.0):
            return True
        after = _processor_s(pid)
        if before is None or after is None or after - before < 0.01:
            return False
    return False


def _child_read(path: Path, to_model_axes: bool, header_frames, send, receive, memory_bytes: int, cpu_s: float,
                parent_pid: int) -> None:
    """In the child: cap the address space and the processor time (SIGXCPU ends it), read, send ("ok",
    recording, warnings) or what went wrong. The library's own output and a crash report go nowhere: the parent
    says what happened, in one line. The child ends with its parent (killed with it, and its pipe's read end
    closed here, so that a send to a dead parent fails instead of waiting for ever on a reader that is
    itself)."""
    try:
        end_with_parent(parent_pid)
        receive.close()
        faulthandler.disable()
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, 1)
        os.dup2(devnull, 2)
        if resource is not None:
            cap = _address_space() + memory_bytes
            resource.setrlimit(resource.RLIMIT_AS, (cap, cap))
            seconds = math.ceil(cpu_s)  # a forked child's count starts at zero
            resource.setrlimit(resource.RLIMIT_CPU, (seconds, seconds + 5))
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            recording = read_c3d_here(path, to_model_axes=to_model_axes, header_frames=header_frames)
        send.send(("ok", recording, [(str(w.message), w.category) for w in caught]))
    except InputError as exc:
        send.send(("input", exc.path, exc.field, exc.problem))
    except MemoryError:
        send.send(("memory", memory_bytes))
    except Exception as exc:  # noqa: BLE001 - an internal error, passed on
        send.send(("error", f"{type(exc).__name__}: {one_line(exc)}"))
    finally:
        send.close()


def _address_space() -> int:
    """This process's virtual memory size in bytes (Linux), 0 where unknown."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmSize:"):
                return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


_UNCHECKED = object()


def read_c3d_here(path, *, to_model_axes: bool = True, header_frames=_UNCHECKED) -> Recording:
    """Read a C3D trial into a :class:`Recording` (metres, newtons, N·m), in this process.

    With ``to_model_axes`` the lab → model rotation from
    :func:`gaitcli.io.axes.infer_lab_to_model` is applied and stored in
    ``lab_to_model``; without it the data stay in lab axes, ``lab_to_model`` is
    the identity and the inferred rotation is given in ``notes``.
    Raises :class:`InputError` for a missing, non-C3D, truncated or MIPS file. ``header_frames``: what
    :func:`~.header.check_file` returned for this file, where the caller has already run it.
    """
    path = Path(path)
    if header_frames is _UNCHECKED:
        header_frames = check_file(path)
    total, per_frame = planned_frames(path)
    part_frames = min(HEADER_FRAMES, max(1, PART_NUMBERS // max(per_frame, 1)))
    if total is None or total <= part_frames:
        c = _open(path)
        n_frames = c["data"]["points"].shape[2]
        if header_frames is not None and n_frames < header_frames:
            raise InputError(path, "data", f"cannot read C3D: file is truncated ({n_frames} of {header_frames} "
                                           "frames)")
        params, header, analog_rate = c["parameters"], c["header"]["points"], c["header"]["analogs"]["frame_rate"]
        points, residuals, platforms, others = _part_arrays(c)
        del c
    else:
        params, header, points, residuals, platforms, others = _read_in_parts(path, total, part_frames)
        analog_rate = float(np.asarray(param(params, "ANALOG", "RATE", [0.0]), dtype=float).ravel()[0])
    notes: list[str] = []
    if total is not None and total > part_frames:
        notes.append(f"{total} frames read in parts of {part_frames}"
                     + (f" (more than the header's {HEADER_FRAMES})" if total > HEADER_FRAMES else ""))
    length_m = point_length_m(path, params, points, notes)
    markers = read_markers(path, {"parameters": params, "header": {"points": header},
                                  "data": {"points": points, "meta_points": {"residuals": residuals}}}, length_m, notes)
    check_body_size(path, params, markers.positions_m)
    del points, residuals
    plates = plates_from(path, params, platforms, frame_rate_hz=float(header["frame_rate"]),
                         n_frames=markers.n_frames, length_m=length_m, markers=markers, notes=notes)
    if not plates:
        warn(f"{path.name}: no usable force plates: markers only", notes)

    events = read_events(path, params, rate_hz=markers.rate_hz, first_frame=markers.first_frame,
                         n_frames=markers.n_frames, notes=notes)
    recording = Recording(markers=markers, plates=plates, source=path, lab_to_model=np.eye(3), notes=notes,
                          subject_metadata=subject_metadata(params), events=events,
                          analogs=analogs_from(params, others, analog_rate))
    R = infer_lab_to_model(markers.positions_m, plates)
    rows = "; ".join(" ".join(f"{v + 0.0:+.4f}" for v in row) for row in R)
    if to_model_axes:
        recording = apply_rotation(recording, R)
        recording.notes.append(f"lab axes rotated to model axes, lab_to_model rows: [{rows}]")
    else:
        recording.notes.append(f"data kept in lab axes; inferred lab_to_model rows: [{rows}]")
    return recording


#: subject data some labs' C3D files carry (Vicon's PROCESSING group, the c3d.org SUBJECT(S) groups)
_PIG_SIDED = ("LegLength", "KneeWidth", "AnkleWidth", "AsisTrocanterDistance")
#: Plug-in Gait's signed subject measurements (offsets and rotations, rad; the sole delta, mm): zero is a value
_PIG_SIGNED = ("TibialTorsion", "ThighRotation", "ShankRotation", "StaticPlantFlex", "StaticRotOff", "SoleDelta")
SUBJECT_PARAMETERS = {"PROCESSING": ("Bodymass", "BodyMass", "Height", "InterAsisDistance", "MarkerDiameter")
                      + tuple(f"{side}{name}" for name in _PIG_SIDED + _PIG_SIGNED
                              for side in ("Left", "Right", "L", "R")),
                      "SUBJECT": ("WEIGHT", "MASS", "HEIGHT"), "SUBJECTS": ("WEIGHT", "MASS", "HEIGHT")}
_SIGNED_NAMES = frozenset(f"{side}{name}" for name in _PIG_SIGNED for side in ("Left", "Right", "L", "R"))


def subject_metadata(params) -> dict[str, float]:
    """``{"GROUP:NAME": value}`` of the :data:`SUBJECT_PARAMETERS` a file has (first value), where finite and
    > 0, or finite for Plug-in Gait's signed offsets (Vicon writes both ``RightKneeWidth`` and ``RKneeWidth``)."""
    out = {}
    for group, names in SUBJECT_PARAMETERS.items():
        for name in names:
            value = param(params, group, name)
            try:
                number = float(np.asarray(value, dtype=float).ravel()[0])
            except (TypeError, ValueError, IndexError):
                continue
            if np.isfinite(number) and (number > 0 or name in _SIGNED_NAMES):
                out[f"{group}:{name}"] = number
    return out


#: the most numbers the C3D library holds at once: a larger trial is read in parts of about this many (the
#: library keeps ~130 bytes per number, so a part costs ~260 MB, while the trial itself is kept as arrays)
PART_NUMBERS = 2_000_000


def _open(path: Path):
    """ezc3d's reading of ``path``, its errors an :class:`InputError` of one line."""
    try:
        return ezc3d.c3d(str(path))
    except Exception as exc:  # ezc3d raises RuntimeError/OSError/ValueError with multi-line text
        text = one_line(exc)
        if "ignoreBadFormatting" in text:  # the library's advice to its own callers, an option gait lacks
            text = "its parameters break the C3D format (a damaged or non-standard file)"
        raise InputError(path, None, f"cannot read C3D: {text}") from None


def _part_arrays(c) -> tuple[np.ndarray, np.ndarray, list, np.ndarray]:
    """The points (4, markers, frames), their residuals (1, markers, frames), the force-platform outputs
    (:func:`~.plates.platform_outputs`) and the other analog channels (channels, samples; :func:`other_channels`)
    of ezc3d's ``c``, as arrays that outlive it."""
    points = np.asarray(c["data"]["points"], dtype=float)
    residuals = np.asarray(c["data"]["meta_points"]["residuals"], dtype=float)
    analogs = c["data"]["analogs"]
    others = other_channels(c["parameters"], analogs.shape[1])
    return points, residuals, platform_outputs(c), np.asarray(analogs[0, others, :], dtype=float)


def other_channels(params, count: int) -> list[int]:
    """The analog channels (0-based, of ``count``) that FORCE_PLATFORM:CHANNEL does not give to a plate."""
    used = np.asarray(param(params, "FORCE_PLATFORM", "CHANNEL", np.zeros((0, 0))), dtype=float).ravel()
    plates = {int(k) - 1 for k in used if np.isfinite(k) and k >= 1}
    return [k for k in range(count) if k not in plates]


def analogs_from(params, values: np.ndarray, rate_hz: float) -> Analogs | None:
    """The :class:`Analogs` of the channels :func:`other_channels` keeps (``values``: channels × samples), their
    labels and units from ANALOG:LABELS and ANALOG:UNITS; None where there are none."""
    if values.shape[0] == 0:
        return None
    used = int(np.asarray(param(params, "ANALOG", "USED", [0]), dtype=float).ravel()[0])
    others = other_channels(params, used)
    if len(others) != values.shape[0]:
        return None  # ANALOG:USED disagrees with the data: nothing to name the channels by
    labels, units = strings(params, "ANALOG", "LABELS"), strings(params, "ANALOG", "UNITS")

    def pick(names):
        return tuple(names[k].strip() if k < len(names) else "" for k in others)

    return Analogs(labels=pick(labels), units=pick(units), rate_hz=float(rate_hz), values=values.T.copy())


def _read_in_parts(path: Path, total: int, part_frames: int) -> tuple:
    """(parameters, point header, points, residuals, platform outputs) of a trial of ``total`` frames read
    ``part_frames`` at a time (:func:`~.long.chunk_files`): the library's objects for one part at a time, the
    trial's arrays joined. The parameters and the first frame are the file's own, not the parts'."""
    points, residuals, platforms, others = [], [], [], []
    params = header = None
    with chunk_files(path, total, part_frames, start_frame=0) as parts:
        for part, count in parts:
            c = _open(part)
            if params is None:
                params, header = c["parameters"], dict(c["header"]["points"])
            more = _part_arrays(c)
            del c
            if more[0].shape[1:] != (points[0].shape[1] if points else more[0].shape[1], count) or (
                    platforms and [isinstance(p, str) for p in more[2]] != [isinstance(p, str) for p in platforms[0]]):
                raise InputError(path, "data", "cannot read C3D: its parts do not match (a damaged file?)")
            for whole, new in zip((points, residuals, platforms, others), more):
                whole.append(new)
    header["first_frame"] = _first_frame(path)
    joined = [{k: (np.concatenate([p[i][k] for p in platforms], axis=1) if k in PLATFORM_SAMPLES else v)
               for k, v in plate.items()} if not isinstance(plate, str) else plate
              for i, plate in enumerate(platforms[0])]
    return (params, header, np.concatenate(points, axis=2), np.concatenate(residuals, axis=2), joined,
            np.concatenate(others, axis=1))


def _first_frame(path: Path) -> int:
    """The header's first frame, counted from 0 as ezc3d counts it."""
    with open(path, "rb") as f:
        return int.from_bytes(f.read(8)[6:8], "little") - 1
