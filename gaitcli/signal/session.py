"""A session's strides pooled: every stride of every walk per side, its features and whether it is used, the
mean ± SD of each cycle variable over the used strides, and Table 3.1 per walk and over the walks.

A stride runs from a heel strike to the next of the same foot (:func:`gaitcli.signal.cycles.strides`). Its
period is the time between the strikes, its stance % the time to the foot's toe off over the period, its
length the forward travel of the pelvis over the stride (steady walking: one stride length) and its speed the
length over the period; its step (:func:`gaitcli.signal.cycles.steps`) is the one its opening heel strike
ends: the distance along and across the walk from the other foot's last footprint. A stride is used for
kinematics when it is complete (a toe off inside it) and for kinetics too when the moments of its own leg are
known over at least :data:`KINETICS_KNOWN` of it (the foot on the force plates whenever it is on the ground); a
heel strike without a next one (the walk ends) is listed as rejected with that reason.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from gaitcli.core.events import Events
from gaitcli.signal.bands import stride_statistics
from gaitcli.signal.cycles import CYCLE_PCT, Step, strides

#: the fraction of a stride's samples with its leg's moments known for its kinetics to be used (one sample short:
#: the closing heel strike off the plates)
KINETICS_KNOWN = 0.95
#: two times closer than this are one event (s; the tables' 6 significant digits, a frame at 200 Hz)
SAME_TIME_S = 0.005
#: the cycle variables of the loads (moments, powers, ground reactions): from the strides whose loads are known
KINETIC_SUFFIXES = ("_per_kg", "_pct_body_weight")
#: the columns of gait_cycle.csv that are not cycle variables
CYCLE_KEYS = ("cycle_pct", "side", "stride", "start_s")
#: Table 3.1 as the idyn stage's summary gives it
TABLE_3_1 = ("stride_length_m", "period_s", "speed_m_s", "stance_right_pct", "stance_left_pct", "double_stance_pct")
#: a walk's features: Table 3.1 and its steps (NaN from an idyn output made before steps were)
WALK_FEATURES = TABLE_3_1 + ("step_length_right_m", "step_length_left_m", "step_width_m")
STATUS_USED, STATUS_KINEMATICS, STATUS_REJECTED = "used", "kinematics only", "rejected"


@dataclass(frozen=True)
class Walk:
    """One walk's outputs: its name, events, pelvis forward position over time (m), its gait_cycle.csv table and
    its Table 3.1 (idyn's summary)."""

    name: str
    events: Events
    time_s: np.ndarray
    pelvis_x_m: np.ndarray
    cycles: pd.DataFrame
    features: dict
    steps: tuple[Step, ...] = ()


@dataclass(frozen=True)
class SessionStrides:
    """The pooled session: ``strides`` one row per stride or rejected heel strike; ``cycle`` per side and
    cycle %, each variable's mean, SD and stride count; ``walks`` Table 3.1 per walk, then its mean and SD."""

    strides: pd.DataFrame
    cycle: pd.DataFrame
    walks: pd.DataFrame

    def summary(self) -> dict:
        """summary.json: the counts per side and status, and Table 3.1 over the used strides and over the walks."""
        s = self.strides
        counts = {side: {status: int(((s.side == side) & (s.status == status)).sum())
                         for status in (STATUS_USED, STATUS_KINEMATICS, STATUS_REJECTED)} for side in ("r", "l")}
        complete = s[s.status != STATUS_REJECTED]
        per_stride = {f"{k}_mean": float(complete[k].mean()) for k in ("period_s", "stride_length_m", "speed_m_s")}
        per_stride.update({f"{k}_sd": float(complete[k].std(ddof=1)) for k in ("period_s", "stride_length_m",
                                                                               "speed_m_s")})
        walks = self.walks.set_index("walk")
        return {"walks": int(len(walks) - 2), "strides": counts, "per_stride": per_stride,
                "table_3_1_mean": {k: float(walks.loc["mean", k]) for k in TABLE_3_1},
                "table_3_1_sd": {k: float(walks.loc["sd", k]) for k in TABLE_3_1}}


def _side_variables(columns, side: str) -> list[str]:
    """The cycle variables of one leg (``_r_`` or ``_l_`` in the name) or of the pelvis and trunk (neither)."""
    other = "l" if side == "r" else "r"
    return [c for c in columns if c not in CYCLE_KEYS and f"_{other}_" not in c]


def stride_rows(walk: Walk) -> list[dict]:
    """Every stride of one walk, its features and status, and each side's last heel strike (rejected)."""
    rows = []
    leg_moments = {side: [c for c in walk.cycles.columns if f"_{side}_" in c and c.endswith("moment_per_kg")]
                   for side in ("r", "l")}
    blocks = {side: [(float(start), group) for start, group in walk.cycles[walk.cycles.side == side]
                     .groupby("start_s", sort=True)] for side in ("r", "l")}
    for st in strides(walk.events):
        x = np.interp([st.start_s, st.end_s], walk.time_s, walk.pelvis_x_m)
        length = float(abs(x[1] - x[0]))
        step = next((s for s in walk.steps if s.side == st.side and abs(s.strike_s - st.start_s) < SAME_TIME_S),
                    None)
        row = {"walk": walk.name, "side": st.side, "start_s": st.start_s, "end_s": st.end_s,
               "toe_off_s": st.toe_off_s, "period_s": st.period_s,
               "stance_pct": 100.0 * (st.toe_off_s - st.start_s) / st.period_s, "stride_length_m": length,
               "speed_m_s": length / st.period_s, "step_length_m": step.length_m if step else np.nan,
               "step_width_m": step.width_m if step else np.nan}
        cycle = next((group for start, group in blocks[st.side] if abs(start - st.start_s) < SAME_TIME_S), None)
        if not np.isfinite(st.toe_off_s):
            row.update(status=STATUS_REJECTED, reason="no toe off between its heel strikes")
        elif cycle is None:
            row.update(status=STATUS_REJECTED, reason="not in gait_cycle.csv")
        else:
            known = np.isfinite(cycle[leg_moments[st.side]].to_numpy()).all(axis=1).mean() if leg_moments[st.side] \
                else 0.0
            row.update(status=STATUS_USED if known >= KINETICS_KNOWN else STATUS_KINEMATICS,
                       reason="" if known >= KINETICS_KNOWN else
                       f"moments known over {100 * known:.0f} % of it: the foot is off the force plates")
            row["stride"] = int(cycle["stride"].iloc[0])
        rows.append(row)
    for side in ("r", "l"):
        strikes = walk.events.times(side, "heel_strike")
        if strikes.size:
            rows.append({"walk": walk.name, "side": side, "start_s": float(strikes[-1]), "status": STATUS_REJECTED,
                         "reason": "the walk ends before the next heel strike"})
    return sorted(rows, key=lambda r: (r["start_s"], r["side"]))


def stride_table(walks: list[Walk]) -> pd.DataFrame:
    """Every stride of every walk (:func:`stride_rows`), one row each."""
    columns = ["walk", "side", "stride", "start_s", "end_s", "toe_off_s", "period_s", "stance_pct",
               "stride_length_m", "speed_m_s", "step_length_m", "step_width_m", "status", "reason"]
    return pd.DataFrame([row for walk in walks for row in stride_rows(walk)], columns=columns)


def side_stacks(walks: list[Walk], table: pd.DataFrame) -> dict[str, dict[str, np.ndarray]]:
    """{side: {cycle variable: (strides, 101)}} over the strides ``table`` (:func:`stride_table`) uses: the
    kinematics of every complete stride, the kinetics (:data:`KINETIC_SUFFIXES`) of those whose moments are
    known."""
    out = {}
    for side in ("r", "l"):
        used, kinematic = [], []
        for walk in walks:
            chosen = table[(table.walk == walk.name) & (table.side == side)]
            for status, target in ((STATUS_USED, used), (STATUS_KINEMATICS, kinematic)):
                for stride in chosen[chosen.status == status].stride:
                    target.append(walk.cycles[walk.cycles.stride == stride])
        variables = _side_variables(walks[0].cycles.columns, side) if walks else []
        out[side] = {name: np.array([b[name].to_numpy() for b in (used if name.endswith(KINETIC_SUFFIXES)
                                                                   else used + kinematic)]).reshape(-1, CYCLE_PCT.size)
                     for name in variables}
    return out


def pool(walks: list[Walk]) -> SessionStrides:
    """The session's strides, mean ± SD cycles and Table 3.1 (module docstring)."""
    table = stride_table(walks)
    cycle_blocks = []
    for side, stacks in side_stacks(walks, table).items():
        block = {"side": np.full(CYCLE_PCT.size, side), "cycle_pct": CYCLE_PCT}
        for name, stack in stacks.items():
            mean, sd, n = stride_statistics(stack)
            block.update({f"{name}_mean": mean, f"{name}_sd": sd, f"{name}_n": n})
        cycle_blocks.append(pd.DataFrame(block))
    return SessionStrides(strides=table, cycle=pd.concat(cycle_blocks, ignore_index=True), walks=walk_table(walks))


def walk_table(walks: list[Walk]) -> pd.DataFrame:
    """Table 3.1 and the steps per walk (:data:`WALK_FEATURES`), then their mean and SD (rows ``mean``, ``sd``)."""
    per_walk = pd.DataFrame([{"walk": w.name, **{k: w.features.get(k, np.nan) for k in WALK_FEATURES}}
                             for w in walks])
    values = per_walk[list(WALK_FEATURES)].astype(float)
    summary_rows = pd.DataFrame([{"walk": "mean", **values.mean().to_dict()},
                                 {"walk": "sd", **values.std(ddof=1).to_dict()}])
    return pd.concat([per_walk, summary_rows], ignore_index=True)
