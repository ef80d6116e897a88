"""``gait run --pipeline muscles_eid`` and ``gait muscles --method so|mso`` on every bundled sample trial but
ankle_weight.

The 12 runs go through ``pipeline.run_stages`` in the test process (the function every command
calls), without figures; the commands themselves are run as processes in test_muscles_cli.py. ankle_weight is
left out: every method converges on it as on the normal trial (measured: EID in 105 IPOPT iterations, SO in 25,
MSO in every frame; normal 126, 21, every frame), so its runs take the normal trial's branches, 2.2 s of
processor time more; ankle_fixed, its sibling (the same subject and gait), stays for MSO's unconverged frames.

Every run writes the stage's files and summary keys; on the normal trial all three methods converge
(exit 0), on the disturbed ones a method may end unconverged (exit 3, ``converged: false``) where a
locked joint's moment is carried by the orthosis or boot (sample_trials/README.md).
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import pytest

from gaitcli.errors import GaitWarning

from .conftest import MUSCLE_FILES, MUSCLE_SUMMARY_KEYS, SAMPLES, build_once, copy_sample

METHODS = ("so", "mso", "eid")
#: the sample trials run here (module docstring)
TRIALS = tuple(name for name in SAMPLES if name != "ankle_weight")


def _build(root: Path) -> dict:
    """Every method on every sample trial, in this process through ``run_stages`` (what the commands call)."""
    from gaitcli.run.config import configure
    from gaitcli.run.pipeline import run_stages

    record = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", GaitWarning)  # the disturbed trials warn; tests/cli/test_warnings.py checks
        for name in TRIALS:
            trial = copy_sample(name, root / name)
            for method in ("eid", "so", "mso"):
                if method == "eid":  # gait run --pipeline muscles_eid: filter, idyn, EID
                    cfg = configure("muscles_eid")
                    names = cfg.stages
                else:  # gait muscles --method so|mso, reusing the fresh filter and idyn outputs
                    cfg, names = configure(None, muscles={"method": method}), ("muscles",)
                outcomes = {o.stage: o for o in run_stages(trial, names, cfg, plots=False)}
                record[f"{name}/{method}"] = {"converged": outcomes["muscles"].converged,
                                              "message": outcomes["muscles"].message,
                                              "statuses": {k: o.status for k, o in outcomes.items()}}
    return record


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    root, record = build_once(tmp_path_factory, "cli_muscles_samples", _build)
    return record, root


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("name", TRIALS)
def test_every_method_runs_on_every_sample_trial(runs, name, method):
    record, root = runs
    run = record[f"{name}/{method}"]
    folder = root / name / "gait_out" / "muscles" / method
    for file in MUSCLE_FILES:
        assert (folder / file).is_file(), f"{folder / file} missing"
    info = json.loads((folder / "summary.json").read_text())
    assert set(MUSCLE_SUMMARY_KEYS) <= set(info) and info["method"] == method
    assert info["converged"] is run["converged"]
    assert bool(run["message"]) is not run["converged"]  # an unconverged run says why (the CLI's exit-3 line)
    if info["converged"]:
        assert info["max_moment_error_Nm"] < 0.5
    if method == "eid":  # gait run ran filter and idyn first, per the pipeline file
        assert run["statuses"] == {"filter": "written", "idyn": "written",
                                   "muscles": "written" if run["converged"] else "unconverged"}
        assert (root / name / "gait_out" / "idyn" / "idyn.h5").is_file()
    else:  # the fresh filter and idyn outputs were read back, not made again
        assert run["statuses"]["filter"] == run["statuses"]["idyn"] == "reused"
    if name == "normal":
        assert run["converged"], run["message"]
