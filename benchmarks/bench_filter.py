"""Filter-stage timings: per trial and per 1000 marker frames, on the sample trials and a real trial.

Run from the repository root: ``python benchmarks/bench_filter.py [--repeat N] [--cli]``.
Each trial is timed in four parts, the median of ``--repeat`` runs each: reading the trial
(C3D via ezc3d, axes, marker map: ``pipeline.load_recording``), the stage itself (``filter_trial``:
gap filling, zero-lag filtering of markers and plates, COP, plate-to-foot assignment, events),
writing its outputs (the stage's writer: CSV tables and filter.h5, plus summary.json, into a folder
written whole, as ``run_stages`` does) and its two figures drawn from filter.h5
(``report.plots.filter_figures``, as the pipeline draws them after writing). Trials: the five bundled sample
trials (560–608 frames at 100 Hz, 2 plates at 1 kHz) and, when ../shared/data/c3d is present,
walking2.c3d (1249 frames at 250 Hz, 2 plates at 2 kHz; its heel, first-metatarsal and pelvis
markers mapped to the model's names). ``--cli`` adds the wall time of the whole ``gait filter``
command in a fresh process (imports included) on the normal sample trial. Threads are limited
to one. Prints a table; asserts nothing.
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import warnings
from pathlib import Path

# timing first, before numpy: one thread, Agg backend (its import sets the environment)
from timing import REPO, copy_sample, median_s, one_core, stage_attrs, time_gait, write_stage

from gaitcli.errors import GaitWarning
from gaitcli.report import plots
from gaitcli.resources import sample_trial
from gaitcli.run.pipeline import load_recording
from gaitcli.run.trial import open_trial
from gaitcli.signal.stage import FilterConfig, filter_trial

SAMPLES = ("normal", "ankle_weight", "knee_orthosis", "ankle_fixed", "ski_boot")
SHARED_C3D = REPO.parent / "shared" / "data" / "c3d"
WALKING2_SUBJECT = """mass_kg: 72.0
stature_m: 1.80
sex: male
marker_map: {RCAL: CAr, RMT1: FMr, LCAL: CAl, LMT1: FMl, RASI: ASISr, LASI: ASISl, RPSI: PSISr, LPSI: PSISl}
"""


def time_trial(folder: Path, out: Path, repeat: int) -> dict:
    """Read, stage, write and figure timings (s, medians) of the filter stage on one trial folder."""
    trial = open_trial(folder)
    cfg = FilterConfig()
    attrs = stage_attrs(folder, "filter")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", GaitWarning)
        read_s, recording = median_s(lambda: load_recording(trial), repeat)
        stage_s, result = median_s(lambda: filter_trial(recording, cfg, path=trial.trial_path), repeat)
        write_s, _ = median_s(lambda: write_stage("filter", out, result, attrs), repeat)
        plots_s, _ = median_s(lambda: plots.filter_figures(out / "filter.h5", out.parent / "plots_only",
                                                           title=folder.name), repeat)
    m = result.markers
    plates = recording.plates
    return {"frames": m.n_frames, "rate_hz": m.rate_hz, "plates": len(plates),
            "analog_hz": plates[0].rate_hz if plates else float("nan"), "read_s": read_s, "stage_s": stage_s,
            "write_s": write_s, "plots_s": plots_s, "events": len(result.events),
            "warnings": len({str(w.message) for w in caught if issubclass(w.category, GaitWarning)})}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5, help="runs per timing; the median is reported")
    parser.add_argument("--cli", action="store_true", help="also time the whole `gait filter` command")
    args = parser.parse_args(argv)
    one_core()

    with tempfile.TemporaryDirectory(prefix="bench_filter_") as tmp:
        tmp = Path(tmp)
        trials = {name: sample_trial(name) for name in SAMPLES}
        if (SHARED_C3D / "walking2.c3d").is_file():
            folder = tmp / "walking2"
            folder.mkdir()
            shutil.copy(SHARED_C3D / "walking2.c3d", folder / "trial.c3d")
            (folder / "subject.yaml").write_text(WALKING2_SUBJECT)
            trials["walking2.c3d"] = folder
        else:
            print(f"({SHARED_C3D / 'walking2.c3d'} not found: sample trials only)")

        print(f"filter stage, median of {args.repeat} runs, one core; ms = milliseconds")
        header = (f"{'trial':14} {'frames':>6} {'Hz':>5} {'plates':>9} {'read ms':>8} {'stage ms':>9} "
                  f"{'write ms':>9} {'plots ms':>9} {'total ms':>9} {'stage ms/1k fr':>15} {'total ms/1k fr':>15} "
                  f"{'events':>7}")
        print(header)
        print("-" * len(header))
        for name, folder in trials.items():
            r = time_trial(folder, tmp / "out" / name / "filter", args.repeat)
            total = r["read_s"] + r["stage_s"] + r["write_s"] + r["plots_s"]
            plates = f"{r['plates']}@{r['analog_hz'] / 1000:g}kHz" if r["plates"] else "none"
            note = f"  ({r['warnings']} warnings)" if r["warnings"] else ""
            print(f"{name:14} {r['frames']:6d} {r['rate_hz']:5g} {plates:>9} {1e3 * r['read_s']:8.1f} "
                  f"{1e3 * r['stage_s']:9.1f} {1e3 * r['write_s']:9.1f} {1e3 * r['plots_s']:9.1f} {1e3 * total:9.1f} "
                  f"{1e6 * r['stage_s'] / r['frames']:15.1f} {1e6 * total / r['frames']:15.1f} {r['events']:7d}{note}")
        if args.cli:
            folder = copy_sample("normal", tmp / "cli_normal")
            repeat = max(1, min(args.repeat, 3))
            print(f"\n`gait -q filter` on the normal sample trial, new process each time (median of {repeat}): "
                  f"{time_gait('-q', 'filter', folder, repeat=repeat):.2f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
