"""What a passive prosthetic ankle law provides to the prediction (Diss. 5.3.3): the interface of
:mod:`gaitcli.predict.prosthesis`'s registry.

A law is a frozen dataclass of a name and its coefficients (SI units, documented by the law), with:

- ``law``: its registry name (a prosthesis file's ``law:``); ``COEFFICIENTS``: the field names in order (the
  optimal device's design variables D, a prosthesis file's keys, the ``prosthesis_<name>`` figures of
  summary.json and study.csv); ``SCALE``: each coefficient's scale in the NLP (D = coefficients / SCALE);
  ``BOUNDS``: (low, high) of the optimal device's coefficients; ``SLOPE_SCALE``: N·m/rad, the scale of the
  monotone constraint's rows;
- :meth:`spring_moment_Nm` τ_s(y) and :meth:`moment_Nm` τ_prosth(y, ẏ), in N·m positive in the sense of the
  model's ankle angle y (rad, plantarflexing; y = −δ, docs/prediction.md, "The ankle's sign"), numpy or
  CasADi; :meth:`nlp_moment_Nm` the twice-differentiable form the NLP uses (default: :meth:`moment_Nm`);
- :meth:`slope_Nm_per_rad` dτ_s/dy, numpy or CasADi (the optimal device's spring must decrease over the
  declared ankle range, 5.3.3);
- :meth:`checked`: the law's own checks of a file's values (an InputError naming the key).

The dissertation's law is (5.58)–(5.59) (:class:`gaitcli.predict.cubic_ankle.ProsthesisCurve`).
"""

from __future__ import annotations

import abc
import dataclasses
from typing import ClassVar

import numpy as np


@dataclasses.dataclass(frozen=True)
class ProsthesisLaw(abc.ABC):
    """Base of the prosthetic ankle laws (module docstring); ``name`` says which device (captions, tables)."""

    name: str

    law: ClassVar[str] = ""
    COEFFICIENTS: ClassVar[tuple[str, ...]] = ()
    SCALE: ClassVar[np.ndarray] = np.zeros(0)
    BOUNDS: ClassVar[tuple[np.ndarray, np.ndarray]] = (np.zeros(0), np.zeros(0))
    SLOPE_SCALE: ClassVar[float] = 1.0

    @classmethod
    def from_values(cls, name: str, values) -> ProsthesisLaw:
        """The device ``name`` of this law with ``values`` in :attr:`COEFFICIENTS` order (numbers or CasADi)."""
        return cls(name, *values)

    def with_values(self, name: str, values) -> ProsthesisLaw:
        """A device of the same law named ``name`` with other coefficients."""
        return type(self).from_values(name, values)

    def coefficients(self) -> np.ndarray:
        """The coefficients as an array, :attr:`COEFFICIENTS` order."""
        return np.array([getattr(self, k) for k in self.COEFFICIENTS], float)

    def scaled(self) -> np.ndarray:
        """The coefficients as the NLP holds them (D = coefficients / :attr:`SCALE`)."""
        return self.coefficients() / self.SCALE

    def named(self, prefix: str = "") -> dict[str, float]:
        """{``prefix`` + name: value} of :attr:`COEFFICIENTS`."""
        return {f"{prefix}{k}": float(getattr(self, k)) for k in self.COEFFICIENTS}

    @abc.abstractmethod
    def spring_moment_Nm(self, y):
        """τ_s(y), N·m, at ankle angles ``y`` (rad; numpy or CasADi)."""

    @abc.abstractmethod
    def moment_Nm(self, y, y_rate):
        """τ_prosth(y, ẏ), N·m: the spring's moment and the damping's."""

    @abc.abstractmethod
    def slope_Nm_per_rad(self, y):
        """dτ_s/dy, N·m/rad, at ``y`` (numpy arrays, or numbers with numeric or CasADi coefficients)."""

    def nlp_moment_Nm(self, y, y_rate):
        """The moment the NLP states (default: :meth:`moment_Nm`; a law whose moment is not twice
        differentiable gives a smooth approximation here)."""
        return self.moment_Nm(y, y_rate)

    def plantarflexor_moment_Nm(self, dorsiflexion_rad):
        """The spring's plantarflexor moment at a dorsiflexion angle in the product's convention (dorsiflexion
        positive, y = −δ)."""
        return self.spring_moment_Nm(-np.asarray(dorsiflexion_rad, float))

    def is_monotone(self, low_rad: float, high_rad: float, samples: int = 401) -> bool:
        """Whether τ_s decreases (dτ_s/dy ≤ 0) over [low, high] in y, checked at ``samples`` angles."""
        return bool(np.all(self.slope_Nm_per_rad(np.linspace(low_rad, high_rad, samples)) <= 0.0))

    def checked(self, path) -> ProsthesisLaw:
        """This device when a prosthesis file may give it, else an InputError naming ``path`` and the key."""
        return self
