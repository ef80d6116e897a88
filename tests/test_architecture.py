"""The import rules of docs/architecture.md, checked on the package's source (AST, imports inside functions too).

Every top-level part of the package has a rule (:data:`ALLOWED`): a new module or subpackage fails here until
docs/architecture.md and this table say where it sits."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parent.parent / "gaitcli"
#: the stage packages, each allowed to import only the ones before it
STAGE_ORDER = ("signal", "emg", "kinematics", "dynamics", "muscles", "predict")
#: the edges: what no stage package may import
EDGES = ("__main__", "cli", "api", "progress", "run", "report", "synth")
#: what every part may import: the package itself ("": ``from gaitcli import __version__``), and below it
BASE = {"", "__init__", "errors"}
#: what each top-level part may import (besides itself), from the top of the layers down
ALLOWED = {
    "cli": {"api", "progress", "run", "report", "synth", *STAGE_ORDER, "io", "core", "resources"},
    "api": {"run", *STAGE_ORDER, "io", "core", "resources"},  # the Python API: what the command line calls
    "progress": {"core"},  # the command line's progress display
    "run": {"report", *STAGE_ORDER, "io", "core", "resources"},
    "report": {*STAGE_ORDER, "io", "core", "resources"},
    "synth": {*STAGE_ORDER, "io", "core", "resources"},
    **{name: {*STAGE_ORDER[:k], "io", "core"} for k, name in enumerate(STAGE_ORDER)},
    "io": {"core"},
    "core": set(),
    "resources": set(),
    "errors": {""},
    "__init__": {"api"},  # its public names, loaded from api.py on first use
    "__main__": {"cli"},  # the gait command: the thread counts, then the command line
}
#: modules of run/ with rules of their own: what each may import (run.X: a module of run/)
RUN_ALLOWED = {
    # output trees by their names and units, knowing no stage; the CLI maps its findings to exit codes
    "compare": {"io", "core"},
    # the workers know what they run no more than a pool does
    "cluster": {"core", "run.dask_workers"},
    "dask_workers": {"core"},
    # trial folders: files and the subject, no stage
    "trial": {"io", "core", "kinematics"},
    # a batch runs the pipeline on its workers, as the command line does, without it or its figures
    "batch": {"io", "core", "run.cluster", "run.config", "run.pipeline", "run.trial"},
}


def module_name(path: Path) -> str:
    return ".".join(path.relative_to(PACKAGE.parent).with_suffix("").parts)


def imported_modules(path: Path, module: str | None = None) -> set[str]:
    """Every ``gaitcli`` module a source file imports, at any depth of the syntax tree (relative ones resolved).

    ``module``: the file's dotted name (default: from its place in the package).
    """
    module = module or module_name(path)
    package = module if path.name == "__init__.py" else module.rsplit(".", 1)[0]
    out = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            out.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - node.level + 1]
                name = ".".join(base + ([node.module] if node.module else []))
            else:
                name = node.module or ""
            out.add(name)
            out.update(f"{name}.{alias.name}" for alias in node.names)
    return {m for m in out if m == "gaitcli" or m.startswith("gaitcli.")}


def first_part(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def run_part(module: str) -> str:
    """A module's part, with run/'s modules told apart: "run.pipeline" for ``gaitcli.run.pipeline.run_stages``."""
    parts = module.split(".")
    return f"run.{parts[2]}" if first_part(module) == "run" and len(parts) > 2 else first_part(module)


def top_level_parts() -> set[str]:
    return {p.stem if p.is_file() else p.name for p in PACKAGE.iterdir()
            if (p.is_dir() and (p / "__init__.py").is_file()) or p.suffix == ".py"}


def sources(package: str) -> list[Path]:
    folder = PACKAGE / package
    return sorted(folder.rglob("*.py")) if folder.is_dir() else [PACKAGE / f"{package}.py"]


def violations(package: str, forbidden: set[str]) -> list[str]:
    return [f"{path.relative_to(PACKAGE.parent)} imports {m}" for path in sources(package)
            for m in sorted(imported_modules(path)) if first_part(m) in forbidden]


def test_every_top_level_part_has_a_rule():
    assert top_level_parts() == set(ALLOWED), "a part without a rule (or a rule without its part)"
    assert {p.stem for p in (PACKAGE / "run").glob("*.py")} >= set(RUN_ALLOWED)


@pytest.mark.parametrize("part", sorted(ALLOWED))
def test_each_part_imports_only_the_parts_below_it(part):
    forbidden = top_level_parts() - ALLOWED[part] - BASE - {part}
    assert not violations(part, forbidden)


@pytest.mark.parametrize("package", STAGE_ORDER)
def test_stage_packages_import_no_edge_and_no_later_stage(package):
    later = set(STAGE_ORDER[STAGE_ORDER.index(package) + 1:])
    assert not violations(package, set(EDGES) | later)


def test_io_imports_no_model_package():
    assert not violations("io", set(STAGE_ORDER) | set(EDGES))


def test_core_imports_only_core_and_errors():
    assert not violations("core", top_level_parts() - {"core", "errors", "__init__"})


def test_nothing_in_run_imports_the_command_line():
    assert not violations("run", {"cli"})


@pytest.mark.parametrize("module", sorted(RUN_ALLOWED))
def test_run_modules_with_rules_of_their_own(module):
    path = PACKAGE / "run" / f"{module}.py"
    allowed = RUN_ALLOWED[module] | BASE | {f"run.{module}", "run"}
    found = {run_part(m) for m in imported_modules(path)}
    assert found <= allowed, f"run/{module}.py imports {sorted(found - allowed)}"


def test_only_the_command_line_imports_its_progress_display():
    importers = sorted(str(path.relative_to(PACKAGE.parent)) for path in PACKAGE.rglob("*.py")
                       if path.name != "progress.py" and any(first_part(m) == "progress"
                                                             for m in imported_modules(path)))
    assert importers == ["gaitcli/cli.py"]


def test_every_hdf5_file_is_opened_by_io_h5():
    # typed records, units from names, damaged files as InputError: no module reads HDF5 around it
    opening = []
    for path in PACKAGE.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = ([alias.name for alias in node.names] if isinstance(node, ast.Import)
                     else [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            if any(name.split(".")[0] == "h5py" for name in names):
                opening.append(str(path.relative_to(PACKAGE.parent)))
    assert sorted(set(opening)) == ["gaitcli/io/h5.py"]


def test_report_holds_the_page_and_the_figures_only():
    # stage writers live beside their stage, exports in io/, the progress display beside the CLI, bands in signal/
    assert {p.stem for p in (PACKAGE / "report").glob("*.py")} == {"__init__", "html", "plots", "predict_plots",
                                                                     "study_plots", "session_plots", "compare_plots",
                                                                     "emg_plots"}
    classes = {n.name for path in sources("report") for n in ast.walk(ast.parse(path.read_text(encoding="utf-8")))
               if isinstance(n, ast.ClassDef)}
    assert classes == {"Page"}  # the pages written; no container a stage could come to need


#: what writes files: the CSV/JSON writers, the HDF5 writer and the atomic staging
FILE_WRITERS = {"gaitcli.io.outputs", "gaitcli.io.atomic", "gaitcli.io.h5.write_h5", "gaitcli.io.h5.record_datasets"}


@pytest.mark.parametrize("package", STAGE_ORDER)
def test_in_a_stage_package_only_outputs_writes_files(package):
    # the stage's writer lives beside it in outputs.py; every other module of the package stays pure
    writing = [f"{path.relative_to(PACKAGE.parent)} imports {m}"
               for path in sources(package) if path.name != "outputs.py"
               for m in sorted(imported_modules(path)) if m in FILE_WRITERS or m.rsplit(".", 1)[0] in FILE_WRITERS]
    assert not writing


def test_the_checker_sees_imports_inside_functions(tmp_path):
    # the rule must not be dodged by a local or relative import inside a function
    probe = tmp_path / "probe.py"
    probe.write_text("import numpy\n\ndef f():\n    from gaitcli.report import plots\n"
                     "    if True:\n        from ..run.pipeline import run_stage\n")
    found = imported_modules(probe, "gaitcli.signal.probe")
    assert {"gaitcli.report", "gaitcli.report.plots", "gaitcli.run.pipeline", "gaitcli.run.pipeline.run_stage"} <= found
    assert {first_part(m) for m in found} == {"report", "run"}
    assert {run_part(m) for m in found} == {"report", "run.pipeline"}


def test_only_the_command_line_and_the_package_import_the_api():
    # the API is the top of the layers beside the command line: run/ and the stage packages know nothing of it
    importers = sorted(str(path.relative_to(PACKAGE.parent)) for path in PACKAGE.rglob("*.py")
                       if path.name != "api.py" and any(first_part(m) == "api" for m in imported_modules(path)))
    assert importers == ["gaitcli/__init__.py", "gaitcli/cli.py"]


def test_no_module_takes_a_public_name_through_the_package():
    # ``from gaitcli import run_trial`` inside the package would load the API below its place in the layers
    import gaitcli

    taking = [f"{path.relative_to(PACKAGE.parent)} imports {m}" for path in PACKAGE.rglob("*.py")
              for m in sorted(imported_modules(path)) if m.split(".", 1)[-1] in gaitcli.__all__
              and m.count(".") == 1]
    assert not taking


def test_no_public_name_is_shadowed_by_a_module():
    # importing gaitcli.run.pipeline sets the attribute gaitcli.run: a public function of that name would vanish
    import gaitcli

    assert not set(gaitcli.__all__) & top_level_parts()
