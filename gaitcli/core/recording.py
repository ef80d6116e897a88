"""The containers carried between stages: markers and force plates in model axes, SI units.

Model axes: x forward along the walk, y to the subject's left, z up; metres,
newtons, seconds. Readers convert to this once (``gaitcli.io``); every stage
after them can rely on it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from gaitcli.core.events import Events


@dataclass
class Markers:
    """Marker trajectories ``positions_m`` (frames, markers, 3); NaN where a marker is not seen."""

    labels: tuple[str, ...]
    positions_m: np.ndarray
    rate_hz: float
    first_frame: int = 1

    @property
    def n_frames(self) -> int:
        return self.positions_m.shape[0]

    @property
    def time_s(self) -> np.ndarray:
        return np.arange(self.n_frames) / self.rate_hz

    def index(self, label: str) -> int:
        return self.labels.index(label)

    def get(self, label: str) -> np.ndarray:
        """Trajectory of one marker, (frames, 3) in metres."""
        return self.positions_m[:, self.index(label), :]

    def __contains__(self, label: str) -> bool:
        return label in self.labels


@dataclass
class ForcePlate:
    """One force platform's ground-reaction wrench at the analog rate, in model axes.

    ``force_N`` (samples, 3) is the force the ground exerts on the subject (vertical
    component positive under load); ``moment_Nm`` (samples, 3) its moment about
    ``centre_m``, the centre of the plate's top surface. ``corners_m`` (4, 3) are
    the top-surface corners. COP and free moment are derived from this wrench
    (``gaitcli.signal.forceplates``) after filtering.
    """

    name: str
    force_N: np.ndarray
    moment_Nm: np.ndarray
    centre_m: np.ndarray
    corners_m: np.ndarray
    rate_hz: float
    plate_type: int = 2

    @property
    def n_samples(self) -> int:
        return self.force_N.shape[0]

    @property
    def time_s(self) -> np.ndarray:
        return np.arange(self.n_samples) / self.rate_hz


@dataclass
class Analogs:
    """A trial's analog channels other than its force plates' (EMG, foot switches, …): ``values`` (samples ×
    channels) in the file's ``units`` per channel (e.g. "V", "mV"), sampled at ``rate_hz`` from the first marker
    frame on."""

    labels: tuple[str, ...]
    units: tuple[str, ...]
    rate_hz: float
    values: np.ndarray

    @property
    def n_samples(self) -> int:
        return self.values.shape[0]


@dataclass
class Recording:
    """One trial as read from disk: markers, plates, where it came from and what was noticed.

    ``subject_metadata``: numbers the file itself records about the subject, by their C3D
    parameter (``{"PROCESSING:Bodymass": 73.4}``), in the file's units. ``events``: the gait events the file
    records (C3D EVENT group; source ``file``), seconds from the first marker frame; empty where it has none.
    ``analogs``: its analog channels that are no force plate's (None where it has none). ``marker_labels``: the
    lab label each marker renamed by the subject's marker set was read under {landmark: lab label}.
    """

    markers: Markers
    plates: list[ForcePlate]
    source: Path | None = None
    lab_to_model: np.ndarray = field(default_factory=lambda: np.eye(3))
    notes: list[str] = field(default_factory=list)
    subject_metadata: dict[str, float] = field(default_factory=dict)
    events: Events = field(default_factory=Events)
    analogs: Analogs | None = None
    marker_labels: dict[str, str] = field(default_factory=dict)
