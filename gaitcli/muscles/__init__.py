"""Muscle stage (Diss. ch. 4): 2-D lower-limb model, Hill muscles, SO | MSO | EID, forward validation.

Entry point: :func:`run_muscles` on a :class:`SagittalMotion` and
:class:`LimbParameters`, returning a :class:`MuscleResult`.
"""

from .forward import ValidationResult, validate_forward
from .hill import MuscleModel, path_angles
from .limb import LimbModel, LimbParameters, MotionInterpolant
from .parameters import MUSCLE_ABBREVIATIONS, MUSCLE_NAMES, JointParameters, MuscleParameters, table_a1
from .passive import JointModel
from .problem import Models, Problem, build_problem, default_interval
from .solver import SolverSettings
from .stage import METHODS, MuscleOptions, MuscleResult, ralston_cost_of_transport, run_muscles

__all__ = [
    "JointModel", "JointParameters", "LimbModel", "LimbParameters", "METHODS", "MUSCLE_ABBREVIATIONS",
    "MUSCLE_NAMES", "Models", "MotionInterpolant", "MuscleModel", "MuscleOptions", "MuscleParameters",
    "MuscleResult", "Problem", "SolverSettings", "ValidationResult", "build_problem",
    "default_interval", "path_angles", "ralston_cost_of_transport", "run_muscles",
    "table_a1", "validate_forward",
]
