"""From a trial to one row per stride with the documented API alone: filter, inverse dynamics, the muscles by
extended inverse dynamics (EID), the outputs read back, a pandas table per stride.

Run it as ``python docs/examples/stride_table.py [WORKDIR]`` (default: a temporary folder); the getting-started
page shows it and ``tests/test_docs.py`` runs it.
"""

from __future__ import annotations

import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd

import gaitcli


def stride_table(workdir: Path) -> pd.DataFrame:
    # a copy of the bundled sample trial (trial.c3d, static.c3d, subject.yaml), so that its gait_out/ is ours
    trial = gaitcli.open_trial(shutil.copytree(gaitcli.sample_trial(), Path(workdir) / "normal",
                                               ignore=shutil.ignore_patterns("gait_out")))
    print(f"{trial.name}: {trial.subject.mass_kg} kg, {trial.subject.stature_m} m")

    # the bundled pipeline muscles_eid (filter, idyn, muscles with method: eid), with a pipeline file's keys
    config = gaitcli.pipeline_config("muscles_eid", filter={"cutoff_hz": 6})
    done = gaitcli.run_trial(trial, config=config)
    for outcome in done.outcomes:
        print(f"{outcome.stage}: {outcome.status} in {outcome.elapsed_s:.1f} s")

    # later, or in another script: everything back from the output folder
    outputs = gaitcli.read_outputs(trial.folder)
    idyn, eid = outputs.idyn, outputs.muscles["eid"]

    rows = []
    for number, cycle in idyn.cycles.groupby("stride"):  # each stride at 0-100 % of its cycle
        side = cycle["side"].iloc[0]
        loading = cycle[cycle["cycle_pct"] <= 30]  # the loading response's knee flexion, then swing's peak
        rows.append({"stride": number,
                     "loading_knee_flexion_deg": loading[f"knee_{side}_flexion_deg"].max(),
                     "peak_knee_flexion_deg": cycle[f"knee_{side}_flexion_deg"].max(),
                     "peak_ankle_power_W_per_kg": cycle[f"ankle_{side}_power_W_per_kg"].max()})
    table = idyn.strides[["stride", "side", "start_s", "period_s", "stance_pct"]].merge(pd.DataFrame(rows))

    # EID analysed one stride of the right leg: its metabolic cost goes on that stride's row
    analysed = np.isclose(table["start_s"], eid.forces["time_s"].iloc[0]) & (table["side"] == "r")
    table["eid_metabolic_cost_J"] = np.where(analysed, eid.metabolic_cost_J, np.nan)
    return table


if __name__ == "__main__":
    with tempfile.TemporaryDirectory() as scratch:
        print(stride_table(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(scratch)).round(2).to_string(index=False))
