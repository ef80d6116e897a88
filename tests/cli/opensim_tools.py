"""OpenSim's own tools on an ``export/opensim/`` folder (the ``opensim`` package: ``pip install gaitcli[opensim]``),
for the export tests (in a process of its own: tests/opensim_runner.py): its InverseDynamicsTool on model.osim +
coordinates.mot + external_loads.xml, and gaitcli's inverse dynamics of the same motion.

OpenSim's tool differentiates the coordinates by its own quintic GCV splines (natural end conditions), gaitcli's idyn
by quintic not-a-knot splines (dynamics/derivatives.py): the two differ by up to 0.1 N·m inside a trial and by tens
at its first and last frames. So the same model is compared on the same motion: gaitcli's
:func:`~gaitcli.dynamics.inverse.inverse_dynamics` is given the coordinates, speeds and accelerations of OpenSim's
splines (``GCVSplineSet(5, …)``, as the tool builds them), and the ground reactions of the filtered trial.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gaitcli.dynamics.inverse import inverse_dynamics
from gaitcli.dynamics.opensim import OPENSIM_COORDINATES, opensim_generalized_forces
from gaitcli.dynamics.stage import external_wrenches
from gaitcli.io.exports import filtered_trial
from gaitcli.io.opensim import read_motion
from gaitcli.io.stage_files import read_idyn_model
from gaitcli.kinematics.model import BodyParameters
from tests.opensim_runner import run_opensim

#: the labels and row count of a .trc as OpenSim's TimeSeriesTableVec3 reads it
TRC_LABELS = """
table = opensim.TimeSeriesTableVec3(arguments["trc"])
np.savez(work / "out.npz", labels=np.array(list(table.getColumnLabels())), rows=table.getNumRows())
"""


#: OpenSim's InverseDynamicsTool on the folder's files over the whole trial, no filter; and the coordinates, speeds
#: and accelerations (rad, m; frames, coordinates) of the quintic GCV splines the tool fits to coordinates.mot
TOOL_AND_SPLINES = """
folder = Path(arguments["folder"])
model = opensim.Model(str(folder / "model.osim"))  # kept alive: the tool holds only a pointer to it
tool = opensim.InverseDynamicsTool()
tool.setModel(model)
tool.setCoordinatesFileName(str(folder / "coordinates.mot"))
tool.setExternalLoadsFileName(str(folder / "external_loads.xml"))
storage = opensim.Storage(str(folder / "coordinates.mot"))
time = opensim.ArrayDouble()
storage.getTimeColumn(time)
times = np.array([time.get(i) for i in range(time.getSize())])
tool.setStartTime(float(times[0]))
tool.setEndTime(float(times[-1]))
tool.setLowpassCutoffFrequency(-1.0)
tool.setResultsDir(str(work))
tool.setOutputGenForceFileName("inverse_dynamics.sto")
assert tool.run()
model.initSystem()
model.getSimbodyEngine().convertDegreesToRadians(storage)
splines = opensim.GCVSplineSet(5, storage)
motion = np.zeros((3, times.size, len(arguments["names"])))
for k, name in enumerate(arguments["names"]):
    spline = splines.get(name)
    for i, t in enumerate(times):
        x = opensim.Vector(1, float(t))
        motion[0, i, k] = spline.calcValue(x)
        motion[1, i, k] = spline.calcDerivative(opensim.StdVectorInt([0]), x)
        motion[2, i, k] = spline.calcDerivative(opensim.StdVectorInt([0, 0]), x)
np.savez(work / "out.npz", motion=motion)
"""


def opensim_tool_and_splines(folder: Path, work: Path) -> tuple[dict[str, np.ndarray], tuple]:
    """OpenSim's inverse dynamics of ``folder`` {label: (frames,)} (N·m, N) and the model's coordinates, speeds and
    accelerations (frames, 27; m, rad) from the tool's splines (:data:`TOOL_AND_SPLINES`)."""
    saved = run_opensim(TOOL_AND_SPLINES, work, folder=str(folder), names=[c.name for c in OPENSIM_COORDINATES])
    sign = np.array([c.sign for c in OPENSIM_COORDINATES])
    motion = tuple(sign * saved["motion"][d] for d in range(3))
    return read_motion(work / "inverse_dynamics.sto")[1], motion


def gaitcli_inverse_dynamics(out_root: Path, q, qd, qdd) -> dict[str, np.ndarray]:
    """gaitcli's inverse dynamics of ``q``, ``qd``, ``qdd`` (frames, 27) with the bodies of ``out_root``'s idyn.h5
    and the ground reactions of its filter.h5, as OpenSim's columns {label: (frames,)}."""
    model = read_idyn_model(out_root / "idyn" / "idyn.h5")
    params = BodyParameters(model.mass_kg, model.inertia_kgm2, model.joint_in_parent_m, model.joint_in_child_m)
    result = inverse_dynamics(q, qd, qdd, params, external_wrenches(filtered_trial(out_root)),
                              gravity_m_s2=model.gravity_m_s2)
    return opensim_generalized_forces(result.generalized_forces)


def largest_differences(out_root: Path, work: Path) -> dict[str, float]:
    """{label: the largest |OpenSim − gaitcli| over the frames} of the two inverse dynamics of ``out_root``'s
    OpenSim export on the same motion (module docstring)."""
    theirs, motion = opensim_tool_and_splines(out_root / "export" / "opensim", work)
    ours = gaitcli_inverse_dynamics(out_root, *motion)
    assert set(ours) <= set(theirs)
    return {label: float(np.max(np.abs(theirs[label] - ours[label]))) for label in ours}


def opensim_trc_labels(trc: Path, work: Path) -> tuple[list[str], int]:
    """The marker labels and frame count of ``trc`` as OpenSim reads it (``TimeSeriesTableVec3``)."""
    saved = run_opensim(TRC_LABELS, work, trc=str(trc))
    return [str(label) for label in saved["labels"]], int(saved["rows"])
