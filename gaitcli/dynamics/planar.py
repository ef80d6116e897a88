"""Equations of motion of planar open chains (trees) of rigid segments, written once in CasADi (2.10–2.13).

The chain moves in the x–z plane of the model axes (x forward, z up, gravity
−z). Every segment carries a frame at its proximal joint (its *origin*) with two
unit vectors: *along* the segment, pointing down the segment from the origin,
and *across* it, pointing forward. A segment at the absolute angle φ has

    e_along(φ) = (sin φ, −cos φ),   e_across(φ) = (cos φ, sin φ),

so φ = 0 is a segment hanging straight down (for a segment above its origin,
e.g. the trunk, use negative *along* distances: φ = 0 is then upright), and
φ grows counter-clockwise seen with x to the right and z up (rotation about
−y: the direction that moves a hanging segment's distal end forward). A point
(a, c) of a segment lies at origin + a·e_along + c·e_across.

Joints are revolute. Each joint's generalized coordinate q_j is either the
child's angle *relative* to its parent (default), φ_child = φ_parent + s_j·q_j,
or its *absolute* angle (``absolute=True``), φ_child = s_j·q_j, from the
downward vertical; s_j = ±1 (``sign``) lets a coordinate follow the clinical
sense (knee flexion turns the shank backward: s = −1). A joint sits at the
point ``at`` = (a, c) of its parent (default: the parent's distal end
(length, 0)).

Bases (variable layout of q):
- ``"floating"``: q = (x, z, φ_root, joint coordinates in joint order); (x, z)
  is the root segment's origin, φ_root its absolute angle;
- ``"prescribed"``: q = (joint coordinates in joint order); joints without a
  parent sit at the base point, an input ``base`` (x, z) with acceleration
  ``base_acc`` (a rheonomic constraint, e.g. the hip of the muscle stage's limb).

The Functions of :class:`PlanarChain` (``n`` = number of coordinates):
- ``mass_matrix(q) → M`` (n × n), symmetric positive definite (2.13);
- ``bias(q, qd[, base_acc]) → k``: Coriolis and centrifugal forces plus, for a
  prescribed base, the inertial forces of its acceleration;
- ``gravity(q) → g``: generalized gravity forces;
- ``inverse_dynamics(q, qd, qdd[, base_acc]) → τ = M·q̈ + k − g``, the joint
  moments that produce the motion without external forces (2.10), summed
  segment by segment in Newton–Euler form;
- ``points(q[, base]) → one (x, z) per named point``; ``point_jacobians(q) →
  ∂(x, z)/∂q`` (2 × n) per point; ``centre_of_mass(q[, base]) → (x, z)``;
- ``applied_force[segment](q[, base], at, force, moment) → Q``: generalized
  force of a force (f_x, f_z) acting on ``segment`` at the world point ``at``
  plus a free moment (positive counter-clockwise, in the sense of φ), Q = J_oᵀf
  + (∂φ/∂q)ᵀ·((at − o) × f + moment), o the segment's origin.

so that the equations of motion read M(q)·q̈ + k(q, q̇) = g(q) + τ + Σ Q (2.13),
τ the joint moments (in the sense of each coordinate). All expressions are SX.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import casadi as ca

from gaitcli.core.physics import GRAVITY_M_S2
from gaitcli.core.validate import one_of
from gaitcli.errors import InputError, shown

BASES = ("floating", "prescribed")


@dataclass(frozen=True)
class Segment:
    """A rigid segment: mass, CoM (along, across its frame), sagittal inertia about the CoM, length
    and named points (a, c) in its frame, SI units."""

    name: str
    mass_kg: float
    inertia_kgm2: float
    length_m: float
    com_along_m: float
    com_across_m: float = 0.0
    points: Mapping[str, tuple[float, float]] = field(default_factory=dict)


@dataclass(frozen=True)
class Joint:
    """A revolute joint between ``parent`` (None: the prescribed base point) and ``child``.

    ``at`` (a, c) in the parent's frame (default its distal end); the coordinate
    ``coordinate`` is the child's angle relative to the parent (or absolute,
    from the downward vertical, with ``absolute``) times ``sign``.
    """

    coordinate: str
    parent: str | None
    child: str
    at: tuple[float, float] | None = None
    sign: float = 1.0
    absolute: bool = False


def _along(phi):
    return ca.vertcat(ca.sin(phi), -ca.cos(phi))


def _across(phi):
    return ca.vertcat(ca.cos(phi), ca.sin(phi))


def _cross(r, f):
    """z-like component of r × f in the plane, positive counter-clockwise (the sense of φ)."""
    return r[0] * f[1] - r[1] * f[0]


class PlanarChain:
    """Compiled equations of motion of one planar chain (see the module docstring for the layout)."""

    def __init__(self, segments: Sequence[Segment], joints: Sequence[Joint], *, base: str = "floating",
                 root: str | None = None, base_coordinates: tuple[str, str, str] = ("base_x", "base_z", "base_angle"),
                 gravity_m_s2: float = GRAVITY_M_S2):
        one_of(base, BASES, where="base")
        self.segments = {s.name: s for s in segments}
        self.base = base
        self.gravity_m_s2 = float(gravity_m_s2)
        floating = base == "floating"
        by_child = {j.child: j for j in joints}
        if floating:
            if root not in self.segments or root in by_child:
                raise InputError(None, "root", f"got {shown(root)} (expected the one segment without a joint)")
        unjointed = [s for s in self.segments if s not in by_child and s != root]
        if unjointed:
            raise InputError(None, "joints", f"segments {', '.join(unjointed)} have no joint")
        self.coordinates = (tuple(base_coordinates) if floating else ()) + tuple(j.coordinate for j in joints)
        n = self.n = len(self.coordinates)
        sym = ca.SX.sym
        q, qd, qdd = sym("q", n), sym("qd", n), sym("qdd", n)
        base_point = ca.SX.zeros(2) if floating else sym("base", 2)
        base_acc = ca.SX.zeros(2) if floating else sym("base_acc", 2)

        origin, angle = {}, {}
        if floating:
            origin[root], angle[root] = q[0:2], q[2]
        for k, joint in enumerate(joints, start=3 if floating else 0):
            if joint.child in origin or joint.child not in self.segments:
                raise InputError(None, "joints", f"{joint.coordinate}: child {shown(joint.child)} is unknown or "
                                                 f"already placed")
            if joint.parent is None:
                if floating:
                    raise InputError(None, "joints", f"{joint.coordinate}: a floating chain has no base point")
                at, parent_angle = base_point, 0
            elif joint.parent in origin:
                p_seg = self.segments[joint.parent]
                a, c = joint.at if joint.at is not None else (p_seg.length_m, 0.0)
                phi_p = angle[joint.parent]
                at, parent_angle = origin[joint.parent] + a * _along(phi_p) + c * _across(phi_p), phi_p
            else:
                raise InputError(None, "joints", f"{joint.coordinate}: parent {shown(joint.parent)} must come "
                                                 f"before its children")
            origin[joint.child] = at
            angle[joint.child] = (0 if joint.absolute else parent_angle) + joint.sign * q[k]

        def place(name, a, c):
            phi, point = angle[name], origin[name]
            if c:
                point = point + c * _across(phi)
            if a:
                point = point + a * _along(phi)
            return point

        up = ca.vertcat(0, self.gravity_m_s2)  # minus the gravitational acceleration
        mass_matrix, bias, gen_gravity = ca.SX.zeros(n, n), ca.SX.zeros(n), ca.SX.zeros(n)
        inverse = ca.SX.zeros(n)
        total_mass, mass_moment = 0.0, ca.SX.zeros(2)
        rate_rows = {}
        for name, seg in self.segments.items():
            mass, inertia = seg.mass_kg, seg.inertia_kgm2
            com = place(name, seg.com_along_m, seg.com_across_m)
            jac = ca.jacobian(com, q)
            rate = rate_rows[name] = ca.jacobian(angle[name], q)  # ω = (∂φ/∂q)·q̇, constant
            jac_dot_qd = ca.jacobian(jac @ qd, q) @ qd  # J̇·q̇
            mass_matrix += mass * jac.T @ jac + inertia * rate.T @ rate
            bias += jac.T @ (mass * (jac_dot_qd + base_acc))
            gen_gravity -= jac.T @ (mass * up)
            # Newton–Euler form of M·q̈ + k − g, summed per segment (the operation order of the muscle
            # stage's former hand-written limb, so that its inverse dynamics stays bit for bit the same)
            acc = jac @ qdd + jac_dot_qd + base_acc  # CoM acceleration
            inverse += jac.T @ (mass * (acc + up)) + rate.T * (inertia * (rate @ qdd))
            total_mass += mass
            mass_moment += mass * com
        self.total_mass_kg = float(total_mass)

        placed = [q] if floating else [q, base_point]
        placed_names = ["q"] if floating else ["q", "base"]
        point_names, point_exprs = [], []
        for name, seg in self.segments.items():
            for point, (a, c) in seg.points.items():
                point_names.append(point)
                point_exprs.append(place(name, a, c))
        self.point_names = tuple(point_names)
        F = ca.Function
        self.mass_matrix = F("mass_matrix", [q], [mass_matrix], ["q"], ["M"])
        self.bias = (F("bias", [q, qd], [bias], ["q", "qd"], ["k"]) if floating else
                     F("bias", [q, qd, base_acc], [bias], ["q", "qd", "base_acc"], ["k"]))
        self.gravity = F("gravity", [q], [gen_gravity], ["q"], ["g"])
        self.inverse_dynamics = (
            F("inverse_dynamics", [q, qd, qdd], [inverse], ["q", "qd", "qdd"], ["tau"]) if floating else
            F("inverse_dynamics", [q, qd, qdd, base_acc], [inverse], ["q", "qd", "qdd", "base_acc"], ["tau"]))
        self.points = F("points", placed, point_exprs, placed_names, point_names)
        self.point_jacobians = F("point_jacobians", [q], [ca.jacobian(p, q) for p in point_exprs], ["q"],
                                 point_names)
        self.centre_of_mass = F("centre_of_mass", placed, [mass_moment / total_mass], placed_names, ["com"])
        self.applied_force = {}
        at, force, moment = sym("at", 2), sym("force", 2), sym("moment")
        for name in self.segments:
            o = origin[name]
            gen = ca.jacobian(o, q).T @ force + rate_rows[name].T * (_cross(at - o, force) + moment)
            self.applied_force[name] = F(f"force_on_{name}", placed + [at, force, moment], [gen],
                                         placed_names + ["at", "force", "moment"], ["Q"])
