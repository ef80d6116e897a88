"""docs/examples/qualisys/README.md's commands, run as written (its bash block, the shared file's and the
example's paths put in), give the figures its first table and its EID paragraph print (issue 52, item 4)."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from .conftest import ENV

pytestmark = pytest.mark.shared
DOC = Path(__file__).resolve().parents[2] / "docs" / "examples" / "qualisys" / "README.md"


def _figure(text: str, pattern: str) -> tuple[float, ...]:
    found = re.search(pattern, text)
    assert found, pattern
    return tuple(float(v) for v in found.groups())


def test_the_qualisys_doc_runs_as_written_and_gives_its_figures(shared_c3d_dir, tmp_path):
    text = DOC.read_text(encoding="utf-8")
    (block,) = re.findall(r"```bash\n(.*?)```", text, flags=re.S)
    script = (block.replace("../shared/data/c3d/", f"{shared_c3d_dir}/")
              .replace("docs/examples/qualisys/", f"{DOC.parent}/"))
    gait = f'gait() {{ "{sys.executable}" -m gaitcli --quiet "$@"; }}\nset -e\n'
    done = subprocess.run(["bash", "-c", gait + script], cwd=tmp_path, env={**os.environ, **ENV},
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    out = tmp_path / "qualisys_trial" / "gait_out"
    idyn = json.loads((out / "idyn" / "summary.json").read_text())
    (mass,) = _figure(text, r"body mass \(from the plates\) \| ([\d.]+) kg")
    speed, stride, period = _figure(text, r"speed, stride length, period \| ([\d.]+) m/s, ([\d.]+) m, ([\d.]+) s")
    right, left, double = _figure(text, r"double stance \| ([\d.]+) %, ([\d.]+) %, ([\d.]+) %")
    frames, force, moment = _figure(text, r"pelvis residual RMS \((\d+) frames[^|]*\| ([\d.]+) N, ([\d.]+) N·m")
    assert idyn["mass_kg"] == pytest.approx(mass, abs=0.05)
    assert (idyn["speed_m_s"], idyn["stride_length_m"], idyn["period_s"]) == pytest.approx((speed, stride, period),
                                                                                            abs=0.005)
    assert (idyn["stance_right_pct"], idyn["stance_left_pct"], idyn["double_stance_pct"]) == pytest.approx(
        (right, left, double), abs=0.05)
    assert idyn["residual_frames"] == frames
    assert (idyn["rms_residual_force_N"], idyn["rms_residual_moment_Nm"]) == pytest.approx((force, moment), abs=0.5)
    eid = json.loads((out / "muscles" / "eid" / "summary.json").read_text())
    joules, transport, ralston = _figure(text, r"converges \((\d+) J for one leg's\s+stride; cost of transport "
                                               r"(\d+) J/m against Ralston's (\d+) J/m")
    assert eid["converged"] is True and eid["side"] == "r"
    assert (eid["metabolic_cost_J"], eid["cost_of_transport_J_per_m"], eid["ralston_J_per_m"]) == pytest.approx(
        (joules, transport, ralston), abs=0.5)
