/* MUMPS's LDL^T ordering strategy ICNTL(12) for the MUMPS that CasADi's IPOPT calls (mumps_ordering.py).

   IPOPT 3.14 sets ICNTL(6), (7), (8) from its options but never ICNTL(12). This library defines dmumps_c and
   is built with the soname libcoinmumps.so.3: loaded before CasADi's IPOPT plugin, it is the library of that
   name libipopt is given, so its dmumps_c is the one IPOPT calls. It sets ICNTL(12) on every analysis (JOB 1,
   4, 6) and forwards each call to the real dmumps_c of the library named to mumps_ordering_bind. It also counts the analyses and the factorisations (JOB 2) and adds up the
   factorisations' processor and wall-clock time, so that a caller can see that it is in the path and what
   a factorisation costs.

   Only the leading members of DMUMPS_STRUC_C are read (sym, par, job, comm_fortran, icntl[60]): their layout
   is that of every MUMPS 4.x and 5.x dmumps_c.h with 32-bit MUMPS_INT. */

#define _GNU_SOURCE
#include <dlfcn.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

typedef struct {
    int32_t sym, par, job, comm_fortran;
    int32_t icntl[60];
} dmumps_head;

typedef void (*dmumps_entry)(void *);

static dmumps_entry real_dmumps_c = 0;
static int32_t ordering_strategy = 0;  /* ICNTL(12) given to each analysis; 0 leaves the caller's value */
static int64_t analyses_seen = 0, analyses_set = 0, factorizations = 0;
static double factorization_cpu_s = 0.0, factorization_wall_s = 0.0;

static double seconds(clockid_t clock)
{
    struct timespec t;
    clock_gettime(clock, &t);
    return (double) t.tv_sec + 1e-9 * (double) t.tv_nsec;
}

/* Bind to the real dmumps_c in `library` (a path): 0 on success, -1 if the library cannot be opened, -2 if it
   has no dmumps_c, -3 if that dmumps_c is this library's own. */
int mumps_ordering_bind(const char *library)
{
    void *handle = dlopen(library, RTLD_NOW | RTLD_LOCAL);
    if (!handle) return -1;
    dmumps_entry found = (dmumps_entry) dlsym(handle, "dmumps_c");
    if (!found) return -2;
    Dl_info mine, theirs;
    if (dladdr((void *) &mumps_ordering_bind, &mine) && dladdr((void *) found, &theirs)
        && mine.dli_fbase == theirs.dli_fbase) return -3;
    real_dmumps_c = found;
    return 0;
}

/* The ICNTL(12) that later analyses get (0: the caller's own); returns the previous one. */
int32_t mumps_ordering_set(int32_t strategy)
{
    int32_t previous = ordering_strategy;
    ordering_strategy = strategy;
    return previous;
}

/* counts[0..2]: analyses seen, analyses given ICNTL(12), factorisations; times[0..1]: the factorisations'
   processor and wall-clock seconds. */
void mumps_ordering_counts(int64_t *counts, double *times)
{
    counts[0] = analyses_seen;
    counts[1] = analyses_set;
    counts[2] = factorizations;
    times[0] = factorization_cpu_s;
    times[1] = factorization_wall_s;
}

void dmumps_c(void *id)
{
    dmumps_head *head = (dmumps_head *) id;
    int32_t job = head->job;
    if (!real_dmumps_c) {
        fputs("mumps_ordering: dmumps_c called before mumps_ordering_bind\n", stderr);
        abort();
    }
    if (job == 1 || job == 4 || job == 6) {
        analyses_seen++;
        if (ordering_strategy != 0 && head->sym == 2) {
            head->icntl[11] = ordering_strategy;
            analyses_set++;
        }
    }
    if (job == 2) {
        double cpu = seconds(CLOCK_PROCESS_CPUTIME_ID), wall = seconds(CLOCK_MONOTONIC);
        real_dmumps_c(id);
        factorization_cpu_s += seconds(CLOCK_PROCESS_CPUTIME_ID) - cpu;
        factorization_wall_s += seconds(CLOCK_MONOTONIC) - wall;
        factorizations++;
        return;
    }
    real_dmumps_c(id);
}
