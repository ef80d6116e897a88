"""The install holds every package: setup.py finds the packages below gaitcli/, which it can only do for folders
with an ``__init__.py``; importing the package does nothing to its host process."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

from gaitcli.__main__ import THREAD_VARIABLES

ROOT = Path(__file__).resolve().parents[1]


def test_every_folder_of_code_is_a_package_the_install_finds():
    from setuptools import find_packages

    found = set(find_packages(str(ROOT), include=["gaitcli", "gaitcli.*"]))
    folders = {".".join(p.parent.relative_to(ROOT).parts) for p in (ROOT / "gaitcli").rglob("*.py")
               if "__pycache__" not in p.parts}
    assert folders <= found, f"folders of code without __init__.py, left out of the install: {folders - found}"


def test_importing_gaitcli_changes_no_environment_variable():
    """Only the ``gait`` command sets the thread counts (gaitcli/__main__.py); a host process importing the
    package keeps its environment."""
    code = ("import os, json; before = dict(os.environ); import gaitcli, gaitcli.cli; "
            "print(json.dumps(sorted(k for k in set(before) | set(os.environ) if before.get(k) != os.environ.get(k))))")
    env = {k: v for k, v in os.environ.items() if k not in THREAD_VARIABLES}
    changed = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert json.loads(changed.stdout) == []
    command = subprocess.run([sys.executable, "-m", "gaitcli", "--version"], env=env, capture_output=True, text=True)
    assert command.returncode == 0 and "0.1.0" in command.stdout, command.stderr
