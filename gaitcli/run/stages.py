"""The registry entries of the built-in stages: one :class:`~gaitcli.core.registry.Stage` each.

Each entry ties a stage's pure function (in its package) to its writer (the
package's ``outputs.py``), its figures (``report/plots.py``) and the reader of
its hand-off (``io/h5.py``). Adding a
stage is one module with its config and run function plus one entry here
(``docs/architecture.md``).
"""

from __future__ import annotations

from gaitcli.core.container import Trial
from gaitcli.core.registry import Stage, StageContext, register
from gaitcli.dynamics.sagittal import SagittalExport
from gaitcli.dynamics.stage import IdynConfig, run_idyn
from gaitcli.io.h5 import read_result
from gaitcli.muscles.stage import MuscleResult, MusclesConfig, run_muscles_stage
from gaitcli.signal.stage import FilterConfig, filter_trial


def _filter(ctx: StageContext, cfg: FilterConfig):
    return filter_trial(ctx.recording(), cfg, path=ctx.trial_path)


def _idyn(ctx: StageContext, cfg: IdynConfig):
    return run_idyn(ctx.inputs["filter"], ctx.static_recording(), ctx.subject, cfg, subject_path=ctx.subject_path,
                    static_path=ctx.static_path, trial_path=ctx.trial_path)


def _muscles(ctx: StageContext, cfg: MusclesConfig):
    ctx.report(f"muscles ({cfg.method.upper()})", 0, 1)
    result = run_muscles_stage(ctx.inputs["idyn"], cfg, stature_m=ctx.subject.stature_m, sex=ctx.subject.sex,
                               source=ctx.input_paths.get("idyn"))
    ctx.report(f"muscles ({cfg.method.upper()})", 1, 1)
    return result


def _unconverged_muscles(result: MuscleResult) -> str:
    why = f": {result.diagnosis}" if result.diagnosis else ""
    return f"{result.method.upper()} did not converge ({result.status}){why}"


def _writer(module: str, name: str):
    """The writer ``<module>.<name>`` (a stage package's ``outputs``), imported when a stage first writes."""
    def write(folder, result, attrs):
        from importlib import import_module

        return getattr(import_module(module), name)(folder, result, attrs)
    return write


def _figures(name: str):
    """The figures ``report.plots.<name>(h5_path, folder, title)``, imported only when plots are drawn."""
    def draw(h5_path, folder, title):
        from gaitcli.report import plots

        return getattr(plots, name)(h5_path, folder, title=title)
    return draw


FILTER = register(Stage(
    name="filter", config=FilterConfig, run=_filter, write=_writer("gaitcli.signal.outputs", "write_filter_outputs"),
    read=lambda path: read_result(path, Trial, "trial"), handoff=lambda result: result.trial,
    h5_name="filter.h5", plots=_figures("filter_figures")))

IDYN = register(Stage(
    name="idyn", config=IdynConfig, depends=("filter",), run=_idyn,
    write=_writer("gaitcli.dynamics.outputs", "write_idyn_outputs"),
    read=lambda path: read_result(path, SagittalExport, "sagittal"), handoff=lambda result: result.sagittal,
    h5_name="idyn.h5", plots=_figures("idyn_figures")))

MUSCLES = register(Stage(
    name="muscles", config=MusclesConfig, depends=("idyn",), run=_muscles,
    write=_writer("gaitcli.muscles.outputs", "write_muscle_outputs"),
    result=MuscleResult, h5_name="muscles.h5",
    plots=_figures("muscle_figures"), folder=lambda cfg: f"muscles/{cfg.method}",
    converged=lambda result: result.converged, unconverged=_unconverged_muscles))
