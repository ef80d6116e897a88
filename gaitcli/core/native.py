"""The native libraries under IPOPT: glibc's allocator and the BLAS that MUMPS factorises with.

Every optimisation of gaitcli (the muscle problems, the predictions) spends most of its time in MUMPS's
factorisations of the KKT system. On Linux x86-64 two things of the process slow them that are not the
problem's (``benchmarks/README.md``, "The solvers' native libraries"):

* glibc hands MUMPS's workspace (over its 32 MB ``mmap`` threshold) back to the system after every
  factorisation and maps it afresh for the next, zero-filled: 10 % of a prediction's time in page faults.
  :func:`prepare_solvers` raises the threshold (``mallopt``), so the freed workspace stays in the heap.
* CasADi's wheels link MUMPS to their own OpenBLAS, built for the Core 2 (no AVX kernels). SciPy, a
  dependency, ships a current OpenBLAS for every x86-64 (its symbols prefixed ``scipy_``). Where a C compiler
  is present, :func:`prepare_solvers` builds once, in the user's cache folder, a library that takes the place
  of CasADi's (the same soname, ``libcasadi-tp-openblas.so.0``) and passes each BLAS and LAPACK routine on to
  SciPy's, and loads it before CasADi loads its IPOPT plugin, which then binds to it.

Both change no result beyond round-off. ``GAITCLI_NATIVE=casadi`` in the environment leaves the process as
CasADi sets it up; without a compiler, on another system or machine, or once CasADi's own OpenBLAS is loaded,
nothing is changed either. :func:`solver_libraries` says what is in use.
"""

from __future__ import annotations

import ctypes
import functools
import hashlib
import os
import platform
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

#: the soname by which CasADi's plugins (MUMPS, IPOPT) ask for their BLAS and LAPACK
CASADI_BLAS_SONAME = "libcasadi-tp-openblas.so.0"
#: glibc's mallopt parameters (malloc.h) and the size under which freed memory stays in the heap
M_TRIM_THRESHOLD, M_MMAP_THRESHOLD = -1, -3
KEEP_BYTES = 1 << 30
#: the environment variable that turns both off (value ``casadi``)
SWITCH = "GAITCLI_NATIVE"


def cache_dir() -> Path:
    """The user's cache folder for gaitcli (``$XDG_CACHE_HOME/gaitcli``, else ``~/.cache/gaitcli``)."""
    root = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(root) / "gaitcli"


@functools.lru_cache(maxsize=1)
def prepare_solvers() -> tuple[str, ...]:
    """Tune this process for MUMPS once (module docstring); returns what was done, one phrase each."""
    if os.environ.get(SWITCH, "").strip().lower() == "casadi" or not sys.platform.startswith("linux"):
        return ()
    done = []
    libc = _libc()
    if libc is not None and libc.mallopt(M_MMAP_THRESHOLD, KEEP_BYTES) and libc.mallopt(M_TRIM_THRESHOLD,
                                                                                             KEEP_BYTES):
        done.append("glibc keeps freed solver workspace")
    blas = _load_scipy_blas()
    if blas:
        done.append(blas)
    return tuple(done)


def solver_libraries() -> str:
    """Which BLAS MUMPS binds to in this process: "SciPy's OpenBLAS", "CasADi's OpenBLAS" or "not loaded"."""
    loaded = _loaded_blas()
    if loaded is None:
        return "not loaded"
    return "SciPy's OpenBLAS" if loaded.is_relative_to(cache_dir().resolve()) else "CasADi's OpenBLAS"


def _libc():
    try:
        return ctypes.CDLL("libc.so.6")
    except OSError:
        return None


def _loaded_blas() -> Path | None:
    """The library this process has loaded under CasADi's BLAS soname (CasADi's own or ours), if any."""
    try:
        lines = Path("/proc/self/maps").read_text().splitlines()
    except OSError:
        return None
    return next((Path(line.split()[-1]) for line in lines
                 if line.split()[-1].startswith("/") and Path(line.split()[-1]).name.startswith(
                     "libcasadi-tp-openblas")), None)


def _load_scipy_blas() -> str:
    """Build (once) and load the library passing CasADi's BLAS calls to SciPy's OpenBLAS; "" where not."""
    if platform.machine() not in ("x86_64", "AMD64") or _loaded_blas() is not None:
        return ""
    scipy_blas, casadi_blas = _scipy_openblas(), _casadi_openblas()
    compiler, nm = shutil.which("cc") or shutil.which("gcc"), shutil.which("nm")
    if not (scipy_blas and casadi_blas and compiler and nm):
        return ""
    try:
        library = _built_library(scipy_blas, casadi_blas, compiler, nm)
        if library is None:
            return ""
        ctypes.CDLL(str(library), mode=ctypes.RTLD_GLOBAL)  # dlopen(3): a file it cannot load is an OSError
        threads = getattr(ctypes.CDLL(str(scipy_blas)), "scipy_openblas_set_num_threads", None)
        if threads is not None:
            threads(1)  # one thread: each worker process has a core of its own
    except (OSError, subprocess.SubprocessError):
        return ""
    return "SciPy's OpenBLAS under MUMPS"


def _scipy_openblas() -> Path | None:
    import scipy

    found = sorted((Path(scipy.__file__).parent.parent / "scipy.libs").glob("libscipy_openblas-*.so"))
    return found[0] if found else None


def _casadi_openblas() -> Path | None:
    import casadi

    path = Path(casadi.__file__).parent / CASADI_BLAS_SONAME
    return path if path.exists() else None


def _symbols(nm: str, *libraries: Path, defined: bool) -> set[str]:
    """The dynamic function symbols the ``libraries`` define (or, ``defined=False``, ask for), by one ``nm``."""
    flag = "--defined-only" if defined else "--undefined-only"
    out = subprocess.run([nm, "-D", flag, *map(str, libraries)], capture_output=True, text=True, timeout=120)
    if out.returncode != 0 and not out.stdout:
        raise subprocess.SubprocessError(out.stderr.strip())
    names = set()
    for line in out.stdout.splitlines():
        parts = line.split()
        if len(parts) >= 2 and (not defined or parts[-2] in ("T", "W")):
            names.add(parts[-1].split("@")[0])
    return names


def _built_library(scipy_blas: Path, casadi_blas: Path, compiler: str, nm: str) -> Path | None:
    """The forwarding library in the cache (built where absent), or None where SciPy's OpenBLAS lacks a routine
    that one of CasADi's libraries asks of its own."""
    import casadi

    stat = scipy_blas.stat()
    key = hashlib.sha256(f"{scipy_blas}|{stat.st_size}|{stat.st_mtime_ns}|{casadi.__version__}|1".encode())
    target = cache_dir() / "blas" / key.hexdigest()[:16] / CASADI_BLAS_SONAME
    digest = target.with_name("sha256")
    if target.exists() and digest.exists() and digest.read_text().strip() == _sha256(target):
        return target  # built here, and unchanged since: anything else is built again
    plugins = [p for p in casadi_blas.parent.glob("*.so*") if not p.is_symlink() and "openblas" not in p.name]
    provided = _symbols(nm, casadi_blas, defined=True)
    asked = _symbols(nm, *plugins, defined=False) & provided  # what every CasADi library asks of its own
    forwarded = {s[len("scipy_"):] for s in _symbols(nm, scipy_blas, defined=True) if s.startswith("scipy_")}
    if not asked or not asked <= forwarded:
        return None
    routines = sorted(provided & forwarded)
    source = [".text"] + [f".globl {r}\n.type {r},@function\n{r}: jmp scipy_{r}@PLT" for r in routines]
    source.append('.section .note.GNU-stack,"",@progbits')
    target.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=target.parent) as tmp:
        asm, built = Path(tmp) / "forward.S", Path(tmp) / CASADI_BLAS_SONAME
        asm.write_text("\n".join(source) + "\n")
        subprocess.run([compiler, "-shared", "-fPIC", "-o", str(built), str(asm), f"-Wl,-soname,{CASADI_BLAS_SONAME}",
                        str(scipy_blas), f"-Wl,-rpath,{scipy_blas.parent}"], capture_output=True, check=True,
                       timeout=120)
        os.replace(built, target)  # whole or not at all, as every output
        (Path(tmp) / "sha256").write_text(_sha256(target) + "\n")
        os.replace(Path(tmp) / "sha256", digest)
    return target


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()
