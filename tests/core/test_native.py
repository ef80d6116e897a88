"""The native libraries under IPOPT (core/native.py): the same solutions with SciPy's OpenBLAS as with CasADi's,
the switch that leaves CasADi's alone, and the cached forwarding library built again when it is not what was
built. Each case runs in a fresh process: which BLAS a process binds to is decided once, when CasADi first loads
its IPOPT plugin."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from gaitcli.core import native

#: a small NLP whose KKT factorisations go through MUMPS's dense kernels: a chain of 300 masses hanging between
#: two points (the positions minimise potential energy, each link no longer than its rest length), solved with
#: the project's IPOPT options; prints the solution, what prepare_solvers did and which BLAS MUMPS bound to
CHAIN = """
import json, sys
import casadi as ca, numpy as np
from gaitcli.core import ipopt, native
n = 300
x, z = ca.MX.sym("x", n), ca.MX.sym("z", n)
px, pz = ca.vertcat(0, x, 2), ca.vertcat(0, z, 0)
links = (px[1:] - px[:-1]) ** 2 + (pz[1:] - pz[:-1]) ** 2
solver = ipopt.build_solver("chain", {"x": ca.vertcat(x, z), "f": ca.sum1(z), "g": links},
                            ipopt.options(tol=1e-10, max_iter=500))
out = solver(x0=np.r_[np.linspace(0, 2, n + 2)[1:-1], -0.1 * np.ones(n)], lbg=0, ubg=(3.0 / (n + 1)) ** 2)
print(json.dumps({"w": np.array(out["x"]).ravel().tolist(), "done": native.prepare_solvers(),
                  "blas": native.solver_libraries(), "status": solver.stats()["return_status"]}))
"""


def _run(tmp_path: Path, **env) -> dict:
    environment = {**os.environ, "XDG_CACHE_HOME": str(tmp_path / "cache"), **env}
    run = subprocess.run([sys.executable, "-c", CHAIN], capture_output=True, text=True, env=environment, timeout=300)
    assert run.returncode == 0, run.stderr
    return json.loads(run.stdout.strip().splitlines()[-1])


def _can_build() -> bool:
    return sys.platform.startswith("linux") and bool(shutil.which("nm")) and bool(shutil.which("cc") or
                                                                                 shutil.which("gcc"))


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("native")
    return tmp, _run(tmp, GAITCLI_NATIVE="casadi"), _run(tmp)


def test_the_solution_is_the_same_with_either_blas(runs):
    """CasADi's own OpenBLAS (``GAITCLI_NATIVE=casadi``) and SciPy's give the same optimum to round-off."""
    _, own, prepared = runs
    assert own["status"] == prepared["status"] == "Solve_Succeeded"
    np.testing.assert_allclose(prepared["w"], own["w"], rtol=0, atol=1e-8)
    assert own["done"] == [] and own["blas"] == "CasADi's OpenBLAS"
    if _can_build():
        assert prepared["done"] == ["glibc keeps freed solver workspace", "SciPy's OpenBLAS under MUMPS"]
        assert prepared["blas"] == "SciPy's OpenBLAS"


def test_a_cached_library_that_changed_is_built_again(runs):
    """A forwarding library in the cache that is not the one built there (truncated, replaced) is never loaded:
    it is built again, and the solve binds to the new one."""
    tmp, own, _ = runs
    if not _can_build():
        pytest.skip("needs Linux with a C compiler and nm")
    (library,) = (tmp / "cache" / "gaitcli" / "blas").glob(f"*/{native.CASADI_BLAS_SONAME}")
    whole = library.read_bytes()
    library.write_bytes(whole[:4096])
    again = _run(tmp)
    assert again["blas"] == "SciPy's OpenBLAS"
    assert library.read_bytes() == whole
    np.testing.assert_allclose(again["w"], own["w"], rtol=0, atol=1e-8)


def test_a_routine_scipy_lacks_leaves_casadis_blas(monkeypatch, tmp_path):
    """Where SciPy's OpenBLAS lacks a routine some CasADi library asks of its own, nothing is built."""
    fake = {"casadi": {"dgemm_", "dgemmt_", "dtrsm_"}, "scipy": {"scipy_dgemm_", "scipy_dtrsm_"},
            "plugin": {"dgemm_", "dgemmt_"}}

    def symbols(nm, *libraries, defined):
        name = libraries[0].name
        return fake["casadi" if "openblas" in name and "scipy" not in name else "scipy" if "scipy" in name
                    else "plugin"]

    monkeypatch.setattr(native, "_symbols", symbols)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    (tmp_path / "casadi").mkdir()
    plugin, casadi_blas, scipy_blas = (tmp_path / "casadi" / n for n in ("libcoinmumps.so.3", native.CASADI_BLAS_SONAME,
                                                                          "libscipy_openblas-x.so"))
    for path in (plugin, casadi_blas, scipy_blas):
        path.write_bytes(b"")
    assert native._built_library(scipy_blas, casadi_blas, "cc", "nm") is None
    assert not (tmp_path / "gaitcli").exists()  # nothing written to the cache
