"""Joint powers (dynamics/powers.py): a pendulum driven about its pivot, whose power integrates to the change of
its mechanical energy."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.dynamics.powers import joint_powers, sagittal_powers
from gaitcli.kinematics.model import JOINTS


def test_a_driven_pendulum_power_is_moment_times_speed_and_integrates_to_its_energy():
    """A rod (m, l, hanging from a fixed 'parent') swung as θ = A sin(ωt) about the y axis by the joint moment
    M = I θ̈ + m g (l/2) sin θ. Power = M θ̇ (positive while the moment drives the motion), and its integral over
    any span equals the change of kinetic plus potential energy."""
    m, length, g, A, w = 3.0, 0.8, 9.81, 0.6, 4.0
    inertia = m * length ** 2 / 3
    t = np.linspace(0.0, 1.3, 13001)
    theta, theta_d, theta_dd = A * np.sin(w * t), A * w * np.cos(w * t), -A * w ** 2 * np.sin(w * t)
    moment = inertia * theta_dd + m * g * length / 2 * np.sin(theta)
    n = t.size
    moments = np.zeros((n, len(JOINTS), 3))
    omega = np.zeros((n, 8, 3))
    joint = JOINTS.index("knee_r")  # any joint: its child body rotates, its parent (the thigh) stays still
    moments[:, joint, 1] = moment
    omega[:, 3, 1] = theta_d  # shank_r
    power = joint_powers(moments, omega)[:, joint]
    np.testing.assert_allclose(power, moment * theta_d, rtol=1e-12, atol=1e-12)
    energy = 0.5 * inertia * theta_d ** 2 + m * g * length / 2 * (1 - np.cos(theta))
    work = np.concatenate([[0.0], np.cumsum((power[1:] + power[:-1]) / 2 * np.diff(t))])
    np.testing.assert_allclose(work, energy - energy[0], atol=1e-5)
    axes = np.zeros((n, len(JOINTS), 3))
    axes[:, :, 1] = 1.0
    np.testing.assert_allclose(sagittal_powers(moments, omega, axes)[:, joint], power, atol=1e-12)
    others = np.delete(joint_powers(moments, omega), joint, axis=1)
    assert not others.any()


def test_a_moment_about_another_axis_does_no_sagittal_work():
    """A moment about x while the joint turns about y: total power zero, sagittal power zero."""
    moments = np.zeros((1, len(JOINTS), 3))
    omega = np.zeros((1, 8, 3))
    moments[0, 1] = (5.0, 0.0, 0.0)
    omega[0, 2] = (0.0, 2.0, 0.0)  # thigh_r
    axes = np.zeros((1, len(JOINTS), 3))
    axes[..., 1] = 1.0
    assert joint_powers(moments, omega)[0, 1] == pytest.approx(0.0)
    assert sagittal_powers(moments, omega, axes)[0, 1] == pytest.approx(0.0)


def test_frame_angular_velocity_of_two_composed_spins():
    """R(t) = Rz(a t) · Rx(b t): ω = a e_z + Rz(a t) b e_x (global axes), exactly; central differences at 200 Hz
    leave O((ω h)²) ≈ 1e-4 relative."""
    from gaitcli.dynamics.powers import frame_angular_velocity
    from gaitcli.kinematics.rotations import rot_x, rot_z

    a, b, rate = 1.5, -2.5, 200.0
    t = np.arange(200) / rate
    R = rot_z(a * t) @ rot_x(b * t)
    expected = np.stack([b * np.cos(a * t), b * np.sin(a * t), np.full_like(t, a)], axis=-1)
    got = frame_angular_velocity(R, rate)
    np.testing.assert_allclose(got[1:-1], expected[1:-1], atol=5e-4)
    np.testing.assert_allclose(got[[0, -1]], expected[[0, -1]], atol=5e-2)  # one-sided at the ends
    R[100] = np.nan  # a gap frame: its neighbours' derivatives are unknown, not made up
    assert np.isnan(frame_angular_velocity(R, rate)[99:102]).all()
