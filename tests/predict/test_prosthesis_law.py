"""A prosthetic ankle law is one module plus one entry of ``prosthesis.LAWS`` (gaitcli/predict/ankle_law.py):
a linear spring and damper, defined here as its own module would define it, goes through the file reader,
the muscles' device moment, the NLP's variables D, their scale and bounds, and the monotone constraint."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gaitcli.predict import prosthesis
from gaitcli.predict.ankle_law import ProsthesisLaw


@dataclasses.dataclass(frozen=True)
class LinearAnkle(ProsthesisLaw):
    """τ_prosth = k·y − d·ẏ: stiffness k N·m/rad (≤ 0, restoring), damping d N·m·s/rad."""

    k_Nm_per_rad: float
    d_Nms_per_rad: float

    law = "linear"
    COEFFICIENTS = ("k_Nm_per_rad", "d_Nms_per_rad")
    SCALE = np.array([100.0, 1.0])
    BOUNDS = (np.array([-800.0, 0.0]), np.array([0.0, 2.0]))
    SLOPE_SCALE = 100.0

    def spring_moment_Nm(self, y):
        return self.k_Nm_per_rad * y

    def moment_Nm(self, y, y_rate):
        return self.spring_moment_Nm(y) - self.d_Nms_per_rad * y_rate

    def slope_Nm_per_rad(self, y):
        return self.k_Nm_per_rad if np.ndim(y) == 0 else np.full(np.shape(y), self.k_Nm_per_rad)


@pytest.fixture
def linear_law(monkeypatch):
    monkeypatch.setitem(prosthesis.LAWS, "linear", LinearAnkle)
    return LinearAnkle


RANGE = (float(np.radians(-25.0)), float(np.radians(10.0)))


def test_a_file_names_its_law_and_gives_that_laws_coefficients(linear_law):
    from gaitcli.errors import InputError

    device = prosthesis.curve_from_mapping({"law": "linear", "name": "spring", "k_Nm_per_rad": -300.0,
                                            "d_Nms_per_rad": 0.5}, "foot.yaml", RANGE)
    assert isinstance(device, LinearAnkle) and device.named() == {"k_Nm_per_rad": -300.0, "d_Nms_per_rad": 0.5}
    np.testing.assert_allclose(device.plantarflexor_moment_Nm(np.radians(10.0)), 300.0 * np.radians(10.0))
    with pytest.raises(InputError) as caught:  # another law's key
        prosthesis.curve_from_mapping({"law": "linear", "k_Nm_per_rad": -300.0, "d_Nms_per_rad": 0.5,
                                       "c0": 1.0}, "foot.yaml", RANGE)
    assert caught.value.field == "c0" and "unknown key" in caught.value.problem
    with pytest.raises(InputError, match="rises"):  # a spring that turns is refused for every law
        prosthesis.curve_from_mapping({"law": "linear", "k_Nm_per_rad": 50.0, "d_Nms_per_rad": 0.5},
                                      "foot.yaml", RANGE)
    with pytest.raises(InputError) as caught:
        prosthesis.curve_from_mapping({"law": "bezier"}, "foot.yaml", RANGE)
    assert caught.value.field == "law" and "expected one of cubic, linear" in caught.value.problem


def test_the_model_and_the_nlp_take_the_laws_moment_scale_and_bounds(linear_law):
    from gaitcli.predict.guess import initial_guess
    from gaitcli.predict.muscles import WalkerMuscles
    from gaitcli.predict.nlp import build_nlp
    from gaitcli.predict.problem import Transcriber
    from gaitcli.predict.reference import read_reference
    from gaitcli.resources import bundled_reference

    device = LinearAnkle("spring", -300.0, 0.5)
    muscles = WalkerMuscles(prosthesis=device)
    rng = np.random.default_rng(3)
    y, yd = rng.uniform(-0.3, 0.3, 9), rng.uniform(-2.0, 2.0, 9)
    moments = np.array(muscles.device(y, yd, device.coefficients())).ravel()
    expected = np.zeros(9)
    expected[[5, 8]] = -300.0 * y[[5, 8]] - 0.5 * yd[[5, 8]]  # the ankles, y6 and y9
    np.testing.assert_allclose(moments, expected, atol=1e-12)

    transcriber = Transcriber(6, muscles=muscles)
    assert transcriber.key != Transcriber(6, muscles=WalkerMuscles(prosthesis=prosthesis.COMMERCIAL_FEET["sach"])).key
    nlp = build_nlp(transcriber, read_reference(bundled_reference()), symmetric=True)
    assert nlp.device_size == 2 and nlp.device_law is LinearAnkle
    low, high = nlp.device_bounds()
    np.testing.assert_allclose(low * LinearAnkle.SCALE, LinearAnkle.BOUNDS[0])
    np.testing.assert_allclose(high * LinearAnkle.SCALE, LinearAnkle.BOUNDS[1])
    # the start solves the defining equations with the law's moment, and D holds the scaled coefficients
    w0 = nlp.start(initial_guess(transcriber, read_reference(bundled_reference()), symmetric=True))
    np.testing.assert_allclose(nlp.device(w0), device.coefficients())
    g = nlp.constraint_values(w0)
    t = transcriber.at(*nlp.gait(w0))
    stated = np.concatenate(t.moment_error_Nm[:transcriber.grid.points // 2])  # the symmetric half
    np.testing.assert_allclose(g[nlp.groups["moment"]], stated, atol=1e-9)
    np.testing.assert_allclose(g[nlp.groups["monotone"]], -3.0)  # k / SLOPE_SCALE at every sampled angle
