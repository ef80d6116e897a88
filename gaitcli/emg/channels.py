"""Which analog channel records which muscle: a lab's ``{channel label: muscle}`` map, or the labels labs commonly
write (presets).

A muscle is named as the muscle model names it (``muscles.parameters.MUSCLE_NAMES``) or as one of the others labs
record (:data:`OTHER_MUSCLES`), with its side: ``tibialis_anterior_r``. A preset label is a side (``R``, ``L``,
``Right``, ``Left``, before or after) and a muscle word (:data:`MUSCLE_WORDS`: ``TA``, ``TIBA``, ``GAS``, the
French ``JUM``, …) after a vendor's prefix (``Voltage.``, ``EMG.``, …), in any case, with or without spaces:
``RTIBA``, ``R TA``, ``Voltage.RGAS``, ``Left Tibialis anterior``, ``LJUM``.
"""

from __future__ import annotations

import re

from gaitcli.errors import InputError, shown

#: the muscle model's muscles (muscles.parameters.MUSCLE_NAMES; emg/ may not import muscles/)
MODEL_MUSCLES = ("iliopsoas", "rectus_femoris", "glutei", "hamstrings", "vasti", "gastrocnemius",
                 "tibialis_anterior", "soleus")
#: muscles labs record that the model lumps with others or leaves out
OTHER_MUSCLES = ("biceps_femoris", "gluteus_medius", "peroneus_longus", "adductors")
#: the words of a preset label (upper case, letters only) → the muscle
MUSCLE_WORDS = {
    "tibialis_anterior": ("TA", "TIBA", "TIB", "TIBANT", "TIBIALISANTERIOR", "TIBIALIS"),
    "soleus": ("SOL", "SOLEUS"),
    "gastrocnemius": ("GAS", "GASM", "GM", "MG", "GASTROC", "GASTROCNEMIUS", "GASTROCNEMIUSMEDIALIS",
                      "GASTROCNEMIUSLATERALIS", "JUM"),
    "rectus_femoris": ("RF", "REC", "RECFEM", "RECTUS", "RECTUSFEMORIS"),
    "vasti": ("VAS", "VL", "VM", "VASLAT", "VASMED", "VASTUSLATERALIS", "VASTUSMEDIALIS"),
    "hamstrings": ("HAM", "MH", "ST", "SM", "SEMT", "SEMI", "ISC", "SEMITENDINOSUS", "SEMIMEMBRANOSUS",
                   "MEDIALHAMSTRINGS"),
    "biceps_femoris": ("BF", "BIC", "BICFEM", "BICEPSFEMORIS", "LATERALHAMSTRINGS"),
    "glutei": ("GMAX", "GLU", "GLUT", "GLUTMAX", "GRF", "GLUTEUSMAXIMUS"),
    "gluteus_medius": ("GMED", "GLUTMED", "GLUTEUSMEDIUS"),
    "peroneus_longus": ("PL", "PER", "PERL", "PERONEUS", "PERONEUSLONGUS"),
    "adductors": ("ADD", "ADDUCTOR", "ADDUCTORS", "ADDUCTORLONGUS"),
}
_WORD_TO_MUSCLE = {word: muscle for muscle, words in MUSCLE_WORDS.items() for word in words}
#: vendors' prefixes before a channel's own label
PREFIXES = ("VOLTAGE", "EMG", "ANALOG", "SENSOR")
SIDES = {"R": "r", "RIGHT": "r", "L": "l", "LEFT": "l"}


def muscle_of(label: str) -> str | None:
    """The sided muscle (``tibialis_anterior_r``) a preset label names, or None."""
    parts = [p for p in re.split(r"[^A-Z0-9]+", label.strip().upper()) if p]
    while parts and (parts[0] in PREFIXES or re.fullmatch(r"(?:%s)\d+" % "|".join(PREFIXES), parts[0])):
        parts = parts[1:]  # "Voltage.RGAS", "EMG 3 R TA"
    while parts and parts[0].isdigit():
        parts = parts[1:]
    if len(parts) >= 2 and parts[0] in SIDES:  # R TA, Left Tibialis anterior
        side, word = SIDES[parts[0]], "".join(parts[1:])
    elif len(parts) >= 2 and parts[-1] in SIDES:  # TA R
        side, word = SIDES[parts[-1]], "".join(parts[:-1])
    else:  # the side in the word: RTIBA, LJUM, TAR
        word = "".join(parts)
        for side_word, side in SIDES.items():
            if word.startswith(side_word) and word[len(side_word):] in _WORD_TO_MUSCLE:
                return f"{_WORD_TO_MUSCLE[word[len(side_word):]]}_{side}"
            if word.endswith(side_word) and word[:-len(side_word)] in _WORD_TO_MUSCLE:
                return f"{_WORD_TO_MUSCLE[word[:-len(side_word)]]}_{side}"
        return None
    return f"{_WORD_TO_MUSCLE[word]}_{side}" if word in _WORD_TO_MUSCLE else None


def sided_muscle(value, where: str, path=None) -> str:
    """A map's muscle name, lower case, checked: a known muscle with ``_r`` or ``_l``; else an InputError naming
    ``where`` (the map's key) in ``path``."""
    known = MODEL_MUSCLES + OTHER_MUSCLES
    text = value.strip().lower() if isinstance(value, str) else ""
    if not (text[-2:] in ("_r", "_l") and text[:-2] in known):
        raise InputError(path, where, f"got {shown(value)} (expected a muscle and its side, e.g. "
                                      f"tibialis_anterior_r; muscles: {', '.join(known)})")
    return text


#: how many labels a message lists (the rest counted)
LABELS_LISTED = 8


def _listed(labels: list[str]) -> str:
    """The first :data:`LABELS_LISTED` labels, comma-separated, and how many more."""
    more = len(labels) - LABELS_LISTED
    return ", ".join(labels[:LABELS_LISTED]) + (f" and {more} more" if more > 0 else "")


def channel_map(labels, mapping: dict | None = None, *, where: str = "emg", source=None) -> dict[str, str]:
    """``{channel label: sided muscle}`` of a trial's analog ``labels``: ``mapping`` as given (every label in it
    must be in the trial: an InputError naming those missing, ``source`` the file), else every label a preset
    names. Two channels of one muscle: an InputError naming both."""
    labels = [str(label).strip() for label in labels]
    if mapping:
        out = {str(label).strip(): sided_muscle(muscle, f"{where}.{label}", source)
               for label, muscle in mapping.items()}
        missing = [label for label in out if label not in labels]
        if missing:
            said = f"channels {_listed(missing)} are" if len(missing) > 1 else f"channel {missing[0]} is"
            raise InputError(source, where, f"{said} not in the trial (its analog channels: "
                                            f"{_listed(labels) or 'none'})")
    else:
        out = {label: muscle for label in labels if (muscle := muscle_of(label))}
    seen: dict[str, str] = {}
    for label, muscle in out.items():
        if muscle in seen:
            raise InputError(source, where, f"channels {seen[muscle]} and {label} both record {muscle} (expected "
                                            "one channel per muscle: name one in the emg map)")
        seen[muscle] = label
    return out
