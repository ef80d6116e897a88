"""The ``gait`` command (console script and ``python -m gaitcli``): one BLAS/OpenMP thread unless the
environment says otherwise, set before numpy and CasADi load their OpenBLAS, then :func:`gaitcli.cli.main`.

Why one thread: with two, IPOPT's MUMPS factorisations are not bit-reproducible and a rerun of a prediction
can end in another local optimum (docs/decisions.md, "One BLAS/OpenMP thread per process"); batches and
studies run one process per core instead. Importing gaitcli as a library changes no environment variable.
"""

import os
import sys

#: the thread-count variables of OpenBLAS, OpenMP and MKL
THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def single_threaded_blas() -> None:
    """One thread for each of :data:`THREAD_VARIABLES` the environment does not set."""
    for name in THREAD_VARIABLES:
        os.environ.setdefault(name, "1")


def main() -> None:
    single_threaded_blas()
    from gaitcli.cli import main as cli_main

    sys.exit(cli_main())


if __name__ == "__main__":
    main()
