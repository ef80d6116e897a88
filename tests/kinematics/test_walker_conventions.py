"""The predictive model's joint moments in clinical senses (kinematics/conventions.py): a joint's power is the
same in either convention — the moment turns with the angle it is reported beside."""

from __future__ import annotations

import numpy as np

from gaitcli.kinematics.conventions import walker_joint_angles, walker_moments_to_clinical


def test_joint_power_is_the_same_in_both_conventions():
    rng = np.random.default_rng(0)
    moments = rng.normal(size=(5, 6))  # model senses: hip y_thigh − y3, knee, ankle; right then left
    y, rates = rng.normal(size=9), rng.normal(size=9)
    h = 1e-7
    clinical_rates = []
    for thigh, knee, ankle in ((3, 4, 5), (6, 7, 8)):
        before = np.array(walker_joint_angles(y[2], y[thigh], y[knee], y[ankle]))
        moved = y + h * rates
        after = np.array(walker_joint_angles(moved[2], moved[thigh], moved[knee], moved[ankle]))
        clinical_rates.append((after - before) / h)
    clinical_rates = np.concatenate(clinical_rates)
    model_rates = np.array([rates[3] - rates[2], rates[4], rates[5], rates[6] - rates[2], rates[7], rates[8]])
    np.testing.assert_allclose(walker_moments_to_clinical(moments) @ clinical_rates, moments @ model_rates,
                               rtol=1e-6)
