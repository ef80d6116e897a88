"""gaitcli's 8-body, 27-coordinate model as an OpenSim model: coordinate names and signs, the ``.osim`` document,
and the generalized forces OpenSim's inverse dynamics reports (docs/opensim.md).

OpenSim's axes are y up: a model-axes vector (x forward, y left, z up) becomes ``TO_OPENSIM · v`` = (x, z, −y).
Every body keeps its frame (origin at its centre of mass, axes along the ground's in the reference posture, 3.1),
so its inertia is ``TO_OPENSIM · I · TO_OPENSIMᵀ`` and its mass centre (0, 0, 0). Each joint is a CustomJoint whose
SpatialTransform turns about the model's Cardan axes in the model's order (rotation1, 2, 3 are successive turns
about axes fixed in the frame before each; translations along the parent's axes): the pelvis x-y-z
(``Rx Ry Rz``), the joints y-x-z (``Ry Rx Rz``). An OpenSim coordinate is ``sign`` times the model's, turning
about ``sign`` times the model's axis in OpenSim's axes, so the rotation is the model's exactly and the value
carries OpenSim's gait models' sense (gait2392 and Rajagopal 2015: hip flexion, knee flexion, ankle dorsiflexion,
subtalar inversion positive; the left side's adduction and rotation mirrored). Its generalized force is then
``sign`` times the model's (3.19): the moment's projection on the coordinate's axis, positive in its sense.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gaitcli.io.exports import TO_OPENSIM
from gaitcli.kinematics.forward import forward_kinematics
from gaitcli.kinematics.model import BODIES, COORDINATES, JOINT_CHILD, JOINT_PARENT, JOINTS, BodyParameters

#: gaitcli's body → OpenSim's gait models' (gait2392, Rajagopal 2015); the foot is ``calcn`` (ExternalLoads' body)
OPENSIM_BODIES = {"pelvis": "pelvis", "hat": "torso", "thigh_r": "femur_r", "shank_r": "tibia_r", "foot_r": "calcn_r",
                  "thigh_l": "femur_l", "shank_l": "tibia_l", "foot_l": "calcn_l"}
#: gaitcli's joint → OpenSim's joint name; the pelvis's six coordinates are ``ground_pelvis``
OPENSIM_JOINTS = {"lumbar": "back", "hip_r": "hip_r", "knee_r": "knee_r", "ankle_r": "ankle_r",
                  "hip_l": "hip_l", "knee_l": "knee_l", "ankle_l": "ankle_l"}


@dataclass(frozen=True)
class OpenSimCoordinate:
    """One of the 27 coordinates in OpenSim: its ``name``, gaitcli's coordinate ``model`` (3.1), ``sign``
    (OpenSim's value = sign · the model's, both in m or rad) and whether it turns (else it translates)."""

    name: str
    model: str
    sign: float
    rotational: bool

    @property
    def axis(self) -> np.ndarray:
        """The unit axis (3,) of its turn or translation in OpenSim's axes, in the frame the SpatialTransform
        turns it in: ``sign`` times the model's axis (x, y or z by the model's name)."""
        word = self.model[-1] if self.model.startswith("pelvis") else _JOINT_AXIS[self.model.rsplit("_", 1)[1]]
        model_axis = "xyz".index(word)
        return self.sign * TO_OPENSIM[:, model_axis]


#: a joint's coordinates by its model name's last word: flexion about y, adduction about x, rotation about z (3.1)
_JOINT_AXIS = {"flexion": "y", "adduction": "x", "rotation": "z"}


def _joint(joint: str, names: tuple[str, str, str], signs: tuple[float, float, float]) -> list[OpenSimCoordinate]:
    return [OpenSimCoordinate(n, f"{joint}_{a}", s, True) for n, a, s in zip(names, ("flexion", "adduction",
                                                                                   "rotation"), signs)]


#: the 27 coordinates in gaitcli's order (3.1), with OpenSim's names and senses (docs/opensim.md's table)
OPENSIM_COORDINATES: tuple[OpenSimCoordinate, ...] = (
    OpenSimCoordinate("pelvis_tx", "pelvis_x", 1.0, False),
    OpenSimCoordinate("pelvis_tz", "pelvis_y", -1.0, False),  # model y is left, OpenSim z right
    OpenSimCoordinate("pelvis_ty", "pelvis_z", 1.0, False),
    OpenSimCoordinate("pelvis_list", "pelvis_rot_x", 1.0, True),
    OpenSimCoordinate("pelvis_tilt", "pelvis_rot_y", -1.0, True),
    OpenSimCoordinate("pelvis_rotation", "pelvis_rot_z", 1.0, True),
    *_joint("lumbar", ("lumbar_extension", "lumbar_bending", "lumbar_rotation"), (-1.0, 1.0, 1.0)),
    *[c for s, m in (("r", 1.0), ("l", -1.0)) for c in (
        _joint(f"hip_{s}", (f"hip_flexion_{s}", f"hip_adduction_{s}", f"hip_rotation_{s}"), (-1.0, m, m))
        + _joint(f"knee_{s}", (f"knee_angle_{s}", f"knee_adduction_{s}", f"knee_rotation_{s}"), (1.0, m, m))
        + _joint(f"ankle_{s}", (f"ankle_angle_{s}", f"subtalar_angle_{s}", f"ankle_rotation_{s}"), (-1.0, m, m)))],
)
OPENSIM_COORDINATES = tuple(sorted(OPENSIM_COORDINATES, key=lambda c: COORDINATES.index(c.model)))
assert [c.model for c in OPENSIM_COORDINATES] == list(COORDINATES)


def force_label(coordinate: OpenSimCoordinate) -> str:
    """The column OpenSim's InverseDynamicsTool names a coordinate's generalized force: ``<name>_moment`` (N·m)
    or ``<name>_force`` (N)."""
    return f"{coordinate.name}_{'moment' if coordinate.rotational else 'force'}"


def opensim_coordinates(q) -> dict[str, np.ndarray]:
    """The 27 coordinates (n, 27) of the model (m, rad; 3.1) → OpenSim's columns {name: (n,)}: degrees for the
    turns, m for the pelvis translations (a ``.mot`` with ``inDegrees=yes``)."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    return {c.name: c.sign * (np.degrees(q[:, k]) if c.rotational else q[:, k])
            for k, c in enumerate(OPENSIM_COORDINATES)}


def model_coordinates(columns) -> np.ndarray:
    """The inverse of :func:`opensim_coordinates`: {name: (n,)} in deg and m → the model's (n, 27) in rad and m."""
    return np.column_stack([c.sign * (np.radians(columns[c.name]) if c.rotational else np.asarray(columns[c.name]))
                            for c in OPENSIM_COORDINATES])


def generalized_forces(q, params: BodyParameters, moments_global_Nm, residual_force_N, residual_moment_Nm):
    """The 27 generalized forces (n, 27) of the model's coordinates (3.19) from its joint moments and residuals:
    ``Q_k = u_k · τ_j`` for the Cardan axis ``u_k`` (global) of coordinate ``k`` of joint ``j`` and its moment
    ``τ_j`` (proximal on distal, (n, 7, 3) global, N·m); the pelvis rows ``[F; Gᵀ L]`` from the residual force
    ``F`` and moment ``L`` about the pelvis CoM (n, 3) (3.22)."""
    states = forward_kinematics(q, params, jacobians=True)
    JR = states.jacobian_rotation
    out = np.empty((JR.shape[0], len(COORDINATES)))
    out[:, 0:3] = residual_force_N
    out[:, 3:6] = np.einsum("nik,ni->nk", JR[:, 0, :, 3:6], residual_moment_Nm)
    for j, child in enumerate(JOINT_CHILD):
        k = 6 + 3 * j
        out[:, k:k + 3] = np.einsum("nik,ni->nk", JR[:, child, :, k:k + 3], moments_global_Nm[:, j])
    return out


def opensim_generalized_forces(model_forces) -> dict[str, np.ndarray]:
    """The model's generalized forces (n, 27) → OpenSim's inverse-dynamics columns {``<name>_moment`` or
    ``_force``: (n,)}, each positive in its coordinate's sense (``sign`` times the model's)."""
    model_forces = np.atleast_2d(np.asarray(model_forces, dtype=float))
    return {force_label(c): c.sign * model_forces[:, k] for k, c in enumerate(OPENSIM_COORDINATES)}


def _vector(v) -> str:
    return " ".join(f"{float(x):.17g}" for x in v)


def _transform_axes(coordinates: list[OpenSimCoordinate], translations: list[OpenSimCoordinate]) -> str:
    """A SpatialTransform's six TransformAxis elements: the turns, then the translations (unused: constant 0 about
    the remaining axes, which OpenSim needs independent)."""
    rows = []
    for kind, used, spare in (("rotation", coordinates, [(1, 0, 0), (0, 1, 0), (0, 0, 1)]),
                              ("translation", translations, [(1, 0, 0), (0, 1, 0), (0, 0, 1)])):
        for k in range(3):
            if k < len(used):
                c = used[k]
                body = (f"<coordinates>{c.name}</coordinates><axis>{_vector(c.axis)}</axis>"
                        "<LinearFunction name=\"function\"><coefficients>1 0</coefficients></LinearFunction>")
            else:
                body = (f"<coordinates></coordinates><axis>{_vector(spare[k])}</axis>"
                        "<Constant name=\"function\"><value>0</value></Constant>")
            rows.append(f"            <TransformAxis name=\"{kind}{k + 1}\">{body}</TransformAxis>")
    return "\n".join(rows)


def _coordinate(c: OpenSimCoordinate) -> str:
    reach = 4 * np.pi if c.rotational else 1000.0  # not clamped: the range only draws OpenSim's sliders
    return (f"            <Coordinate name=\"{c.name}\"><default_value>0</default_value>"
            f"<range>{-reach:.10g} {reach:.10g}</range><clamped>false</clamped><locked>false</locked>"
            "</Coordinate>")


def _custom_joint(name: str, parent: str, child: str, in_parent_m, in_child_m, rotations, translations) -> str:
    frames = "\n".join(
        f"            <PhysicalOffsetFrame name=\"{body}_offset\"><socket_parent>/{path}</socket_parent>"
        f"<translation>{_vector(TO_OPENSIM @ np.asarray(where, float))}</translation>"
        "<orientation>0 0 0</orientation></PhysicalOffsetFrame>"
        for body, path, where in ((parent, parent if parent == "ground" else f"bodyset/{parent}", in_parent_m),
                                  (child, f"bodyset/{child}", in_child_m)))
    return f"""        <CustomJoint name="{name}">
          <socket_parent_frame>{parent}_offset</socket_parent_frame>
          <socket_child_frame>{child}_offset</socket_child_frame>
          <coordinates>
{chr(10).join(_coordinate(c) for c in rotations + translations)}
          </coordinates>
          <frames>
{frames}
          </frames>
          <SpatialTransform>
{_transform_axes(rotations, translations)}
          </SpatialTransform>
        </CustomJoint>"""


def _body(name: str, mass_kg: float, inertia_kgm2) -> str:
    inertia = TO_OPENSIM @ np.asarray(inertia_kgm2, float) @ TO_OPENSIM.T
    moments = (inertia[0, 0], inertia[1, 1], inertia[2, 2], inertia[0, 1], inertia[0, 2], inertia[1, 2])
    return (f"        <Body name=\"{name}\"><mass>{float(mass_kg):.17g}</mass><mass_center>0 0 0</mass_center>"
            f"<inertia>{_vector(moments)}</inertia></Body>")


def osim_model(params: BodyParameters, *, name: str, gravity_m_s2: float) -> str:
    """The OpenSim 4 model document (``.osim`` text) of the calibrated bodies ``params``: 8 bodies at their CoMs
    with their masses and inertias, the ground–pelvis joint and 7 CustomJoints at the calibrated joint centres,
    the 27 coordinates of :data:`OPENSIM_COORDINATES`, gravity ``gravity_m_s2`` along −y (module docstring)."""
    bodies = "\n".join(_body(OPENSIM_BODIES[b], params.mass_kg[i], params.inertia_kgm2[i])
                       for i, b in enumerate(BODIES))
    pelvis = list(OPENSIM_COORDINATES[:6])
    joints = [_custom_joint("ground_pelvis", "ground", "pelvis", np.zeros(3), np.zeros(3), pelvis[3:],
                            [pelvis[0], pelvis[2], pelvis[1]])]  # translations along OpenSim's x, y, z
    for j, joint in enumerate(JOINTS):
        own = list(OPENSIM_COORDINATES[6 + 3 * j:9 + 3 * j])
        joints.append(_custom_joint(OPENSIM_JOINTS[joint], OPENSIM_BODIES[BODIES[JOINT_PARENT[j]]],
                                    OPENSIM_BODIES[BODIES[JOINT_CHILD[j]]], params.joint_in_parent_m[j],
                                    params.joint_in_child_m[j], own, []))
    return f"""<?xml version="1.0" encoding="UTF-8" ?>
<OpenSimDocument Version="40000">
  <Model name="{name}">
    <credits>gaitcli: the 8-body, 27-coordinate model of the idyn stage, calibrated on this subject</credits>
    <length_units>meters</length_units>
    <force_units>N</force_units>
    <gravity>0 {-gravity_m_s2:.10g} 0</gravity>
    <BodySet name="bodyset">
      <objects>
{bodies}
      </objects>
    </BodySet>
    <JointSet name="jointset">
      <objects>
{chr(10).join(joints)}
      </objects>
    </JointSet>
  </Model>
</OpenSimDocument>
"""
