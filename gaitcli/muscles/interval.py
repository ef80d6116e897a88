"""Which leg and which part of a trial the muscle stage analyses: a whole stride measured on the plates,
or a swing phase."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from gaitcli.core.events import Events
from gaitcli.dynamics.sagittal import SagittalExport, SagittalMotion
from gaitcli.errors import InputError
from gaitcli.signal.cycles import strides

from .limb import LimbParameters


def analysis_interval(events: Events, time_s: np.ndarray, load_known: np.ndarray, side: str, phase: str,
                      *, source=None) -> tuple[float, float, bool]:
    """``(start_s, end_s, periodic)`` for ``side``.

    ``cycle``: the first stride (heel strike to heel strike) throughout which the
    foot's load is known — its stance on a plate — analysed as periodic (4.3.5). The
    closing heel strike is the next stride's: the foot lands there with no load yet,
    wherever it lands.
    ``swing``: the first swing phase (toe off to heel strike), where the foot carries
    no load, analysed with extra nodes before and after (4.3.6).
    """
    if phase == "cycle":
        for st in strides(events):
            inside = (time_s >= st.start_s) & (time_s < st.end_s)
            if st.side == side and load_known[inside].all():
                return st.start_s, st.end_s, True
        raise InputError(source, f"{side} side", "no stride whose stance was recorded on a force plate "
                                                 "(expected one heel strike to heel strike on the plates; "
                                                 "use --phase swing to analyse a swing phase)")
    swings = events.swings(side)
    if swings:
        return swings[0][0], swings[0][1], False
    raise InputError(source, f"{side} side", "no swing phase (toe off followed by heel strike) in the events")


@dataclass(frozen=True)
class LegAnalysis:
    """One leg's sagittal motion and limb parameters, and the interval (s) to analyse."""

    motion: SagittalMotion
    limb: LimbParameters
    interval_s: tuple[float, float]
    periodic: bool


def prepare_leg(export: SagittalExport, side: str, phase: str, *, stature_m: float, sex: str,
                source=None) -> LegAnalysis:
    """The muscle stage's inputs for ``side`` from the idyn stage's :class:`SagittalExport`.

    ``source`` names the idyn output in error messages.
    """
    start, end, periodic = analysis_interval(export.events, export.time_s, export.load_known[side], side, phase,
                                             source=source)
    motion = dataclasses.replace(export.legs[side], source=None if source is None else str(source))
    limb = LimbParameters.from_body(export.parameters, side, body_mass_kg=export.body_mass_kg, stature_m=stature_m,
                                    sex=sex)
    return LegAnalysis(motion=motion, limb=limb, interval_s=(start, end), periodic=periodic)
