"""When the forefoot lands and the heel rises in real level walking: foot flat and heel off in % of the stride.

Run from the repository root: ``python benchmarks/survey_foot_events.py``. Reads the level-walking trials in
../shared/data (walking2, walking5: Vicon; Qualisys; BTS; the Motion Analysis Gait.c3d) through `gait filter`
(gap filling, 6 Hz, heel strikes and toe offs from the plates or the foot markers), and for each stance whose
stride is complete (heel strike to the next heel strike of that foot) finds, from the filtered markers:

- foot flat: the first frame after the heel strike at which the forefoot marker (first/second metatarsal head
  or toe) is within ``THRESHOLD_M`` of its lowest height over the stride's first 40 %;
- heel off: the frame after the last one, from foot flat to toe off, at which the heel marker is within
  ``THRESHOLD_M`` of its lowest height over that span (from there it rises until toe off).

Prints each stance and the mean, SD, minimum and maximum of both over all of them; the prediction's bounds
(``predict/settings.PredictSettings.stance_timing_pct``) come from here. Asserts nothing.
"""

from __future__ import annotations

import shutil
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

from gaitcli.run.pipeline import load_recording
from gaitcli.run.trial import open_trial
from gaitcli.signal.cycles import strides
from gaitcli.signal.stage import FilterConfig, filter_trial

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data"
#: a marker this far above its stance minimum is off the ground, m
THRESHOLD_M = 0.005
HELEN_HAYES = "mass_kg: 70.0\nstature_m: 1.75\nsex: male\nmarker_set: plug_in_gait\n"
BTS = "mass_kg: 70.0\nstature_m: 1.75\nsex: male\nmarker_map: {r heel: CAr, l heel: CAl, r met: MT2r, l met: MT2l}\n"
TRIALS = {"walking2": ("c3d/walking2.c3d", REPO / "docs/examples/walking2/subject.yaml"),
          "walking5": ("c3d/walking5.c3d", REPO / "docs/examples/walking2/subject.yaml"),
          "Qualisys": ("c3d/Qualisys.c3d", REPO / "docs/examples/qualisys/subject.yaml"),
          "BTS": ("c3d/BTS.c3d", BTS), "Gait (Motion Analysis)": ("emg/Gait.c3d", HELEN_HAYES)}
HEEL = {"r": ("CAr",), "l": ("CAl",)}
FOREFOOT = {"r": ("MT2r", "FMr", "VMr"), "l": ("MT2l", "FMl", "VMl")}


def stance_events(name: str) -> list[tuple[str, float, float]]:
    """(side, foot flat %, heel off %) of every complete stride of one trial."""
    file, subject = TRIALS[name]
    with tempfile.TemporaryDirectory() as tmp, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        shutil.copy(DATA / file, Path(tmp) / "trial.c3d")
        text = subject.read_text() if isinstance(subject, Path) else subject
        (Path(tmp) / "subject.yaml").write_text(text)
        trial = filter_trial(load_recording(open_trial(tmp)), FilterConfig()).trial
    markers, t = trial.markers, trial.time_s
    out = []
    for stride in strides(trial.events):
        s = stride.side
        heel = next((markers.get(n)[:, 2] for n in HEEL[s] if n in markers), None)
        fore = next((markers.get(n)[:, 2] for n in FOREFOOT[s] if n in markers), None)
        if heel is None or fore is None or not np.isfinite(stride.toe_off_s):
            continue
        stance = (t >= stride.start_s) & (t <= stride.toe_off_s)
        if not (np.isfinite(heel[stance]).all() and np.isfinite(fore[stance]).all()):
            continue
        idx = np.flatnonzero(stance)
        early = idx[t[idx] <= stride.start_s + 0.4 * stride.period_s]  # the forefoot lands in this part
        flat = early[np.argmax(fore[early] <= np.min(fore[early]) + THRESHOLD_M)]
        after = idx[idx >= flat]
        grounded = after[heel[after] <= np.min(heel[after]) + THRESHOLD_M]
        if grounded[-1] >= idx[-1]:
            continue
        off = grounded[-1] + 1  # from here the heel rises until toe off
        flat_pct, off_pct = (100 * (t[i] - stride.start_s) / stride.period_s for i in (flat, off))
        out.append((s, flat_pct, off_pct))
    return out


def main() -> int:
    if not DATA.is_dir():
        print("../shared/data is not present")
        return 0
    rows = []
    print(f"{'trial':<24} {'side':>4} {'foot flat %':>12} {'heel off %':>11}")
    for name, (file, _) in TRIALS.items():
        if not (DATA / file).is_file():
            continue
        for side, flat, off in stance_events(name):
            rows.append((flat, off))
            print(f"{name:<24} {side:>4} {flat:>12.1f} {off:>11.1f}")
    values = np.array(rows)
    for k, label in enumerate(("foot flat", "heel off")):
        v = values[:, k]
        print(f"{label}: mean {v.mean():.1f} %, SD {v.std(ddof=1):.1f}, min {v.min():.1f}, max {v.max():.1f} "
              f"({v.size} stances)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
