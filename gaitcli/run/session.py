"""A session (``gait run SESSION``): every walk of a session folder through the pipeline on the workers of
:func:`gaitcli.run.batch.run_batch`, each walk's outputs in ``gait_out/<walk>/``, then the session's own in
``gait_out/session/``: ``strides.csv`` (every stride of every walk and why one is not used), ``cycle.csv``
(mean ± SD per side over the used strides), ``walks.csv`` (Table 3.1 per walk, their mean and SD),
``summary.json`` (:mod:`gaitcli.signal.session`); the walks' batch summary in ``gait_out/batch_summary.csv``."""

from __future__ import annotations

import json
import warnings
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from gaitcli.core.events import Events
from gaitcli.core.registry import stage
from gaitcli.errors import GaitWarning, InputError
from gaitcli.io.atomic import check_output_folder, check_replaceable
from gaitcli.io.outputs import stage_folder, write_json, write_table
from gaitcli.run.batch import BATCH_SUMMARY, BatchResult, run_batch, stages_of
from gaitcli.run.config import PipelineConfig
from gaitcli.run.trial import SESSION_OUTPUT, output_root, session_walks
from gaitcli.signal.bands import BAND_ANGLE_CONVENTION, BAND_FILE, default_band
from gaitcli.signal.cycles import Step, steps
from gaitcli.signal.profile import gait_profile
from gaitcli.signal.session import SessionStrides, Walk, pool
from gaitcli.signal.stage import HEEL


@dataclass(frozen=True)
class SessionRun:
    """What ``gait run SESSION`` did: the walks' batch, and the pooled strides (None without idyn in the
    pipeline or without a walk whose idyn output exists)."""

    folder: Path
    walks: list[Path]
    batch: BatchResult
    pooled: SessionStrides | None

    @property
    def output(self) -> Path:
        return self.folder / "gait_out" / SESSION_OUTPUT


def session_folder(folder: str | Path) -> list[Path] | None:
    """The walks of ``folder`` when it is a session folder (at least one walk), else None (a trial folder)."""
    walks = session_walks(Path(folder)) if Path(folder).is_dir() else None
    return walks or None


def read_walk(ref: Path, cfg: PipelineConfig, root: Path | None = None) -> Walk | None:
    """A walk's filter and idyn outputs (in ``root``, default its own output root) as
    :class:`~gaitcli.signal.session.Walk` (None where idyn wrote none)."""
    root = output_root(ref) if root is None else root
    idyn = root / stage("idyn").output_folder(cfg.section("idyn"))
    filtered = root / stage("filter").output_folder(cfg.section("filter"))
    if not (idyn / "gait_cycle.csv").is_file() or not (filtered / "events.csv").is_file():
        return None
    events = pd.read_csv(filtered / "events.csv")
    events = Events(frame=events.frame, time_s=events.time_s, side=events.side, kind=events.event,
                    source=events.source)
    coordinates = pd.read_csv(idyn / "coordinates.csv", usecols=["time_s", "pelvis_x"])
    return Walk(name=ref.stem, events=events, time_s=coordinates.time_s.to_numpy(),
                pelvis_x_m=coordinates.pelvis_x.to_numpy(), cycles=pd.read_csv(idyn / "gait_cycle.csv"),
                features=json.loads((idyn / "summary.json").read_text()),
                steps=tuple(_steps(filtered / "markers_filtered.csv", events)))


def _steps(markers_csv: Path, events: Events) -> list[Step]:
    """The walk's steps from the heels in the filter's markers (none where its table has no heel)."""
    if not markers_csv.is_file():
        return []
    header = pd.read_csv(markers_csv, nrows=0).columns
    heels = {side: next((name for name in HEEL[side] if f"{name}_x_m" in header), None) for side in ("r", "l")}
    if None in heels.values():
        return []
    columns = ["time_s"] + [f"{heels[s]}_{a}_m" for s in ("r", "l") for a in ("x", "y")]
    table = pd.read_csv(markers_csv, usecols=columns)
    positions = {s: table[[f"{heels[s]}_x_m", f"{heels[s]}_y_m"]].to_numpy(float) for s in ("r", "l")}
    return steps(events, positions, table.time_s.to_numpy(float))


def session_profile(pooled: SessionStrides, angle_conventions: tuple[str, ...] = ()) -> dict:
    """The Gait Profile Score of the session's mean curves against the package's normal band
    (:mod:`gaitcli.signal.profile`); ``angle_conventions`` the walks' angle frames (idyn's ``angle_frames``):
    where one is not the band's, a ``warning`` says the score compares two conventions."""
    means = {side: {c[:-len("_mean")]: block[c].to_numpy() for c in block.columns if c.endswith("_mean")}
             for side, block in pooled.cycle.groupby("side")}
    try:
        profile = gait_profile(means, default_band())
    except ValueError:  # no kinematic variable in common (a pipeline without angles)
        return {}
    out = {**profile.as_dict(), "band": str(BAND_FILE.name), "band_angle_convention": BAND_ANGLE_CONVENTION,
           "angle_conventions": sorted(set(angle_conventions))}
    other = sorted(set(angle_conventions) - {BAND_ANGLE_CONVENTION})
    if other:
        out["warning"] = (f"the walks' angles are in {', '.join(other)} frames, the band's in Plug-in Gait's: the "
                          "score mixes two conventions (pelvis tilt alone differs by about 12°); set marker_set: "
                          "plug_in_gait for Plug-in Gait's frames")
    return out


def write_session(folder: Path, pooled: SessionStrides, profile: dict | None = None) -> Path:
    """``gait_out/session/`` whole (replacing the previous one); ``profile`` its Gait Profile Score
    (:func:`session_profile`, the default's without the walks' conventions)."""
    target = folder / "gait_out" / SESSION_OUTPUT
    check_replaceable(target)
    with stage_folder(target) as tmp:
        for name, table in (("strides.csv", pooled.strides), ("cycle.csv", pooled.cycle), ("walks.csv", pooled.walks)):
            write_table(tmp / name, {c: table[c].to_numpy() for c in table.columns})
        write_json(tmp / "summary.json", {**pooled.summary(), "gait_profile": session_profile(pooled)
                                          if profile is None else profile})
    return target


def run_session(folder: str | Path, cfg: PipelineConfig, **batch) -> SessionRun:
    """Run the pipeline on every walk of the session ``folder`` (``batch``: the options of
    :func:`gaitcli.run.batch.run_batch`), then pool its strides (module docstring)."""
    folder = Path(folder).resolve()
    walks = session_folder(folder)
    if walks is None:
        raise InputError(folder, None, "no walks (expected the session's walking C3Ds beside its static, or "
                                       "`trials:` in subject.yaml naming them)")
    check_output_folder(folder / "gait_out" / SESSION_OUTPUT)
    summary_path = folder / "gait_out" / BATCH_SUMMARY
    result = run_batch(folder, cfg, summary_path=summary_path, **batch)
    pooled = None
    if "idyn" in stages_of(cfg):
        # the walks whose idyn this batch made or found current (a failed walk's older outputs are not its own)
        done = {r.trial for r in result.rows if r.stage == "idyn" and r.status != "failed"}
        read = [read_walk(w, cfg) for w in walks if w.relative_to(folder).as_posix() in done]
        read = [w for w in read if w is not None]
        if read:
            pooled = pool(read)
            conventions = tuple(str(w.features.get("angle_frames")) for w in read if w.features.get("angle_frames"))
            profile = session_profile(pooled, conventions)
            write_session(folder, pooled, profile)
            if profile.get("warning"):
                warnings.warn(f"session: gait profile score: {profile['warning']}", GaitWarning, stacklevel=2)
    return SessionRun(folder, walks, result, pooled)
