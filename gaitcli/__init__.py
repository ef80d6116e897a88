"""gaitcli: gait-lab processing from C3D trials to joint moments, muscle forces and predictive gait."""

import os as _os

# One BLAS/OpenMP thread unless the user says otherwise (set before numpy and CasADi load their OpenBLAS):
# with more, IPOPT's MUMPS factorisations are not bit-reproducible and a prediction rerun can end in another
# local optimum (docs/decisions.md, "One BLAS/OpenMP thread per process"); batches run one process per core.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    _os.environ.setdefault(_var, "1")

__version__ = "0.1.0"
