"""MUMPS's LDLᵀ ordering strategy ICNTL(12) for CasADi's IPOPT, which does not expose it: the loader of
``mumps_ordering.c`` for ``bench_mumps_ordering.py`` (measured, not kept: benchmarks/README.md, "Prediction").

IPOPT factorises its KKT matrix with MUMPS (``libcoinmumps.so.3`` beside CasADi's ``libipopt.so.3``). MUMPS's
compressed ordering (ICNTL(12) = 2) orders each zero-diagonal constraint row together with a variable it is
matched to (ICNTL(6)'s maximum matching), so the pair can be a 2×2 pivot in one front instead of a delayed one.
``mumps_ordering.c`` is a library that defines ``dmumps_c``, sets ICNTL(12) on each analysis and forwards every
call to MUMPS's own ``dmumps_c``. CasADi opens its IPOPT plugin with the plugin's own dependencies searched
first (``RTLD_DEEPBIND``), so neither ``LD_PRELOAD`` nor a library loaded with ``RTLD_GLOBAL`` reaches
``libipopt``: the library is built with the soname ``libcoinmumps.so.3`` instead, and once it is loaded the
dynamic linker gives it to ``libipopt`` in place of the file of that name (a needed library is matched by the
sonames already loaded). It must therefore be loaded before the process's first IPOPT solver (:func:`load`).

:func:`load` compiles the source once with the system C compiler into the user's cache folder, keyed by the
source's hash and CasADi's version. Where that is impossible (no compiler, no CasADi MUMPS library, not Linux,
IPOPT already loaded) it returns ``None`` with the reason.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import shutil
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

#: the C source compiled by :func:`build`
SOURCE = Path(__file__).with_suffix(".c")
#: MUMPS's library as CasADi's IPOPT names it (its DT_NEEDED entry), which the built library's soname matches
MUMPS_SONAME = "libcoinmumps.so.3"
#: ICNTL(12)'s values: 0 MUMPS's automatic choice, 1 the usual ordering, 2 the compressed graph's
COMPRESSED = 2


@dataclass(frozen=True)
class FactorizationCounts:
    """What the library has seen since it was loaded: ``analyses`` (MUMPS JOB 1, 4, 6), ``analyses_set`` (those
    given ICNTL(12)), ``factorizations`` (JOB 2) and their processor and wall-clock seconds."""

    analyses: int
    analyses_set: int
    factorizations: int
    factorization_cpu_s: float
    factorization_wall_s: float


class MumpsOrdering:
    """The loaded library: :meth:`set` chooses the ICNTL(12) of later analyses, :meth:`counts` reads its counters."""

    def __init__(self, library: ctypes.CDLL, path: Path):
        self._library, self.path = library, path
        library.mumps_ordering_set.argtypes = [ctypes.c_int32]
        library.mumps_ordering_set.restype = ctypes.c_int32
        library.mumps_ordering_counts.argtypes = [ctypes.POINTER(ctypes.c_int64), ctypes.POINTER(ctypes.c_double)]
        library.mumps_ordering_counts.restype = None

    def set(self, strategy: int) -> int:
        """ICNTL(12) for the analyses from now on (0: leave IPOPT's, i.e. MUMPS's default); the previous one."""
        return int(self._library.mumps_ordering_set(int(strategy)))

    def counts(self) -> FactorizationCounts:
        """The library's counters (:class:`FactorizationCounts`)."""
        counts, times = (ctypes.c_int64 * 3)(), (ctypes.c_double * 2)()
        self._library.mumps_ordering_counts(counts, times)
        return FactorizationCounts(*(int(c) for c in counts), *(float(t) for t in times))


def casadi_mumps() -> Path | None:
    """The MUMPS library that CasADi's IPOPT links, or None (not this platform's layout)."""
    try:
        import casadi
    except ImportError:
        return None
    path = Path(casadi.__file__).parent / MUMPS_SONAME
    return path if path.is_file() else None


def cache_folder() -> Path:
    """Where built libraries are kept: ``$XDG_CACHE_HOME/gaitcli`` (default ``~/.cache/gaitcli``)."""
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "gaitcli"


def library_name() -> str:
    """The built library's file name: the source's hash and CasADi's version in it."""
    import casadi

    digest = hashlib.sha256(SOURCE.read_bytes()).hexdigest()[:16]
    return f"mumps_ordering-{digest}-casadi{casadi.__version__}.so"


def build(folder: Path, compiler: str | None = None) -> Path:
    """Compile :data:`SOURCE` into ``folder`` (kept: a second call finds it) with ``compiler`` (default ``$CC``
    or ``cc``); raises ``OSError`` where there is no compiler, ``subprocess.CalledProcessError`` where it fails."""
    target = folder / library_name()
    if target.is_file():
        return target
    compiler = compiler or os.environ.get("CC") or "cc"
    if shutil.which(compiler) is None:
        raise OSError(f"no C compiler {compiler!r}")
    folder.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=folder) as work:
        built = Path(work) / target.name
        subprocess.run([compiler, "-O2", "-shared", "-fPIC", f"-Wl,-soname,{MUMPS_SONAME}", "-o", str(built),
                        str(SOURCE), "-ldl"], check=True, capture_output=True, timeout=120)
        os.replace(built, target)  # atomic: a concurrent build of the same source wins or loses whole
    return target


def _ipopt_loaded() -> bool:
    """Whether this process has already mapped MUMPS's library (an IPOPT solver was made)."""
    try:
        maps = Path("/proc/self/maps").read_text()
    except OSError:
        return False
    return any(line.rstrip().endswith("/" + MUMPS_SONAME) and "mumps_ordering" not in line
               for line in maps.splitlines())


_loaded: MumpsOrdering | None = None


def loaded() -> MumpsOrdering | None:
    """The library :func:`load` loaded in this process, or None."""
    return _loaded


def load(strategy: int = COMPRESSED, *, folder: Path | None = None,
         compiler: str | None = None) -> tuple[MumpsOrdering | None, str]:
    """Build (once) and load the library, its ICNTL(12) set to ``strategy``: (the library or None, why not).

    Loaded once per process; a later call only sets ``strategy``. None where the platform is not Linux,
    CasADi has no MUMPS library of that name, IPOPT already runs in this process, or the compiler is missing
    or fails; IPOPT then runs with MUMPS's own ordering.
    """
    global _loaded
    if _loaded is not None:
        _loaded.set(strategy)
        return _loaded, ""
    if not sys.platform.startswith("linux"):
        return None, f"not on Linux ({sys.platform})"
    mumps = casadi_mumps()
    if mumps is None:
        return None, f"CasADi has no {MUMPS_SONAME}"
    if _ipopt_loaded():
        return None, "IPOPT was loaded before the ordering library"
    try:
        path = build(folder or cache_folder(), compiler)
    except (OSError, subprocess.SubprocessError) as error:
        detail = getattr(error, "stderr", b"") or b""
        return None, f"could not compile {SOURCE.name}: {error} {detail.decode(errors='replace').strip()}".strip()
    library = ctypes.CDLL(str(path), mode=os.RTLD_LOCAL)
    library.mumps_ordering_bind.argtypes = [ctypes.c_char_p]
    bound = library.mumps_ordering_bind(str(mumps).encode())
    if bound != 0:
        import _ctypes

        _ctypes.dlclose(library._handle)  # not left where IPOPT would find a dmumps_c bound to nothing
        return None, f"{path.name} could not bind to {mumps} (code {bound})"
    _loaded = MumpsOrdering(library, path)
    _loaded.set(strategy)
    return _loaded, ""
