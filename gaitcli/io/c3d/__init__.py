"""C3D reader: markers and force plates in SI units, lab axes mapped to model axes.

:func:`read_c3d` composes the package's parts: :mod:`.header` checks the file
before ezc3d opens it and reads parameters, :mod:`.markers` converts the points
(units, labels, missing samples) and :mod:`.plates` the force platforms (ezc3d's
force-platform module, with the corrections described there); the lab → model
rotation comes from :mod:`gaitcli.io.axes`.
"""

from __future__ import annotations

from pathlib import Path

import ezc3d
import numpy as np

from gaitcli.core.recording import Recording
from gaitcli.errors import InputError
from gaitcli.io.axes import apply_rotation, infer_lab_to_model
from gaitcli.io.c3d.header import check_file, one_line, warn
from gaitcli.io.c3d.markers import MODEL_OUTPUT_GROUPS, point_length_m, read_markers
from gaitcli.io.c3d.plates import plate_axes, read_plates

__all__ = ["read_c3d", "MODEL_OUTPUT_GROUPS", "plate_axes"]


def read_c3d(path, *, to_model_axes: bool = True) -> Recording:
    """Read a C3D trial into a :class:`Recording` (metres, newtons, N·m).

    With ``to_model_axes`` the lab → model rotation from
    :func:`gaitcli.io.axes.infer_lab_to_model` is applied and stored in
    ``lab_to_model``; without it the data stay in lab axes, ``lab_to_model`` is
    the identity and the inferred rotation is given in ``notes``.
    Raises :class:`InputError` for a missing, non-C3D, truncated or MIPS file.
    """
    path = Path(path)
    header_frames = check_file(path)
    try:
        c = ezc3d.c3d(str(path))
    except Exception as exc:  # ezc3d raises RuntimeError/OSError/ValueError with multi-line text
        raise InputError(path, None, f"cannot read C3D: {one_line(exc)}") from None
    n_frames = c["data"]["points"].shape[2]
    if header_frames is not None and n_frames < header_frames:
        raise InputError(path, "data", f"cannot read C3D: file is truncated ({n_frames} of {header_frames} frames)")

    params = c["parameters"]
    notes: list[str] = []
    length_m = point_length_m(path, params, c["data"]["points"], notes)
    markers = read_markers(path, c, length_m, notes)
    plates = read_plates(path, c, length_m, markers, notes)
    if not plates:
        warn(f"{path.name}: no usable force plates: markers only", notes)

    recording = Recording(markers=markers, plates=plates, source=path, lab_to_model=np.eye(3), notes=notes)
    R = infer_lab_to_model(markers.positions_m, plates)
    rows = "; ".join(" ".join(f"{v + 0.0:+.4f}" for v in row) for row in R)
    if to_model_axes:
        recording = apply_rotation(recording, R)
        recording.notes.append(f"lab axes rotated to model axes, lab_to_model rows: [{rows}]")
    else:
        recording.notes.append(f"data kept in lab axes; inferred lab_to_model rows: [{rows}]")
    return recording
