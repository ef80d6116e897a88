"""The install holds every package: setup.py finds the packages below gaitcli/, which it can only do for folders
with an ``__init__.py``."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_every_folder_of_code_is_a_package_the_install_finds():
    from setuptools import find_packages

    found = set(find_packages(str(ROOT), include=["gaitcli", "gaitcli.*"]))
    folders = {".".join(p.parent.relative_to(ROOT).parts) for p in (ROOT / "gaitcli").rglob("*.py")
               if "__pycache__" not in p.parts}
    assert folders <= found, f"folders of code without __init__.py, left out of the install: {folders - found}"
