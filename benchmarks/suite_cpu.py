"""CPU seconds each test costs, its subprocesses included: a pytest plugin for finding the suite's costly tests.

Wall times on this shared 2-core machine say more about the other engineers' work than about a test; CPU time
does not. Each test's set-up, call and tear-down is charged the CPU (user + system) that the test process and
every live process below it (the ``gait`` runner processes, Dask, Chromium) spent during it, plus what exited
children spent (their times reach the parent's ``children`` times when reaped). A session fixture's cost is
charged to the set-up of the first test that needs it. Usage, from the repository root::

    python -m pytest -n 1 -q -p no:cacheprovider -p benchmarks.suite_cpu --cpu-json cpu.json
    python benchmarks/suite_cpu.py cpu.json [--top 40] [--by-file]

With ``-n 2`` each worker writes its own file (``cpu.json.gw0`` …); the summary reads them all.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from collections import defaultdict
from pathlib import Path

import pytest


def tree_cpu_s() -> float:
    """CPU seconds (user + system, own and reaped children's) of this process and every live descendant."""
    import psutil

    me = psutil.Process()
    total = 0.0
    for proc in [me, *me.children(recursive=True)]:
        try:
            t = proc.cpu_times()
        except (psutil.NoSuchProcess, psutil.AccessDenied):
            continue
        total += t.user + t.system + t.children_user + t.children_system
    return total


# --------------------------------------------------------------------------------------- the pytest plugin

def pytest_addoption(parser):
    parser.addoption("--cpu-json", default=None, help="write each test phase's CPU seconds to this JSON file")


_PHASES: dict = defaultdict(dict)


def _measure(item, phase: str):
    start_cpu, start_wall = tree_cpu_s(), time.perf_counter()
    try:
        return (yield)
    finally:
        _PHASES[item.nodeid][phase] = [tree_cpu_s() - start_cpu, time.perf_counter() - start_wall, time.time()]


@pytest.hookimpl(wrapper=True)
def pytest_runtest_setup(item):
    yield from _measure(item, "setup")


@pytest.hookimpl(wrapper=True)
def pytest_runtest_call(item):
    yield from _measure(item, "call")


@pytest.hookimpl(wrapper=True)
def pytest_runtest_teardown(item, nextitem):
    yield from _measure(item, "teardown")




def pytest_sessionfinish(session):
    out = session.config.getoption("--cpu-json")
    if not out:
        return
    worker = os.environ.get("PYTEST_XDIST_WORKER")
    if worker is None and hasattr(session.config, "workerinput"):
        worker = session.config.workerinput.get("workerid")
    if worker is None and session.config.pluginmanager.hasplugin("dsession"):
        return  # the xdist controller runs no test
    path = Path(f"{out}.{worker}" if worker else out)
    path.write_text(json.dumps(_PHASES, indent=0))


# --------------------------------------------------------------------------------------- the summary

def _load(base: Path) -> dict:
    files = [base] if base.is_file() else sorted(base.parent.glob(base.name + ".gw*"))
    phases: dict = {}
    for f in files:
        phases.update(json.loads(f.read_text()))
    return phases


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("json", type=Path)
    parser.add_argument("--top", type=int, default=40)
    parser.add_argument("--by-file", action="store_true", help="sum per test file")
    args = parser.parse_args(argv)
    phases = _load(args.json)
    rows = []
    for nodeid, by_phase in phases.items():
        cpu = sum(v[0] for v in by_phase.values())
        wall = sum(v[1] for v in by_phase.values())
        setup = by_phase.get("setup", [0.0, 0.0])[0]
        rows.append((cpu, wall, setup, nodeid))
    total_cpu, total_wall = sum(r[0] for r in rows), sum(r[1] for r in rows)
    print(f"{len(rows)} tests: {total_cpu:.1f} s CPU, {total_wall:.1f} s wall (sum over tests)")
    if args.by_file:
        per_file: dict = defaultdict(lambda: [0.0, 0.0, 0])
        for cpu, wall, _, nodeid in rows:
            acc = per_file[nodeid.split("::")[0]]
            acc[0] += cpu
            acc[1] += wall
            acc[2] += 1
        print(f"{'CPU s':>7} {'wall s':>7} {'tests':>5}  file")
        for name, (cpu, wall, n) in sorted(per_file.items(), key=lambda kv: -kv[1][0])[:args.top]:
            print(f"{cpu:7.2f} {wall:7.2f} {n:5d}  {name}")
        return 0
    print(f"{'CPU s':>7} {'wall s':>7} {'setup':>6}  test")
    for cpu, wall, setup, nodeid in sorted(rows, reverse=True)[:args.top]:
        print(f"{cpu:7.2f} {wall:7.2f} {setup:6.2f}  {nodeid}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
