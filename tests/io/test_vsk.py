"""Reading Vicon subject files (gaitcli/io/vsk.py): the model and the numeric parameters under the C3D's
PROCESSING keys, bounded size, no document type declarations, one-line errors."""

from __future__ import annotations

import re

import ezc3d
import pytest

from gaitcli.errors import InputError
from gaitcli.io import vsk as vsk_module
from gaitcli.io.vsk import MAX_VSK_BYTES, read_vsk

#: a small subject file in Vicon's layout: the values below are what it must give back
SMALL = """<?xml version="1.0" encoding="UTF-8" standalone="no"?>
<KinematicModel MODEL="PlugInGait LowerBody Ai" VERSION="3.2">
\t<Parameters>
\t\t<StaticParameter NAME="Bodymass" VALUE="72.5" PRIOR="65" QUANTITY="mass"/>
\t\t<StaticParameter NAME="Height" VALUE="1712" PRIOR="1700" QUANTITY="length"/>
\t\t<StaticParameter NAME="RightKneeWidth" VALUE="101.25" PRIOR="120" QUANTITY="length"/>
\t\t<StaticParameter NAME="LeftTibialTorsion" PRIOR="0" QUANTITY="angle"/>
\t\t<StaticParameter NAME="LeftSoleDelta" VALUE="" PRIOR="0" QUANTITY="length"/>
\t\t<StaticParameter NAME="LeftStaticPlantFlex" VALUE="0.25269871950149536" READONLY="true" QUANTITY="angle"/>
\t\t<Parameter NAME="RBWT_Root_X" VALUE="-47.252189636230469" PRIOR="-36.2" SD="0"/>
\t\t<Parameter NAME="Tiny" VALUE="1.5e-3" SD="0"/>
\t</Parameters>
\t<Skeleton>
\t\t<Segment NAME="Pelvis"><Parameter NAME="Inside" VALUE="9"/></Segment>
\t</Skeleton>
</KinematicModel>
"""
SMALL_VALUES = {"PROCESSING:Bodymass": 72.5, "PROCESSING:Height": 1712.0, "PROCESSING:RightKneeWidth": 101.25,
                "PROCESSING:LeftStaticPlantFlex": 0.25269871950149536, "PROCESSING:RBWT_Root_X": -47.252189636230469,
                "PROCESSING:Tiny": 0.0015}


def _write(tmp_path, text, name="Subject.vsk"):
    path = tmp_path / name
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text, encoding="utf-8")
    return path


def _refused(path, pattern) -> InputError:
    with pytest.raises(InputError, match=pattern) as info:
        read_vsk(path)
    message = str(info.value)
    assert "\n" not in message and message.startswith(str(path)), message
    assert info.value.exit_code == 2
    return info.value


def test_a_small_file_is_read_back_exactly(tmp_path):
    """Every numeric VALUE of a StaticParameter or Parameter directly in <Parameters>, under PROCESSING:<NAME>;
    a parameter with no VALUE (or an empty one) is absent; nothing outside <Parameters> is a parameter."""
    subject = read_vsk(_write(tmp_path, SMALL))
    assert subject.model == "PlugInGait LowerBody Ai"
    assert subject.parameters == SMALL_VALUES
    assert all(type(v) is float for v in subject.parameters.values())
    assert subject.value("Bodymass") == 72.5 and subject.value("LeftTibialTorsion") is None
    assert subject.source == tmp_path / "Subject.vsk"


def test_utf16_and_no_declaration_are_fine(tmp_path):
    utf16 = SMALL.replace('encoding="UTF-8"', 'encoding="UTF-16"').encode("utf-16")
    assert read_vsk(_write(tmp_path, utf16)).parameters == SMALL_VALUES
    plain = SMALL.split("\n", 1)[1]
    assert read_vsk(_write(tmp_path, plain, "plain.vsk")).parameters == SMALL_VALUES


def test_a_model_without_parameters_or_name(tmp_path):
    subject = read_vsk(_write(tmp_path, "<KinematicModel><Skeleton/></KinematicModel>"))
    assert subject.model == "" and subject.parameters == {}


BILLION_LAUGHS = """<?xml version="1.0"?>
<!DOCTYPE KinematicModel [
 <!ENTITY a "aaaaaaaaaa">
 <!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;">
 <!ENTITY c "&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;">
 <!ENTITY d "&c;&c;&c;&c;&c;&c;&c;&c;&c;&c;">
]>
<KinematicModel MODEL="&d;"><Parameters><StaticParameter NAME="Bodymass" VALUE="1"/></Parameters></KinematicModel>
"""


@pytest.mark.parametrize("text", [
    BILLION_LAUGHS,
    '<?xml version="1.0"?>\n<!DOCTYPE KinematicModel SYSTEM "file:///etc/passwd">\n<KinematicModel/>',
    '<?xml version="1.0"?>\n<!DOCTYPE x [<!ENTITY secret SYSTEM "file:///etc/hostname">]>\n'
    '<KinematicModel MODEL="&secret;"/>',
    '<!DOCTYPE KinematicModel>\n<KinematicModel MODEL="PlugInGait"/>',
], ids=["entity expansion", "external DTD", "external entity", "bare doctype"])
def test_a_document_type_declaration_is_refused(tmp_path, text):
    err = _refused(_write(tmp_path, text), r"Subject\.vsk: line [12]: has a document type declaration")
    assert "passwd" not in str(err) and "hostname" not in str(err) and "aaaa" not in str(err)


def test_the_size_is_bounded_before_reading(tmp_path, monkeypatch):
    path = _write(tmp_path, SMALL)
    monkeypatch.setattr(vsk_module, "MAX_VSK_BYTES", 100)
    _refused(path, rf"{path.stat().st_size:,} bytes \(expected a Vicon subject file of at most 100 bytes\)")
    assert MAX_VSK_BYTES >= 1_000_000  # a real full-body file is 62 kB


def test_the_parameter_count_is_bounded(tmp_path, monkeypatch):
    monkeypatch.setattr(vsk_module, "MAX_PARAMETERS", 3)
    _refused(_write(tmp_path, SMALL), "more than 3 parameters")


@pytest.mark.parametrize("text,pattern", [
    ("", r"not valid XML \(no element found; expected a Vicon subject file"),
    ('<KinematicModel MODEL="x"><Parameters>', r"line 1: not valid XML"),
    (b"\x89HDF\r\n\x1a\n\x00\x00\xff binary", "not valid XML"),
    ("mass_kg: 70\nstature_m: 1.7\n", r"line 1: not valid XML"),
    ('<?xml version="1.0"?>\n<Skeleton/>', r"line 2: root element <Skeleton> \(expected a Vicon subject file: XML "
                                           r"with a <KinematicModel> root element\)"),
    ('<KinematicModel>\n<Parameters>\n<Parameter NAME="Bodymass" VALUE="heavy"/></Parameters></KinematicModel>',
     r"line 3: Bodymass: VALUE 'heavy' \(expected a finite number\)"),
    ('<KinematicModel><Parameters><Parameter NAME="Height" VALUE="nan"/></Parameters></KinematicModel>',
     r"Height: VALUE 'nan' \(expected a finite number\)"),
    ('<KinematicModel><Parameters><Parameter NAME="Height" VALUE="1e999"/></Parameters></KinematicModel>',
     r"Height: VALUE '1e999' \(expected a finite number\)"),
    ('<KinematicModel><Parameters><Parameter VALUE="3"/></Parameters></KinematicModel>',
     r"<Parameter> NAME None \(expected a parameter name"),
    ('<KinematicModel><Parameters><Parameter NAME="a/b" VALUE="3"/></Parameters></KinematicModel>',
     r"<Parameter> NAME 'a/b' \(expected a parameter name"),
    ('<KinematicModel><Parameters>\n<Parameter NAME="H" VALUE="3"/>\n<StaticParameter NAME="H" VALUE="3"/>'
     '</Parameters></KinematicModel>', r"line 3: H: given twice"),
], ids=["empty", "unclosed", "binary", "yaml", "other root", "text value", "nan", "overflow", "no name",
        "bad name", "twice"])
def test_a_malformed_or_foreign_file_is_one_line(tmp_path, text, pattern):
    _refused(_write(tmp_path, text), pattern)


def test_missing_file_and_folder(tmp_path):
    _refused(tmp_path / "gone.vsk", "file not found")
    (tmp_path / "dir.vsk").mkdir()
    _refused(tmp_path / "dir.vsk", "is a folder")


# ------------------------------------------------------------------------------------ the real session


@pytest.mark.shared
def test_the_real_subject_file(shared_pig_dir):
    """Test.vsk's measurements as the session's README lists them."""
    subject = read_vsk(shared_pig_dir / "Test.vsk")
    assert subject.model == "PlugInGait FullBody Ai"
    expected = {"Bodymass": 85.0, "Height": 1679.0, "RightKneeWidth": 139.0, "LeftKneeWidth": 144.0,
                "RightAnkleWidth": 89.0, "LeftAnkleWidth": 85.0, "InterAsisDistance": 306.0,
                "RightLegLength": 866.0, "LeftLegLength": 877.0}
    assert {name: subject.value(name) for name in expected} == expected
    for absent in ("LeftTibialTorsion", "RightTibialTorsion", "LeftSoleDelta", "RightSoleDelta", "MarkerDiameter"):
        assert subject.value(absent) is None  # no VALUE in the file


@pytest.mark.shared
def test_the_real_subject_file_agrees_with_the_c3d_processing_group(shared_pig_dir):
    """Units: every parameter equals the one Nexus wrote into Static_trial.c3d's PROCESSING group (mm, kg, rad;
    float32 there), whose names spell Left/Right as L/R."""
    subject = read_vsk(shared_pig_dir / "Test.vsk")
    processing = ezc3d.c3d(str(shared_pig_dir / "Static_trial.c3d"))["parameters"]["PROCESSING"]
    compared = 0
    for key, value in subject.parameters.items():
        name = key.removeprefix("PROCESSING:")
        c3d_name = name if name in processing else re.sub(r"^(L|R)(eft|ight)", r"\1", name)
        if c3d_name not in processing:
            continue
        assert float(processing[c3d_name]["value"][0]) == pytest.approx(value, rel=1e-6, abs=1e-6), name
        compared += 1
    assert compared == len(subject.parameters) - 1  # all but HeadOffset, which the C3D does not carry
    assert subject.value("LeftStaticPlantFlex") == pytest.approx(0.2527, abs=1e-4)  # radians (14.5°), not degrees
