"""Sensitivity of the EID optimum to round-off-sized changes of its input (normal sample, right leg).

Run from the repository root:
``python benchmarks/bench_eid_sensitivity.py [-K 6] [--step 1e-15] [--side r] [--nodes 50]``.

The filter and idyn stages run once on a copy of ``sample_trials/normal``; the leg's motion is read
back from idyn.h5 (``stage("idyn").read`` → ``SagittalExport``, ``muscles.interval.prepare_leg`` on
the periodic stride). EID (``muscles.stage.run_muscles``, method "eid", 50 nodes, default options)
then runs on: the unperturbed motion, twice (the same input must give the same result: this shows the
solve is deterministic, so any spread below comes from the input); and the motion with
``thigh_angle_rad`` and, separately, ``knee_flexion_rad`` multiplied by (1 + k·1e-15), k = 1..K
(default 6) — changes of a few units in the last place (``--step`` replaces 1e-15, to see how the
cost follows larger changes). Prints each run's metabolic cost of one leg
(J), IPOPT iterations, converged flag and the input change actually made (samples changed, largest
|Δ| in rad), then per family the spread of the cost (max − min, absolute and relative to the
unperturbed cost) beside the 1e-6 relative criterion used to compare EID costs, and which side of it
the spread falls. One core, one thread; asserts nothing.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import tempfile
import textwrap
import time
from pathlib import Path

import numpy as np

# timing first, before numpy: one thread, Agg backend (its import sets the environment)
from timing import one_core, sample_legs

from gaitcli.muscles.stage import run_muscles

CRITERION = 1e-6  # relative: what tests and comparisons of EID costs have asked of "the same" cost
EXPLANATION = (
    "What this measures: how far the EID optimum (the metabolic cost of one leg over a stride) moves when "
    "the joint angles it is given change by round-off — the thigh or knee angle multiplied by 1 + k·1e-15, "
    "a few units in the last place of a double, far below any measurement or filtering error. Why: EID "
    "costs are compared (between runs, versions, machines and BLAS builds) to 1e-6 relative; that criterion "
    "is only meaningful if the problem itself moves less than that under round-off. The EID NLP (400 "
    "variables, non-convex, smoothed heat-rate kinks, solved by IPOPT to tol 1e-8) can end at a slightly "
    "different point of a flat optimum when its input changes in the last bit — an experiment moved the "
    "right leg's cost from 223.351 to 223.442 J (4e-4 relative) for the thigh angle × (1 + 1e-15). If the "
    "spread below exceeds 1e-6 relative, a 1e-6 reproducibility check of EID costs tests round-off, not the "
    "code: identical input gives identical output (the repeated run), but any change of the arithmetic "
    "upstream (BLAS, compiler, library version, the order of a sum) is allowed to move the cost by the "
    "spread shown, and comparisons should use a tolerance above it.")


def scaled(motion, field: str, factor: float):
    """The motion with ``field`` multiplied by ``factor``, and (samples changed, largest |Δ| rad)."""
    values = getattr(motion, field)
    changed = values * factor
    delta = np.abs(changed - values)
    finite = np.isfinite(delta)
    return dataclasses.replace(motion, **{field: changed}), (int(np.count_nonzero(delta[finite])),
                                                            float(delta[finite].max(initial=0.0)))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-K", type=int, default=6, help="perturbations per angle: k = 1..K")
    parser.add_argument("--step", type=float, default=1e-15, help="the inputs are scaled by 1 + k·STEP")
    parser.add_argument("--side", choices=("r", "l"), default="r")
    parser.add_argument("--nodes", type=int, default=50, help="EID nodes")
    args = parser.parse_args(argv)
    one_core()
    print(textwrap.fill(EXPLANATION, width=110) + "\n")
    with tempfile.TemporaryDirectory(prefix="bench_eid_sensitivity_") as tmp:
        _, legs = sample_legs(Path(tmp), args.side, ("cycle",))
    leg = legs["cycle"]
    start, end = leg.interval_s

    def eid(motion):
        return run_muscles(motion, leg.limb, method="eid", nodes=args.nodes, interval=leg.interval_s,
                           periodic=leg.periodic)

    print(f"sample_trials/normal, side {args.side}, stride {start:.2f}–{end:.2f} s (periodic: {leg.periodic}), "
          f"EID on {args.nodes} nodes; one core")
    header = (f"{'input':34} {'E (J)':>12} {'iter':>5} {'conv.':>6} {'samples changed':>16} "
              f"{'max |Δ| (rad)':>14} {'s':>5}")
    print(header)
    print("-" * len(header))

    def show(label, result, change, seconds):
        samples, delta = change
        print(f"{label:34} {result.metabolic_cost_J:12.6f} {result.iterations:5d} {result.converged!s:>6} "
              f"{samples:16d} {delta:14.2e} {seconds:5.1f}")
        return result.metabolic_cost_J

    def timed(motion):
        t = time.perf_counter()
        result = eid(motion)
        return result, time.perf_counter() - t

    base = show("unperturbed", *_swap(timed(leg.motion), (0, 0.0)))
    again = show("unperturbed, again", *_swap(timed(leg.motion), (0, 0.0)))
    families = {}
    for field, name in (("thigh_angle_rad", "thigh angle"), ("knee_flexion_rad", "knee angle")):
        costs = [base]
        for k in range(1, args.K + 1):
            motion, change = scaled(leg.motion, field, 1.0 + k * args.step)
            result, seconds = timed(motion)
            costs.append(show(f"{name} × (1 + {k}·{args.step:g})", result, change, seconds))
        families[name] = np.array(costs)
    print(f"\nrepeat of the unperturbed run: {'identical' if again == base else f'differs by {again - base:.3e} J'}")
    print(f"{'spread, unperturbed and k = 1..' + str(args.K):34} {'max − min (J)':>14} {'relative':>10} "
          f"{'/ criterion ' + format(CRITERION, 'g'):>18}")
    everything = np.concatenate(list(families.values()))
    for name, costs in list(families.items()) + [("both angles", everything)]:
        finite = costs[np.isfinite(costs)]
        spread = float(finite.max() - finite.min()) if finite.size else float("nan")
        relative = spread / abs(base)
        print(f"{name:34} {spread:14.6f} {relative:10.2e} {relative / CRITERION:18.2g}")
    side = "ABOVE" if relative > CRITERION else "below"
    print(f"\nverdict: under inputs scaled by up to 1 + {args.K}·{args.step:g} the EID cost moved by {relative:.2e} "
          f"relative, {side} the {CRITERION:g} criterion"
          + (" (the criterion is finer than the problem's own sensitivity)." if relative > CRITERION else
             f" (a factor {CRITERION / relative:.2g} below it: changes of this size do not move the cost past "
             "the criterion)." if relative > 0 else "."))
    return 0


def _swap(timed_result, change):
    result, seconds = timed_result
    return result, change, seconds


if __name__ == "__main__":
    sys.exit(main())
