"""Prediction studies (``gait predict --study``) beside the dissertation's Tables 5.2 and 5.3, with the wall time.

Run from the repository root: ``python benchmarks/bench_studies.py [--study prostheses foot_mass] [--out DIR]
[--workers N] [--force]``. Runs each bundled study (``pipelines/study_*.yaml``) through
``run.studies.run_study`` — what the command runs — into DIR (default ``/tmp/gaitcli_bench_studies``); a case
already computed there with the same inputs is read back, so a second run prints the tables at once (``--force``
solves everything again). Prints the whole study's wall time against the 30-minute target and the
dissertation's "about a day per case", our J, Et, Jdev beside the dissertation's for every case, and whether
each ordering the issue names holds, with the numbers. Asserts nothing.

Orderings (Diss. 5.3.2–5.3.3, as Tables 5.2–5.3 show them): Table 5.2 — with +2 kg per foot J and Jdev rise for
all four weight sets and Et for a)–c); Table 5.3 at 1.00 and 1.33 m/s, weights b) and d) — Flex has the lowest Et
and the highest Jdev of the three feet; in every case the optimal device has a lower J and Jdev than all three
feet; its τ_s at −0.1 rad within ±40 % of Flex's 30.9 N·m and at −0.2 rad between Flex's 67.1 and Seattle's
131.1 N·m.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from timing import solver_libraries

from gaitcli.resources import study_file
from gaitcli.run.config import configure
from gaitcli.run.studies import run_study

#: Table 5.2: weight set → (normal J, Et, Jdev), (+2 kg J, Et, Jdev)
TABLE_5_2 = {"a": ((14.17, 468.8, 10.04), (22.00, 547.2, 17.46)), "b": ((14.22, 432.7, 11.86), (18.25, 489.6, 18.41)),
             "c": ((10.57, 384.1, 11.82), (14.07, 449.1, 18.32)), "d": ((8.49, 333.9, 14.33), (10.36, 316.7, 26.41))}
#: Table 5.3: (speed, weight set, condition) → (J, Et, Jdev); ∗ entries (local minima) included as printed
TABLE_5_3 = {}
for _w, _rows in {
    "a": {"sach": ((15.97, 467.7, 12.05), (23.79, 586.8, 18.56)),
          "seattle": ((15.05, 437.2, 11.07), (25.29, 520.8, 21.00)),
          "flex": ((21.96, 373.2, 18.91), (29.71, 489.7, 25.83)),
          "optimal": ((9.87, 294.3, 7.31), (12.46, 352.0, 9.44)),
          "normal": ((6.94, 375.2, 3.41), (8.57, 439.0, 4.40))},
    "b": {"sach": ((12.18, 350.6, 11.85), (19.78, 550.7, 19.34)),
          "seattle": ((11.93, 362.0, 11.60), (15.00, 453.2, 14.16)),
          "flex": ((17.46, 341.7, 20.31), (20.85, 417.3, 23.95)),
          "optimal": ((9.99, 317.9, 9.12), (11.15, 323.5, 10.88)),
          "normal": ((8.01, 310.6, 4.36), (8.51, 401.4, 5.13))},
    "c": {"sach": ((10.75, 367.0, 13.19), (16.48, 512.2, 21.54)),
          "seattle": ((10.28, 350.7, 12.21), (14.30, 425.8, 20.16)),
          "flex": ((12.43, 256.1, 21.83), (14.89, 334.7, 24.82)),
          "optimal": ((6.39, 188.7, 8.87), (10.37, 289.5, 15.42)),
          "normal": ((6.39, 270.5, 5.59), (7.78, 306.3, 7.77))},
    "d": {"sach": ((10.37, 391.9, 19.36), (13.01, 447.9, 27.76)),
          "seattle": ((8.11, 290.2, 17.82), (10.54, 428.0, 24.61)),
          "flex": ((7.68, 191.3, 24.13), (10.03, 286.2, 27.90)),
          "optimal": ((6.08, 199.7, 14.68), (6.44, 218.5, 14.56)),
          "normal": ((5.42, 208.4, 9.66), (6.76, 229.1, 15.36))}}.items():
    for _condition, (_slow, _fast) in _rows.items():
        TABLE_5_3[(1.00, _w, _condition)], TABLE_5_3[(1.33, _w, _condition)] = _slow, _fast
TARGET_S = 30 * 60
DISSERTATION_S_PER_CASE = 24 * 3600  # "about a day per case"
FEET = ("sach", "seattle", "flex")


def _check(label: str, holds: bool, numbers: str) -> None:
    print(f"  [{'holds' if holds else 'FAILS'}] {label}: {numbers}")


def _print_table(rows, dissertation) -> None:
    print(f"  {'case':<22} {'J':>7} {'Et':>7} {'Jdev':>6} | {'diss. J':>7} {'Et':>7} {'Jdev':>6} | "
          "iters  wall s  status")
    for r in rows:
        d = dissertation(r)
        theirs = f"{d[0]:>7.2f} {d[1]:>7.1f} {d[2]:>6.2f}" if d else f"{'–':>7} {'–':>7} {'–':>6}"
        status = ("ok" if r["converged"] else "NOT CONVERGED") + (", reused" if r["reused"] else "")
        print(f"  {r['case']:<22} {r['objective']:>7.2f} {r['cost_of_transport_J_per_m']:>7.1f} "
              f"{r['deviation']:>6.2f} | {theirs} | {r['iterations']:>5} {r['wall_time_s']:>7.0f}  {status}")


def foot_mass(rows) -> None:
    by = {(r["weights"], r["condition"]): r for r in rows}
    _print_table(rows, lambda r: TABLE_5_2[r["weights"]][0 if r["condition"] == "normal" else 1])
    for w in "abcd":
        normal, heavy = by[(w, "normal")], by[(w, "foot_mass")]
        for key, name in (("objective", "J"), ("deviation", "Jdev")) + ((("cost_of_transport_J_per_m", "Et"),)
                                                                          if w in "abc" else ()):
            _check(f"+2 kg raises {name}, weights {w}", heavy[key] > normal[key],
                   f"{normal[key]:.2f} → {heavy[key]:.2f}")


def prostheses(rows) -> None:
    by = {(r["speed_m_s"], r["weights"], r["condition"]): r for r in rows}
    _print_table(rows, lambda r: TABLE_5_3.get((round(r["speed_m_s"], 2), r["weights"], r["condition"])))
    for speed in sorted({r["speed_m_s"] for r in rows}):
        for w in sorted({r["weights"] for r in rows}):
            feet = {f: by[(speed, w, f)] for f in FEET}
            optimal = by.get((speed, w, "optimal"))
            case = f"{speed:.2f} m/s, weights {w}"
            if w in ("b", "d"):
                et = {f: feet[f]["cost_of_transport_J_per_m"] for f in FEET}
                jdev = {f: feet[f]["deviation"] for f in FEET}
                _check(f"Flex has the lowest Et, {case}", min(et, key=et.get) == "flex",
                       ", ".join(f"{f} {v:.1f}" for f, v in et.items()))
                _check(f"Flex has the highest Jdev, {case}", max(jdev, key=jdev.get) == "flex",
                       ", ".join(f"{f} {v:.2f}" for f, v in jdev.items()))
            if optimal is not None:
                for key, name in (("objective", "J"), ("deviation", "Jdev")):
                    _check(f"the optimal device has the lowest {name}, {case}",
                           all(optimal[key] < feet[f][key] for f in FEET),
                           f"optimal {optimal[key]:.2f}; " + ", ".join(f"{f} {feet[f][key]:.2f}" for f in FEET))
                t1, t2 = optimal["tau_s_at_minus_0.1_rad_Nm"], optimal["tau_s_at_minus_0.2_rad_Nm"]
                _check(f"optimal τ_s(−0.1) within ±40 % of Flex's 30.9 N·m, {case}", 18.5 <= t1 <= 43.3,
                       f"{t1:.1f} N·m")
                _check(f"optimal τ_s(−0.2) between Flex's 67.1 and Seattle's 131.1 N·m, {case}", 67.1 <= t2 <= 131.1,
                       f"{t2:.1f} N·m")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--study", nargs="+", default=["prostheses", "foot_mass"], choices=["prostheses", "foot_mass"])
    parser.add_argument("--out", type=Path, default=Path("/tmp/gaitcli_bench_studies"))
    parser.add_argument("--workers", type=int, default=None)
    parser.add_argument("--force", action="store_true")
    args = parser.parse_args()
    for name in args.study:
        start = time.perf_counter()
        rows, folder = run_study(None, study_file(name), configure(None), out=args.out / name,
                                 workers_count=args.workers, force=args.force)
        wall = time.perf_counter() - start
        solved = [r for r in rows if not r["reused"]]
        print(f"\nstudy {name}: {len(rows)} cases ({len(solved)} solved, {len(rows) - len(solved)} reused) in "
              f"{wall:.0f} s wall; target {TARGET_S} s (ratio {wall / TARGET_S:.2f}); the dissertation about "
              f"{DISSERTATION_S_PER_CASE * len(rows) / 3600:.0f} h ({DISSERTATION_S_PER_CASE * len(rows) / wall:.0f}× "
              f"ours); {sum(not r['converged'] for r in rows)} unconverged; {folder / 'study.csv'}")
        if solved:
            iterations = sum(r["iterations"] for r in solved)
            print(f"  per solved case: {sum(r['wall_time_s'] for r in solved) / len(solved):.0f} s in a worker, "
                  f"{iterations / len(solved):.0f} IPOPT iterations; {sum(r['problems_built'] for r in solved)} "
                  f"problems built for {len(solved)} cases, {sum(r['build_time_s'] for r in solved):.0f} s of "
                  f"building in all")
        (prostheses if name == "prostheses" else foot_mass)(rows)
    print(solver_libraries() + " (the workers prepare themselves the same way)")


if __name__ == "__main__":
    main()
