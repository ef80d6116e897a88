"""OpenSim's Python package run in a process of its own, for the tests that check gaitcli's exports with it.

``import opensim`` (4.6, Linux) puts its own folder on ``LD_LIBRARY_PATH`` in ``os.environ`` and loads the CasADi
3.7 it bundles for Moco: in a process that has imported CasADi (gaitcli's muscles and predict do) it fails
(undefined symbol), and every process started after it loads OpenSim's CasADi instead of gaitcli's (the ``gait``
runners' then fail). So the tests never import it: :func:`run_opensim` runs a script in a fresh interpreter that
imports only OpenSim and numpy, and reads back what it saved.
"""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest


def opensim_installed() -> bool:
    """Whether the ``opensim`` package is installed (``pip install ".[opensim]"``), without importing it."""
    return importlib.util.find_spec("opensim") is not None


def require_opensim() -> None:
    """Skip the test where the ``opensim`` package is not installed."""
    if not opensim_installed():
        pytest.skip("the opensim package is not installed (pip install gaitcli[opensim])")


def run_opensim(script: str, work: Path, **arguments) -> dict[str, np.ndarray]:
    """Run ``script`` (Python; ``opensim``, ``np``, ``work`` (a Path) and ``arguments`` (a dict) defined; it saves
    its results with ``np.savez(work / "out.npz", …)``) in a new interpreter, and return what it saved."""
    require_opensim()
    work.mkdir(parents=True, exist_ok=True)
    prelude = ("import json, sys\nfrom pathlib import Path\nimport numpy as np\nimport opensim\n"
               "work = Path(sys.argv[1])\narguments = json.loads(sys.argv[2])\n")
    done = subprocess.run([sys.executable, "-c", prelude + script, str(work), json.dumps(arguments)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    with np.load(work / "out.npz") as saved:
        return {name: saved[name] for name in saved.files}
