"""gaitcli: gait-lab processing from C3D trials to joint moments, muscle forces and predictive gait.

The Python API (docs/api.rst) is :mod:`gaitcli.api`'s, loaded on first use of one of the names in
:data:`__all__` (``gaitcli.run``, ``gaitcli.read_outputs``, …): ``import gaitcli`` itself imports nothing else,
so that the ``gait`` command can set its thread counts before numpy loads (docs/architecture.md).
"""

__version__ = "0.1.0"

#: the public API, every name of it from :mod:`gaitcli.api` (docs/api.rst documents each)
__all__ = [
    "open_trial", "TrialFolder", "sample_trial", "pipeline_config", "PipelineConfig", "run_trial", "predict_gait",
    "read_outputs", "Outputs", "FilterOutputs", "IdynOutputs", "MuscleOutputs", "PredictionOutputs",
    "StageOutcome", "InputError", "NotConvergedError",
]


def __getattr__(name: str):
    if name in __all__:
        from gaitcli import api

        return getattr(api, name)
    raise AttributeError(f"module 'gaitcli' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *__all__])
