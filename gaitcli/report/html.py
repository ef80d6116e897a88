"""``gait report``: one self-contained HTML page per trial, prediction or study, and an index for a batch.

A page embeds its figures as data URIs (PNG, the prediction's GIF): it opens from a file or an e-mail
attachment with no network, and its Content-Security-Policy allows nothing else to load. Figures are drawn
again from the stages' HDF5 files (:mod:`gaitcli.report.plots`, :mod:`gaitcli.report.predict_plots`), the
cycle figures over the grey normal band (:mod:`gaitcli.signal.bands`); a study's figures are its own PNGs.
Right is red and left blue throughout, every axis has its unit, every figure a caption, and titles name the
trial folder, never a path outside it.

What a folder is (:func:`find_report`): a session (``gait_out/session/``: the session's page and a page per
walk), a batch (``batch_summary.csv``: an index page and a page per trial), a trial output root (stage folders
with ``summary.json``; or a trial folder holding ``gait_out/``), or a predict study (``study/study.csv`` or
``study.csv``). Every page opens with the warnings its stages gave (their ``summary.json``'s ``warnings``).
"""

from __future__ import annotations

import base64
import csv
import html
import json
import math
import tempfile
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path

from gaitcli import __version__
from gaitcli.errors import InputError, shown
from gaitcli.io.atomic import atomic_path
from gaitcli.io.h5 import file_attrs
from gaitcli.io.outputs import plain_text
from gaitcli.predict.checks import failed_checks
from gaitcli.signal.bands import BAND_SOURCE, Band, speed_outside_band
from gaitcli.signal.profile import GPS_VARIABLES

#: 3.3.3: self-selected normal walking measured in the Orthopaedic University Clinic Heidelberg (26 subjects,
#: Wolf and Rettig), the literature values the dissertation compares Table 3.1 with
NORMAL_FEATURES = {"speed_m_s": 1.38, "stride_length_m": 1.41, "stance_right_pct": 61.0, "stance_left_pct": 61.0,
                   "step_length_right_m": 1.41 / 2, "step_length_left_m": 1.41 / 2}
FEATURES = (("speed_m_s", "walking speed", "m/s", 2), ("stride_length_m", "stride length", "m", 2),
            ("period_s", "stride period", "s", 2), ("stance_right_pct", "stance, right", "% of cycle", 1),
            ("stance_left_pct", "stance, left", "% of cycle", 1),
            ("double_stance_pct", "double stance", "% of cycle", 1),
            ("step_length_right_m", "step length, right", "m", 2), ("step_length_left_m", "step length, left", "m", 2),
            ("step_width_m", "step width", "m", 2))
STYLE = """
body { font-family: system-ui, sans-serif; margin: 2em auto; max-width: 1250px; color: #222; }
h1 { font-size: 1.5em; margin-bottom: 0.2em; } \
h2 { font-size: 1.15em; margin-top: 1.8em; border-bottom: 1px solid #ccc; }
table { border-collapse: collapse; margin: 0.5em 0; } td, th { padding: 0.2em 0.8em; border-bottom: 1px solid #eee;
text-align: right; } th { background: #f4f4f4; } td:first-child, th:first-child { text-align: left; }
figure { margin: 1em 0; } figure img { max-width: 100%; border: 1px solid #eee; }
figcaption { font-size: 0.9em; color: #444; max-width: 1100px; } .meta { color: #666; font-size: 0.9em; }
.right { color: #d62728; } .left { color: #1f77b4; } .bad { color: #b00; font-weight: bold; }
.warnings { background: #fff4e5; border-left: 4px solid #e69500; padding: 0.4em 1em; }
@media print { body { margin: 0; max-width: none; font-size: 10pt; } h2 { break-before: auto; }
figure, table { break-inside: avoid; } @page { size: A4; margin: 12mm; } }
"""
#: nothing but inline styles and data-URI images may load
CSP = "default-src 'none'; img-src data:; style-src 'unsafe-inline'"


@dataclass(frozen=True)
class Page:
    """One page to write: its path and, for a batch index, its status."""

    path: Path
    title: str
    status: str = ""


#: summary.json's segment_inertias as the report says it
SEGMENT_TABLES_SHOWN = {"de_leva": "de Leva (1996)",
                        "plug_in_gait": "Plug-in Gait's legs (Dempster's, as Vicon Nexus), de Leva's trunk"}


def _data_uri(path: Path) -> str:
    kind = {".png": "image/png", ".gif": "image/gif"}[path.suffix.lower()]
    return f"data:{kind};base64,{base64.b64encode(path.read_bytes()).decode('ascii')}"


def _figure(path: Path, caption: str) -> str:
    return (f'<figure><img src="{_data_uri(path)}" alt="{html.escape(caption)}">'
            f"<figcaption>{html.escape(caption)}</figcaption></figure>")


def _table(header, rows) -> str:
    head = "".join(f"<th>{html.escape(str(h))}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in row) + "</tr>" for row in rows)
    return f"<table><tr>{head}</tr>{body}</table>"


def _page(title: str, body: str) -> str:
    stamp = datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    return (f'<!DOCTYPE html><html lang="en"><head><meta charset="utf-8">'
            f'<meta http-equiv="Content-Security-Policy" content="{CSP}">'
            f"<title>{html.escape(title)}</title><style>{STYLE}</style></head><body>{body}"
            f'<p class="meta">gaitcli {__version__}, {stamp}</p></body></html>')


def _summary(folder: Path, numbers: tuple[str, ...]) -> dict:
    """A stage's summary.json (empty without one) whose keys ``numbers`` (those the page shows) are numbers or
    absent; damaged or foreign is an InputError naming it."""
    path = folder / "summary.json"
    if not path.is_file():
        return {}
    try:
        summary = json.loads(path.read_text(encoding="utf-8"))
    except (ValueError, RecursionError) as exc:  # JSONDecodeError, UnicodeDecodeError; nested too deeply
        raise InputError(path, None, f"not valid JSON ({type(exc).__name__}; expected a stage's summary)") from None
    except OSError as exc:
        raise InputError(path, None, f"cannot be read ({exc.strerror})") from None
    if not isinstance(summary, dict):
        raise InputError(path, None, f"holds a {type(summary).__name__} (expected a mapping: a stage's summary)")
    for key in numbers:  # NaN is allowed: a feature that could not be measured
        if not _number_or_null(summary.get(key)):
            raise InputError(path, key, f"got {shown(summary[key])} (expected a number)")
    return summary


def _number_or_null(value) -> bool:
    """Whether a summary's value is a number (NaN allowed; no bool, nothing beyond 1e300) or null."""
    return value is None or (not isinstance(value, bool) and isinstance(value, (int, float)) and
                             not abs(value) > 1e300)


def _records(folder: Path, summary: dict, key: str, numbers: tuple[str, ...]) -> dict[str, dict]:
    """``summary[key]``, a mapping of name → record (a muscle's figures), each record's ``numbers`` numbers or
    null; anything else an InputError naming the summary and the key."""
    value = summary.get(key) or {}
    path = folder / "summary.json"
    if not isinstance(value, dict) or not all(isinstance(v, dict) for v in value.values()):
        raise InputError(path, key, f"got {shown(value)} (expected a mapping of muscle → its figures)")
    for name, record in value.items():
        for field in numbers:
            if not _number_or_null(record.get(field)):
                raise InputError(path, f"{key}.{name}.{field}", f"got {shown(record[field])} (expected a number)")
    return value


def _number(value, digits: int) -> str:
    """A number for people with ``digits`` decimals; "—" for none or NaN (never the text "nan")."""
    return "—" if value is None or not math.isfinite(float(value)) else f"{float(value):.{digits}f}"


def _mean_sd(mean, sd, digits: int) -> str:
    """"mean ± SD" for people; the mean alone where the SD is missing or NaN (one walk), "—" without a mean."""
    if _number(mean, digits) == "—" or _number(sd, digits) == "—":
        return _number(mean, digits)
    return f"{_number(mean, digits)} ± {_number(sd, digits)}"


def _rows(path: Path, columns: tuple[str, ...], numbers: tuple[str, ...] = ()) -> list[dict]:
    """The rows of a CSV table gaitcli wrote (batch_summary.csv, study.csv): every one of ``columns`` present,
    ``numbers`` numeric or empty; anything else is an InputError naming the file, the row and the column."""
    try:
        with path.open(encoding="utf-8", newline="") as fh:
            rows = list(csv.DictReader(fh))
    except (UnicodeDecodeError, csv.Error) as exc:
        raise InputError(path, None, f"not a CSV table ({type(exc).__name__})") from None
    except OSError as exc:
        raise InputError(path, None, f"cannot be read ({exc.strerror})") from None
    for k, row in enumerate(rows, start=2):  # line 1 is the header
        for column in columns:
            if row.get(column) is None:
                raise InputError(path, f"line {k}: {column}", f"missing (expected the columns "
                                                              f"{', '.join(columns)})")
        for column in numbers:
            try:
                float(row[column] or 0)
            except ValueError:
                raise InputError(path, f"line {k}: {column}", f"got {shown(row[column])} (expected a number)") \
                    from None
    return rows


def _trial_subject(trial_folder: Path | None):
    """The trial's subject.yaml, read, when the output root sits in its trial folder (None without one)."""
    if trial_folder is None or not (trial_folder / "subject.yaml").is_file():
        return None
    try:
        from gaitcli.kinematics.subject import load_subject

        return load_subject(trial_folder / "subject.yaml")
    except InputError:
        return None


def _subject(trial_folder: Path | None, s=None) -> str:
    """The subject line from the trial's subject.yaml (``s``, where already read)."""
    s = s if s is not None else _trial_subject(trial_folder)
    if s is None:
        return ""
    mass = "mass from the trial" if s.mass_kg is None else f"{s.mass_kg:g} kg"
    return f"{s.sex}, {mass}, {s.stature_m:g} m" + (f", marker set {s.marker_set}" if s.marker_set else "")


def _muscle_variant(folder: str) -> str:
    """A muscle output folder's name for people: ``eid_l_swing`` → "EID, left leg, swing"."""
    return folder.upper().replace("_L", ", left leg").replace("_SWING", ", swing").replace("_CB", ", Σ(F/Fmax)³")


#: leg length (floor to greater trochanter) per stature, for a trial's dimensionless speed (Winter's segment
#: proportions, 0.530 H); a stature of :data:`DEFAULT_STATURE_M` where the trial folder gives none
LEG_PER_STATURE = 0.530
DEFAULT_STATURE_M = 1.70


def trial_body(root: Path, name: str, band: Band | None, work: Path) -> str:
    """The sections of a trial output root's page (``root``: the folder holding filter/, idyn/, ...)."""
    from gaitcli.report.plots import filter_figures, idyn_figures, muscle_figures

    trial_folder = root.parent if root.name == "gait_out" else None
    read = _trial_subject(trial_folder)
    subject = _subject(trial_folder, read)
    stature_m = read.stature_m if read is not None else DEFAULT_STATURE_M
    idyn = _summary(root / "idyn", ("mass_kg", *(key for key, *_ in FEATURES)))
    if not subject and idyn.get("mass_kg"):
        subject = f"body mass {float(idyn['mass_kg']):.1f} kg"
    parts = [f"<h1>{html.escape(name)}</h1>",
             f'<p class="meta">{html.escape(subject)}{"; " if subject else ""}outputs in {html.escape(root.name)}/; '
             f'<span class="right">right in red</span>, <span class="left">left in blue</span></p>',
             warnings_block(stage_warnings(root))]
    if idyn:
        rows = [(label, _number(idyn.get(key), digits), _number(NORMAL_FEATURES.get(key), digits), unit)
                for key, label, unit, digits in FEATURES]
        parts.append("<h2>Gait features (Table 3.1)</h2>" + _table(
            ("feature", "this trial", "normal walking (3.3.3: 26 subjects, Heidelberg)", "unit"), rows))
        figures = idyn_figures(root / "idyn" / "idyn.h5", work / "idyn", title=name, band=band)
        band_text = f"the grey band is the normal mean ± 1 SD ({band.source})" if band else "no normal band given"
        speed = idyn.get("speed_m_s")
        unlike = (speed_outside_band(float(speed), LEG_PER_STATURE * stature_m)  # the package band's
                  if band and band.source == BAND_SOURCE and isinstance(speed, (int, float)) and speed > 0 else None)
        if unlike:  # in the captions (escaped there) and as a line of its own
            band_text += f". Warning: {unlike}"
        captions = {
            "cycle.png": f"Sagittal hip, knee and ankle angles (deg), joint moments (N·m/kg, internal; signs as the "
                         f"axis labels and joint_moments.csv say: by default Plug-in Gait's, extensor and "
                         f"plantarflexor positive) and joint powers (W/kg, generated positive) over the gait cycle "
                         f"from heel strike to heel strike: mean ± SD of each side's strides; {band_text}. Moments "
                         f"and powers are blank where the foot's load was not measured.",
            "cycle_frontal.png": f"Frontal angles (deg) and moments (N·m/kg) over the gait cycle: hip adduction, knee "
                                 f"varus, ankle inversion positive; {band_text}.",
            "residuals.png": "Pelvis residual force (N) and moment (N·m): what the model and the measured ground "
                             "reactions leave unexplained (3.22); grey where a foot on the ground stood off the "
                             "plates (the residuals are meaningless there). Lines: heel strike (solid), toe off "
                             "(dashed)."}
        parts.append("<h2>Joint angles and moments</h2>"
                     + (f"<p><strong>Warning:</strong> {html.escape(unlike)}.</p>" if unlike else "")
                     + "".join(_figure(p, captions[p.name]) for p in figures if p.name != "residuals.png"))
        parts.append("<h2>Pelvis residuals</h2>" + "".join(_figure(p, captions[p.name]) for p in figures
                                                           if p.name == "residuals.png"))
    if (root / "filter" / "filter.h5").is_file():
        mass = idyn.get("mass_kg")
        figures = filter_figures(root / "filter" / "filter.h5", work / "filter", title=name, body_mass_kg=mass)
        unit = f"% of body weight ({mass:.1f} kg)" if mass else "N"
        captions = {"markers.png": "Marker trajectories (m), raw and after the zero-lag low-pass filter.",
                    "grf.png": f"Ground reaction per foot ({unit}): vertical, fore-aft and mediolateral (positive to "
                               "the left), and its centre of pressure, with the gait events (heel strike solid, toe "
                               "off dashed)."}
        parts.append("<h2>Signals</h2>" + "".join(_figure(p, captions.get(p.name, p.stem)) for p in figures))
    if (root / "emg" / "emg.h5").is_file():
        parts.append(emg_section(root / "emg", name, work / "emg"))
    for h5 in sorted((root / "muscles").glob("*/muscles.h5")) if (root / "muscles").is_dir() else ():
        method = h5.parent.name
        summary = _summary(h5.parent, ("metabolic_cost_J", "cost_of_transport_J_per_m"))
        figures = muscle_figures(h5, work / "muscles" / method, title=name)
        cost = summary.get("metabolic_cost_J")
        state = "" if summary.get("converged", True) else ' <span class="bad">(did not converge)</span>'
        variant = _muscle_variant(method)
        parts.append(f"<h2>Muscles: {html.escape(variant)}{state}</h2>"
                     f"<p>metabolic cost of one leg over the interval: {_number(cost, 1)} J; cost of transport "
                     f"{_number(summary.get('cost_of_transport_J_per_m'), 1)} J/m</p>")
        names = {"forces.png": "forces (N)", "activations.png": "activations (0–1)",
                 "excitations.png": "excitations (0–1)", "metabolic_cost.png": "metabolic energy per muscle (J)"}
        parts += [_figure(p, f"The 8 muscles of Table A.1: {names.get(p.name, p.stem)}, {method.upper()}.")
                  for p in figures if p.name != "activations_emg.png"]
        if summary.get("emg"):
            agreement = _records(h5.parent, summary, "emg", ("correlation", "lag_s", "on_off_agreement_pct"))
            rows = [(muscle.replace("_", " "), str(values.get("channel", "")), _number(values.get("correlation"), 2),
                     _number(None if values.get("lag_s") is None else 1e3 * values["lag_s"], 0),
                     _number(values.get("on_off_agreement_pct"), 0)) for muscle, values in agreement.items()]
            parts.append("<h3>Activations against the trial's EMG (4.5.4)</h3>" + _table(
                ("muscle", "EMG channel", "r", "lag (ms, EMG leading)", "on/off agreement (%)"), rows))
            parts += [_figure(p, f"{method.upper()} activations (colour) over the EMG envelopes (black), normalised "
                                 "to the peak of the mean over strides; bars: on (activation above, EMG below).")
                      for p in figures if p.name == "activations_emg.png"]
    if (root / "predict" / "predict.h5").is_file():
        parts.append(predict_section(root / "predict", name, work / "predict"))
    return "".join(parts)


def emg_section(folder: Path, name: str, work: Path) -> str:
    """The EMG section: per muscle its channel, strides, where its mean envelope peaks and how much of the cycle
    it is on; the clipping channels; the raw and cycle figures."""
    from gaitcli.report.emg_plots import emg_figures, muscle_title

    summary = _summary(folder, ("strides_right", "strides_left"))
    muscles = _records(folder, summary, "muscles", ("strides", "peak_pct", "on_pct"))
    rows = [(muscle_title(muscle), str(values.get("channel", "")), _number(values.get("strides"), 0),
             _number(values.get("peak_pct"), 0), _number(values.get("on_pct"), 0))
            for muscle, values in muscles.items()]
    reference = "an MVC trial" if summary.get("normalisation") == "mvc" else "the peak of its mean over strides"
    clipped = summary.get("clipped") or []
    note = (f' <span class="bad">Clipping: {html.escape(", ".join(map(str, clipped)))}</span> (envelopes too low '
            "where the signal is at the amplifier's limit).") if isinstance(clipped, list) and clipped else ""
    figures = emg_figures(folder / "emg.h5", work, title=name)
    captions = {"emg_raw.png": "Raw EMG (mV, mean removed), its linear envelope and on/off over the trial.",
                "emg_cycle.png": f"Each muscle's envelope over its foot's gait cycle, mean ± SD over the strides "
                                 f"(normalised to {reference}), and its on/off per stride."}
    return (f"<h2>EMG</h2><p>{len(rows)} channels, {summary.get('strides_right', 0)} right and "
            f"{summary.get('strides_left', 0)} left strides; envelopes normalised to {reference}.{note}</p>"
            + _table(("muscle", "channel", "strides", "mean envelope peaks at (% cycle)", "on (% of cycle)"), rows)
            + "".join(_figure(p, captions.get(p.name, p.stem)) for p in figures))


def predict_section(folder: Path, name: str, work: Path) -> str:
    """A prediction's figures (stick figure, animation, angles and GRF against its reference, moments,
    muscles, the prosthesis curve) and key figures."""
    from gaitcli.report.predict_plots import predict_figures

    summary = _summary(folder, ("speed_m_s", "cost_of_transport_J_per_m", "deviation", "objective"))
    figures = predict_figures(folder / "predict.h5", work, title=name)
    state = "" if summary.get("converged", True) else ' <span class="bad">(did not converge)</span>'
    rows = [("speed", _number(summary.get("speed_m_s"), 2), "m/s"),
            ("metabolic cost of transport Et", _number(summary.get("cost_of_transport_J_per_m"), 1), "J/m"),
            ("deviation from the reference Jdev", _number(summary.get("deviation"), 2), ""),
            ("objective J", _number(summary.get("objective"), 3), "")]
    captions = {
        "angles.png": "Predicted hip, knee and ankle angles (deg) over the cycle against the reference (grey, mean ± "
                      "1 SD).",
        "grf.png": "Predicted ground reactions (N/kg) against the reference (grey, mean ± 1 SD).",
        "moments.png": "Joint moments (N·m): inverse dynamics of the predicted motion and the muscles' and passive "
                       "structures' moments.", "muscles.png": "Muscle activations over the cycle (0–1).",
        "stick.png": "Stick figure of the predicted cycle.", "walk.gif": "The predicted gait, animated.",
        "prosthesis.png": "The prosthetic ankle's spring moment (N·m) against its angle (rad), beside Table A.7's "
                          "feet."}
    body = "".join(_figure(p, captions.get(p.name, p.stem)) for p in figures)
    return (f"<h2>Predicted gait{state}</h2>" + prediction_status(summary)
            + _table(("", "value", "unit"), rows) + body)


def prediction_status(summary: dict) -> str:
    """A prediction's outcome first: converged or not (IPOPT's status), in how many iterations, and which of
    the gait checks (stance, double support, knee swing, vertical GRF, ankle moment peak) failed."""
    checks = summary.get("gait_checks") if isinstance(summary.get("gait_checks"), dict) else {}
    failed = failed_checks(checks)
    converged = summary.get("converged", True)
    text = (f"{'converged' if converged else 'did not converge'} ({html.escape(str(summary.get('status', '')))}) in "
            f"{html.escape(str(summary.get('iterations', '—')))} iterations; "
            + (f"gait checks failed: {html.escape(', '.join(failed))}" if failed else
               f"all {len(checks)} gait checks passed" if checks else "no gait checks"))
    return f'<p class="{"" if converged and not failed else "bad"}">{text}</p>'.replace(' class=""', "")


def study_body(folder: Path) -> str:
    """A predict study's page: its table and its figures (study.png, curves.png)."""
    rows = _rows(folder / "study.csv", ("case", "speed_m_s", "weights", "condition", "objective",
                                        "cost_of_transport_J_per_m", "deviation", "converged"),
                 ("objective", "cost_of_transport_J_per_m", "deviation"))
    header = ("case", "speed (m/s)", "weights", "condition", "J", "Et (J/m)", "Jdev", "converged")
    table = [(r["case"], r["speed_m_s"], r["weights"], r["condition"], _number(r["objective"] or None, 3),
              _number(r["cost_of_transport_J_per_m"] or None, 1), _number(r["deviation"] or None, 2),
              "yes" if r["converged"] in ("True", "true", "1") else "NO") for r in rows]
    parts = [f"<h1>Study {html.escape(folder.parent.name)}/{html.escape(folder.name)}</h1>",
             "<h2>Cases (as Table 5.3)</h2>" + _table(header, table)]
    captions = {"study.png": "J per condition, weight set and speed (as Fig. 5.15).",
                "curves.png": "The optimal prostheses' spring moment (N·m) against ankle angle (rad) beside the "
                              "commercial feet (as Fig. 5.16)."}
    for name, caption in captions.items():
        path = folder / name
        if path.is_file():
            if not path.resolve().is_relative_to(folder.resolve()):
                raise InputError(path, None, "links outside the study folder (expected the figure the study drew)")
            parts.append(_figure(path, caption))
    return "".join(parts)


def stage_warnings(root: Path) -> list[tuple[str, str]]:
    """(stage folder, message) of every warning the stages below the output root ``root`` recorded."""
    found = []
    for path in sorted(root.glob("*/summary.json")) + sorted(root.glob("muscles/*/summary.json")):
        said = _summary(path.parent, ()).get("warnings") or []
        found += [(path.parent.relative_to(root).as_posix(), str(w)) for w in said if isinstance(w, str)]
    return found


def warnings_block(found: list[tuple[str, str]]) -> str:
    """The warnings at the top of a page, one line each (or that there were none)."""
    if not found:
        return '<p class="meta">No stage gave a warning.</p>'
    lines = "".join(f"<li>{html.escape(where)}: {html.escape(message)}</li>" for where, message in found)
    return f'<div class="warnings"><strong>{len(found)} warning{"s" * (len(found) != 1)}</strong><ul>{lines}</ul></div>'


def side_rows(strides) -> list[list[str]]:
    """A session's temporal-spatial parameters per side from its strides.csv (complete strides): speed, cadence
    (two steps a stride: 120 / period, steps/min), stride length and period, step length and width (the step
    each stride opens with), stance and swing (% of the cycle), single support (the other foot's swing) and double
    support (stance − single support), beside the values 3.3.3's normal walking implies (none for step width)."""
    import numpy as np

    complete = strides[strides.status != "rejected"]
    by_side = {side: complete[complete.side == side] for side in ("r", "l")}
    stance = {side: by_side[side].stance_pct.to_numpy(float) for side in by_side}
    normal_stance = NORMAL_FEATURES["stance_right_pct"]
    normal_period = NORMAL_FEATURES["stride_length_m"] / NORMAL_FEATURES["speed_m_s"]

    def cell(values, digits):
        values = np.asarray(values, float)
        values = values[np.isfinite(values)]
        if not values.size:
            return "—"
        sd = f" ± {values.std(ddof=1):.{digits}f}" if values.size > 1 else ""
        return f"{values.mean():.{digits}f}{sd}"

    other = {"r": "l", "l": "r"}
    rows = [("walking speed (m/s)", lambda s: by_side[s].speed_m_s, NORMAL_FEATURES["speed_m_s"], 2),
            ("cadence (steps/min)", lambda s: 120.0 / by_side[s].period_s, 120.0 / normal_period, 1),
            ("stride length (m)", lambda s: by_side[s].stride_length_m, NORMAL_FEATURES["stride_length_m"], 2),
            ("stride period (s)", lambda s: by_side[s].period_s, normal_period, 2),
            ("step length (m)", lambda s: by_side[s].get("step_length_m", ()), NORMAL_FEATURES["step_length_right_m"],
             2),
            ("step width (m)", lambda s: by_side[s].get("step_width_m", ()), None, 2),
            ("stance = foot off (% of cycle)", lambda s: stance[s], normal_stance, 1),
            ("swing (% of cycle)", lambda s: 100.0 - stance[s], 100.0 - normal_stance, 1),
            ("single support (% of cycle)", lambda s: 100.0 - stance[other[s]], 100.0 - normal_stance, 1),
            ("double support (% of cycle)",
             lambda s: stance[s] - (100.0 - np.nanmean(stance[other[s]]) if stance[other[s]].size else np.nan),
             2 * normal_stance - 100.0, 1)]
    return [[label, cell(values("r"), digits), cell(values("l"), digits), _number(normal, digits)]
            for label, values, normal, digits in rows]


def _plates_filter(filtered: dict) -> str:
    """How the filter stage's summary says the plates were treated: "6 Hz forces", "forces unfiltered, each frame
    the mean of its samples"."""
    cutoff = filtered.get("force_cutoff_hz", "—")
    text = "forces unfiltered" if cutoff == 0 else f"{cutoff} Hz forces"
    return text + (", each frame the mean of its samples" if filtered.get("plate_frames") == "mean" else "")


def session_body(root: Path, band: Band | None, work: Path, walk_pages: dict[str, Path]) -> str:
    """The session's page (``root``: its ``gait_out``): subject and session, every walk's warnings, Table 3.1
    per walk beside normal walking, the strides used and rejected, the Gait Profile Score, the mean ± SD
    figures of every stride."""
    import pandas as pd

    from gaitcli.report.session_plots import session_figures

    session = root / "session"
    folder = root.parent
    summary = _summary(session, ())
    walks = pd.read_csv(session / "walks.csv")
    strides = pd.read_csv(session / "strides.csv", keep_default_na=False, na_values=["NaN"])
    names = [w for w in walks.walk if w not in ("mean", "sd")]
    first = _summary(root / names[0] / "idyn", ()) if names else {}
    filtered = _summary(root / names[0] / "filter", ()) if names else {}
    subject = _subject(folder)
    facts = [("subject", subject or f"body mass {first.get('mass_kg', '—')} kg"),
             ("walks", f"{len(names)}: " + ", ".join(names)),
             ("marker set", first.get("marker_set", "—")), ("hip joint centres", first.get("hip_joint_centre", "—")),
             ("segment inertias", SEGMENT_TABLES_SHOWN.get(first.get("segment_inertias"), "—")),
             ("static", first.get("static") or "none (standing frames of the walk)"),
             ("filter cut-off", f"{filtered.get('cutoff_hz', '—')} Hz markers, " + _plates_filter(filtered)),
             ("angles", f"{first.get('angles', '—')} ({first.get('angle_frames', '—')}); moments "
                        f"{first.get('moment_convention', '—')}")]
    parts = [f"<h1>Session {html.escape(folder.name)}</h1>",
             _table(("session", ""), facts),
             "<h2>Warnings</h2>",
             warnings_block([(f"{walk} / {where}", message) for walk in names
                             for where, message in stage_warnings(root / walk)])]
    rows = []
    for key, label, unit, digits in FEATURES:
        values = dict(zip(walks.walk, walks[key])) if key in walks else {}
        rows.append([f"{label} ({unit})", *[_number(values.get(w), digits) for w in names],
                     _mean_sd(values.get("mean"), values.get("sd"), digits),
                     _number(NORMAL_FEATURES.get(key), digits)])
    parts += ["<h2>Temporal-spatial parameters (Table 3.1)</h2>",
              _table(("", *names, "session mean ± SD", "normal (3.3.3)"), rows),
              "<p>Per side, over every complete stride of every walk (mean ± SD; normal: from 3.3.3's speed, "
              "stride and stance, walking having no flight phase):</p>",
              _table(("", "right", "left", "normal"), side_rows(strides))]
    counts = summary.get("strides", {})
    used = [[side, *[counts.get(side, {}).get(k, 0) for k in ("used", "kinematics only", "rejected")]]
            for side in ("r", "l")]
    rejected = strides[strides.status != "used"]
    parts += ["<h2>Strides</h2>", _table(("side", "used", "kinematics only", "rejected"), used),
              _table(("walk", "side", "start (s)", "status", "reason"),
                     [[r.walk, r.side, f"{r.start_s:.2f}", r.status, r.reason] for r in rejected.itertuples()])]
    profile = summary.get("gait_profile") or {}
    if profile:
        gvs = profile.get("gvs_deg", {})
        columns = {variable.removesuffix("_deg"): pattern for pattern, variable in GPS_VARIABLES}
        rows = [[label, *[_number(gvs.get(side, {}).get(columns[label].format(s=s)), 1)
                          for side, s in (("right", "r"), ("left", "l"))]]
                for label in sorted(columns) if any(columns[label].format(s=s) in gvs.get(side, {})
                                                    for side, s in (("right", "r"), ("left", "l")))]
        parts += ["<h2>Gait Profile Score</h2>",
                  f"<p>GPS {_number(profile.get('gps_deg'), 1)}° (right {_number(profile.get('gps_right_deg'), 1)}°,"
                  f" left {_number(profile.get('gps_left_deg'), 1)}°) against the band "
                  f"{html.escape(str(profile.get('band', '')))}: the RMS difference from the normal mean over the "
                  "cycle, per variable (GVS) and over the variables (Baker et al. 2009).</p>",
                  *([f"<p><strong>Warning:</strong> {html.escape(str(profile['warning']))}.</p>"]
                    if profile.get("warning") else []),
                  _table(("variable (GVS, deg)", "right", "left"), rows)]
    muscles = [[walk, _muscle_variant(path.parent.name), "yes" if summary.get("converged") else "no",
                _number(summary.get("metabolic_cost_J"), 1), _number(summary.get("cost_of_transport_J_per_m"), 1)]
               for walk in names for path in sorted((root / walk / "muscles").glob("*/summary.json"))
               for summary in [_summary(path.parent, ("metabolic_cost_J", "cost_of_transport_J_per_m"))]]
    if muscles:
        parts += ["<h2>Muscles</h2>", "<p>Each walk's muscle stage (one leg over its interval; the walk's page has "
                                      "the forces, activations and excitations):</p>",
                  _table(("walk", "method", "converged", "metabolic cost (J)", "cost of transport (J/m)"), muscles)]
    figures = session_figures(session, work / "session", title=folder.name, band=band)
    captions = {"kinematics.png": "Kinematics (deg) in three planes, each side's mean ± SD over every stride of "
                                  "every walk (right red, left blue; n strides), over the grey normal band; foot off "
                                  "of each side dashed, normal walking's (61 %, 3.3.3) dash-dotted.",
                "kinetics.png": "Joint moments (N·m/kg, Plug-in Gait's signs) in three planes, total joint powers "
                                "(W/kg, generated positive) and the foot's ground reaction (% body weight: vertical, "
                                "anterior, medial) of the strides whose foot was on the force plates."}
    parts += ["<h2>Kinematics and kinetics</h2>", *[_figure(p, captions[p.name]) for p in figures]]
    links = "".join(f'<li><a href="{html.escape(path.relative_to(root).as_posix())}">{html.escape(walk)}</a></li>'
                    for walk, path in walk_pages.items())
    parts += ["<h2>Walks</h2>", f"<ul>{links}</ul>"]
    return "".join(parts)


def compare_body(compare: Path, band: Band | None, work: Path) -> str:
    """The page of a comparison of conditions (``compare``: its ``OUT/compare`` folder): the conditions' warnings,
    Table 3.1 per condition, where each differs from the first (SPM) and the overlaid mean ± SD figures."""
    import pandas as pd

    from gaitcli.report.compare_plots import compare_figures

    summary = _summary(compare, ())
    names = [str(n) for n in summary.get("conditions", [])]
    conditions = pd.read_csv(compare / "conditions.csv").assign(condition=lambda t: t.condition.astype(str))
    spans = pd.read_csv(compare / "spm.csv").assign(condition=lambda t: t.condition.astype(str))
    said = summary.get("warnings", {})
    parts = [f"<h1>Conditions compared: {html.escape(', '.join(names))}</h1>", "<h2>Warnings</h2>",
             warnings_block([(name, message) for name in names for message in said.get(name, [])])]
    by_name = conditions.set_index("condition")
    rows = [[f"{label} ({unit})", *[_number(by_name.loc[n, key], digits) for n in names],
             _number(NORMAL_FEATURES.get(key), digits)] for key, label, unit, digits in FEATURES]
    rows.append(["strides (right / left)",
                 *[f"{by_name.loc[n, 'strides_right']} / {by_name.loc[n, 'strides_left']}" for n in names], ""])
    parts += ["<h2>Temporal-spatial parameters (Table 3.1)</h2>", _table(("", *names, "normal (3.3.3)"), rows)]
    tested = summary.get("variables_tested", {})
    units = {"_moment_per_kg": "N·m/kg", "_W_per_kg": "W/kg"}
    found = [[s.condition, {"r": "right", "l": "left"}.get(s.side, s.side), s.variable,
              f"{s.start_pct:.0f}–{s.end_pct:.0f} %",
              f"{s.largest_difference:+.2f} {next((u for k, u in units.items() if s.variable.endswith(k)), 'deg')}",
              "< 0.001" if s.p < 0.001 else f"{s.p:.3f}"] for s in spans.itertuples()]
    parts += [f"<h2>Where each condition differs from {html.escape(names[0] if names else '')}</h2>",
              f"<p>Statistical parametric mapping: a two-sample t-test over the strides at every point of the cycle "
              f"(spm1d; two-tailed, unequal variances), family-wise α = {summary.get('alpha', '—')} over each "
              "side's variables (Šidák: "
              + ", ".join(f"{html.escape(k)} {v} variables" for k, v in tested.items())
              + "). A span is where |t| exceeds the critical t; its largest difference is the condition's mean minus "
                "the first's.</p>",
              _table(("condition", "side", "variable", "span", "largest difference", "p"), found)
              if found else "<p>No condition differs from the first anywhere along the cycle.</p>"]
    captions = {"kinematics": "Kinematics (deg) in three planes", "kinetics": "Joint moments (N·m/kg, Plug-in "
                "Gait's signs) in three planes, total joint powers (W/kg, generated positive) and the foot's ground "
                "reaction (% body weight: vertical, anterior, medial)"}
    figures = compare_figures(compare, work / "compare", band=band)
    parts += ["<h2>Kinematics and kinetics</h2>"]
    for path in figures:
        kind, side = path.stem.split("_")
        parts.append(_figure(path, f"{captions[kind]}, {'right' if side == 'r' else 'left'} side: each condition's "
                                   f"mean ± SD over its strides (n strides) over the grey normal band; a bar under "
                                   f"the curves in a condition's colour where it differs from {names[0]}."))
    return "".join(parts)


def write_compare_report(compare: Path, band: Band | None) -> Page:
    """``compare/report.html`` of a written comparison (:func:`gaitcli.run.conditions.write_comparison`)."""
    with tempfile.TemporaryDirectory() as tmp:
        title = "conditions compared"
        return Page(write_page(compare / "report.html", title, compare_body(compare, band, Path(tmp))), title)


def find_report(out_dir: Path) -> tuple[str, Path]:
    """(kind, root) of a folder: ``session``, ``batch``, ``study`` or ``trial`` (see the module docstring)."""
    out_dir = Path(out_dir)
    if not out_dir.is_dir():
        raise InputError(out_dir, None, "not found (expected an output folder: a trial's gait_out, a batch's lab "
                                        "folder or a predict study)")
    for root in (out_dir, out_dir / "gait_out"):
        if (root / "session" / "summary.json").is_file():
            return "session", root
    if (out_dir / "batch_summary.csv").is_file():
        return "batch", out_dir
    for study in (out_dir / "study", out_dir):
        if (study / "study.csv").is_file():
            return "study", study
    for root in (out_dir, out_dir / "gait_out"):
        if any((root / s / "summary.json").is_file() for s in ("filter", "idyn", "emg", "predict")) or \
                list(root.glob("muscles/*/summary.json")):
            return "trial", root
    raise InputError(out_dir, None, "holds no stage outputs (expected filter/, idyn/, muscles/ or predict/ with "
                                    "summary.json, a study.csv or a batch_summary.csv)")


def _trial_name(root: Path) -> str:
    """The trial folder's name as the stages recorded it (HDF5 attribute ``trial``), else the output root's folder."""
    for path in sorted(root.glob("*/*.h5")) + sorted(root.glob("muscles/*/*.h5")):
        try:
            name = file_attrs(path).get("trial")
        except InputError:  # a damaged file names no trial
            continue
        if name:
            return str(name)
    root = root.resolve()
    return root.parent.name if root.name == "gait_out" else root.name


def write_page(path: Path, title: str, body: str) -> Path:
    with atomic_path(path) as tmp:
        tmp.write_text(_page(title, body), encoding="utf-8")
    return path


def write_report(out_dir: Path, band: Band | None) -> list[Page]:
    """Write the report pages of ``out_dir`` (a trial's ``report.html`` in its output root, a study's in its
    folder, a batch's ``report.html`` index in the lab folder beside each trial's own page)."""
    kind, root = find_report(Path(out_dir).resolve())
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        if kind == "study":
            return [Page(write_page(root / "report.html", f"study {root.parent.name}", study_body(root)), "study")]
        if kind == "trial":
            name = _trial_name(root)
            return [Page(write_page(root / "report.html", name, trial_body(root, name, band, work)), name)]
        if kind == "session":
            walks = [w for w in _rows(root / "session" / "walks.csv", ("walk",)) if w["walk"] not in ("mean", "sd")]
            pages = {}
            for row in walks:
                walk = row["walk"]
                output = (root / walk).resolve()
                if not output.is_relative_to(root) or not output.is_dir():
                    raise InputError(root / "session" / "walks.csv", "walk", f"got {shown(walk)} (expected a walk's "
                                                                            f"output folder in {root})")
                title = f"{root.parent.name} / {walk}"
                pages[walk] = write_page(output / "report.html", title,
                                         trial_body(output, title, band, work / f"walk{len(pages)}"))
            page = write_page(root / "report.html", f"session {root.parent.name}",
                              session_body(root, band, work, pages))
            return [Page(page, f"session {root.parent.name}", "session"),
                    *[Page(path, walk, "walk") for walk, path in pages.items()]]
        rows = [{**r, "trial": plain_text(r["trial"]), "reason": plain_text(r["reason"])}
                for r in _rows(root / "batch_summary.csv", ("trial", "status", "reason"))]
        for r in rows:  # every page stays in the lab folder
            if Path(r["trial"]).is_absolute() or not (root / r["trial"] / "gait_out").resolve().is_relative_to(root):
                raise InputError(root / "batch_summary.csv", "trial", f"got {shown(r['trial'])}, outside the lab "
                                                                      "folder (expected a trial folder below it)")
        status: dict[str, str] = {}
        for r in rows:
            order = ("failed", "unconverged", "ok", "skipped")
            before = status.get(r["trial"], "skipped")
            status[r["trial"]] = min(before, r["status"], key=lambda s: order.index(s) if s in order else 0)
        reasons = {r["trial"]: r["reason"] for r in rows if r["reason"]}
        pages, links = [], []
        for trial, state in sorted(status.items()):
            walk = Path(trial)  # a session's walk is its C3D; its outputs are in the session's gait_out/<walk>/
            output = (root / walk.parent / "gait_out" / walk.stem if walk.suffix.lower() == ".c3d"
                      else root / trial / "gait_out")
            if state != "failed" and output.is_dir():
                page = write_page(output / "report.html", trial,
                                  trial_body(output, trial, band, work / trial.replace("/", "_")))
                pages.append(Page(page, trial, state))
                link = f'<a href="{html.escape(page.relative_to(root).as_posix())}">{html.escape(trial)}</a>'
            else:
                link = html.escape(trial)
            links.append((link, state, reasons.get(trial, "")))
        table = ("<table><tr><th>trial</th><th>status</th><th>reason</th></tr>" + "".join(
            f"<tr><td>{link}</td><td>{html.escape(s)}</td><td>{html.escape(reason)}</td></tr>"
            for link, s, reason in links) + "</table>")
        index = write_page(root / "report.html", f"batch {root.name}",
                           f"<h1>Batch {html.escape(root.name)}</h1><p>{len(links)} trials</p>{table}")
        return [Page(index, f"batch {root.name}", "index"), *pages]
