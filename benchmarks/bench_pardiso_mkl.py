"""Intel oneMKL's PARDISO under CasADi's IPOPT (``pardiso_mkl.c``) against MUMPS, on the default prediction.

Run from the repository root: ``python benchmarks/bench_pardiso_mkl.py --mkl PATH [--no-predictions]``, PATH
either PyPI's ``mkl`` wheel (``pip download mkl --no-deps -d DIR``) or a folder holding its ``libmkl_*.so.*``;
a C compiler builds the interface library. The script runs itself again with that folder on
``LD_LIBRARY_PATH`` (MKL finds its parts there). Prints:

* the default prediction's first KKT matrix (IPOPT dumps it, ``IPOPT_WRITE_MAT``), factorised by PARDISO with
  IPOPT's weighted matching and scaling and without: entries of the factor, MFlop, seconds of analysis and of
  factorisation, perturbed pivots, the residual max |K x − b| after the solve's own refinement, and the negative
  pivots against the constraint count IPOPT requires;
* the default prediction solved with MUMPS (the package's options), with PARDISO as IPOPT configures it
  (matching; a symbolic factorisation again only where the inertia is wrong), and with PARDISO without
  matching, perturbations 10⁻⁸ and IPOPT's ``perturb_always_cd``: iterations, solve seconds, convergence, J.

One core (``BENCH_CORE``, timing.py); asserts nothing. Nothing here is used by the package.
"""

from __future__ import annotations

import argparse
import ctypes
import dataclasses
import os
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

from timing import one_core, prediction_options

HERE = Path(__file__).resolve().parent
#: pardiso_mkl.c's settings: IPOPT's own (weighted matching and scaling, pivots perturbed by 10⁻¹²), or neither
#: matching nor scaling and pivots perturbed by 10⁻⁸ (MKL's default for symmetric indefinite matrices)
PARDISO_MODES = {"matching": {"PARDISO_MKL_MATCHING": "1", "PARDISO_MKL_PERTURBATION": "12"},
                 "no matching": {"PARDISO_MKL_MATCHING": "0", "PARDISO_MKL_PERTURBATION": "8"}}


def mkl_folder(path: Path, scratch: Path) -> Path:
    """The folder of MKL's libraries: ``path`` itself, or the wheel ``path``'s ``lib`` unpacked into ``scratch``."""
    if path.is_dir():
        return path
    with zipfile.ZipFile(path) as wheel:
        for name in wheel.namelist():
            if "/data/lib/libmkl_" in name:
                (scratch / Path(name).name).write_bytes(wheel.read(name))
    return scratch


def build(folder: Path, scratch: Path) -> Path:
    """``pardiso_mkl.c`` compiled against ``folder``'s libmkl_rt."""
    library = scratch / "libpardiso_mkl.so"
    subprocess.run(["cc", "-O2", "-shared", "-fPIC", "-o", str(library), str(HERE / "pardiso_mkl.c"),
                    f"-L{folder}", "-l:libmkl_rt.so.3", f"-Wl,-rpath,{folder}"], check=True)
    return library


def default_prediction(extra: dict) -> str:
    """The default prediction (``bench_predict.py``'s) with the IPOPT options ``extra``: one line."""
    import bench_predict

    from gaitcli.predict.stage import PredictConfig

    cfg, tracked, _ = bench_predict.tracking(dataclasses.replace(PredictConfig(), max_iterations=400))
    with prediction_options(extra):
        out = bench_predict.predict(cfg, tracked)
    r = out["result"]
    return f"{r.iterations:5d} {out['solve_s']:8.1f} {str(r.converged):>5} {r.objective:.10f}"


def first_kkt(library: Path, scratch: Path) -> tuple:
    """The default prediction's first search direction's KKT matrix and right-hand side as IPOPT hands them to
    PARDISO (one-based upper-triangle CSR), and the number of constraints (the negative pivots IPOPT requires)."""
    import bench_predict
    import numpy as np

    from gaitcli.predict.stage import PredictConfig

    cfg, tracked, _ = bench_predict.tracking(PredictConfig())
    os.environ.update({"IPOPT_WRITE_MAT": "1", "IPOPT_WRITE_PREFIX": str(scratch / "kkt")})
    try:
        with prediction_options({"ipopt.linear_solver": "pardiso", "ipopt.pardisolib": str(library),
                                 "ipopt.max_iter": 1}):
            constraints = bench_predict.predict(cfg, tracked)["result"].constraint_multipliers.size
    finally:
        del os.environ["IPOPT_WRITE_MAT"]
    # IPOPT numbers the files by factorisation and writes one at each solve: the first is the multipliers'
    # least-squares system, the next the first search direction's (after any factorisation of wrong inertia)
    lines = sorted(scratch.glob("kkt_000-*.iajaa"))[1].read_text().split()
    n, nnz = int(lines[0]), int(lines[1])
    ia = np.array(lines[2:3 + n], dtype=np.int32)
    ja = np.array(lines[3 + n:3 + n + nnz], dtype=np.int32)
    a = np.array(lines[3 + n + nnz:3 + n + 2 * nnz], dtype=float)
    b = np.array(lines[3 + n + 2 * nnz:3 + 2 * n + 2 * nnz], dtype=float)
    return ia, ja, a, b, constraints


def factorise(library: Path, ia, ja, a, b, constraints: int, mode: dict) -> str:
    """One analysis, factorisation and solve of the matrix by PARDISO in ``mode``: one line."""
    import numpy as np
    import scipy.sparse as sp

    os.environ.update(mode)
    lib = ctypes.CDLL(str(library))
    n = ia.size - 1
    pt, iparm = (ctypes.c_void_p * 64)(), (ctypes.c_int * 64)()
    dparm, error = (ctypes.c_double * 64)(), ctypes.c_int(0)
    mtype, one, zero = ctypes.c_int(-2), ctypes.c_int(1), ctypes.c_int(0)
    lib.pardisoinit(pt, ctypes.byref(mtype), ctypes.byref(zero), iparm, dparm, ctypes.byref(error))
    # IPOPT's settings as it makes them; -1 in [17] and [18]: report the factor's entries and MFlop
    for k, v in {0: 1, 1: 2, 5: 1, 9: 12, 10: 2, 12: 2, 17: -1, 18: -1, 20: 3}.items():
        iparm[k] = v
    x, rhs = np.zeros(n), b.copy()
    pointer = ctypes.POINTER

    def call(phase: int) -> float:
        began = time.process_time()
        lib.pardiso(pt, ctypes.byref(one), ctypes.byref(one), ctypes.byref(mtype), ctypes.byref(ctypes.c_int(phase)),
                    ctypes.byref(ctypes.c_int(n)), a.ctypes.data_as(pointer(ctypes.c_double)),
                    ia.ctypes.data_as(pointer(ctypes.c_int)), ja.ctypes.data_as(pointer(ctypes.c_int)),
                    ctypes.byref(zero), ctypes.byref(one), iparm, ctypes.byref(zero),
                    rhs.ctypes.data_as(pointer(ctypes.c_double)), x.ctypes.data_as(pointer(ctypes.c_double)),
                    ctypes.byref(error), dparm)
        if error.value:
            raise SystemExit(f"PARDISO phase {phase}: error {error.value}")
        return time.process_time() - began

    analysis, factor = call(11), call(22)
    call(33)
    upper = sp.csr_matrix((a, ja - 1, ia - 1), shape=(n, n))
    residual = np.abs((upper + sp.triu(upper, 1).T) @ rhs - b).max()
    call(-1)
    return (f"{iparm[17]:>10,} {iparm[18]:>7,} {analysis:10.3f} {factor:8.3f} {iparm[13]:9,} {residual:9.1e} "
            f"{iparm[22]:>6,} of {constraints:,}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mkl", type=Path, required=True, help="PyPI's mkl wheel, or a folder of its libmkl_*.so.*")
    ap.add_argument("--no-predictions", action="store_true", help="the KKT matrix only")
    ap.add_argument("--folder", type=Path, help=argparse.SUPPRESS)  # the restarted process's MKL folder
    args = ap.parse_args()
    if args.folder is None:
        with tempfile.TemporaryDirectory(prefix="pardiso_mkl_") as scratch:
            folder = mkl_folder(args.mkl.resolve(), Path(scratch))
            env = {**os.environ, "LD_LIBRARY_PATH": f"{folder}:{os.environ.get('LD_LIBRARY_PATH', '')}"}
            raise SystemExit(subprocess.run([sys.executable, *sys.argv, "--folder", str(folder)], env=env).returncode)
    one_core()
    with tempfile.TemporaryDirectory(prefix="pardiso_mkl_") as scratch:
        measure(args, Path(scratch))


def measure(args, scratch: Path) -> None:
    """The matrix's factorisations and the predictions (module docstring), the library built in ``scratch``."""
    library = build(args.folder, scratch)
    ia, ja, a, b, constraints = first_kkt(library, scratch)
    print(f"first KKT matrix: order {ia.size - 1:,}, {ja.size:,} entries in its upper triangle")
    print(f"{'PARDISO':<12} {'factor nnz':>10} {'MFlop':>7} {'analysis s':>10} {'factor s':>8} {'perturbed':>9} "
          f"{'residual':>9} negative pivots")
    for name, mode in PARDISO_MODES.items():
        print(f"{name:<12} {factorise(library, ia, ja, a, b, constraints, mode)}", flush=True)
    if args.no_predictions:
        return
    print(f"\n{'default prediction':<42} {'iter':>5} {'solve s':>8} {'conv':>5} J")
    print(f"{'MUMPS (the package)':<42} {default_prediction({})}", flush=True)
    pardiso = {"ipopt.linear_solver": "pardiso", "ipopt.pardisolib": str(library)}
    os.environ.update(PARDISO_MODES["matching"])
    print(f"{'PARDISO, matching':<42} "
          f"{default_prediction({**pardiso, 'ipopt.pardiso_redo_symbolic_fact_only_if_inertia_wrong': 'yes'})}",
          flush=True)
    os.environ.update(PARDISO_MODES["no matching"])
    print(f"{'PARDISO, no matching, perturb_always_cd':<42} "
          f"{default_prediction({**pardiso, 'ipopt.perturb_always_cd': 'yes'})}", flush=True)


if __name__ == "__main__":
    main()
