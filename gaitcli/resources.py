"""Files shipped with the package: the bundled sample trials and pipelines.

They live at the top of the repository (``sample_trials/``, ``pipelines/``) and
are installed as ``gaitcli.sample_trials`` / ``gaitcli.pipelines``, so both an
editable and a regular install find them.
"""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path


def _shipped_folder(package: str, folder: str) -> Path:
    # gaitcli imported from a source checkout (``python -m pytest`` at the repository root puts ./gaitcli first
    # on sys.path; a git worktree beside an editable install): the checkout's own folder, beside the package
    checkout = Path(__file__).resolve().parent.parent
    if (checkout / "pyproject.toml").is_file() and (checkout / folder).is_dir():
        return checkout / folder
    return Path(str(files(package)))


def sample_trials_dir() -> Path:
    """Folder holding the bundled synthetic trials (``normal``, one per disturbance)."""
    return _shipped_folder("gaitcli.sample_trials", "sample_trials")


def sample_trial(name: str = "normal") -> Path:
    """The bundled trial folder ``name`` (default: the normal-walking sample trial)."""
    return sample_trials_dir() / name


def bundled_reference() -> Path:
    """The reference gait that ships with the package (``gait reference`` on the normal sample trial;
    sample_trials/README.md gives the command)."""
    return sample_trials_dir() / "reference_normal.csv"


def pipeline_file(name: str) -> Path:
    """A bundled pipeline YAML by name (``standard``, ``muscles_eid``, ...)."""
    return _shipped_folder("gaitcli.pipelines", "pipelines") / f"{name}.yaml"


def bundled_pipelines() -> tuple[str, ...]:
    """Names of the bundled pipelines (``--pipeline NAME``; the ``study_*`` files are prediction studies)."""
    return tuple(sorted(p.stem for p in _shipped_folder("gaitcli.pipelines", "pipelines").glob("*.yaml")
                        if not p.stem.startswith("study_")))


def study_file(name: str) -> Path:
    """A bundled prediction study (``gait predict --study``): ``pipelines/study_NAME.yaml``."""
    return _shipped_folder("gaitcli.pipelines", "pipelines") / f"study_{name}.yaml"
