/* pardiso-project's interface, the one IPOPT 3.14 loads at run time (linear_solver pardiso, pardisolib), on
   Intel oneMKL's PARDISO (libmkl_rt.so.3 of PyPI's `mkl` wheel): bench_pardiso_mkl.py builds and loads it.

   The two libraries share the routine names but not their arguments: pardiso-project's pardisoinit takes
   (pt, mtype, solver, iparm, dparm, error) and its pardiso a trailing dparm; MKL's take (pt, mtype, iparm) and
   no dparm. Their iparm also differ where IPOPT sets them (PardisoSolverInterface::InitializeImpl): IPOPT's
   processor count in iparm[2] is reserved in MKL, its scaling 2 and matching 2 are MKL's 1 (MKL's
   matching is on or off), its pivoting 3 (pardiso-project's "1x1 and 2x2 with accuracy checks") is MKL's 1
   (Bunch-Kaufman 1x1 and 2x2), its parallel solve and supernode size (iparm[24], [29]) are MKL's sequential
   solve and an output. Both report the same outputs in the same places: refinement steps [6], perturbed
   pivots [13], entries of the factor [17] and MFlop [18] (when asked for with -1), positive and negative pivots
   [21], [22].

   The environment chooses what the measurement varies: PARDISO_MKL_MATCHING (0 or 1, default IPOPT's),
   scaling with it; PARDISO_MKL_PERTURBATION (the pivot perturbation 10^-k, default IPOPT's 12). */

#include <stdlib.h>
#include <string.h>

typedef int ipfint;

extern void PARDISO(void **pt, const ipfint *maxfct, const ipfint *mnum, const ipfint *mtype, const ipfint *phase,
                    const ipfint *n, const double *a, const ipfint *ia, const ipfint *ja, ipfint *perm,
                    const ipfint *nrhs, ipfint *iparm, const ipfint *msglvl, double *b, double *x, ipfint *error);
extern void PARDISOINIT(void *pt, const ipfint *mtype, ipfint *iparm);
extern int MKL_Set_Threading_Layer(int);
extern int MKL_Set_Interface_Layer(int);

static int setting(const char *name, int fallback) {
    const char *value = getenv(name);
    return value && *value ? atoi(value) : fallback;
}

/* IPOPT asks for this symbol to check that it was given pardiso-project >= 4. */
void pardiso_ipopt_newinterface(void) {}

void pardisoinit(void *pt, const ipfint *mtype, const ipfint *solver, ipfint *iparm, double *dparm, ipfint *error) {
    (void)solver;
    (void)dparm;
    MKL_Set_Interface_Layer(0); /* LP64: 32-bit integers, as IPOPT's */
    MKL_Set_Threading_Layer(1); /* sequential: one core, as MUMPS here */
    memset(pt, 0, 64 * sizeof(void *)); /* IPOPT clears 64 bytes of the 64 handles */
    PARDISOINIT(pt, mtype, iparm);
    *error = 0;
}

void pardiso(void **pt, const ipfint *maxfct, const ipfint *mnum, const ipfint *mtype, const ipfint *phase,
             const ipfint *n, const double *a, const ipfint *ia, const ipfint *ja, ipfint *perm, const ipfint *nrhs,
             ipfint *iparm, const ipfint *msglvl, double *b, double *x, ipfint *error, double *dparm) {
    static const int outputs[] = {6, 13, 14, 15, 16, 17, 18, 21, 22};
    ipfint mkl[64];
    (void)dparm;
    memcpy(mkl, iparm, sizeof mkl);
    int matching = setting("PARDISO_MKL_MATCHING", iparm[12] ? 1 : 0);
    mkl[2] = 0;
    mkl[9] = setting("PARDISO_MKL_PERTURBATION", iparm[9]);
    mkl[10] = matching;
    mkl[12] = matching;
    mkl[20] = 1;
    mkl[23] = 0;
    mkl[24] = 0;
    mkl[27] = 0; /* double precision */
    mkl[28] = 0;
    mkl[29] = 0;
    mkl[34] = 0; /* one-based ia, ja */
    PARDISO(pt, maxfct, mnum, mtype, phase, n, a, ia, ja, perm, nrhs, mkl, msglvl, b, x, error);
    for (size_t k = 0; k < sizeof outputs / sizeof *outputs; ++k)
        iparm[outputs[k]] = mkl[outputs[k]];
}
