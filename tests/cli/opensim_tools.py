"""OpenSim's own tools on an ``export/opensim/`` folder (the ``opensim`` package: ``pip install gaitcli[opensim]``),
for the export tests: its InverseDynamicsTool on model.osim + coordinates.mot + external_loads.xml, and gaitcli's
inverse dynamics of the same motion.

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


def opensim_inverse_dynamics(folder: Path, results: Path) -> dict[str, np.ndarray]:
    """OpenSim's InverseDynamicsTool on ``folder``'s model.osim, coordinates.mot and external_loads.xml over the
    whole trial, no filter: its generalized forces {label: (frames,)} (N·m, N)."""
    import opensim

    model = opensim.Model(str(folder / "model.osim"))  # kept alive: the tool holds only a pointer to it
    tool = opensim.InverseDynamicsTool()
    tool.setModel(model)
    tool.setCoordinatesFileName(str(folder / "coordinates.mot"))
    tool.setExternalLoadsFileName(str(folder / "external_loads.xml"))
    time = read_motion(folder / "coordinates.mot")[1]["time"]
    tool.setStartTime(float(time[0]))
    tool.setEndTime(float(time[-1]))
    tool.setLowpassCutoffFrequency(-1.0)
    tool.setResultsDir(str(results))
    tool.setOutputGenForceFileName("inverse_dynamics.sto")
    assert tool.run()
    return read_motion(results / "inverse_dynamics.sto")[1]


def opensim_spline_motion(folder: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The model's coordinates, speeds and accelerations (frames, 27; m, rad) at coordinates.mot's times from the
    quintic GCV splines OpenSim's InverseDynamicsTool fits to it."""
    import opensim

    storage = opensim.Storage(str(folder / "coordinates.mot"))
    model = opensim.Model(str(folder / "model.osim"))
    model.initSystem()
    model.getSimbodyEngine().convertDegreesToRadians(storage)
    splines = opensim.GCVSplineSet(5, storage)
    time = read_motion(folder / "coordinates.mot")[1]["time"]
    motion = np.zeros((3, time.size, len(OPENSIM_COORDINATES)))
    orders = ([], [0], [0, 0])
    for k, c in enumerate(OPENSIM_COORDINATES):
        spline = splines.get(c.name)
        for i, t in enumerate(time):
            x = opensim.Vector(1, float(t))
            for d, order in enumerate(orders):
                value = spline.calcValue(x) if not order else spline.calcDerivative(opensim.StdVectorInt(order), x)
                motion[d, i, k] = c.sign * value
    return motion[0], motion[1], motion[2]


def gaitcli_inverse_dynamics(out_root: Path, q, qd, qdd) -> dict[str, np.ndarray]:
    """gaitcli's inverse dynamics of ``q``, ``qd``, ``qdd`` (frames, 27) with the bodies of ``out_root``'s idyn.h5
    and the ground reactions of its filter.h5, as OpenSim's columns {label: (frames,)}."""
    model = read_idyn_model(out_root / "idyn" / "idyn.h5")
    params = BodyParameters(model.mass_kg, model.inertia_kgm2, model.joint_in_parent_m, model.joint_in_child_m)
    result = inverse_dynamics(q, qd, qdd, params, external_wrenches(filtered_trial(out_root)),
                              gravity_m_s2=model.gravity_m_s2)
    return opensim_generalized_forces(result.generalized_forces)


def largest_differences(out_root: Path, results: Path) -> dict[str, float]:
    """{label: the largest |OpenSim − gaitcli| over the frames} of the two inverse dynamics of ``out_root``'s
    OpenSim export on the same motion (module docstring)."""
    folder = out_root / "export" / "opensim"
    theirs = opensim_inverse_dynamics(folder, results)
    ours = gaitcli_inverse_dynamics(out_root, *opensim_spline_motion(folder))
    assert set(ours) <= set(theirs)
    return {label: float(np.max(np.abs(theirs[label] - ours[label]))) for label in ours}
