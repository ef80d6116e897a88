"""The import rules of docs/architecture.md, checked on the package's source (AST, imports inside functions too)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parent.parent / "gaitcli"
#: the stage packages, each allowed to import only the ones before it
STAGE_ORDER = ("signal", "kinematics", "dynamics", "muscles", "predict")
#: the edges: what no stage package may import
EDGES = ("cli", "progress", "run", "report", "synth")


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


def sources(package: str) -> list[Path]:
    folder = PACKAGE / package
    return sorted(folder.rglob("*.py")) if folder.is_dir() else [PACKAGE / f"{package}.py"]


def violations(package: str, forbidden: set[str]) -> list[str]:
    return [f"{path.relative_to(PACKAGE.parent)} imports {m}" for path in sources(package)
            for m in sorted(imported_modules(path)) if first_part(m) in forbidden]


@pytest.mark.parametrize("package", STAGE_ORDER)
def test_stage_packages_import_no_edge_and_no_later_stage(package):
    later = set(STAGE_ORDER[STAGE_ORDER.index(package) + 1:])
    assert not violations(package, set(EDGES) | later)


def test_io_imports_no_model_package():
    assert not violations("io", set(STAGE_ORDER) | set(EDGES))


def test_core_imports_only_core_and_errors():
    everything = {p.stem if p.is_file() else p.name for p in PACKAGE.iterdir()
                  if (p.is_dir() and (p / "__init__.py").is_file()) or p.suffix == ".py"}
    assert not violations("core", everything - {"core", "errors", "__init__"})


def test_compare_imports_only_io_core_and_errors():
    everything = {p.stem if p.is_file() else p.name for p in PACKAGE.iterdir()
                  if (p.is_dir() and (p / "__init__.py").is_file()) or p.suffix == ".py"}
    assert (PACKAGE / "run" / "compare.py").is_file()
    assert not violations("run/compare", everything - {"io", "core", "errors", "__init__"})


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
                                                                     "study_plots"}
    classes = {n.name for path in sources("report") for n in ast.walk(ast.parse(path.read_text(encoding="utf-8")))
               if isinstance(n, ast.ClassDef)}
    assert classes == {"Page"}  # the pages written; no container a stage could come to need


#: what writes files: the CSV/JSON writers, the HDF5 writer and the atomic staging
FILE_WRITERS = {"gaitcli.io.outputs", "gaitcli.io.atomic", "gaitcli.io.h5.write_h5", "gaitcli.io.h5.record_datasets"}


@pytest.mark.parametrize("package", STAGE_ORDER)
def test_in_a_stage_package_only_outputs_writes_files(package):
    # the stage's writer lives beside it in outputs.py; every other module of the package stays pure
    writing = [f"{path.relative_to(PACKAGE.parent)} imports {m}" for path in sources(package) if path.name != "outputs.py"
               for m in sorted(imported_modules(path)) if m in FILE_WRITERS or m.rsplit(".", 1)[0] in FILE_WRITERS]
    assert not writing


def test_the_checker_sees_imports_inside_functions(tmp_path):
    # the rule must not be dodged by a local or relative import inside a function
    probe = tmp_path / "probe.py"
    probe.write_text("import numpy\n\ndef f():\n    from gaitcli.report import plots\n"
                     "    if True:\n        from ..pipeline import run_stage\n")
    found = imported_modules(probe, "gaitcli.signal.probe")
    assert {"gaitcli.report", "gaitcli.report.plots", "gaitcli.pipeline", "gaitcli.pipeline.run_stage"} <= found
    assert {first_part(m) for m in found} == {"report", "pipeline"}
