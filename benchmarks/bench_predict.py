"""Predictive-gait timings (``gaitcli.predict``) beside the dissertation's Table 5.1, the previous formulation
and two peers; the stride across speeds against Winter's cadences.

Run from the repository root: ``python benchmarks/bench_predict.py [--nodes 14 16 18 20] [--full 18]
[--start walk guess] [--speeds 1.0 1.1275 1.325 1.6] [--reference-at 1.0=slow.csv …] [--bundled]
[--stride-sweep 1.325 1.12 1.28 1.44] [--stride-follows 1.325 1.45]``. One core (``BENCH_CORE``: which,
timing.py); asserts nothing.

Per node count, model and start (``PredictConfig.start``: the shipped walk, or 5.2.10's guess): normal walking
as ``gait predict`` walks by default (subject 1, weights 4/3, 2/3, 1.1275 m/s, the shipped reference of that
speed and its group's stride ± 1 SD; ``--bundled``: every prediction tracks the bundled reference, the earlier
default, the stride in the box) by ``run_predict``. The problem and its first
IPOPT solver are built first into the run's cache (``construct s``: CasADi's expressions, then IPOPT's
derivative functions), so that ``solve s`` is IPOPT's iterations (with the transcription of the result). The
full model solves the symmetric model first and starts from that solution laid on its own grid, where it is
exactly a point of the full model (``layout.full_from_symmetric``, ``run_predict``); its ``solve s`` includes
both solves and the full problem's construction, its ``construct s`` is the symmetric problem's. Printed:
IPOPT iterations and solves, J, Et, Jdev, the non-zeros of the constraint Jacobian and of the Hessian of the
Lagrangian (lower triangle, as IPOPT counts them), the ratio to Table 5.1's hours and to Falisse et al.'s 2-D
predictions (44–55 s).

``--stride-sweep SPEED STRIDE…``: the default prediction at SPEED (its reference) with every step fixed at half
of each STRIDE (m), printing J, Et and Jdev: which stride the cost prefers.

``--stride-follows SPEED STRIDE``: the walk at SPEED forced to STRIDE, made a reference, then tracked with the
stride free: whether the stride follows a speed's own reference (5.3.3's per-speed data).

``--speeds``: the stride and cadence at each speed as ``gait predict --speed V`` walks by default (tracking the
shipped reference of that speed, the stride bounded by its group's ± 1 SD: ``predict/speed_reference.py``),
beside the tracked group's stride and cadence for subject 1, whether the stride bound is active, and the
joint moments' shapes against Schwartz et al.'s free-speed group's means (the package's normal band;
Pearson r of hip, knee and ankle sagittal moments over the cycle). ``--reference-at SPEED=FILE``: that speed
tracks FILE instead, the stride in the box. Winter's cadences as recalled (87, 105, 123 steps per minute at
1.00, 1.325 and 1.68 m/s; not checked against his book here) are printed beside.
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import numpy as np
from timing import one_core, solver_libraries

from gaitcli.predict.layout import DesignLayout
from gaitcli.predict.model import WalkerParameters
from gaitcli.predict.nlp import instant_segments
from gaitcli.predict.problem import Transcriber
from gaitcli.predict.reference import VARIABLES, as_reference, read_reference
from gaitcli.predict.solve import NlpCache, checked_design, ipopt_options
from gaitcli.predict.speed_reference import speed_reference
from gaitcli.predict.stage import PredictConfig, default_start, run_predict, settings_of
from gaitcli.resources import bundled_reference
from gaitcli.run.stages import PredictionInputs
from gaitcli.signal.bands import BAND_FILE, read_band
from gaitcli.signal.cycles import CYCLE_PCT

TABLE_5_1_HOURS = {14: 11.3, 16: 15.9, 18: 22.3, 20: 28.9}
FALISSE_S = (44.0, 55.0)
#: the previous formulation (nodal values' segment coefficients, continuity rows; 5.2.10's guess), measured on
#: this machine at commit f784669, one core: nn = 18 symmetric, default `gait predict`
PREVIOUS = {("symmetric", 18): {"iterations": 938, "solve_s": 1830.0, "J": 11.380150, "jac": None, "hess": 38547}}
#: Winter's cadences (steps/min) at the speeds (m/s) 5.3.3 tracks: slow, natural, fast
WINTER_CADENCE = ((1.00, 87.0), (1.325, 105.0), (1.68, 123.0))


def construct(cfg: PredictConfig, settings, reference, cache: NlpCache) -> tuple[float, int, int]:
    """Build ``cfg``'s symmetric problem at the default start's windows and its first IPOPT solver into
    ``cache``: (seconds, Jacobian non-zeros, Hessian non-zeros)."""
    transcriber = Transcriber(cfg.nodes)
    x0 = default_start(cfg, transcriber, reference, settings, symmetric=True)
    layout = DesignLayout.build(cfg.nodes, symmetric=True)
    began = time.perf_counter()
    nlp = cache.nlp(transcriber, reference, settings, symmetric=True,
                    segments=instant_segments(transcriber, layout, checked_design(transcriber, layout, x0)[0]))
    solver, _ = cache.solver(nlp, ipopt_options(settings, warm=False))
    seconds = time.perf_counter() - began
    jacobian = solver.get_function("nlp_jac_g").sparsity_out(1).nnz()
    hessian = solver.get_function("nlp_hess_l").sparsity_out(0).nnz()
    return seconds, jacobian, hessian


def predict(cfg: PredictConfig, reference, cop_sd_m: float = 0.0, step_m: float = 0.0) -> dict:
    """One prediction, its construction timed apart (module docstring); ``cop_sd_m`` > 0: Jdev also tracks the
    feet's centres of pressure (``PredictSettings.cop_sd_m``); ``step_m`` > 0: every step this long."""
    cache, settings = NlpCache(), dataclasses.replace(settings_of(cfg), cop_sd_m=cop_sd_m, step_m=step_m)
    built, jacobian, hessian = construct(cfg, settings, reference, cache)
    began = time.perf_counter()
    result = run_predict(cfg, reference=reference, cache=cache, settings=settings)
    if cfg.symmetric and len(cache) != 1:
        print(f"    (the prediction built {len(cache) - 1} more problems: windows moved, or construct() missed)")
    return {"result": result, "construct_s": built, "solve_s": time.perf_counter() - began, "jac": jacobian,
            "hess": hessian}


def kinetics(r) -> str:
    """What a normal walker's kinetics show, of result ``r``: the knee's largest extensor moment in 5–20 % of
    the cycle, where the ankle's plantarflexor moment peaks in stance, the vasti's largest stance activation,
    the share of the cycle each saturated muscle spends above 0.95, the excitations on the 4× grid."""
    moments = r.joint_moments_Nm / r.body_mass_kg  # senses of the clinical angles: flexion, dorsiflexion > 0
    pct = 100 * r.point_time_s / r.period_s
    stance_pct = r.summary()["stance_pct"]
    early, stance = (pct >= 5) & (pct <= 20), pct <= stance_pct
    names = list(r.muscle_names)
    right = [k for k, n in enumerate(names) if n.endswith("_r")]
    above = (r.activations[:, right] > 0.95).mean(axis=0)
    saturated = {names[k].removesuffix("_r"): round(100 * float(s), 1) for k, s in zip(right, above) if s > 0}
    vasti = r.activations[r.cycle_pct <= stance_pct, names.index("vasti_r")].max()
    fine = r.fine_grid
    return (f"knee extensor {-moments[early, 1].min():.2f} N·m/kg in 5–20 %, ankle plantarflexor peak at "
            f"{pct[stance][np.argmin(moments[stance, 2])]:.0f} %, vasti {vasti:.2f} in stance, saturated % "
            f"{saturated or '-'}, excitations on the 4× grid {fine['min_excitation']:.2f}…{fine['max_excitation']:.2f}")


def moment_shapes(r) -> str:
    """Pearson r of the predicted hip, knee and ankle sagittal moments over the cycle against the normal band's
    means (Schwartz et al.'s free group; the band's extensor / plantarflexor senses, hence −r)."""
    band = read_band(BAND_FILE)
    pct = 100 * r.point_time_s / r.period_s
    moments = r.joint_moments_Nm / r.body_mass_kg  # flexion, flexion, dorsiflexion positive
    out = []
    for k, (joint, name) in enumerate((("hip", "hip_extensor"), ("knee", "knee_extensor"),
                                       ("ankle", "ankle_plantarflexor"))):
        mean = np.interp(pct, CYCLE_PCT, band.mean[f"{name}_moment_per_kg"])
        out.append(f"{joint} {-np.corrcoef(moments[:, k], mean)[0, 1]:.2f}")
    return "moment shapes r vs the free group's means: " + ", ".join(out)


def winter_stride_m(speed: float) -> float:
    """Winter's stride at ``speed`` (m/s): 2·60·v/cadence, the cadence interpolated between his three."""
    speeds, cadences = np.array(WINTER_CADENCE).T
    return 2 * 60 * speed / float(np.interp(speed, speeds, cadences))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nodes", type=int, nargs="*", default=[14, 16, 18, 20])
    parser.add_argument("--full", type=int, nargs="*", default=[18], help="node counts of the full model")
    parser.add_argument("--start", nargs="+", default=["walk"], choices=["walk", "guess"])
    parser.add_argument("--speeds", type=float, nargs="*", default=[1.0, 1.1275, 1.325])
    parser.add_argument("--stride-follows", type=float, nargs=2, metavar=("SPEED", "STRIDE"),
                        help="a speed, m/s, and a stride, m: the walk at that stride as the reference, the stride free")
    parser.add_argument("--reference-at", nargs="*", default=[], metavar="SPEED=FILE",
                        help="--speeds: the reference table this speed tracks (5.3.3: Winter's per speed)")
    parser.add_argument("--bundled", action="store_true",
                        help="every prediction tracks the bundled reference (the previous default), the stride "
                             "in the box")
    parser.add_argument("--iterations", type=int, default=3000)
    parser.add_argument("--cop-sd-m", type=float, default=0.0, help="> 0: Jdev also tracks the centres of pressure")
    parser.add_argument("--stride-sweep", type=float, nargs="*", default=[], metavar="SPEED STRIDE",
                        help="a speed, m/s, then strides, m: J, Et and Jdev with every step fixed at half of each")
    args = parser.parse_args()
    one_core()
    reference = read_reference(bundled_reference())
    print(f"{'nn':>3} {'model':<9} {'start':<5} {'construct s':>11} {'solve s':>8} {'iter':>5} {'solves':>6}"
          f" {'conv':>5} {'J':>8} {'Et J/m':>7} {'Jdev':>6} {'jac nnz':>8} {'hess nnz':>8} {'vs Table 5.1':>12}"
          f" {'vs Falisse':>11}", flush=True)
    cases = [(n, True) for n in args.nodes] + [(n, False) for n in args.full]
    for nodes, symmetric in cases:
        for start in args.start:
            cfg = PredictConfig(nodes=nodes, symmetric=symmetric, start=start, max_iterations=args.iterations)
            cfg, tracked, _ = tracking(cfg, reference if args.bundled else None)
            run = predict(cfg, tracked, args.cop_sd_m)
            r, wall = run["result"], run["construct_s"] + run["solve_s"]
            hours = TABLE_5_1_HOURS.get(nodes)
            print(f"{nodes:>3} {'symmetric' if symmetric else 'full':<9} {start:<5} {run['construct_s']:11.1f}"
                  f" {run['solve_s']:8.1f} {r.iterations:>5} {r.rounds:>6} {str(r.converged):>5} {r.objective:8.4f}"
                  f" {r.cost_of_transport_J_per_m:7.1f} {r.deviation:6.2f} {run['jac']:>8} {run['hess']:>8}"
                  f" {f'{hours * 3600 / wall:,.0f}x' if hours else '-':>12}"
                  f" {FALISSE_S[0] / wall:5.1f}–{FALISSE_S[1] / wall:.1f}x", flush=True)
            print_checks(r)
    for (model, nodes), old in PREVIOUS.items():
        print(f"{nodes:>3} {model:<9} {'guess':<5} {'-':>11} {old['solve_s']:8.1f} {old['iterations']:>5} {'':>6}"
              f" {'True':>5} {old['J']:8.4f} {'':>7} {'':>6} {'-':>8} {old['hess']:>8}   (previous formulation)")
    if args.speeds:
        print(f"\n{'speed m/s':>9} {'stride m':>8} {'period s':>8} {'cad/min':>7} {'group m':>7} {'ratio':>6}"
              f" {'grp cad':>7} {'ratio':>6} {'bound':>13} {'Winter m':>8} {'conv':>5} {'iter':>5} {'solve s':>7}"
              f" {'J':>8} {'Et J/m':>7} {'Jdev':>6}")
    own = {float(speed): read_reference(file) for speed, file in (a.split("=", 1) for a in args.reference_at)}
    for speed in args.speeds:
        cfg, tracked, group = tracking(at_speed(speed, args.iterations),
                                       own.get(speed, reference if args.bundled else None))
        run = predict(cfg, tracked, args.cop_sd_m)
        r = run["result"]
        stride, cadence = r.stride_m, r.cadence_steps_per_min
        bound = cfg.stride_range_m
        active = "-" if bound is None else ("low" if stride <= bound[0] + 1e-4 else
                                            "high" if stride >= bound[1] - 1e-4 else "inside")
        shown = "box" if bound is None else f"{bound[0]:.3f}–{bound[1]:.3f}"
        print(f"{speed:9.4f} {stride:8.3f} {r.period_s:8.3f} {cadence:7.1f} {group.stride_m:7.3f}"
              f" {stride / group.stride_m:6.2f} {group.cadence_steps_per_min:7.1f}"
              f" {cadence / group.cadence_steps_per_min:6.2f} {shown:>11} {active[:1]}"
              f" {winter_stride_m(speed):8.3f} {str(r.converged):>5} {r.iterations:>5} {run['solve_s']:7.1f}"
              f" {r.objective:8.4f} {r.cost_of_transport_J_per_m:7.1f} {r.deviation:6.2f}", flush=True)
        print_checks(r)
        print("    " + moment_shapes(r) + f"; tracked: {tracked.source or 'bundled'}", flush=True)
    given = reference if args.bundled else None
    if args.stride_sweep:
        stride_sweep(args.stride_sweep[0], args.stride_sweep[1:], given, args.iterations)
    if args.stride_follows:
        stride_follows(*args.stride_follows, given, args.iterations)
    print(solver_libraries())


def tracking(cfg: PredictConfig, reference=None):
    """(cfg, reference, speed reference) as ``gait predict`` resolves them for subject 1
    (``run.stages.PredictionInputs.at_speed``): ``reference`` with the stride in the box, else the shipped one
    of cfg's speed with its group's stride ± 1 SD. The speed reference is returned either way (its stride and
    cadence are the comparison)."""
    params = WalkerParameters.subject_1()
    group = speed_reference(cfg.speed_m_s, params.leg_length_m)
    cfg, tracked, _ = PredictionInputs(params, reference).at_speed(cfg)
    return cfg, tracked, group


def print_checks(r) -> None:
    """The five gait checks and the kinetics of result ``r``."""
    checks = r.gait_checks()
    print("    gait checks: " + ", ".join(f"{k} {v['value']} {'ok' if v['ok'] else 'FAILS'}"
                                          for k, v in checks.items()), flush=True)
    print("    " + kinetics(r), flush=True)


def at_speed(speed: float, iterations: int) -> PredictConfig:
    """The default prediction at ``speed`` (m/s), stopped after ``iterations``."""
    return dataclasses.replace(PredictConfig(), speed_m_s=speed, max_iterations=iterations)


def stride_sweep(speed: float, strides: list[float], reference, iterations: int) -> None:
    """J, Et and Jdev at ``speed`` with the stride fixed at each of ``strides`` (``PredictSettings.step_m``):
    which stride the cost itself prefers, apart from where IPOPT stops from the shipped walk's."""
    print(f"\nstrides fixed at {speed} m/s\n{'stride m':>8} {'period s':>8} {'conv':>5} {'iter':>5} {'J':>8}"
          f" {'Et J/m':>7} {'Jdev':>6}")
    cfg, tracked, _ = tracking(at_speed(speed, iterations), reference)
    for stride in strides:
        r = predict(cfg, tracked, step_m=stride / 2)["result"]
        print(f"{stride:8.3f} {r.period_s:8.3f} {str(r.converged):>5} {r.iterations:>5}"
              f" {r.objective:8.4f} {r.cost_of_transport_J_per_m:7.1f} {r.deviation:6.2f}", flush=True)


def reference_of(result, reference):
    """The :data:`~gaitcli.predict.reference.VARIABLES` of a predicted cycle over 0–100 % as a reference, with
    ``reference``'s SDs: a walker at that speed and stride, the data a speed's own reference would hold."""
    pct, point_pct = result.cycle_pct, 100 * result.point_time_s / result.period_s
    columns = [np.interp(CYCLE_PCT, pct, a, period=100.0) for a in result.clinical_angles_deg.T]
    columns += [np.interp(CYCLE_PCT, point_pct, f / result.body_mass_kg, period=100.0) for f in result.grf_N.T]
    return as_reference(np.column_stack(columns), reference.arrays(VARIABLES)[1], np.zeros(len(VARIABLES)),
                        "a predicted walk")


def stride_follows(speed: float, stride: float, reference, iterations: int) -> None:
    """Whether the stride follows the reference, as 5.3.3's per-speed references need: the walk at ``speed``
    with every step fixed at half of ``stride``, made a reference (:func:`reference_of`), then tracked with the
    stride free from the default start."""
    cfg, tracked, _ = tracking(at_speed(speed, iterations), reference)
    forced = predict(cfg, tracked, step_m=stride / 2)["result"]
    free = predict(dataclasses.replace(cfg, stride_range_m=None), reference_of(forced, tracked))["result"]
    print(f"\nat {speed} m/s the walk at a {stride} m stride as the reference: the stride free returns to "
          f"{free.stride_m:.3f} m (period {free.period_s:.3f} s, "
          f"converged {free.converged}, {free.iterations} iterations, J {free.objective:.4f}, Jdev "
          f"{free.deviation:.3f}; the forced walk's J {forced.objective:.4f})", flush=True)


if __name__ == "__main__":
    main()
