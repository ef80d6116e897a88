"""Reading a Vicon subject file (``.vsk``): the kinematic model's name and the subject's parameters.

A ``.vsk`` is XML: ``<KinematicModel MODEL="PlugInGait FullBody Ai">`` holding ``<Parameters>`` with
``<StaticParameter NAME="Bodymass" VALUE="85" …/>`` (the measurements a lab types in) and ``<Parameter …/>``
(the ones Nexus fits). Their values are in Vicon's units — mm, kg, radians — exactly as Nexus copies them into
a C3D file's ``PROCESSING`` group, so they are returned under the same keys ``Recording.subject_metadata`` uses:
``{"PROCESSING:<NAME>": value}``. The C3D spells some names shorter (``RKneeWidth``); the vsk's own names are kept.

Untrusted files are read with bounded cost and without surprises:

- at most ``MAX_VSK_BYTES`` (a full-body subject file is about 60 kB) and ``MAX_PARAMETERS`` parameters;
- a document type declaration is refused outright (no entities, internal or external, are ever expanded);
- expat is driven directly, building no tree: only the parameters are kept.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

from gaitcli.errors import InputError, shown

MAX_VSK_BYTES = 5_000_000
MAX_PARAMETERS = 10_000
#: the elements whose NAME and VALUE are parameters, directly inside ``<KinematicModel><Parameters>``
PARAMETER_ELEMENTS = ("StaticParameter", "Parameter")
#: a parameter name: an identifier, as Vicon's expressions (``0.1288 * LeftLegLength``) use them
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,99}")
EXPECTED = "expected a Vicon subject file: XML with a <KinematicModel> root element"


@dataclass(frozen=True)
class VskSubject:
    """A ``.vsk``'s kinematic model (``"PlugInGait FullBody Ai"``, "" when unnamed) and its numeric parameters,
    ``{"PROCESSING:<NAME>": value}`` in Vicon's units (mm, kg, rad). Parameters without a VALUE are absent."""

    source: Path
    model: str
    parameters: dict[str, float] = field(default_factory=dict)

    def value(self, name: str) -> float | None:
        """The parameter ``name`` (the vsk's spelling, e.g. ``"Bodymass"``), None when absent."""
        return self.parameters.get(f"PROCESSING:{name}")


class _Refused(Exception):
    def __init__(self, line: int | None, problem: str):
        self.line, self.problem = line, problem


class _Reader:
    """expat callbacks: the root's MODEL and the parameters directly inside ``<Parameters>``."""

    def __init__(self, parser) -> None:
        self.parser = parser
        self.depth = 0
        self.in_parameters = False
        self.model: str | None = None
        self.parameters: dict[str, float] = {}

    def refuse(self, problem: str):
        raise _Refused(self.parser.CurrentLineNumber, problem)

    def start(self, tag: str, attrs: dict) -> None:
        self.depth += 1
        if self.depth == 1:
            if tag != "KinematicModel":
                self.refuse(f"root element <{tag[:40]}> ({EXPECTED})")
            self.model = attrs.get("MODEL", "")
        elif self.depth == 2 and tag == "Parameters":
            self.in_parameters = True
        elif self.depth == 3 and self.in_parameters and tag in PARAMETER_ELEMENTS:
            self.parameter(tag, attrs)

    def end(self, tag: str) -> None:
        if self.depth == 2 and tag == "Parameters":
            self.in_parameters = False
        self.depth -= 1

    def parameter(self, tag: str, attrs: dict) -> None:
        name = attrs.get("NAME")
        if name is None or not _NAME.fullmatch(name):
            self.refuse(f"<{tag}> NAME {shown(name)} (expected a parameter name: letters, digits and _)")
        text = attrs.get("VALUE", "").strip()
        if not text:
            return  # a parameter the lab left empty: absent
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        if not math.isfinite(value):
            self.refuse(f"{name}: VALUE {shown(text)} (expected a finite number)")
        key = f"PROCESSING:{name}"
        if key in self.parameters:
            self.refuse(f"{name}: given twice (expected each parameter once)")
        if len(self.parameters) >= MAX_PARAMETERS:
            self.refuse(f"more than {MAX_PARAMETERS:,} parameters (expected a subject file)")
        self.parameters[key] = value

    def doctype(self, *_) -> None:
        self.refuse("has a document type declaration (<!DOCTYPE>; expected a plain Vicon subject file, which "
                    "has none)")

    def entity(self, *_) -> None:
        self.refuse("declares an entity (expected a plain Vicon subject file, which declares none)")


def read_vsk(path: str | Path) -> VskSubject:
    """Read a Vicon ``.vsk`` (module docstring for the limits); any problem is one :class:`InputError` line."""
    path = Path(path)
    try:
        size = path.stat().st_size
        if size > MAX_VSK_BYTES:
            raise InputError(path, None, f"{size:,} bytes (expected a Vicon subject file of at most "
                                         f"{MAX_VSK_BYTES:,} bytes)")
        data = path.read_bytes()
    except FileNotFoundError:
        raise InputError(path, None, "file not found (expected a Vicon subject file, .vsk)") from None
    except PermissionError:
        raise InputError(path, None, "cannot be read (permission denied)") from None
    except IsADirectoryError:
        raise InputError(path, None, "is a folder (expected a Vicon subject file, .vsk)") from None
    parser = expat.ParserCreate()
    parser.SetParamEntityParsing(expat.XML_PARAM_ENTITY_PARSING_NEVER)
    reader = _Reader(parser)
    parser.StartElementHandler = reader.start
    parser.EndElementHandler = reader.end
    parser.StartDoctypeDeclHandler = reader.doctype
    parser.EntityDeclHandler = reader.entity
    parser.ExternalEntityRefHandler = lambda *_: reader.refuse("refers to an external entity (expected none)")
    try:
        parser.Parse(data, True)
    except _Refused as refused:
        where = None if refused.line is None else f"line {refused.line}"
        raise InputError(path, where, refused.problem) from None
    except expat.ExpatError as exc:
        raise InputError(path, f"line {exc.lineno}", f"not valid XML ({expat.ErrorString(exc.code)}; "
                                                     f"{EXPECTED})") from None
    if reader.model is None:
        raise InputError(path, None, f"empty ({EXPECTED})")
    return VskSubject(source=path, model=reader.model.strip(), parameters=reader.parameters)
