"""Figure timings: each PNG of each stage, drawn from the stage's HDF5 output, beside the 0.3 s target.

Run from the repository root: ``python benchmarks/bench_plots.py [--repeat N]``.

The filter, idyn and muscles (EID, default options) stages run once on a copy of
``sample_trials/normal`` without figures; then each stage's figure function
(``report.plots.filter_figures``, ``idyn_figures``, ``muscle_figures``) draws its PNGs from
filter.h5, idyn.h5 and muscles.h5, as ``gait`` and ``gait report`` do. Each figure's time runs from
the end of the previous figure (the first: from the call, so it includes reading the HDF5 file) to
the end of its PNG; "saving" is ``report.plots.save`` alone (tick locators, render, PNG written).
The first call of each function is reported on its own ("first": the first figures drawn in this
process also pay matplotlib's first-use costs, as every ``gait`` process does), then the median of
``--repeat`` (default 5) further calls. One core, one thread. Prints the ratio of the median to the
issue's target (each figure under 0.3 s); asserts nothing.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

# timing first, before numpy: one thread, Agg backend (its import sets the environment)
from timing import figure_times, median_of, one_core, sample_outputs

TARGET_S = 0.3
FIGURES = {"filter": "filter_figures", "idyn": "idyn_figures", "muscles": "muscle_figures"}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5, help="calls per figure function; the median is reported")
    args = parser.parse_args(argv)
    one_core()
    with tempfile.TemporaryDirectory(prefix="bench_plots_") as tmp:
        tmp = Path(tmp)
        _, h5 = sample_outputs(tmp, ("muscles",))
        from gaitcli.report import plots

        print(f"figures of the normal sample trial drawn from its HDF5 outputs; first call, then the median of "
              f"{args.repeat} more; one core; s")
        header = (f"{'stage':8} {'figure':20} {'first':>7} {'median':>7} {'(saving)':>9} {'target':>7} "
                  f"{'ratio':>6}")
        print(header)
        print("-" * len(header))
        for name, function in FIGURES.items():
            draw = getattr(plots, function)
            folder = tmp / "plots" / name
            first = figure_times(draw, h5[name], folder, "normal")
            runs = [figure_times(draw, h5[name], folder, "normal") for _ in range(max(1, args.repeat))]
            seconds = median_of([{k: v[0] for k, v in r.items()} for r in runs])
            saving = median_of([{k: v[1] for k, v in r.items()} for r in runs])
            for figure in seconds:
                print(f"{name:8} {figure:20} {first[figure][0]:7.3f} {seconds[figure]:7.3f} {saving[figure]:9.3f} "
                      f"{TARGET_S:7.1f} {seconds[figure] / TARGET_S:6.2f}")
            print(f"{name:8} {'(all, ' + h5[name].name + ')':20} {sum(v[0] for v in first.values()):7.3f} "
                  f"{sum(seconds.values()):7.3f} {sum(saving.values()):9.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
