"""The starts χ of a prediction: the shipped normal walk (the default) and the dissertation's initial guess.

:func:`shipped_walk` is ``gait predict``'s own solution with its defaults (``data/normal_symmetric_nn18.csv``)
on the problem's nodes, retimed to its speed: a gait that already walks, from which IPOPT needs tens of
iterations where it needs hundreds from 5.2.10's guess (``benchmarks/README.md``).
:func:`initial_guess` is 5.2.10's: a walk read off the reference, not yet clipped; it may lie outside the box
bounds (``layout.box_bounds``), e.g. a reference's knee hyperextended by 2°: the solve checks it against them,
reports what lies outside and clips it (``solve.solve_windowed``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gaitcli.predict.layout import DesignLayout, box_bounds, full_from_symmetric, symmetric_on_nodes
from gaitcli.predict.problem import Transcriber
from gaitcli.predict.reference import VARIABLES
from gaitcli.predict.settings import PredictSettings
from gaitcli.signal.bands import Band
from gaitcli.signal.cycles import CYCLE_PCT

#: m: the guess's step, about half of a 1.24 m stride at the dissertation's subject 1's speed
GUESS_STEP_M = 0.62
#: the guess's phase durations per half cycle (HSr→TCr, TCr→TOl, TOl→HOr, HOr→HSl): a 60 % stance
GUESS_PHASE_FRACTIONS = (0.07, 0.13, 0.55, 0.25)
#: the guess's tendon stretch ŝ: forces at 10 % of F_max (F = F_max·ŝ²)
GUESS_STRETCH = float(np.sqrt(0.1))
#: the guess's hip height per leg length (thigh + shank + ankle to sole): the standing foot on the floor
GUESS_HIP_HEIGHT = 0.97
DATA = Path(__file__).resolve().parent / "data"
#: a converged normal walk: χ of ``gait predict`` at 1.1275 m/s tracking the bundled reference (subject 1, weights
#: 4/3, 2/3), symmetric model, on this many nodes; the start where no speed group's walk is shipped
SHIPPED_WALK = DATA / "normal_symmetric_nn18.csv"
SHIPPED_WALK_NODES = 18
#: the default starts: subject 1's prediction at each speed group's speed, tracking its reference
#: (``scripts/make_speed_walks.py``; the speed in each file's first header line)
SPEED_WALKS = tuple(sorted(DATA.glob("walk_*_nn18.csv")))


def walk_speed_m_s(path: Path) -> float:
    """The speed of a shipped walk (its header's ``speed_m_s: V``)."""
    with open(path) as f:
        return float(f.readline().split("speed_m_s:")[1])


def nearest_walk(speed_m_s: float) -> Path:
    """The shipped walk of the speed nearest ``speed_m_s`` (:data:`SHIPPED_WALK` where none is shipped)."""
    if not SPEED_WALKS:
        return SHIPPED_WALK
    return min(SPEED_WALKS, key=lambda path: abs(walk_speed_m_s(path) - speed_m_s))


#: the starts ``PredictConfig.start`` names
STARTS = ("walk", "guess")


def shipped_walk(nodes: int, settings: PredictSettings | None = None, *, symmetric: bool = False) -> np.ndarray:
    """The default start χ: the shipped walk of the nearest speed (:func:`nearest_walk`) on ``nodes`` nodes (its
    splines fitted, ``layout.symmetric_on_nodes``, and clipped into the box; the full model's as
    ``layout.full_from_symmetric``), its step fixed at ``settings.step_m`` where that is set (else brought into
    ``settings.step_range_m``), its phase durations scaled so that it walks at the settings' speed (5.43:
    ΣT = ΔS/v)."""
    s = settings or PredictSettings()
    x = symmetric_on_nodes(np.loadtxt(nearest_walk(s.speed_m_s)), SHIPPED_WALK_NODES, nodes)
    layout = DesignLayout.build(nodes, symmetric=True)
    blocks = layout.unpack(x)
    if s.step_m > 0:
        blocks["steps"] = np.full_like(blocks["steps"], s.step_m)
    elif s.step_range_m is not None:
        blocks["steps"] = np.clip(blocks["steps"], *s.step_range_m)
    period = 2 * float(blocks["steps"].sum()) / s.speed_m_s
    blocks["durations"] = blocks["durations"] * period / (2 * float(blocks["durations"].sum()))
    x = np.clip(layout.pack(blocks), *box_bounds(layout))  # a fit on other nodes may overshoot a bound a little
    return x if symmetric else full_from_symmetric(nodes, x)


def initial_guess(transcriber: Transcriber, reference: Band, settings: PredictSettings | None = None, *,
                  symmetric: bool = False) -> np.ndarray:
    """5.2.10's initial guess χ: a walk read off the reference (``PredictConfig.start`` "guess").

    Parameters
    ----------
    transcriber : Transcriber
        The subject's model (its leg length) and node count.
    reference : Band
        Its mean hip and knee flexion and ankle dorsiflexion give the legs' angles (the HAT upright).
    settings : PredictSettings, optional
        Its speed sets the phase durations (a 60 % stance, steps of :data:`GUESS_STEP_M`).
    symmetric : bool
        The symmetric model's χ or the full one's.

    Returns
    -------
    array
        χ of the layout, the hip at :data:`GUESS_HIP_HEIGHT` of the leg's length, forces at 10 % of F_max
        (ŝ = √0.1); not clipped into the box bounds.
    """
    s = settings or PredictSettings()
    layout = DesignLayout.build(transcriber.layout.nodes, symmetric=symmetric)
    p = transcriber.model.params
    n = layout.nodes - 1
    pct = 100 * np.arange(n) / n
    mean = np.column_stack([np.interp(pct, CYCLE_PCT, reference.mean[v]) for v in VARIABLES])
    rad = np.radians
    hip_flex_r, knee_r, dorsi_r = (mean[:, VARIABLES.index(v)] for v in VARIABLES[:3])
    leg = p.leg_length_m
    right = [-rad(hip_flex_r), rad(knee_r), -rad(dorsi_r)]
    half = GUESS_STEP_M / s.speed_m_s  # s: half a cycle
    phases = np.array(GUESS_PHASE_FRACTIONS) * half
    if symmetric:
        n_h = layout.blocks["trunk"][1]
        trunk = np.column_stack([np.zeros(n_h), np.full(n_h, GUESS_HIP_HEIGHT * leg), np.zeros(n_h)])
        return layout.pack({"trunk": trunk, "right_leg": np.column_stack(right),
                            "right_stretch": np.full((n, 8), GUESS_STRETCH), "durations": phases,
                            "steps": [GUESS_STEP_M]})
    n_t = layout.blocks["trunk"][1]
    trunk = np.column_stack([np.zeros(n_t), np.full(n_t, GUESS_HIP_HEIGHT * leg), np.zeros(n_t)])
    left_pct = (pct + 50.0) % 100.0  # the left leg's nodes lie half a cycle after the right's (layout.py)
    left = [np.interp(left_pct, CYCLE_PCT, reference.mean[v]) for v in VARIABLES[3:6]]
    return layout.pack({"trunk": trunk, "right_leg": np.column_stack(right),
                        "left_leg": np.column_stack([-rad(left[0]), rad(left[1]), -rad(left[2])]),
                        "right_stretch": np.full((n, 8), GUESS_STRETCH), "left_stretch": np.full((n, 8), GUESS_STRETCH),
                        "durations": np.tile(phases, 2), "steps": [GUESS_STEP_M, GUESS_STEP_M]})
