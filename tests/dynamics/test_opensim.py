"""gaitcli's model as OpenSim's (dynamics/opensim.py): the .osim document composed by hand gives the model's body
poses; each coordinate turns in the sense docs/opensim.md states; the generalized forces are the inverse
dynamics' rows; and, where the ``opensim`` package is installed, OpenSim's own model of the document has the same
poses and the same inverse dynamics of an analytic motion."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pytest

from gaitcli.dynamics.inverse import inverse_dynamics
from gaitcli.dynamics.opensim import (
    OPENSIM_BODIES,
    OPENSIM_COORDINATES,
    TO_OPENSIM,
    generalized_forces,
    model_coordinates,
    opensim_coordinates,
    opensim_generalized_forces,
    osim_model,
)
from gaitcli.kinematics.forward import forward_kinematics
from gaitcli.kinematics.model import BODIES
from tests.opensim_runner import require_opensim, run_opensim

from .synthetic_model import random_parameters, random_wrenches, sine_motion


def _turn(axis, angle):
    """Rodrigues: the rotation by ``angle`` about the unit ``axis``."""
    k = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def _numbers(element, tag):
    return np.array([float(x) for x in element.find(tag).text.split()])


def _poses_from_document(text: str, values: dict[str, float]) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """{OpenSim body: (rotation, origin) in ground} of the .osim ``text`` at coordinate ``values`` (m, rad),
    composed from its joints' offset frames and SpatialTransforms alone: successive turns about each
    TransformAxis, translations along the parent offset frame's axes."""
    poses = {"ground": (np.eye(3), np.zeros(3))}
    joints = ET.fromstring(text).find("Model/JointSet/objects").findall("CustomJoint")
    for joint in joints:  # parents come first in the document
        frames = {f.get("name"): f for f in joint.find("frames")}
        parent = frames[joint.find("socket_parent_frame").text]
        child = frames[joint.find("socket_child_frame").text]
        R_parent, p_parent = poses[parent.find("socket_parent").text.rsplit("/", 1)[1]]
        R, p = np.eye(3), np.zeros(3)
        for axis in joint.find("SpatialTransform"):
            names = (axis.find("coordinates").text or "").split()
            value = values[names[0]] if names else 0.0
            if axis.find("LinearFunction") is not None:
                slope, offset = _numbers(axis.find("LinearFunction"), "coefficients")
                value = slope * value + offset
            if axis.get("name").startswith("rotation"):
                R = R @ _turn(_numbers(axis, "axis"), value)
            else:
                p = p + value * _numbers(axis, "axis")
        assert not _numbers(parent, "orientation").any() and not _numbers(child, "orientation").any()
        R_child = R_parent @ R
        origin = p_parent + R_parent @ (_numbers(parent, "translation") + p) - R_child @ _numbers(child, "translation")
        poses[child.find("socket_parent").text.rsplit("/", 1)[1]] = (R_child, origin)
    return poses


def _radians(columns: dict[str, np.ndarray], frame: int = 0) -> dict[str, float]:
    rotational = {c.name: c.rotational for c in OPENSIM_COORDINATES}
    return {k: float(np.radians(v[frame]) if rotational[k] else v[frame]) for k, v in columns.items()}


def test_the_documents_joints_place_every_body_where_the_model_does():
    rng = np.random.default_rng(3)
    params = random_parameters(rng)
    text = osim_model(params, name="synthetic", gravity_m_s2=9.81)
    for _ in range(3):
        q = np.r_[rng.normal(0, 1, 3), rng.uniform(-1.2, 1.2, 24)]
        poses = _poses_from_document(text, _radians(opensim_coordinates(q)))
        states = forward_kinematics(q, params)
        for b, body in enumerate(BODIES):
            R, origin = poses[OPENSIM_BODIES[body]]
            np.testing.assert_allclose(R, TO_OPENSIM @ states.rotation[0, b] @ TO_OPENSIM.T, atol=1e-12)
            np.testing.assert_allclose(origin, TO_OPENSIM @ states.com_m[0, b], atol=1e-12)
    body = ET.fromstring(text).find("Model/BodySet/objects/Body[@name='femur_l']")
    inertia = TO_OPENSIM @ params.inertia_kgm2[5] @ TO_OPENSIM.T
    np.testing.assert_allclose(_numbers(body, "inertia"), inertia[[0, 1, 2, 0, 0, 1], [0, 1, 2, 1, 2, 2]])
    assert float(body.find("mass").text) == params.mass_kg[5]


#: each coordinate's positive sense (docs/opensim.md): a body, one of its axes (OpenSim's: x forward, y up, z right;
#: None: its origin) and the ground direction that axis turns towards (or the origin moves along)
SENSES = {
    "pelvis_tx": ("pelvis", None, "+x"), "pelvis_ty": ("pelvis", None, "+y"), "pelvis_tz": ("pelvis", None, "+z"),
    "pelvis_list": ("pelvis", "+z", "-y"),  # the right side down
    "pelvis_tilt": ("pelvis", "+x", "+y"),  # posterior tilt: the front up
    "pelvis_rotation": ("pelvis", "+x", "-z"),  # the front to the left
    "lumbar_extension": ("torso", "+y", "-x"), "lumbar_bending": ("torso", "+y", "+z"),  # to the right
    "lumbar_rotation": ("torso", "+x", "-z"),  # to the left
    **{name: value for s, medial, lateral in (("r", "-z", "+z"), ("l", "+z", "-z")) for name, value in {
        f"hip_flexion_{s}": (f"femur_{s}", "-y", "+x"),  # the knee forward
        f"hip_adduction_{s}": (f"femur_{s}", "-y", medial), f"hip_rotation_{s}": (f"femur_{s}", "+x", medial),
        f"knee_angle_{s}": (f"tibia_{s}", "-y", "-x"),  # the ankle back: flexion
        f"knee_adduction_{s}": (f"tibia_{s}", "-y", medial), f"knee_rotation_{s}": (f"tibia_{s}", "+x", medial),
        f"ankle_angle_{s}": (f"calcn_{s}", "+x", "+y"),  # the toes up: dorsiflexion
        f"subtalar_angle_{s}": (f"calcn_{s}", "+y", lateral),  # the sole faces medially: inversion
        f"ankle_rotation_{s}": (f"calcn_{s}", "+x", medial)}.items()},
}


def _direction(signed_axis: str) -> np.ndarray:
    return (1.0 if signed_axis[0] == "+" else -1.0) * np.eye(3)["xyz".index(signed_axis[1])]


@pytest.mark.parametrize("name", [c.name for c in OPENSIM_COORDINATES])
def test_each_coordinate_turns_the_way_docs_opensim_md_says(name):
    params = random_parameters(np.random.default_rng(4))
    body, axis, towards = SENSES[name]
    b = BODIES.index(next(k for k, v in OPENSIM_BODIES.items() if v == body))
    columns = {c.name: np.zeros(1) for c in OPENSIM_COORDINATES}
    moved = []
    for value in (0.0, 5.0):  # m or deg
        columns[name] = np.array([value])
        states = forward_kinematics(model_coordinates(columns), params)
        R = TO_OPENSIM @ states.rotation[0, b] @ TO_OPENSIM.T
        moved.append(TO_OPENSIM @ states.com_m[0, b] if axis is None else R @ _direction(axis))
    change = moved[1] - moved[0]
    assert change @ _direction(towards) > 0.9 * np.linalg.norm(change) > 0


def test_the_generalized_forces_are_the_inverse_dynamics_rows():
    rng = np.random.default_rng(5)
    params = random_parameters(rng)
    t = np.linspace(0.0, 1.0, 40)
    q, qd, qdd = sine_motion(rng, t)
    result = inverse_dynamics(q, qd, qdd, params, random_wrenches(rng, t))
    forces = generalized_forces(q, params, result.joint_moments_global_Nm, result.residual_force_N,
                                result.residual_moment_Nm)
    np.testing.assert_allclose(forces, result.generalized_forces, rtol=1e-10, atol=1e-9)
    columns = opensim_generalized_forces(forces)
    assert list(columns)[:7] == ["pelvis_tx_force", "pelvis_tz_force", "pelvis_ty_force", "pelvis_list_moment",
                                 "pelvis_tilt_moment", "pelvis_rotation_moment", "lumbar_extension_moment"]
    np.testing.assert_array_equal(columns["knee_angle_l_moment"], forces[:, 21])  # knee flexion: the model's sign
    np.testing.assert_array_equal(columns["hip_flexion_l_moment"], -forces[:, 18])  # hip flexion: its negative
    np.testing.assert_allclose(model_coordinates(opensim_coordinates(q)), q, rtol=1e-14, atol=1e-15)


#: OpenSim's model of work/model.osim at the motion of work/motion.npz (OpenSim's coordinates, speeds and
#: accelerations, rad and m): every body's origin in ground and the InverseDynamicsSolver's generalized forces,
#: both in OPENSIM_COORDINATES' order
SOLVER = """
model = opensim.Model(str(work / "model.osim"))
state = model.initSystem()
coordinates = [model.getCoordinateSet().get(name) for name in arguments["names"]]
mobility = []  # each coordinate's place among the state's speeds
for c in coordinates:
    for other in coordinates:
        other.setSpeedValue(state, 1.0 if other is c else 0.0)
    mobility.append(int(np.argmax([state.getU().get(i) for i in range(state.getNU())])))
q, qd, qdd = np.load(work / "motion.npz")["motion"]
solver = opensim.InverseDynamicsSolver(model)
origins = np.zeros((q.shape[0], len(arguments["bodies"]), 3))
forces = np.zeros(q.shape)
for i in range(q.shape[0]):
    udot = opensim.Vector(state.getNU(), 0.0)
    for k, c in enumerate(coordinates):
        c.setValue(state, q[i, k], False)
        c.setSpeedValue(state, qd[i, k])
        udot.set(mobility[k], qdd[i, k])
    model.assemble(state)
    model.realizeAcceleration(state)
    for b, body in enumerate(arguments["bodies"]):
        p = model.getBodySet().get(body).getTransformInGround(state).p()
        origins[i, b] = [p.get(0), p.get(1), p.get(2)]
    solved = solver.solve(state, udot)
    forces[i] = [solved.get(m) for m in mobility]
np.savez(work / "out.npz", origins=origins, forces=forces)
"""


def test_opensims_model_of_the_document_has_the_models_poses_and_inverse_dynamics(tmp_path):
    """OpenSim's InverseDynamicsSolver on an analytic motion (q, q̇, q̈ exact) under gravity: gaitcli's
    generalized forces to 1e-9 N·m (N), its body origins to 1e-12 m."""
    require_opensim()
    rng = np.random.default_rng(6)
    params = random_parameters(rng)
    (tmp_path / "model.osim").write_text(osim_model(params, name="synthetic", gravity_m_s2=9.81))
    t = np.linspace(0.0, 1.0, 3)
    q, qd, qdd = sine_motion(rng, t)
    sign = np.array([c.sign for c in OPENSIM_COORDINATES])
    np.savez(tmp_path / "motion.npz", motion=np.stack([sign * q, sign * qd, sign * qdd]))
    saved = run_opensim(SOLVER, tmp_path, names=[c.name for c in OPENSIM_COORDINATES],
                        bodies=[OPENSIM_BODIES[b] for b in BODIES])
    states = forward_kinematics(q, params)
    np.testing.assert_allclose(saved["origins"], states.com_m @ TO_OPENSIM.T, atol=1e-12)
    ours = inverse_dynamics(q, qd, qdd, params, (), gravity_m_s2=9.81).generalized_forces
    np.testing.assert_allclose(saved["forces"], sign * ours, rtol=0, atol=1e-9)
